//! A primitive's accessors, checked before the crate reads them, decoded
//! once however many nodes place the primitive, and placed per instance.

use std::collections::HashMap;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::{Mode, Semantic};
use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DVec3, Vec2, Vec3};

use super::Reader;
use crate::scene::numbers::{self, show3};
use crate::scene::parts::{place_normals, place_positions, Parts, Placed};

/// What a primitive's accessors hold, checked: every index in range and
/// every number finite.
#[derive(Clone)]
pub(super) struct Decoded {
    positions: Vec<DVec3>,
    normals: Option<Vec<DVec3>>,
    uvs: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec3>>,
    indices: Vec<[u32; 3]>,
}

/// The accessors and mode that decide a primitive's [`Decoded`]: primitives
/// (of one mesh placed many times, or of many meshes) that share them
/// share it.
pub(super) type Key = [Option<usize>; 6];

fn key(p: &::gltf::Primitive) -> Key {
    let index = |a: Option<::gltf::Accessor>| a.map(|a| a.index());
    [
        index(p.get(&Semantic::Positions)),
        index(p.get(&Semantic::Normals)),
        index(p.get(&Semantic::TexCoords(0))),
        index(p.get(&Semantic::Colors(0))),
        index(p.indices()),
        Some(p.mode().as_gl_enum() as usize),
    ]
}

/// Whether rayterm draws a primitive of this mode (triangles, strips and
/// fans; not points or lines).
pub(super) fn drawn(mode: Mode) -> bool {
    matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    )
}

/// The triangles `corners` make in `mode`: what [`Reader::decode`] makes of
/// them, counted before anything is read.
pub(super) fn triangles(mode: Mode, corners: usize) -> usize {
    match mode {
        Mode::Triangles => corners / 3,
        _ => corners.saturating_sub(2),
    }
}

impl Reader<'_> {
    /// `; read from buffer B, FILE`: where the values of accessor `a` come
    /// from, when that is a file (a buffer's URI may name any file, and a
    /// wrong one gives values that make no sense as geometry).
    fn origin(&self, a: Option<&::gltf::Accessor>) -> String {
        let b = a.and_then(|a| a.view()).map(|v| v.buffer().index());
        match b.and_then(|b| Some((b, self.origins.get(b)?))) {
            Some((b, o)) if !o.is_empty() => format!("; read from buffer {b}, {o}"),
            _ => String::new(),
        }
    }

    /// `value` as read from accessor `a`, or nothing of it where its
    /// buffer lies outside the glTF's folder ([`Outside`]).
    ///
    /// [`Outside`]: crate::scene::source::Outside
    pub(super) fn shown(&self, a: Option<&::gltf::Accessor>, value: String) -> String {
        let b = a.and_then(|a| a.view()).map(|v| v.buffer().index());
        match b.and_then(|b| self.foreign.get(b)?.as_ref()) {
            Some(_) => "(not shown: its buffer lies outside the glTF's folder)".into(),
            None => value,
        }
    }

    /// Checks what the crate's reader takes on trust (it panics or reads
    /// garbage otherwise): the accessor's type is one glTF allows for
    /// `what`, and every element it reads lies, aligned, inside its view
    /// and buffer.
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
                dims.iter()
                    .map(|d| format!("{d:?}"))
                    .collect::<Vec<_>>()
                    .join(" or "),
                types
                    .iter()
                    .map(|t| format!("{t:?}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        if a.sparse().is_some() {
            bail!("{name} is sparse, which rayterm does not read");
        }
        let Some(view) = a.view() else {
            bail!("{name} has no buffer view");
        };
        if a.count() == 0 {
            bail!("{name} has no elements (count 0)");
        }
        let component = a.data_type().size() as u128;
        let element = a.size() as u128;
        let stride = view.stride().map_or(element, |s| s as u128);
        if stride < element {
            bail!("{name}: the buffer view's byteStride {stride} is smaller than one element ({element} bytes)");
        }
        let start = view.offset() as u128 + a.offset() as u128;
        if !start.is_multiple_of(component) || !stride.is_multiple_of(component) {
            bail!("{name} is not aligned to its {component}-byte components (offset {start}, stride {stride})");
        }
        let end_in_view = a.offset() as u128 + stride * (a.count() as u128 - 1) + element;
        let buffer = self.buffers.get(view.buffer().index()).map_or(0, Vec::len) as u128;
        let view_end = view.offset() as u128 + view.length() as u128;
        if end_in_view > view.length() as u128 || view_end > buffer {
            bail!(
                "{name}: its {} elements end at byte {end_in_view} of a {}-byte buffer view \
                 ending at byte {view_end} of a {buffer}-byte buffer (truncated or wrong counts?)",
                a.count(),
                view.length()
            );
        }
        Ok(())
    }

    /// The triangles of one primitive, placed by `xf`; `None` for points
    /// and lines.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn primitive(
        &mut self,
        parts: &mut Parts,
        p: ::gltf::Primitive,
        mesh_name: &str,
        node_name: &str,
        xf: &DAffine3,
        material: Option<u32>,
    ) -> Result<Option<Placed>> {
        let here = self.place(mesh_name, &p, node_name);
        if !drawn(p.mode()) {
            self.unmapped
                .note("points and lines", || format!("mesh {mesh_name}"));
            return Ok(None);
        }
        // Kept for the primitive's next instance, if any: the last one
        // takes it.
        let k = key(&p);
        let d = match self.decoded.remove(&k) {
            Some(d) => d,
            None => self.decode(&here, &p)?,
        };
        let left = self.uses.get_mut(&k).map_or(0, |n| {
            *n = n.saturating_sub(1);
            *n
        });
        if left > 0 {
            self.decoded.insert(k, d.clone());
        }
        let placed = place_positions(d.positions, xf, |i, p, q, why| {
            anyhow!(
                "{here}: position {i} {} lands at {} once placed, which {why}",
                show3(p),
                show3(q)
            )
        })?;
        let textured = p.material().pbr_metallic_roughness().base_color_texture();
        if material.is_none() && d.uvs.is_none() && textured.is_some() {
            self.unmapped.note(
                "base colour textures on primitives without TEXCOORD_0 (drawn in the \
                 material's colour)",
                || {
                    let m = p.material();
                    let m = super::named(m.name(), m.index().unwrap_or_default());
                    format!("material {m}, mesh {mesh_name}")
                },
            );
        }
        let material = match material {
            Some(m) => m,
            None => self.material(parts, p.material())?,
        };
        // An unnamed mesh or node is known by its index.
        let name = if mesh_name.parse::<usize>().is_ok() {
            format!("mesh {mesh_name} (node {node_name})")
        } else if mesh_name == node_name {
            mesh_name.to_string()
        } else {
            format!("{mesh_name} (node {node_name})")
        };
        Ok(Some(Placed {
            name,
            positions: placed,
            normals: d.normals.map(|n| place_normals(&n, xf)),
            uvs: d.uvs,
            colors: d.colors,
            indices: d.indices,
            material,
        }))
    }

    /// Checks a primitive's accessors before anything reads them (`here`
    /// names it in messages).
    fn check_primitive(&self, here: &str, p: &::gltf::Primitive) -> Result<()> {
        use DataType::{F32, U16, U32, U8};
        use Dimensions::{Scalar, Vec2 as V2, Vec3 as V3, Vec4 as V4};
        let Some(position) = p.get(&Semantic::Positions) else {
            bail!("{here}: no POSITION attribute");
        };
        self.check_accessor(here, "POSITION", &position, &[F32], &[V3])?;
        if let Some(a) = p.get(&Semantic::Normals) {
            self.check_accessor(here, "NORMAL", &a, &[F32], &[V3])?;
        }
        if let Some(a) = p.get(&Semantic::TexCoords(0)) {
            self.check_accessor(here, "TEXCOORD_0", &a, &[F32, U8, U16], &[V2])?;
        }
        if let Some(a) = p.get(&Semantic::Colors(0)) {
            self.check_accessor(here, "COLOR_0", &a, &[F32, U8, U16], &[V3, V4])?;
        }
        if let Some(a) = p.indices() {
            self.check_accessor(here, "indices", &a, &[U8, U16, U32], &[Scalar])?;
        }
        Ok(())
    }

    /// Reads a primitive's accessors, checked by [`Reader::instanced`]
    /// (`here` names it in messages).
    fn decode(&self, here: &str, p: &::gltf::Primitive) -> Result<Decoded> {
        let buffers = &self.buffers;
        let reader = p.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
        let Some(positions) = reader.read_positions() else {
            bail!("{here}: POSITION cannot be read");
        };
        let positions: Vec<DVec3> = positions
            .map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
            .collect();
        if let Some((i, v)) = positions.iter().enumerate().find(|(_, v)| {
            v.to_array()
                .into_iter()
                .any(|x| numbers::unusable(x).is_some())
        }) {
            let a = p.get(&Semantic::Positions);
            bail!(
                "{here}: position {i} is {}, not a finite number{}",
                self.shown(a.as_ref(), show3(*v)),
                self.origin(a.as_ref())
            );
        }
        let n = positions.len();
        let count_of = |what: &str, len: usize| -> Result<()> {
            if len != n {
                bail!("{here}: {what} has {len} values for {n} positions");
            }
            Ok(())
        };
        let normals: Option<Vec<DVec3>> = reader.read_normals().map(|it| {
            it.map(|v| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64))
                .collect()
        });
        if let Some(v) = &normals {
            count_of("NORMAL", v.len())?;
        }
        // glTF puts v = 0 at the top of the image, rayterm at the bottom.
        let uvs: Option<Vec<Vec2>> = reader
            .read_tex_coords(0)
            .map(|t| t.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect());
        if let Some(v) = &uvs {
            count_of("TEXCOORD_0", v.len())?;
        }
        let colors: Option<Vec<Vec3>> = reader
            .read_colors(0)
            .map(|c| c.into_rgb_f32().map(Vec3::from_array).collect());
        if let Some(v) = &colors {
            count_of("COLOR_0", v.len())?;
        }
        let finite = |ok: bool, what: &str| -> Result<()> {
            if !ok {
                bail!("{here}: {what} holds a number that is not finite");
            }
            Ok(())
        };
        finite(normals.iter().flatten().all(|v| v.is_finite()), "NORMAL")?;
        finite(uvs.iter().flatten().all(|v| v.is_finite()), "TEXCOORD_0")?;
        finite(colors.iter().flatten().all(|v| v.is_finite()), "COLOR_0")?;
        let corners: Vec<u32> = match reader.read_indices() {
            Some(ix) => ix.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some((k, &i)) = corners.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            let a = p.indices();
            bail!(
                "{here}: index {k} is {}, out of range ({n} vertices){}",
                self.shown(a.as_ref(), i.to_string()),
                self.origin(a.as_ref())
            );
        }
        let indices: Vec<[u32; 3]> = match p.mode() {
            Mode::TriangleStrip => (2..corners.len())
                .map(|k| {
                    let [a, b, c] = [corners[k - 2], corners[k - 1], corners[k]];
                    // Every other triangle of a strip turns the other way.
                    if k % 2 == 0 {
                        [a, b, c]
                    } else {
                        [b, a, c]
                    }
                })
                .collect(),
            Mode::TriangleFan => (2..corners.len())
                .map(|k| [corners[0], corners[k - 1], corners[k]])
                .collect(),
            _ => corners
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
        };
        Ok(Decoded {
            positions,
            normals,
            uvs,
            colors,
            indices,
        })
    }
}

impl Reader<'_> {
    /// `FILE: mesh M primitive P (node N)`, as messages name a primitive.
    fn place(&self, mesh_name: &str, p: &::gltf::Primitive, node_name: &str) -> String {
        format!(
            "{}: mesh {mesh_name} primitive {} (node {node_name})",
            self.at(),
            p.index()
        )
    }

    /// What the scene's nodes place, known before any accessor is read:
    /// its vertices and triangles, every instance counted (placing it
    /// takes that: a node's, and each of its `EXT_mesh_gpu_instancing`
    /// instances), and how many primitives each [`Decoded`] is placed
    /// for. Each primitive's accessors are checked on the way, so that
    /// counts they cannot hold are named as such. Its hierarchy a forest,
    /// each node is visited once.
    pub(super) fn instanced(
        &self,
        scene: &::gltf::Scene,
    ) -> Result<(u64, u64, HashMap<Key, usize>)> {
        let (mut v, mut t, mut uses) = (0u64, 0u64, HashMap::new());
        let mut stack: Vec<::gltf::Node> = scene.nodes().collect();
        while let Some(node) = stack.pop() {
            let node_name = super::named(node.name(), node.index());
            if let Some(mesh) = node.mesh() {
                let mesh_name = super::named(mesh.name(), mesh.index());
                let copies = self.copies(&node, &node_name)?;
                for p in mesh.primitives().filter(|p| drawn(p.mode())) {
                    let n = *uses
                        .entry(key(&p))
                        .and_modify(|n| *n += copies)
                        .or_insert(copies);
                    if n == copies {
                        self.check_primitive(&self.place(&mesh_name, &p, &node_name), &p)?;
                    }
                    let count = p.get(&Semantic::Positions).map_or(0, |a| a.count());
                    let corners = p.indices().map_or(count, |a| a.count());
                    let copies = copies as u64;
                    v = v.saturating_add((count as u64).saturating_mul(copies));
                    t = t.saturating_add(
                        (triangles(p.mode(), corners) as u64).saturating_mul(copies),
                    );
                }
            }
            stack.extend(node.children());
        }
        Ok((v, t, uses))
    }
}
