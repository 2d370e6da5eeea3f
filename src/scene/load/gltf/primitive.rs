//! A primitive's accessors, checked before anything is read, decoded
//! once however many nodes place the primitive, and placed per instance.

use std::collections::HashMap;

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::{Mode, Semantic};
use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DVec3, Vec2, Vec3, Vec4};

use super::Reader;
use crate::scene::load::numbers;
use crate::scene::load::parts::{place_normals, place_positions, place_tangents, Parts, Placed};
use crate::scene::load::tangents;
use crate::scene::show::show3;

/// What a primitive's accessors hold, checked: every index in range and
/// every number finite.
#[derive(Clone)]
pub(super) struct Decoded {
    positions: Vec<DVec3>,
    normals: Option<Vec<DVec3>>,
    uvs: Option<Vec<Vec2>>,
    /// `TEXCOORD_1`, read only where the material's textures read it.
    uvs1: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec3>>,
    /// Tangents (the file's `TANGENT`, or MikkTSpace's) where the
    /// material has a normal map and the primitive normals.
    tangents: Option<Vec<Vec4>>,
    indices: Vec<[u32; 3]>,
}

/// The accessors and mode that decide a primitive's [`Decoded`]: primitives
/// (of one mesh placed many times, or of many meshes) that share them
/// share it.
pub(super) type Key = [Option<usize>; 9];

fn key(p: &::gltf::Primitive) -> Key {
    let index = |a: Option<::gltf::Accessor>| a.map(|a| a.index());
    [
        index(p.get(&Semantic::Positions)),
        index(p.get(&Semantic::Normals)),
        index(p.get(&Semantic::TexCoords(0))),
        index(second_set(p)),
        index(p.get(&Semantic::Colors(0))),
        index(p.indices()),
        Some(p.mode().as_gl_enum() as usize),
        index(tangent(p)),
        normal_set(p).map(|s| s as usize),
    ]
}

/// The UV set a primitive's normal map reads, where its material has one
/// and it has normals: then it needs tangents.
fn normal_set(p: &::gltf::Primitive) -> Option<u32> {
    p.get(&Semantic::Normals)?;
    let n = p.material().normal_texture()?;
    let t = n
        .extension_value(super::TEXTURE_TRANSFORM)
        .and_then(|v| super::texcoord::Transform::of_json(v).ok());
    Some(super::texcoord::Transform::set(t.as_ref(), n.tex_coord()))
}

/// A primitive's `TANGENT`, where its normal map reads it (glTF ignores
/// it without normals).
fn tangent<'a>(p: &::gltf::Primitive<'a>) -> Option<::gltf::Accessor<'a>> {
    normal_set(p)?;
    p.get(&Semantic::Tangents)
}

/// A primitive's `TEXCOORD_1`, where its material's textures read it.
fn second_set<'a>(p: &::gltf::Primitive<'a>) -> Option<::gltf::Accessor<'a>> {
    let read = super::texcoord::sets(&p.material()).contains(&1);
    p.get(&Semantic::TexCoords(1)).filter(|_| read)
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
        let b = a.and_then(|a| self.buffer_of(a));
        match b.and_then(|b| Some((b, self.origins.get(b)?))) {
            Some((b, o)) if !o.is_empty() => format!("; read from buffer {b}, {o}"),
            _ => String::new(),
        }
    }

    /// `value` as read from accessor `a`, or nothing of it where its
    /// buffer lies outside the glTF's folder ([`Outside`]).
    ///
    /// [`Outside`]: crate::scene::load::source::Outside
    pub(super) fn shown(&self, a: Option<&::gltf::Accessor>, value: String) -> String {
        let b = a.and_then(|a| self.buffer_of(a));
        match b.and_then(|b| self.foreign.get(b)?.as_ref()) {
            Some(_) => "(not shown: its buffer lies outside the glTF's folder)".into(),
            None => value,
        }
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
        if p.get(&Semantic::Positions).is_none() {
            // glTF asks that such a primitive not be drawn.
            self.unmapped.note("primitives without POSITION", || {
                format!("mesh {mesh_name} primitive {}", p.index())
            });
            return Ok(None);
        }
        // Kept for the primitive's next instance, if any: the last one
        // takes it.
        let k = key(&p);
        let d = match self.decoded.remove(&k) {
            Some(d) => d,
            None => {
                let used = [
                    Semantic::Positions,
                    Semantic::Normals,
                    Semantic::TexCoords(0),
                    Semantic::Colors(0),
                ];
                let used: Vec<_> = used
                    .iter()
                    .filter_map(|s| p.get(s))
                    .chain(second_set(&p))
                    .chain(tangent(&p))
                    .chain(p.indices())
                    .collect();
                self.unpack(&used)?;
                self.decode(&here, &p)?
            }
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
        if material.is_none() {
            // Each slot's texture needs the coordinates it reads.
            let m = p.material();
            let has = [d.uvs.is_some(), d.uvs1.is_some()];
            let base = m.pbr_metallic_roughness().base_color_texture();
            let base = base.map(|i| {
                let t = i
                    .texture_transform()
                    .map(|t| super::texcoord::Transform::of_info(&t));
                super::texcoord::Transform::set(t.as_ref(), i.tex_coord())
            });
            let mut sets = super::texcoord::sets(&m);
            sets.sort_unstable();
            sets.dedup();
            for set in sets {
                if set < 2 && !has[set as usize] {
                    let what = match Some(set) == base {
                        true => "textures (the base colour's among them)",
                        false => "textures",
                    };
                    self.unmapped.note(
                        &format!(
                            "{what} on primitives without TEXCOORD_{set} (drawn in the \
                             material's colour)"
                        ),
                        || {
                            let name = super::named(m.name(), m.index().unwrap_or_default());
                            format!("material {name}, mesh {mesh_name}")
                        },
                    );
                }
            }
        }
        // A material given in place of the file's reads neither.
        let own = material.is_none();
        let (uvs, uvs1) = (d.uvs, d.uvs1.filter(|_| own));
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
            uvs,
            uvs1,
            colors: d.colors,
            tangents: d.tangents.filter(|_| own).map(|t| place_tangents(&t, xf)),
            indices: d.indices,
            material,
        }))
    }

    /// Checks a primitive's accessors before anything reads them (`here`
    /// names it in messages): the types glTF allows, with those
    /// `KHR_mesh_quantization` adds, and as many values of each attribute
    /// as positions. One without positions is not drawn, so not read.
    fn check_primitive(&self, here: &str, p: &::gltf::Primitive) -> Result<()> {
        use DataType::{F32, I16, I8, U16, U32, U8};
        use Dimensions::{Scalar, Vec2 as V2, Vec3 as V3, Vec4 as V4};
        let Some(position) = p.get(&Semantic::Positions) else {
            return Ok(());
        };
        self.check_accessor(here, "POSITION", &position, &[F32, I8, U8, I16, U16], &[V3])?;
        let attributes: [(_, _, &[_], &[_]); 4] = [
            (Semantic::Normals, "NORMAL", &[F32, I8, I16], &[V3]),
            (
                Semantic::TexCoords(0),
                "TEXCOORD_0",
                &[F32, I8, U8, I16, U16],
                &[V2],
            ),
            (
                Semantic::TexCoords(1),
                "TEXCOORD_1",
                &[F32, I8, U8, I16, U16],
                &[V2],
            ),
            (Semantic::Colors(0), "COLOR_0", &[F32, U8, U16], &[V3, V4]),
        ];
        for (semantic, what, types, dims) in attributes {
            if let Some(a) = p.get(&semantic) {
                self.check_accessor(here, what, &a, types, dims)?;
                if a.count() != position.count() {
                    bail!(
                        "{here}: {what} (accessor {}) has {} values for {} positions",
                        a.index(),
                        a.count(),
                        position.count()
                    );
                }
            }
        }
        if let Some(a) = tangent(p) {
            self.check_accessor(here, "TANGENT", &a, &[F32, I8, I16], &[V4])?;
            if a.count() != position.count() {
                bail!(
                    "{here}: TANGENT (accessor {}) has {} values for {} positions",
                    a.index(),
                    a.count(),
                    position.count()
                );
            }
        }
        if let Some(a) = p.indices() {
            self.check_accessor(here, "indices", &a, &[U8, U16, U32], &[Scalar])?;
        }
        Ok(())
    }

    /// The values of accessor `a`, if any, each made by `f` from its
    /// components.
    fn all<T>(
        &self,
        here: &str,
        what: &str,
        a: Option<::gltf::Accessor>,
        f: impl Fn(&[f64]) -> T,
    ) -> Result<Option<Vec<T>>> {
        let Some(a) = a else {
            return Ok(None);
        };
        let mut out = Vec::with_capacity(a.count());
        self.each(here, what, &a, |v| out.push(f(v)))?;
        Ok(Some(out))
    }

    /// Reads a primitive's accessors, checked by [`Reader::instanced`]
    /// and unpacked by [`Reader::unpack`] (`here` names it in messages).
    fn decode(&self, here: &str, p: &::gltf::Primitive) -> Result<Decoded> {
        let d3 = |v: &[f64]| DVec3::new(v[0], v[1], v[2]);
        let Some(positions) = self.all(here, "POSITION", p.get(&Semantic::Positions), d3)? else {
            bail!("{here}: no POSITION attribute");
        };
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
        let normals = self.all(here, "NORMAL", p.get(&Semantic::Normals), d3)?;
        // glTF puts v = 0 at the top of the image, rayterm at the bottom.
        let uv = |v: &[f64]| Vec2::new(v[0] as f32, 1.0 - v[1] as f32);
        let uvs = self.all(here, "TEXCOORD_0", p.get(&Semantic::TexCoords(0)), uv)?;
        let uvs1 = self.all(here, "TEXCOORD_1", second_set(p), uv)?;
        // Integer colours are normalised (glTF allows no others).
        let color = p.get(&Semantic::Colors(0));
        let scale = match color.as_ref().map(|a| (a.data_type(), a.normalized())) {
            Some((DataType::U8, false)) => 255.0,
            Some((DataType::U16, false)) => 65535.0,
            _ => 1.0,
        };
        let colors = self.all(here, "COLOR_0", color, |v| {
            Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32) / scale
        })?;
        let file_tangents = self.all(here, "TANGENT", tangent(p), |v| {
            Vec4::new(v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32)
        })?;
        let finite = |ok: bool, what: &str| -> Result<()> {
            if !ok {
                bail!("{here}: {what} holds a number that is not finite");
            }
            Ok(())
        };
        finite(normals.iter().flatten().all(|v| v.is_finite()), "NORMAL")?;
        finite(uvs.iter().flatten().all(|v| v.is_finite()), "TEXCOORD_0")?;
        finite(uvs1.iter().flatten().all(|v| v.is_finite()), "TEXCOORD_1")?;
        finite(colors.iter().flatten().all(|v| v.is_finite()), "COLOR_0")?;
        finite(
            file_tangents.iter().flatten().all(|v| v.is_finite()),
            "TANGENT",
        )?;
        let corners = match self.all(here, "indices", p.indices(), |v| v[0] as u32)? {
            Some(c) => c,
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
        let (mut positions, mut normals, mut uvs, mut uvs1, mut colors) =
            (positions, normals, uvs, uvs1, colors);
        let mut indices = indices;
        // Generated where the file gives none, in the primitive's own
        // space, as glTF asks.
        let set = normal_set(p).filter(|&s| s < 2);
        let generated = match (&file_tangents, set, &normals) {
            (None, Some(set), Some(n)) => [&uvs, &uvs1][set as usize].as_ref().map(|uv| {
                let f = |v: &[DVec3]| v.iter().map(|v| v.as_vec3()).collect::<Vec<_>>();
                tangents::generate(&f(&positions), &f(n), uv, &mut indices)
            }),
            _ => None,
        };
        let tangents = match generated {
            Some((t, copies)) => {
                tangents::extend(&mut positions, &copies);
                for v in normals.iter_mut() {
                    tangents::extend(v, &copies);
                }
                for v in uvs.iter_mut().chain(uvs1.iter_mut()) {
                    tangents::extend(v, &copies);
                }
                for v in colors.iter_mut() {
                    tangents::extend(v, &copies);
                }
                Some(t)
            }
            None => file_tangents,
        };
        Ok(Decoded {
            positions,
            normals,
            uvs,
            uvs1,
            colors,
            tangents,
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
        roots: &[::gltf::Node],
    ) -> Result<(u64, u64, HashMap<Key, usize>)> {
        let (mut v, mut t, mut uses) = (0u64, 0u64, HashMap::new());
        let mut stack: Vec<::gltf::Node> = roots.to_vec();
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
