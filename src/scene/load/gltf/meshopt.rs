//! `EXT_meshopt_compression`: buffer views stored with meshoptimizer's
//! codecs (gltfpack `-c`, `-cc`), decoded as the extension's bitstream
//! appendix specifies. Written here rather than taken from a crate: the
//! `meshopt` crate compiles the C++ library, and the pure-Rust ports take
//! a compile-time vertex size or bring a whole optimiser; the format is
//! frozen by the extension and its decoders are short. Every read is
//! bounds-checked: a malformed stream is an error, never a panic.

use std::collections::HashMap;

use serde_json::Value;

const NAME: &str = "EXT_meshopt_compression";

/// The compressed buffer views of a document by index, each as its
/// extension object reads ([`Compressed::parse`]).
pub(super) fn views(doc: &::gltf::Document) -> HashMap<usize, Result<Compressed, String>> {
    doc.views()
        .filter_map(|v| {
            let ext = v.extension_value(NAME)?;
            Some((v.index(), Compressed::parse(ext, v.length(), v.stride())))
        })
        .collect()
}

/// Whether a buffer is marked as the fallback of compressed views: never
/// read, as those views are decoded from their compressed bytes (it often
/// has no data at all).
pub(super) fn fallback(b: &::gltf::Buffer) -> bool {
    b.extension_value(NAME)
        .and_then(|e| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

/// How a view's bytes are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    Attributes,
    Triangles,
    Indices,
}

/// What is done to the elements once decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
}

/// A compressed view: where its encoded bytes lie and what they decode to
/// (`count` elements of `stride` bytes).
#[derive(Clone, Debug)]
pub(super) struct Compressed {
    pub(crate) buffer: usize,
    pub(crate) offset: usize,
    pub(crate) length: usize,
    pub(crate) stride: usize,
    pub(crate) count: usize,
    pub(crate) mode: Mode,
    pub(crate) filter: Filter,
}

impl Compressed {
    /// The extension object of a view whose `byteLength` is `view_length`
    /// (and `byteStride`, `view_stride`), checked as the extension requires.
    pub(crate) fn parse(
        ext: &Value,
        view_length: usize,
        view_stride: Option<usize>,
    ) -> Result<Compressed, String> {
        let int = |key: &str, default: Option<usize>| -> Result<usize, String> {
            match ext.get(key) {
                None => default.ok_or_else(|| format!("it has no {key}")),
                Some(v) => v
                    .as_u64()
                    .and_then(|n| usize::try_from(n).ok())
                    .ok_or_else(|| format!("its {key} {v} is not a count of bytes or elements")),
            }
        };
        let word = |key: &str, default: &'static str| match ext.get(key) {
            None => Ok(default),
            Some(Value::String(s)) => Ok(s.as_str()),
            Some(v) => Err(format!("its {key} {v} is not a string")),
        };
        let c = Compressed {
            buffer: int("buffer", None)?,
            offset: int("byteOffset", Some(0))?,
            length: int("byteLength", None)?,
            stride: int("byteStride", None)?,
            count: int("count", None)?,
            mode: match word("mode", "")? {
                "ATTRIBUTES" => Mode::Attributes,
                "TRIANGLES" => Mode::Triangles,
                "INDICES" => Mode::Indices,
                m => return Err(format!("its mode {} is not one glTF defines", quoted(m))),
            },
            filter: match word("filter", "NONE")? {
                "NONE" => Filter::None,
                "OCTAHEDRAL" => Filter::Octahedral,
                "QUATERNION" => Filter::Quaternion,
                "EXPONENTIAL" => Filter::Exponential,
                f => return Err(format!("its filter {} is not one glTF defines", quoted(f))),
            },
        };
        let s = c.stride;
        let bad_stride = match (c.mode, c.filter) {
            (Mode::Attributes, Filter::Octahedral) => s != 4 && s != 8,
            (Mode::Attributes, Filter::Quaternion) => s != 8,
            (Mode::Attributes, _) => s == 0 || s > 256 || !s.is_multiple_of(4),
            (_, Filter::None) => s != 2 && s != 4,
            (m, f) => return Err(format!("mode {m:?} takes no filter ({f:?})")),
        };
        if bad_stride {
            return Err(format!(
                "byteStride {s} is not one {:?} with filter {:?} allows",
                c.mode, c.filter
            ));
        }
        if c.mode == Mode::Triangles && !c.count.is_multiple_of(3) {
            return Err(format!("{} indices do not make whole triangles", c.count));
        }
        if view_stride.is_some_and(|v| v != s) {
            return Err(format!(
                "byteStride {s} differs from the buffer view's {}",
                view_stride.unwrap_or_default()
            ));
        }
        let size = c.count as u128 * s as u128;
        if size != view_length as u128 {
            return Err(format!(
                "{} elements of {s} bytes make {size} bytes, the buffer view's byteLength is \
                 {view_length}",
                c.count
            ));
        }
        // The least each encoding takes: 2 header bits per 16 bytes of
        // attributes, a code byte per triangle, a byte per index.
        let least = match c.mode {
            Mode::Attributes => size / 64,
            Mode::Triangles => c.count as u128 / 3,
            Mode::Indices => c.count as u128,
        };
        if (c.length as u128) < least {
            return Err(format!(
                "{} bytes cannot encode {} elements of {s} bytes (truncated?)",
                c.length, c.count
            ));
        }
        Ok(c)
    }

    /// The `count * stride` bytes `src` (the extension's byte range)
    /// encodes.
    pub(crate) fn decode(&self, src: &[u8]) -> Result<Vec<u8>, String> {
        let mut out = vec![0u8; self.count * self.stride];
        match self.mode {
            Mode::Attributes => {
                vertices(&mut out, self.count, self.stride, src)?;
                match self.filter {
                    Filter::None => {}
                    Filter::Octahedral => octahedral(&mut out, self.stride),
                    Filter::Quaternion => quaternion(&mut out),
                    Filter::Exponential => exponential(&mut out),
                }
            }
            Mode::Triangles => triangles(&mut out, self.stride, src)?,
            Mode::Indices => sequence(&mut out, self.stride, src)?,
        }
        Ok(out)
    }
}

fn quoted(s: &str) -> String {
    crate::words::quoted(s)
}

const SHORT: &str = "the data ends too soon";

/// A cursor over encoded bytes that errors, rather than panics, at the end.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn byte(&mut self) -> Result<u8, String> {
        let b = *self.data.get(self.at).ok_or(SHORT)?;
        self.at += 1;
        Ok(b)
    }

    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let s = self
            .data
            .get(self.at..self.at.checked_add(n).ok_or(SHORT)?)
            .ok_or(SHORT)?;
        self.at += n;
        Ok(s)
    }

    /// An unsigned LEB128 number of at most 32 bits.
    fn varint(&mut self) -> Result<u32, String> {
        let mut n = 0u32;
        for shift in (0..35).step_by(7) {
            let b = self.byte()?;
            n |= ((b & 0x7f) as u32).checked_shl(shift).unwrap_or(0);
            if b < 0x80 {
                return Ok(n);
            }
        }
        Err("a variable-length number runs past 32 bits".into())
    }
}

/// Zigzag decoding: 0, 1, 2, 3 ... to 0, -1, 1, -2 ...
fn unzig8(v: u8) -> u8 {
    (v >> 1) ^ (v & 1).wrapping_neg()
}

fn unzig32(v: u32) -> u32 {
    (v >> 1) ^ (v & 1).wrapping_neg()
}

/// Mode 0: each block of elements holds, for each byte of an element,
/// the deltas from the element before, in groups of 16 (2 header bits a
/// group give their width); the first element's deltas are from the
/// baseline in the tail.
fn vertices(out: &mut [u8], count: usize, stride: usize, src: &[u8]) -> Result<(), String> {
    match src.first() {
        Some(0xa0) => {}
        Some(h) if h & 0xf0 == 0xa0 => {
            return Err(format!(
                "attribute encoding version {} is not the version 0 the extension specifies",
                h & 0x0f
            ))
        }
        _ => return Err("it does not start as attribute data does (0xa0)".into()),
    }
    // The tail: the baseline element, padded to 32 bytes.
    let tail = stride.max(32);
    if src.len() < 1 + tail {
        return Err(SHORT.into());
    }
    let mut last = src[src.len() - stride..].to_vec();
    let mut data = Bytes {
        data: &src[..src.len() - tail],
        at: 1,
    };
    let block = ((8192 / stride) & !15).min(256);
    let mut deltas = vec![0u8; block * stride];
    let mut base = 0;
    while base < count {
        let n = (count - base).min(block);
        let groups = n.div_ceil(16);
        for byte in 0..stride {
            let header = data.take(groups.div_ceil(4))?;
            let row = &mut deltas[byte * block..byte * block + groups * 16];
            for (g, d) in row.chunks_exact_mut(16).enumerate() {
                match (header[g / 4] >> ((g % 4) * 2)) & 3 {
                    0 => d.fill(0),
                    1 => sentinel(d, &mut data, 2)?,
                    2 => sentinel(d, &mut data, 4)?,
                    _ => d.copy_from_slice(data.take(16)?),
                }
            }
        }
        for e in 0..n {
            let element = &mut out[(base + e) * stride..(base + e + 1) * stride];
            for (byte, (o, l)) in element.iter_mut().zip(&mut last).enumerate() {
                *l = l.wrapping_add(unzig8(deltas[byte * block + e]));
                *o = *l;
            }
        }
        base += n;
    }
    if data.at != data.data.len() {
        return Err(format!(
            "{} bytes are left over after the attribute data",
            data.data.len() - data.at
        ));
    }
    Ok(())
}

/// 16 deltas of `bits` bits (most significant first in each byte); one
/// with all its bits set is read whole from the bytes that follow.
fn sentinel(d: &mut [u8], data: &mut Bytes, bits: u32) -> Result<(), String> {
    let packed = data.take(16 * bits as usize / 8)?;
    let per = 8 / bits as usize;
    let mask = (1u8 << bits) - 1;
    for (m, v) in d.iter_mut().enumerate() {
        let shift = 8 - bits as usize * (m % per + 1);
        let x = (packed[m / per] >> shift) & mask;
        *v = if x == mask { data.byte()? } else { x };
    }
    Ok(())
}

/// Writes index `i` of `out`, `stride` 2 or 4 bytes an index.
fn put(out: &mut [u8], stride: usize, i: usize, v: u32) -> Result<(), String> {
    if stride == 2 && v > u16::MAX as u32 {
        return Err(format!("index {v} does not fit 16 bits"));
    }
    out[i * stride..(i + 1) * stride].copy_from_slice(&v.to_le_bytes()[..stride]);
    Ok(())
}

/// A FIFO of the last 16 (or 32) values pushed, read from the newest.
struct Fifo<const N: usize> {
    v: [u32; N],
    at: usize,
}

impl<const N: usize> Fifo<N> {
    fn push(&mut self, x: u32) {
        self.v[self.at] = x;
        self.at = (self.at + 1) % N;
    }

    fn get(&self, back: usize) -> u32 {
        self.v[(self.at + N - 1 - back) % N]
    }
}

/// The triangle decoder's state: the next new vertex, the last index
/// given explicitly, and the recent edges and vertices.
struct Tri {
    next: u32,
    last: u32,
    edges: Fifo<32>,
    verts: Fifo<16>,
}

impl Tri {
    fn fresh(&mut self) -> u32 {
        self.next = self.next.wrapping_add(1);
        self.next.wrapping_sub(1)
    }

    /// An index given as a zigzag delta from the last.
    fn explicit(&mut self, data: &mut Bytes) -> Result<u32, String> {
        self.last = self.last.wrapping_add(unzig32(data.varint()?));
        Ok(self.last)
    }

    /// A triangle's second or third index by its nibble `x`: the next new
    /// vertex (0), an explicit one (15, where `explicit` allows it) or a
    /// recent one; and whether it goes into the vertex FIFO.
    fn other(&mut self, x: usize, explicit: bool, data: &mut Bytes) -> Result<(u32, bool), String> {
        Ok(match x {
            0 => (self.fresh(), true),
            15 if explicit => (self.explicit(data)?, true),
            _ => (self.verts.get(x - 1), false),
        })
    }
}

/// Mode 1: a code byte per triangle, most naming an edge of a recent
/// triangle and a recent or next vertex; extra bytes after the codes, and
/// a 16-byte table at the end.
fn triangles(out: &mut [u8], stride: usize, src: &[u8]) -> Result<(), String> {
    if src.first() != Some(&0xe1) {
        return Err("it does not start as triangle data does (0xe1)".into());
    }
    let count = out.len() / stride / 3;
    if src.len() < 1 + count + 16 {
        return Err(SHORT.into());
    }
    let codes = &src[1..1 + count];
    let aux = &src[src.len() - 16..];
    let mut data = Bytes {
        data: &src[..src.len() - 16],
        at: 1 + count,
    };
    let mut s = Tri {
        next: 0,
        last: 0,
        edges: Fifo { v: [0; 32], at: 0 },
        verts: Fifo { v: [0; 16], at: 0 },
    };
    for (t, &code) in codes.iter().enumerate() {
        let (hi, lo) = ((code >> 4) as usize, (code & 15) as usize);
        let [a, b, c] = if hi < 15 {
            // A recent edge and a third vertex.
            let (a, b) = (s.edges.get(hi * 2), s.edges.get(hi * 2 + 1));
            let c = match lo {
                0 => s.fresh(),
                1..=12 => s.verts.get(lo),
                13 => {
                    s.last = s.last.wrapping_sub(1);
                    s.last
                }
                14 => {
                    s.last = s.last.wrapping_add(1);
                    s.last
                }
                _ => s.explicit(&mut data)?,
            };
            if lo == 0 || lo >= 13 {
                s.verts.push(c);
            }
            for v in [b, c, c, a] {
                s.edges.push(v);
            }
            [a, b, c]
        } else {
            // Three vertices: from the table, or from a byte (0 restarts
            // the new vertices) and explicit indices.
            let (a, zw) = if lo < 14 {
                (s.fresh(), aux[lo])
            } else {
                let e = data.byte()?;
                if e == 0 {
                    s.next = 0;
                }
                match lo {
                    14 => (s.fresh(), e),
                    _ => (s.explicit(&mut data)?, e),
                }
            };
            let (z, w) = ((zw >> 4) as usize, (zw & 15) as usize);
            let (b, push_b) = s.other(z, lo >= 14, &mut data)?;
            let (c, push_c) = s.other(w, lo >= 14, &mut data)?;
            s.verts.push(a);
            if push_b {
                s.verts.push(b);
            }
            if push_c {
                s.verts.push(c);
            }
            for v in [a, b, b, c, c, a] {
                s.edges.push(v);
            }
            [a, b, c]
        };
        for (k, v) in [a, b, c].into_iter().enumerate() {
            put(out, stride, t * 3 + k, v)?;
        }
    }
    if data.at != data.data.len() {
        return Err(format!(
            "{} bytes are left over after the triangle data",
            data.data.len() - data.at
        ));
    }
    Ok(())
}

/// Mode 2: each index a varint delta from one of two baselines (its low
/// bit says which); 4 reserved bytes at the end.
fn sequence(out: &mut [u8], stride: usize, src: &[u8]) -> Result<(), String> {
    if src.first() != Some(&0xd1) {
        return Err("it does not start as index data does (0xd1)".into());
    }
    if src.len() < 1 + 4 {
        return Err(SHORT.into());
    }
    let mut data = Bytes {
        data: &src[..src.len() - 4],
        at: 1,
    };
    let mut last = [0u32; 2];
    for i in 0..out.len() / stride {
        let v = data.varint()?;
        let b = (v & 1) as usize;
        last[b] = last[b].wrapping_add(unzig32(v >> 1));
        put(out, stride, i, last[b])?;
    }
    if data.at != data.data.len() {
        return Err(format!(
            "{} bytes are left over after the index data",
            data.data.len() - data.at
        ));
    }
    Ok(())
}

/// The signed components of each 4-component element of `data`, 8 or 16
/// bits (`stride` 4 or 8), read, changed by `f` and written back.
fn each_element(data: &mut [u8], stride: usize, mut f: impl FnMut(&mut [f32; 4], f32)) {
    let bits = stride * 2;
    let max = ((1u32 << (bits - 1)) - 1) as f32;
    for e in data.chunks_exact_mut(stride) {
        let mut v = [0f32; 4];
        for (k, x) in v.iter_mut().enumerate() {
            *x = match stride {
                4 => e[k] as i8 as f32,
                _ => i16::from_le_bytes([e[2 * k], e[2 * k + 1]]) as f32,
            };
        }
        f(&mut v, max);
        for (k, x) in v.iter().enumerate() {
            match stride {
                4 => e[k] = *x as i8 as u8,
                _ => e[2 * k..2 * k + 2].copy_from_slice(&(*x as i16).to_le_bytes()),
            }
        }
    }
}

/// Filter 1: unit vectors in octahedral coordinates, the third component
/// the encoding's 1.0, back to x, y, z as normalised integers.
fn octahedral(data: &mut [u8], stride: usize) {
    each_element(data, stride, |v, max| {
        let one = v[2];
        if one == 0.0 {
            *v = [0.0, 0.0, 0.0, v[3]];
            return;
        }
        let (mut x, mut y) = (v[0] / one, v[1] / one);
        let z = 1.0 - x.abs() - y.abs();
        let t = z.min(0.0);
        x -= t.copysign(x);
        y -= t.copysign(y);
        let h = max / (x * x + y * y + z * z).sqrt();
        *v = [(x * h).round(), (y * h).round(), (z * h).round(), v[3]];
    });
}

/// Filter 2: quaternions with their largest component left out (its
/// index in the last component's low 2 bits), back to 4 normalised
/// 16-bit components.
fn quaternion(data: &mut [u8]) {
    each_element(data, 8, |v, max| {
        let w_in = v[3] as i32;
        let s = std::f32::consts::FRAC_1_SQRT_2 / (w_in | 3) as f32;
        let (x, y, z) = (v[0] * s, v[1] * s, v[2] * s);
        let w = (1.0 - x * x - y * y - z * z).max(0.0).sqrt();
        let at = (w_in & 3) as usize;
        for (k, c) in [w, x, y, z].into_iter().enumerate() {
            v[(at + k) % 4] = (c * max).round();
        }
    });
}

/// Filter 3: 32-bit values of an 8-bit exponent and a 24-bit mantissa
/// (both signed), to floats `m * 2^e`.
fn exponential(data: &mut [u8]) {
    for e in data.chunks_exact_mut(4) {
        let v = i32::from_le_bytes([e[0], e[1], e[2], e[3]]);
        let (exp, mantissa) = (v >> 24, (v << 8) >> 8);
        let f = 2f32.powi(exp) * mantissa as f32;
        e.copy_from_slice(&f.to_le_bytes());
    }
}

#[cfg(test)]
mod tests {
    //! Streams written by meshoptimizer's own encoder (see
    //! tests/files/meshopt/make.mjs), decoded and checked against the
    //! formulas that made their values.

    use super::*;

    fn stream(name: &str) -> Vec<u8> {
        let path = format!("{}/tests/files/meshopt/{name}", env!("CARGO_MANIFEST_DIR"));
        std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
    }

    fn decode(name: &str, mode: Mode, filter: Filter, count: usize, stride: usize) -> Vec<u8> {
        let src = stream(name);
        let ext = serde_json::json!({
            "buffer": 0, "byteLength": src.len(), "byteStride": stride, "count": count,
            "mode": format!("{mode:?}").to_uppercase(), "filter": format!("{filter:?}").to_uppercase(),
        });
        let c = Compressed::parse(&ext, count * stride, None).unwrap();
        c.decode(&src).unwrap()
    }

    #[test]
    fn attributes_decode_to_their_bytes_over_two_blocks() {
        let (n, s) = (300, 12);
        let got = decode("attributes.bin", Mode::Attributes, Filter::None, n, s);
        for i in 0..n {
            for k in 0..s {
                let want = [i, i * i * 31 + k * 17 + (i >> 3), 0, (i >> 4) * 5 + k][k % 4] & 255;
                assert_eq!(got[i * s + k] as usize, want, "element {i} byte {k}");
            }
        }
    }

    /// The grid and scattered triangles make.mjs encodes, `off` added to
    /// the scattered ones.
    fn triangles_made(off: u32) -> Vec<[u32; 3]> {
        let mut t = Vec::new();
        for y in 0..8 {
            for x in 0..8 {
                let v = y * 9 + x;
                t.push([v, v + 1, v + 10]);
                t.push([v, v + 10, v + 9]);
            }
        }
        for k in 0..20 {
            t.push([
                (k * 7) % 81 + off,
                (k * 13 + 5) % 81 + off,
                (k * 29 + 11) % 81 + off,
            ]);
        }
        t
    }

    #[test]
    fn triangles_decode_to_the_same_triangles_in_order() {
        for (name, stride, off) in [("triangles16.bin", 2, 0), ("triangles32.bin", 4, 100_000)] {
            let got = decode(name, Mode::Triangles, Filter::None, 148 * 3, stride);
            let got: Vec<u32> = got
                .chunks_exact(stride)
                .map(|b| match stride {
                    2 => u16::from_le_bytes([b[0], b[1]]) as u32,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                })
                .collect();
            // The encoder may start a triangle at another corner; the
            // winding stays.
            for (t, (g, w)) in got.chunks_exact(3).zip(triangles_made(off)).enumerate() {
                let turns = [[g[0], g[1], g[2]], [g[1], g[2], g[0]], [g[2], g[0], g[1]]];
                assert!(turns.contains(&w), "{name} triangle {t}: {g:?}, want {w:?}");
            }
        }
    }

    #[test]
    fn indices_decode_from_two_baselines() {
        let got = decode("indices.bin", Mode::Indices, Filter::None, 100, 2);
        for (i, b) in got.chunks_exact(2).enumerate() {
            let want = if i % 2 == 0 { i / 2 } else { 1000 - i };
            assert_eq!(u16::from_le_bytes([b[0], b[1]]) as usize, want, "index {i}");
        }
    }

    /// Component `k` of element `i` of signed normalised integers.
    fn snorm(d: &[u8], stride: usize, i: usize, k: usize) -> f32 {
        match stride {
            4 => d[i * 4 + k] as i8 as f32 / 127.0,
            _ => i16::from_le_bytes([d[i * 8 + 2 * k], d[i * 8 + 2 * k + 1]]) as f32 / 32767.0,
        }
    }

    #[test]
    fn octahedral_filter_gives_unit_vectors_back() {
        for (name, stride, tolerance) in
            [("octahedral4.bin", 4, 0.03), ("octahedral8.bin", 8, 2e-3)]
        {
            let got = decode(name, Mode::Attributes, Filter::Octahedral, 50, stride);
            for i in 0..50 {
                let (a, b) = (i as f32 * 0.37, i as f32 * 0.21 + 0.3);
                let want = [a.cos() * b.sin(), a.sin() * b.sin(), b.cos()];
                for (k, w) in want.iter().enumerate() {
                    let g = snorm(&got, stride, i, k);
                    assert!((g - w).abs() < tolerance, "{name} {i}.{k}: {g} for {w}");
                }
            }
        }
    }

    #[test]
    fn quaternion_filter_gives_unit_quaternions_back() {
        let got = decode(
            "quaternion.bin",
            Mode::Attributes,
            Filter::Quaternion,
            50,
            8,
        );
        for i in 0..50 {
            let x = i as f32;
            let q = [
                (x * 0.3).sin(),
                (x * 0.7).cos(),
                (x * 1.1 + 1.0).sin(),
                (x * 0.5).cos(),
            ];
            let l = q.iter().map(|v| v * v).sum::<f32>().sqrt();
            let g: Vec<f32> = (0..4).map(|k| snorm(&got, 8, i, k)).collect();
            // q and -q are the same rotation; the encoder keeps the largest
            // component positive.
            let same = |s: f32| q.iter().zip(&g).all(|(w, g)| (s * w / l - g).abs() < 2e-3);
            assert!(same(1.0) || same(-1.0), "{i}: {g:?} for {q:?}");
        }
    }

    #[test]
    fn exponential_filter_gives_floats_back() {
        let got = decode(
            "exponential.bin",
            Mode::Attributes,
            Filter::Exponential,
            50,
            12,
        );
        for i in 0..50 {
            for k in 0..3 {
                let at = (i * 3 + k) * 4;
                let g = f32::from_le_bytes(got[at..at + 4].try_into().unwrap());
                let w = (i as f32 - 25.0 + k as f32 * 0.5) * 3.7 * 2f32.powi(i as i32 % 7 - 3);
                assert!(
                    (g - w).abs() <= w.abs() * 1e-4 + 1e-6,
                    "{i}.{k}: {g} for {w}"
                );
            }
        }
    }

    #[test]
    fn damaged_streams_are_errors_not_panics() {
        let cases = [
            ("attributes.bin", Mode::Attributes, 300, 12),
            ("triangles16.bin", Mode::Triangles, 444, 2),
            ("indices.bin", Mode::Indices, 100, 2),
        ];
        for (name, mode, count, stride) in cases {
            let src = stream(name);
            let c = Compressed {
                buffer: 0,
                offset: 0,
                length: src.len(),
                stride,
                count,
                mode,
                filter: Filter::None,
            };
            // Cut anywhere, or with a byte changed anywhere: an error or
            // some bytes, never a panic.
            for cut in 0..src.len() {
                assert!(c.decode(&src[..cut]).is_err(), "{name} cut to {cut} bytes");
            }
            for at in 0..src.len() {
                let mut bad = src.clone();
                bad[at] ^= 0x5a;
                let _ = c.decode(&bad);
            }
        }
        let short = serde_json::json!({"buffer": 0, "byteLength": 10, "byteStride": 12,
                                       "count": 1000, "mode": "ATTRIBUTES"});
        let e = Compressed::parse(&short, 12000, None).unwrap_err();
        assert!(e.contains("10 bytes cannot encode 1000 elements"), "{e}");
        let odd = serde_json::json!({"buffer": 0, "byteLength": 10, "byteStride": 6,
                                     "count": 2, "mode": "ATTRIBUTES"});
        let e = Compressed::parse(&odd, 12, None).unwrap_err();
        assert!(e.contains("byteStride 6 is not one Attributes"), "{e}");
    }
}
