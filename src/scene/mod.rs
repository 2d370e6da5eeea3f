//! The scene model: geometry, materials, textures, lights, camera,
//! environment and render settings, as the renderer reads them. Built from
//! files by [`load`], which this model never calls.

pub(crate) mod camera;
pub(crate) mod emitters;
pub mod envlight;
pub mod light;
pub mod load;
pub(crate) mod material;
mod reach;
pub mod rebase;
pub(crate) mod show;
pub(crate) mod summary;
pub(crate) mod texture;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

pub use camera::{Camera, Projection};
pub use envlight::EnvLight;
pub use light::Light;
pub use material::{Alpha, Material, Pbr};
pub use reach::check_reach;
pub use texture::{CubeMap, Texture, UvMap, Wrap};

use crate::choice::Choice;
use crate::geometry::Aabb;

/// All triangles of a scene in one indexed soup.
///
/// Normals and UVs are per vertex; a mesh without them has `smooth` / `textured`
/// cleared in its [`MeshInfo`] and zeros in those slots.
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    pub(crate) positions: Vec<Vec3>,
    pub(crate) normals: Vec<Vec3>,
    pub(crate) uvs: Vec<Vec2>,
    /// A second UV set (glTF's `TEXCOORD_1`), held only for the vertices
    /// of meshes whose textures read it ([`MeshInfo`]'s `uv1`): it does
    /// not run in parallel with the others.
    pub(crate) uvs1: Vec<Vec2>,
    /// Tangents for normal maps (xyz, and w the sign of the bitangent,
    /// `w · normal × tangent`; zero where there is none), held only for
    /// the vertices of normal-mapped meshes with vertex normals
    /// ([`MeshInfo`]'s `tangent`), as `uvs1`.
    pub(crate) tangents: Vec<Vec4>,
    /// Linear RGB per vertex when some mesh has colours (white for the
    /// others); empty when none has.
    pub(crate) colors: Vec<Vec3>,
    pub(crate) indices: Vec<[u32; 3]>,
    pub(crate) tri_material: Vec<u32>,
    pub(crate) tri_mesh: Vec<u32>,
}

/// Read-only views for tests and tools: the arrays run in parallel (one
/// entry per vertex, or per triangle), so only the loaders, which keep
/// them so, write them.
impl Geometry {
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    pub fn normals(&self) -> &[Vec3] {
        &self.normals
    }

    pub fn uvs(&self) -> &[Vec2] {
        &self.uvs
    }

    /// The second UV set of the meshes that have one.
    pub fn uvs1(&self) -> &[Vec2] {
        &self.uvs1
    }

    /// The tangents of the normal-mapped meshes that have them.
    pub fn tangents(&self) -> &[Vec4] {
        &self.tangents
    }

    /// Linear RGB per vertex, or empty when no mesh has colours.
    pub fn colors(&self) -> &[Vec3] {
        &self.colors
    }

    pub fn indices(&self) -> &[[u32; 3]] {
        &self.indices
    }

    /// The material of each triangle.
    pub fn tri_material(&self) -> &[u32] {
        &self.tri_material
    }

    /// The mesh ([`Scene::meshes`]) each triangle came from.
    pub fn tri_mesh(&self) -> &[u32] {
        &self.tri_mesh
    }
}

impl Geometry {
    /// A triangle soup: three corners of their own per triangle, no
    /// normals or UVs, one material and one mesh (the BVH's and the
    /// stability battery's test scenes).
    pub fn from_triangles(tris: &[[Vec3; 3]]) -> Self {
        let mut g = Geometry::default();
        for (i, t) in tris.iter().enumerate() {
            g.positions.extend_from_slice(t);
            g.normals.extend([Vec3::ZERO; 3]);
            g.uvs.extend([Vec2::ZERO; 3]);
            let b = 3 * i as u32;
            g.indices.push([b, b + 1, b + 2]);
            g.tri_material.push(0);
            g.tri_mesh.push(0);
        }
        g
    }

    /// The coordinates of UV set `set` at the corners of triangle `prim`
    /// of `mesh`, where the mesh has that set.
    #[inline]
    pub(crate) fn corner_uvs(&self, mesh: &MeshInfo, prim: usize, set: u8) -> Option<[Vec2; 3]> {
        let idx = self.indices[prim];
        match set {
            0 => mesh.textured.then(|| idx.map(|i| self.uvs[i as usize])),
            _ => mesh
                .uv1
                .map(|shift| idx.map(|i| self.uvs1[(i - shift) as usize])),
        }
    }

    /// The tangents at the corners of triangle `prim` of `mesh`, where it
    /// has them.
    #[inline]
    pub(crate) fn corner_tangents(&self, mesh: &MeshInfo, prim: usize) -> Option<[Vec4; 3]> {
        let shift = mesh.tangent?;
        Some(self.indices[prim].map(|i| self.tangents[(i - shift) as usize]))
    }

    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.indices[i].map(|v| self.positions[v as usize])
    }

    /// The box of the triangles' corners, on every core: min and max are
    /// exact, so the order they are taken in changes nothing but the sign
    /// of a zero, made + by adding 0.
    pub fn bounds(&self) -> Aabb {
        let b = self
            .indices
            .par_iter()
            .with_min_len(1 << 14)
            .fold(
                || Aabb::EMPTY,
                |b, t| t.iter().fold(b, |b, &v| b.grow(self.positions[v as usize])),
            )
            .reduce(|| Aabb::EMPTY, Aabb::union);
        Aabb {
            min: b.min + 0.0,
            max: b.max + 0.0,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }
}

/// One named mesh of the scene (an OBJ object or a whole file).
#[derive(Clone, Debug)]
pub struct MeshInfo {
    pub name: String,
    pub(crate) smooth: bool,
    pub textured: bool,
    /// Vertex colours multiply the material's diffuse colour.
    pub colored: bool,
    /// Where its vertices' second UV set is, when it has one: vertex `i`'s
    /// is `Geometry::uvs1[i - shift]`.
    pub(crate) uv1: Option<u32>,
    /// Where its vertices' tangents are, likewise (`Geometry::tangents`).
    pub(crate) tangent: Option<u32>,
}

/// What a ray that leaves the scene sees.
#[derive(Clone, Debug)]
pub enum Environment {
    Color(Vec3),
    CubeMap(Box<CubeMap>),
    /// An environment light: a constant or an equirectangular map, which
    /// can also be sampled as a light.
    Light(Box<EnvLight>),
}

/// How light is followed from the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    Whitted,
    Path,
}

impl Choice for Integrator {
    const ALL: &'static [Self] = &[Integrator::Whitted, Integrator::Path];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            Integrator::Whitted => (
                "whitted",
                "Whitted ray tracing: direct light, mirror and glossy reflection",
            ),
            Integrator::Path => (
                "path",
                "Path tracing: light arriving by any number of bounces",
            ),
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.choice().0)
    }
}

/// Which BVH builder to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Builder {
    #[default]
    Sah,
    Median,
}

impl Choice for Builder {
    const ALL: &'static [Self] = &[Builder::Sah, Builder::Median];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            Builder::Sah => ("sah", "Binned surface area heuristic"),
            Builder::Median => ("median", "Object median on the largest axis"),
        }
    }
}

impl std::fmt::Display for Builder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.choice().0)
    }
}

/// The most samples per pixel any render takes, and the end of every
/// range of samples.
pub(crate) const MAX_SPP: u32 = 1 << 20;

/// The most bounces a ray tree or path may take.
pub(crate) const MAX_DEPTH: u32 = 64;

/// Render defaults a scene can set; the CLI and TUI override them.
#[derive(Clone, Debug)]
pub struct Settings {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub spp: u32,
    pub max_depth: u32,
    /// The integrator asked for; `None` leaves it to the plan.
    pub integrator: Option<Integrator>,
    pub builder: Builder,
    /// Constant light added as `kd * ambient`, so surfaces no light reaches are not pitch black.
    pub ambient: Vec3,
    /// Samples per area light per shading point (rounded up to a square for parallelograms).
    pub light_samples: u32,
    /// Glossy reflection directions per glossy hit.
    pub glossy_samples: u32,
    /// Jittered sub-pixel positions and area-light samples; independent
    /// uniform samples when false, to measure what stratification buys.
    pub stratify: bool,
    pub(crate) bloom: BloomSettings,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BloomSettings {
    pub(crate) threshold: f32,
    pub(crate) sigma: f32,
    pub(crate) radius: u32,
    pub(crate) strength: f32,
}

impl Default for BloomSettings {
    fn default() -> Self {
        Self {
            threshold: 1.0,
            sigma: 4.0,
            radius: 12,
            strength: 0.6,
        }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            width: 1280,
            height: 720,
            spp: 16,
            max_depth: 5,
            integrator: None,
            builder: Builder::Sah,
            ambient: Vec3::ZERO,
            light_samples: 16,
            glossy_samples: 1,
            stratify: true,
            bloom: BloomSettings::default(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub description: String,
    pub geometry: Geometry,
    pub meshes: Vec<MeshInfo>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub camera: Camera,
    pub environment: Environment,
    pub settings: Settings,
    /// Non-fatal problems found while loading (missing MTL or texture, degenerate triangles).
    pub warnings: Vec<String>,
    /// The emissive triangles as lights, found when first asked for
    /// ([`Scene::emitters`]).
    pub(crate) emitters: std::sync::OnceLock<emitters::Emitters>,
}

impl Scene {
    /// Whether some material looks a texture up: its colour's, or any of
    /// a metallic-roughness material's.
    pub fn has_textures(&self) -> bool {
        self.materials.iter().any(|m| {
            m.texture.is_some()
                || m.pbr.as_ref().is_some_and(|p| {
                    p.metallic_roughness.is_some()
                        || p.roughness_texture.is_some()
                        || p.metallic_texture.is_some()
                        || p.specular_texture.is_some()
                        || p.specular_color_texture.is_some()
                        || p.normal.is_some()
                        || p.occlusion.is_some()
                        || p.emissive_texture.is_some()
                })
        })
    }

    /// The emissive triangles, for light sampling.
    pub(crate) fn emitters(&self) -> &emitters::Emitters {
        self.emitters.get_or_init(|| emitters::Emitters::of(self))
    }

    pub(crate) fn has_vertex_normals(&self) -> bool {
        self.meshes.iter().any(|m| m.smooth)
    }

    pub(crate) fn bounds(&self) -> Aabb {
        self.geometry.bounds()
    }

    /// Applies `f` to every position (and the camera and lights), for the
    /// stability battery's scale and offset cases.
    pub fn transform(&mut self, scale: f32, offset: Vec3) {
        let f = |p: Vec3| p * scale + offset;
        self.move_vertices(f);
        self.camera.eye = f(self.camera.eye);
        self.camera.target = f(self.camera.target);
        self.camera.projection = self.camera.projection.scaled(scale);
        for l in &mut self.lights {
            l.transform(scale, offset);
        }
    }

    /// Moves every vertex by `f`, alone (the camera and lights stay): the
    /// tests' controls round a scene as an older loader did.
    pub fn move_vertices(&mut self, f: impl Fn(Vec3) -> Vec3) {
        self.emitters = Default::default();
        for p in &mut self.geometry.positions {
            *p = f(*p);
        }
    }
}

impl Scene {
    /// Moves a scene that lies far from the origin for its size (see
    /// [`rebase::FAR`]) next to it, and says so in `warnings`; returns the
    /// shift subtracted. For scenes moved in code (the stability battery):
    /// the loaders do the same in f64, before rounding ([`rebase::Rebase`]).
    ///
    /// Far out, f32 positions are coarse (1/16 apart at 1e6): every hit point
    /// and spawned ray origin would be rounded to that grid, which speckles
    /// shadows and reflections. Moving the stored positions is exact (the
    /// difference of two nearby floats is a float), so the image becomes the
    /// one of the scene as stored. Axes on which the scene is not far from
    /// the origin are left alone.
    pub fn recentre(&mut self) -> Option<Vec3> {
        let b = self.bounds();
        if b.is_empty() {
            return None;
        }
        let (min, max) = (b.min.as_dvec3(), b.max.as_dvec3());
        let shift = rebase::far_shift(min, max)?.as_vec3();
        self.transform(1.0, -shift);
        self.warnings
            .push(rebase::far_warning(shift.as_dvec3(), min, max));
        Some(shift)
    }
}
