//! What the integrator reports as it shades, and the cheap recorder used
//! when nobody is watching.
//!
//! The integrator calls these hooks from the one shading code path. The
//! inspector's recorder builds a ray tree from them; [`RayCounter`] only
//! counts rays, and every hook it does not override is an empty inline
//! function, so recording costs nothing when off. Hooks whose arguments are
//! expensive to gather are guarded by [`Recorder::ACTIVE`], a constant.

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::bvh::{Bvh, Hit, TraversalStats};
use crate::geometry::Ray;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    Camera,
    Reflection,
    Glossy,
    Transmission,
    /// A path's bounce drawn from a diffuse lobe.
    Diffuse,
}

/// Everything known about a hit, gathered only for active recorders.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct HitInfo {
    pub(crate) t: f32,
    pub point: Vec3,
    pub triangle: u32,
    pub mesh: String,
    pub(crate) material: String,
    /// Weights of the triangle's three vertices.
    pub(crate) barycentric: Vec3,
    pub(crate) geometric_normal: Vec3,
    pub shading_normal: Vec3,
    pub vertex_normals: Option<[Vec3; 3]>,
    pub(crate) uv: Option<Vec2>,
    pub texel: Option<Vec3>,
    /// Diffuse colour used (texel or kd).
    pub kd: Vec3,
    pub ks: Vec3,
    pub(crate) ns: f32,
    /// A metallic-roughness material's parameters here (absent for
    /// Phong).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) pbr: Option<PbrInfo>,
}

/// A metallic-roughness material at a hit, after its textures.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub(crate) struct PbrInfo {
    pub(crate) metallic: f32,
    pub(crate) roughness: f32,
    /// Emitted radiance.
    pub(crate) emitted: Vec3,
    /// The occlusion map's factor on ambient light (1 without one).
    pub(crate) occlusion: f32,
    /// The normal after the normal map, when one tilted it.
    pub(crate) normal_mapped: Option<Vec3>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct MissInfo {
    /// Where an environment map was looked up: a cube face (`posx` ...),
    /// or `latlong` for an environment light's equirectangular map (u from
    /// the left, v from the top), and the coordinates there.
    pub face: Option<String>,
    pub(crate) uv: Option<Vec2>,
    pub color: Vec3,
    /// On a path: how the environment's light found this way is weighed
    /// against sampling it (absent where it counts whole).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mis: Option<Mis>,
}

/// Multiple importance sampling (the power heuristic) of one light
/// arrival that two strategies could have found: the densities of both
/// per solid angle, and both weights (they sum to 1; the one for the
/// strategy that found it applies).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Mis {
    pub light_pdf: f32,
    pub bsdf_pdf: f32,
    pub light_weight: f32,
    pub bsdf_weight: f32,
}

impl Mis {
    pub(crate) fn new(light_pdf: f32, bsdf_pdf: f32) -> Self {
        let light_weight = super::bsdf::power_heuristic(light_pdf, bsdf_pdf);
        Self {
            light_pdf,
            bsdf_pdf,
            light_weight,
            bsdf_weight: 1.0 - light_weight,
        }
    }
}

/// How a path went on from a hit: the lobe drawn, its density (`None` for
/// a mirror or a pass through), the throughput factor (BSDF times cosine
/// over the density) and the chance Russian roulette let the path live;
/// whether the surface's lobes were made rougher for the bounce
/// ([`Bsdf::regularized`](super::bsdf::Bsdf::regularized)).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Bounce {
    pub(crate) lobe: super::bsdf::Lobe,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub(crate) regularized: bool,
    pub pdf: Option<f32>,
    pub factor: Vec3,
    pub survival: f32,
}

/// Light a surface gives off, seen along a ray, and how it is weighed
/// against sampling the emitter (absent where it counts whole).
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Emission {
    pub(crate) radiance: Vec3,
    pub(crate) mis: Option<Mis>,
}

/// One shadow-tested point on a light.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LightSample {
    pub(crate) point: Vec3,
    pub color: Vec3,
    /// `None` when the light is behind the surface and no ray was traced.
    pub shadow_ray: Option<Ray>,
    pub visible: bool,
    /// Mesh and triangle that blocked the light.
    pub occluder: Option<(String, u32)>,
    pub diffuse: Vec3,
    pub(crate) specular: Vec3,
    /// On a path, for lights a bounce could also find: the weighing of
    /// this sample against the BSDF's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mis: Option<Mis>,
}

pub trait Recorder {
    /// Whether the integrator should gather details for the hooks below.
    const ACTIVE: bool;
    /// Whether [`Recorder::intersect`] is the plain traversal, which a pass
    /// may then do ahead for a batch of camera rays in packets and hand in
    /// ([`crate::render::Tracer::sample_from_hit`]).
    const PLAIN_TRAVERSAL: bool = false;

    /// Closest hit; the inspector's recorder counts the BVH work here.
    #[inline(always)]
    fn intersect(&mut self, bvh: &Bvh, ray: &Ray) -> Option<Hit> {
        bvh.intersect::<false>(ray, &mut TraversalStats::default())
    }

    /// Any hit; returns the blocking triangle (leaf order index mapped back).
    #[inline(always)]
    fn occluded(&mut self, bvh: &Bvh, ray: &Ray) -> Option<u32> {
        bvh.occluded::<false>(ray, &mut TraversalStats::default())
    }

    /// Where in its pixel the sample's camera ray passes (0..1 on each
    /// axis), and its sub-pixel stratum when samples are jittered.
    #[inline(always)]
    fn pixel_sample(&mut self, _offset: Vec2, _stratum: Option<u32>) {}
    /// A ray starts; `weight` is its factor in the pixel's colour.
    #[inline(always)]
    fn begin_ray(&mut self, _kind: RayKind, _ray: &Ray, _weight: Vec3) {}
    #[inline(always)]
    fn hit(&mut self, _info: HitInfo) {}
    #[inline(always)]
    fn miss(&mut self, _info: MissInfo) {}
    #[inline(always)]
    fn begin_light(&mut self, _index: usize, _kind: &'static str) {}
    #[inline(always)]
    fn light_sample(&mut self, _s: LightSample) {}
    /// A shadow ray was traced (counted by [`RayCounter`]).
    #[inline(always)]
    fn shadow_ray(&mut self) {}
    /// The light's averaged diffuse and specular terms.
    #[inline(always)]
    fn end_light(&mut self, _diffuse: Vec3, _specular: Vec3) {}
    /// On a path: the hit's own light.
    #[inline(always)]
    fn emission(&mut self, _e: Emission) {}
    /// On a path: how it goes on from the hit, before the next ray begins.
    #[inline(always)]
    fn bounce(&mut self, _b: Bounce) {}
    /// The ray's radiance.
    #[inline(always)]
    fn end_ray(&mut self, _color: Vec3) {}
}

/// Counts rays for Mrays/s and records nothing else.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCounter {
    pub rays: u64,
}

impl Recorder for RayCounter {
    const ACTIVE: bool = false;
    const PLAIN_TRAVERSAL: bool = true;

    #[inline(always)]
    fn begin_ray(&mut self, _kind: RayKind, _ray: &Ray, _weight: Vec3) {
        self.rays += 1;
    }

    #[inline(always)]
    fn shadow_ray(&mut self) {
        self.rays += 1;
    }
}

/// Counts rays and the BVH work of every traversal, for the TUI's BVH panel.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct WorkCounter {
    pub(crate) rays: u64,
    pub(crate) work: TraversalStats,
}

impl Recorder for WorkCounter {
    const ACTIVE: bool = false;

    fn intersect(&mut self, bvh: &Bvh, ray: &Ray) -> Option<Hit> {
        bvh.intersect::<true>(ray, &mut self.work)
    }

    fn occluded(&mut self, bvh: &Bvh, ray: &Ray) -> Option<u32> {
        bvh.occluded::<true>(ray, &mut self.work)
    }

    fn begin_ray(&mut self, _kind: RayKind, _ray: &Ray, _weight: Vec3) {
        self.rays += 1;
    }

    fn shadow_ray(&mut self) {
        self.rays += 1;
    }
}
