//! Accumulates meshes, materials and textures into one scene.
//!
//! Loaders place meshes in f64 ([`Placed`]) and add them once the scene's
//! [`Rebase`] is known, so rounding to f32 comes last; scenes built in code
//! add f32 meshes directly ([`Parts::add_mesh`]).

use std::path::{Path, PathBuf};

use anyhow::Result;
use glam::{Affine3A, DAffine3, DVec3, Vec2, Vec3, Vec4};
use rayon::prelude::*;

use super::source::{resolve, FileKind, Outside, Source};
use crate::memory;
use crate::scene::rebase::Rebase;
use crate::scene::texture::Encoding;
use crate::scene::{Camera, Environment, Geometry, Material, MeshInfo, Scene, Settings, Texture};

/// Mesh placement for meshes built in code.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub(crate) transform: Affine3A,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            transform: Affine3A::IDENTITY,
        }
    }
}

/// One mesh to add: positions and optional per-vertex normals and UVs.
pub struct MeshData<'a> {
    pub name: String,
    pub positions: &'a [Vec3],
    pub normals: Option<&'a [Vec3]>,
    pub uvs: Option<&'a [Vec2]>,
    pub indices: &'a [[u32; 3]],
    pub material: u32,
}

/// A mesh placed in file coordinates (f64): every index is in range and
/// every position finite and within the range of f32.
#[derive(Clone, Debug)]
pub struct Placed {
    pub(crate) name: String,
    pub positions: Vec<DVec3>,
    /// Unit normals, already transformed.
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// A second UV set, for the textures that read it.
    pub uvs1: Option<Vec<Vec2>>,
    /// Tangents for a normal map, already transformed (see
    /// [`place_tangents`]).
    pub tangents: Option<Vec<Vec4>>,
    /// Linear RGB per vertex, multiplying the material's diffuse colour.
    pub colors: Option<Vec<Vec3>>,
    pub indices: Vec<[u32; 3]>,
    pub(crate) material: u32,
}

/// `points` placed by `xf` in f64, in place; the first point that lands
/// beyond the range of f32 is an error made by `err(index, point, placed,
/// why)`.
pub(crate) fn place_positions(
    mut points: Vec<DVec3>,
    xf: &DAffine3,
    err: impl Fn(usize, DVec3, DVec3, &str) -> anyhow::Error,
) -> Result<Vec<DVec3>> {
    let unusable = |q: DVec3| q.to_array().into_iter().find_map(super::numbers::unusable);
    let bad = points
        .par_iter()
        .with_min_len(1 << 12)
        .position_first(|&p| unusable(xf.transform_point3(p)).is_some());
    if let Some(i) = bad {
        let (p, q) = (points[i], xf.transform_point3(points[i]));
        return Err(err(i, p, q, unusable(q).unwrap_or_default()));
    }
    points
        .par_iter_mut()
        .with_min_len(1 << 12)
        .for_each(|p| *p = xf.transform_point3(*p));
    Ok(points)
}

/// Normals turned by `xf` (its inverse transpose) and made unit length.
pub(crate) fn place_normals(normals: &[DVec3], xf: &DAffine3) -> Vec<Vec3> {
    let nxf = xf.matrix3.inverse().transpose();
    normals
        .iter()
        .map(|&n| (nxf * n).normalize_or_zero().as_vec3())
        .collect()
}

/// Tangents turned by `xf` and made unit length. Their bitangents,
/// `w · normal × tangent`, must turn as the surface does: a transform that
/// mirrors (a negative determinant) turns the cross product of the placed
/// normal and tangent the other way, so it flips `w`.
pub(crate) fn place_tangents(tangents: &[Vec4], xf: &DAffine3) -> Vec<Vec4> {
    let m = xf.matrix3;
    let flip = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
    tangents
        .iter()
        .map(|t| {
            let d = (m * t.truncate().as_dvec3()).normalize_or_zero().as_vec3();
            d.extend(if t.w < 0.0 { -flip } else { flip })
        })
        .collect()
}

/// Refuses a mesh of `vertices` and `triangles` when it would take more
/// than `available` bytes ([`memory::mesh_bytes`]): the message, without a
/// place.
pub(crate) fn mesh_fits(vertices: u64, triangles: u64, available: u64) -> Result<(), String> {
    let needed = memory::mesh_bytes(vertices, triangles);
    if needed > available {
        let what = match vertices > triangles {
            true => format!("{triangles} triangles and {vertices} vertices"),
            false => format!("{triangles} triangles"),
        };
        return Err(format!(
            "{what} would need {} of memory; {} is available",
            memory::bytes(needed),
            memory::bytes(available)
        ));
    }
    Ok(())
}

/// Bounds of the vertices the triangles of `meshes` use (min > max when none).
pub(crate) fn bounds<'a>(meshes: impl IntoIterator<Item = &'a Placed>) -> (DVec3, DVec3) {
    let empty = || (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let join = |a: (DVec3, DVec3), b: (DVec3, DVec3)| (a.0.min(b.0), a.1.max(b.1));
    // On every core: min and max are exact in any order, but for the sign
    // of a zero, made + by adding 0.
    let (lo, hi) = meshes.into_iter().fold(empty(), |b, m| {
        let of_mesh = m
            .indices
            .par_iter()
            .with_min_len(1 << 14)
            .fold(empty, |b, t| {
                t.iter().fold(b, |b, &i| {
                    let p = m.positions[i as usize];
                    join(b, (p, p))
                })
            })
            .reduce(empty, join);
        join(b, of_mesh)
    });
    (lo + 0.0, hi + 0.0)
}

/// `v` grown to `len` with `x`: when it is empty and `x` is 0, as the
/// kernel's zeroed pages, without writing them.
fn grow(v: &mut Vec<u32>, len: usize, x: u32) {
    if v.is_empty() && x == 0 {
        *v = vec![0; len];
    } else {
        v.resize(len, x);
    }
}

/// Accumulates meshes, materials and textures into one scene.
#[derive(Debug, Default)]
pub struct Parts {
    pub geometry: Geometry,
    pub meshes: Vec<MeshInfo>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub warnings: Vec<String>,
    /// The memory the meshes still to come may take.
    pub(crate) budget: memory::Budget,
    /// Textures read so far, by path and encoding.
    texture_ids: Vec<((PathBuf, Encoding), Option<u32>)>,
}

impl Parts {
    /// The scene of these parts seen by `camera`: no lights, a black
    /// background and default settings until the caller sets them.
    pub fn into_scene(self, name: String, camera: Camera) -> Scene {
        Scene {
            name,
            description: String::new(),
            geometry: self.geometry,
            meshes: self.meshes,
            materials: self.materials,
            textures: self.textures,
            lights: Vec::new(),
            camera,
            environment: Environment::Color(Vec3::ZERO),
            settings: Settings::default(),
            warnings: self.warnings,
            emitters: Default::default(),
        }
    }

    /// Loads the texture `written` in the file `base` names once per path;
    /// `None` (with a warning naming `from`, where it was asked for) when
    /// missing, unreadable or too large. One outside `base`'s folder is
    /// read at arm's length ([`Outside`]).
    pub(crate) fn texture(
        &mut self,
        src: &dyn Source,
        base: &Path,
        written: &str,
        from: &str,
    ) -> Option<u32> {
        self.texture_at(
            src,
            &resolve(base, written),
            src.outside(base, &resolve(base, written)),
            written,
            from,
            Encoding::Srgb,
        )
    }

    /// [`Parts::texture`] at `path`, resolved by the caller, its values
    /// read as `encoding` says.
    pub(crate) fn texture_at(
        &mut self,
        src: &dyn Source,
        path: &Path,
        outside: Option<Outside>,
        written: &str,
        from: &str,
        encoding: Encoding,
    ) -> Option<u32> {
        let key = (path.to_path_buf(), encoding);
        if let Some((_, id)) = self.texture_ids.iter().find(|(k, _)| *k == key) {
            return *id;
        }
        let name = crate::words::path(path);
        if let Some(o) = &outside {
            self.warnings.push(o.warning(from, "texture", written));
        }
        let decoded = src
            .read(path, FileKind::Image)
            .map_err(anyhow::Error::from)
            .and_then(|bytes| {
                Texture::decode(&name, &bytes, encoding).map_err(|e| {
                    anyhow::anyhow!("{}", crate::words::clip_quotes(&format!("{e:#}")))
                })
            });
        let decoded = match &outside {
            Some(o) => o.quiet(FileKind::Image, decoded, &mut self.warnings, usize::MAX),
            None => decoded,
        };
        let id = match decoded {
            Ok(t) => {
                self.textures.push(t);
                Some(self.textures.len() as u32 - 1)
            }
            Err(e) => {
                self.warnings.push(format!(
                    "{from}: texture {name}: {e:#}; using the material colour"
                ));
                None
            }
        };
        self.texture_ids.push((key, id));
        id
    }

    /// Adds a mesh built in code, transformed in f32.
    pub fn add_mesh(&mut self, m: MeshData, place: &Placement) {
        let xf = place.transform;
        let nxf = glam::Mat3::from(xf.matrix3).inverse().transpose();
        let positions = m.positions.iter().map(|&p| xf.transform_point3(p));
        let normals = m
            .normals
            .map(|n| n.iter().map(|&n| (nxf * n).normalize_or_zero()).collect());
        self.push(
            m.name,
            positions.collect(),
            [normals, None],
            [m.uvs.map(<[Vec2]>::to_vec), None],
            None,
            m.indices.to_vec(),
            m.material,
        );
    }

    /// Adds a placed mesh, mapped through the scene's frame and rounded to f32.
    pub fn add_placed(&mut self, m: Placed, frame: &Rebase) {
        let positions = m
            .positions
            .par_iter()
            .with_min_len(1 << 12)
            .map(|&p| frame.point(p))
            .collect();
        self.push(
            m.name,
            positions,
            [m.normals, m.colors],
            [m.uvs, m.uvs1],
            m.tangents,
            m.indices,
            m.material,
        );
    }

    /// Appends a mesh; drops zero-area triangles and counts them.
    #[allow(clippy::too_many_arguments)]
    fn push(
        &mut self,
        name: String,
        positions: Vec<Vec3>,
        [normals, colors]: [Option<Vec<Vec3>>; 2],
        [uvs, uvs1]: [Option<Vec<Vec2>>; 2],
        tangents: Option<Vec<Vec4>>,
        mut kept: Vec<[u32; 3]>,
        material: u32,
    ) {
        let g = &mut self.geometry;
        let base = g.positions.len() as u32;
        let mesh_id = self.meshes.len() as u32;
        let n = positions.len();
        let (smooth, textured, colored) = (normals.is_some(), uvs.is_some(), colors.is_some());
        // Colours are stored once some mesh has them, white for the others.
        if colored && g.colors.is_empty() {
            g.colors.resize(g.positions.len(), Vec3::ONE);
        }
        match colors {
            Some(v) => g.colors.extend(v),
            None if !g.colors.is_empty() => g.colors.extend(std::iter::repeat_n(Vec3::ONE, n)),
            None => {}
        }
        // A normal map turns the normal in the frame of the texture
        // coordinates; where they span no area there is none to turn in.
        let normal_mapped = self
            .materials
            .get(material as usize)
            .is_some_and(|m| m.pbr.as_ref().is_some_and(|p| p.normal.is_some()));
        if normal_mapped
            && ![&uvs, &uvs1]
                .iter()
                .any(|u| spans_area(u.as_deref(), &kept))
        {
            let m = &self.materials[material as usize].name;
            let m = match m.starts_with("material ") {
                true => m.clone(),
                false => format!("material {}", crate::words::quoted(m)),
            };
            self.warnings.push(format!(
                "{}: the normal map of {m} needs texture coordinates that span an area, and \
                 these span none: drawn without it",
                crate::words::quoted(&name),
            ));
        }
        let g = &mut self.geometry;
        if g.positions.is_empty() {
            g.positions = positions;
        } else {
            g.positions.extend(positions);
        }
        match normals {
            Some(v) => g.normals.extend(v),
            None => g.normals.extend(std::iter::repeat_n(Vec3::ZERO, n)),
        }
        match uvs {
            Some(v) => g.uvs.extend(v),
            None => g.uvs.extend(std::iter::repeat_n(Vec2::ZERO, n)),
        }
        let uv1 = uvs1.map(|v| {
            let shift = base - g.uvs1.len() as u32;
            g.uvs1.extend(v);
            shift
        });
        let tangent = tangents.map(|v| {
            let shift = base - g.tangents.len() as u32;
            g.tangents.extend(v);
            shift
        });
        let positions = &g.positions;
        // Exactly zero, in f64: in f32 the products (let alone a squared
        // length) underflow for slivers and tiny triangles.
        let flat = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
            (b - a).cross(c - a) == DVec3::ZERO
        };
        // In place, and counted first: most meshes have none to drop.
        let degenerate: usize = kept
            .par_iter_mut()
            .with_min_len(1 << 12)
            .map(|t| {
                *t = t.map(|i| i + base);
                flat(t) as usize
            })
            .sum();
        if degenerate > 0 {
            kept.retain(|t| !flat(t));
        }
        if g.indices.is_empty() {
            g.indices = kept;
        } else {
            g.indices.extend(kept);
        }
        grow(&mut g.tri_material, g.indices.len(), material);
        grow(&mut g.tri_mesh, g.indices.len(), mesh_id);
        if degenerate > 0 {
            self.warnings.push(format!(
                "{}: skipped {degenerate} degenerate (zero-area) triangle{}",
                crate::words::quoted(&name),
                if degenerate == 1 { "" } else { "s" }
            ));
        }
        self.meshes.push(MeshInfo {
            name,
            smooth,
            textured,
            colored,
            uv1,
            tangent,
        });
    }

    /// The warnings, as the reason a scene came out without triangles.
    pub(crate) fn why_empty(&self) -> String {
        match self.warnings.is_empty() {
            true => String::new(),
            false => format!(" ({})", self.warnings.join("; ")),
        }
    }

    /// Adds a texture decoded by the caller (one held inside a file).
    pub(crate) fn add_texture(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        self.textures.len() as u32 - 1
    }

    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }
}

/// Whether some triangle of `indices` covers an area in texture space.
fn spans_area(uvs: Option<&[Vec2]>, indices: &[[u32; 3]]) -> bool {
    let Some(uv) = uvs else {
        return false;
    };
    indices.iter().any(|t| {
        let [a, b, c] = t.map(|i| uv.get(i as usize).copied().unwrap_or_default().as_dvec2());
        let area = (b - a).perp_dot(c - a);
        area.is_finite() && area.abs() > 1e-20
    })
}
