//! Accessors, checked and read by rayterm itself rather than through the
//! crate's reader (which takes them on trust and reads floats only): every
//! component type with its `normalized` flag (`KHR_mesh_quantization`),
//! sparse substitutions, zeros where there is no view, values not aligned
//! to their components (read byte by byte, with a warning), and views
//! decoded from `EXT_meshopt_compression`.

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::buffer::View;
use anyhow::{anyhow, bail, Result};

use super::Reader;
use crate::memory;

/// A component as a number, as glTF reads it: floats as they are,
/// normalised integers to -1..1 (signed, the most negative value
/// clamped to -1) or 0..1, other integers as they are.
fn number(t: DataType, normalized: bool, b: &[u8]) -> f64 {
    let (v, max) = match t {
        DataType::I8 => (b[0] as i8 as f64, 127.0),
        DataType::U8 => (b[0] as f64, 255.0),
        DataType::I16 => (i16::from_le_bytes([b[0], b[1]]) as f64, 32767.0),
        DataType::U16 => (u16::from_le_bytes([b[0], b[1]]) as f64, 65535.0),
        DataType::U32 => return u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        DataType::F32 => return f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    };
    match normalized {
        true => (v / max).max(-1.0),
        false => v,
    }
}

fn listed<T: std::fmt::Debug>(items: &[T], sep: &str) -> String {
    items
        .iter()
        .map(|d| format!("{d:?}"))
        .collect::<Vec<_>>()
        .join(sep)
}

impl Reader<'_> {
    /// The bytes of buffer view `v` (decoded, where compressed, by
    /// [`Reader::unpack`]); empty where they lie outside its buffer, which
    /// [`Reader::check_accessor`] refuses first.
    fn view_bytes(&self, v: &View) -> &[u8] {
        if let Some(d) = self.unpacked.get(&v.index()) {
            return d;
        }
        self.buffers
            .get(v.buffer().index())
            .and_then(|b| b.get(v.offset()..v.offset().checked_add(v.length())?))
            .unwrap_or(&[])
    }

    /// The buffer accessor `a`'s values are read from: its view's, or for
    /// a compressed view, the one its compressed bytes lie in.
    pub(super) fn buffer_of(&self, a: &::gltf::Accessor) -> Option<usize> {
        let v = a.view()?;
        match self.compressed.get(&v.index()) {
            Some(Ok(c)) => Some(c.buffer),
            _ => Some(v.buffer().index()),
        }
    }

    /// Checks that `count` `things` of `size` bytes (`component`-byte
    /// components) from `offset` lie inside view `v` and the view inside
    /// its buffer (or, compressed, its compressed bytes in theirs); what
    /// is wrong with their alignment, if anything.
    #[allow(clippy::too_many_arguments)]
    fn check_span(
        &self,
        name: &str,
        things: &str,
        v: &View,
        offset: usize,
        count: usize,
        size: usize,
        component: usize,
    ) -> Result<Option<String>> {
        let (element, component) = (size as u128, component as u128);
        let stride = v.stride().map_or(element, |s| s as u128);
        if stride < element {
            bail!("{name}: the buffer view's byteStride {stride} is smaller than one element ({element} bytes)");
        }
        let compressed = match self.compressed.get(&v.index()) {
            Some(Err(e)) => bail!(
                "{name}: buffer view {} (EXT_meshopt_compression): {e}",
                v.index()
            ),
            Some(Ok(c)) => Some(c),
            None => None,
        };
        // A decoded view starts a buffer of its own.
        let view_offset = compressed.map_or(v.offset() as u128, |_| 0);
        let start = view_offset + offset as u128;
        // Values are read byte by byte, so misaligned ones read as well as
        // others; glTF requires alignment, so it is said.
        let misaligned = (!start.is_multiple_of(component) || !stride.is_multiple_of(component))
            .then(|| {
                format!(
                    "{name}: its {things} are not aligned to their {component}-byte components \
                     (offset {start}, stride {stride})"
                )
            });
        let end_in_view = offset as u128 + stride * (count as u128).saturating_sub(1) + element;
        let (buffer, view_end) = match compressed {
            Some(c) => {
                let b = self.buffers.get(c.buffer).map_or(0, Vec::len) as u128;
                let end = c.offset as u128 + c.length as u128;
                if end > b {
                    bail!(
                        "{name}: buffer view {} (EXT_meshopt_compression): its compressed bytes \
                         end at byte {end} of a {b}-byte buffer (truncated?)",
                        v.index()
                    );
                }
                (v.length() as u128, v.length() as u128)
            }
            None => (
                self.buffers.get(v.buffer().index()).map_or(0, Vec::len) as u128,
                v.offset() as u128 + v.length() as u128,
            ),
        };
        if end_in_view > v.length() as u128 || view_end > buffer {
            bail!(
                "{name}: its {count} {things} end at byte {end_in_view} of a {}-byte buffer view \
                 ending at byte {view_end} of a {buffer}-byte buffer (truncated or wrong counts?)",
                v.length()
            );
        }
        Ok(misaligned)
    }

    /// Checks what reading accessor `a` takes: its type is one glTF allows
    /// for `what`, and every element it reads (and every sparse index and
    /// value) lies inside its view and buffer; one that is not aligned is
    /// noted for [`Reader::misaligned_warning`].
    pub(super) fn check_accessor(
        &self,
        here: &str,
        what: &str,
        a: &::gltf::Accessor,
        types: &[DataType],
        dims: &[Dimensions],
    ) -> Result<()> {
        let name = format!("{here}: {what} (accessor {})", a.index());
        if !types.contains(&a.data_type()) || !dims.contains(&a.dimensions()) {
            bail!(
                "{name} is {:?} {:?}; glTF allows {} of {}",
                a.dimensions(),
                a.data_type(),
                listed(dims, " or "),
                listed(types, ", ")
            );
        }
        if a.count() == 0 {
            bail!("{name} has no elements (count 0)");
        }
        let (size, component) = (a.size(), a.data_type().size());
        // Without a view, its values are zeros (glTF says so), with or
        // without sparse ones over them.
        let mut misaligned = None;
        if let Some(v) = a.view() {
            misaligned = self.check_span(
                &name,
                "elements",
                &v,
                a.offset(),
                a.count(),
                size,
                component,
            )?;
        }
        if let Some(s) = a.sparse().filter(|s| s.count() > 0) {
            if s.count() > a.count() {
                bail!(
                    "{name}: {} sparse values for {} elements",
                    s.count(),
                    a.count()
                );
            }
            let (ix, values) = (s.indices(), s.values());
            let index = ix.index_type().size();
            let indices = self.check_span(
                &name,
                "sparse indices",
                &ix.view(),
                ix.offset(),
                s.count(),
                index,
                index,
            )?;
            let values = self.check_span(
                &name,
                "sparse values",
                &values.view(),
                values.offset(),
                s.count(),
                size,
                component,
            )?;
            misaligned = misaligned.or(indices).or(values);
        }
        if let Some(why) = misaligned {
            self.misaligned.borrow_mut().entry(a.index()).or_insert(why);
        }
        Ok(())
    }

    /// The warning for the accessors not aligned as glTF requires, read
    /// all the same: the first named, the others counted.
    pub(super) fn misaligned_warning(&self) -> Option<String> {
        let all = self.misaligned.borrow();
        let first = all.values().next()?;
        let more = match all.len() {
            1 => String::new(),
            n => format!(
                " (and {})",
                crate::words::count(n as u64 - 1, "more accessor", "more accessors")
            ),
        };
        Some(format!(
            "{first}, which glTF requires{more}: read all the same"
        ))
    }

    /// Decodes the compressed views accessors `used` read (their own and
    /// their sparse parts'), each once, its size checked against the
    /// memory available first.
    pub(super) fn unpack(&mut self, used: &[::gltf::Accessor]) -> Result<()> {
        let views = used.iter().flat_map(|a| {
            let sparse = a.sparse().map(|s| [s.indices().view(), s.values().view()]);
            a.view().into_iter().chain(sparse.into_iter().flatten())
        });
        for v in views {
            let i = v.index();
            let Some(Ok(c)) = self.compressed.get(&i) else {
                continue;
            };
            if self.unpacked.contains_key(&i) {
                continue;
            }
            let at = format!(
                "{}: buffer view {i} (EXT_meshopt_compression, {:?})",
                self.at(),
                c.mode
            );
            memory::check(&at, (c.count * c.stride) as u64, None)?;
            let src = self
                .buffers
                .get(c.buffer)
                .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
                .ok_or_else(|| {
                    anyhow!("{at}: its compressed bytes lie outside buffer {}", c.buffer)
                })?;
            let data = c.decode(src).map_err(|e| anyhow!("{at}: {e}"))?;
            self.unpacked.insert(i, data);
        }
        Ok(())
    }

    /// The sparse indices of `a`, checked: strictly increasing, each below
    /// its count.
    fn sparse_indices(&self, name: &str, a: &::gltf::Accessor) -> Result<Vec<usize>> {
        let Some(s) = a.sparse().filter(|s| s.count() > 0) else {
            return Ok(Vec::new());
        };
        let ix = s.indices();
        let size = ix.index_type().size();
        let stride = ix.view().stride().unwrap_or(size);
        let bytes = self.view_bytes(&ix.view());
        let mut out = Vec::with_capacity(s.count());
        for k in 0..s.count() {
            let at = ix.offset() + k * stride;
            let b = bytes
                .get(at..at + size)
                .ok_or_else(|| anyhow!("{name}: sparse index {k} cannot be read"))?;
            let i = match size {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= a.count() {
                bail!(
                    "{name}: sparse index {k} is {i}, out of range ({} elements)",
                    a.count()
                );
            }
            if out.last().is_some_and(|&l| i <= l) {
                bail!(
                    "{name}: sparse index {k} is {i}, not above the one before ({}); glTF \
                     requires them strictly increasing",
                    out[k - 1]
                );
            }
            out.push(i);
        }
        Ok(out)
    }

    /// Calls `f` with each element of accessor `a` in order, as numbers
    /// ([`number`]), with its sparse substitutions (over zeros where it
    /// has no view). `what` names it in messages; [`Reader::check_accessor`]
    /// and [`Reader::unpack`] come first.
    pub(super) fn each(
        &self,
        here: &str,
        what: &str,
        a: &::gltf::Accessor,
        mut f: impl FnMut(&[f64]),
    ) -> Result<()> {
        let name = format!("{here}: {what} (accessor {})", a.index());
        let (t, normalized) = (a.data_type(), a.normalized());
        let (n, size, component) = (a.dimensions().multiplicity(), a.size(), t.size());
        let mut e = [0f64; 16];
        let read = |bytes: &[u8], at: usize, e: &mut [f64; 16]| -> Result<()> {
            let b = bytes
                .get(at..at + size)
                .ok_or_else(|| anyhow!("{name} cannot be read"))?;
            for (k, x) in e[..n].iter_mut().enumerate() {
                *x = number(t, normalized, &b[k * component..]);
            }
            Ok(())
        };
        let base = a.view().map(|v| {
            let stride = v.stride().unwrap_or(size);
            (self.view_bytes(&v), stride)
        });
        let sparse = self.sparse_indices(&name, a)?;
        let values = a.sparse().map(|s| {
            let v = s.values().view();
            (
                self.view_bytes(&v),
                s.values().offset(),
                v.stride().unwrap_or(size),
            )
        });
        let mut next = 0;
        for i in 0..a.count() {
            match (sparse.get(next), values) {
                (Some(&s), Some((bytes, offset, stride))) if s == i => {
                    read(bytes, offset + next * stride, &mut e)?;
                    next += 1;
                }
                _ => match base {
                    Some((bytes, stride)) => read(bytes, a.offset() + i * stride, &mut e)?,
                    None => e = [0.0; 16],
                },
            }
            f(&e[..n]);
        }
        Ok(())
    }
}
