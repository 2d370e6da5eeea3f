//! Building the ray tree of one sample of one pixel from the integrator's hooks.

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::bvh::{Bvh, Hit, TraversalStats};
use crate::geometry::Ray;
use crate::render::post::Displayed;
use crate::render::recorder::{
    Bounce, Emission, HitInfo, LightSample, MissInfo, RayKind, Recorder,
};
use crate::render::Tracer;

/// One traced ray and everything that happened along it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RayNode {
    pub kind: RayKind,
    pub(crate) origin: Vec3,
    pub dir: Vec3,
    /// Factor of this ray's radiance in the pixel colour.
    pub weight: Vec3,
    pub bvh: TraversalStats,
    pub hit: Option<HitInfo>,
    pub miss: Option<MissInfo>,
    pub lights: Vec<LightNode>,
    /// On a path: the hit's own light, and how the path went on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) emission: Option<Emission>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounce: Option<Bounce>,
    pub children: Vec<RayNode>,
    /// Radiance returned along the ray.
    pub color: Vec3,
    /// `weight * color`: what this ray adds to the pixel.
    pub contribution: Vec3,
}

/// One light's part in shading a hit.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct LightNode {
    pub(crate) index: usize,
    pub kind: String,
    pub samples: Vec<LightSample>,
    /// BVH work of this light's shadow rays, summed.
    pub(crate) bvh: TraversalStats,
    pub(crate) diffuse: Vec3,
    pub(crate) specular: Vec3,
}

/// The tree of one sample of one pixel.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PixelTree {
    pub(crate) scene: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) sample: u32,
    pub(crate) seed: u64,
    /// Where in the pixel the camera ray passes (0..1 on each axis).
    pub offset: Vec2,
    /// The sample's sub-pixel stratum (`i + 4 j` of a 4x4 grid) when
    /// pixel samples are jittered.
    pub stratum: Option<u32>,
    /// The sample's value: exactly what the renderer adds to the film.
    pub color: Vec3,
    /// When bloom runs: the pixel's value in the image it belongs to,
    /// rendered at `pixel_spp` samples per pixel, before and after bloom.
    pub(crate) pixel_before_bloom: Option<Vec3>,
    pub(crate) pixel_after_bloom: Option<Vec3>,
    pub(crate) pixel_spp: Option<u32>,
    pub root: RayNode,
    /// Light samples traced but not listed: a tree lists at most
    /// [`LISTED_LIGHT_SAMPLES`] (the rest still count in their lights'
    /// terms and BVH work).
    #[serde(default)]
    pub light_samples_not_listed: u64,
}

/// The most light samples one tree lists. A sample's tree holds up to
/// [`MAX_PATHS`](crate::render::integrator::MAX_PATHS) paths of up to 65
/// hits, each with up to 4096 samples of every light: all of them would
/// take gigabytes, and no one reads them.
pub const LISTED_LIGHT_SAMPLES: u64 = 1 << 18;

/// Builds the tree from the hooks, with a stack of open rays.
#[derive(Default)]
pub struct TreeRecorder {
    stack: Vec<RayNode>,
    done: Option<RayNode>,
    offset: Vec2,
    stratum: Option<u32>,
    /// Light samples listed, and those past [`LISTED_LIGHT_SAMPLES`].
    listed: u64,
    not_listed: u64,
}

impl TreeRecorder {
    pub(crate) fn into_root(self) -> Option<RayNode> {
        self.done
    }

    fn light(&mut self) -> Option<&mut LightNode> {
        self.stack.last_mut().and_then(|n| n.lights.last_mut())
    }
}

impl Recorder for TreeRecorder {
    const ACTIVE: bool = true;

    fn intersect(&mut self, bvh: &Bvh, ray: &Ray) -> Option<Hit> {
        let mut st = TraversalStats::default();
        let h = bvh.intersect::<true>(ray, &mut st);
        if let Some(n) = self.stack.last_mut() {
            n.bvh += st;
        }
        h
    }

    fn occluded(&mut self, bvh: &Bvh, ray: &Ray) -> Option<u32> {
        let mut st = TraversalStats::default();
        let h = bvh.occluded::<true>(ray, &mut st);
        if let Some(l) = self.light() {
            l.bvh += st;
        }
        h
    }

    fn pixel_sample(&mut self, offset: Vec2, stratum: Option<u32>) {
        self.offset = offset;
        self.stratum = stratum;
    }

    fn begin_ray(&mut self, kind: RayKind, ray: &Ray, weight: Vec3) {
        self.stack.push(RayNode {
            kind,
            origin: ray.origin,
            dir: ray.dir,
            weight,
            bvh: TraversalStats::default(),
            hit: None,
            miss: None,
            lights: Vec::new(),
            emission: None,
            bounce: None,
            children: Vec::new(),
            color: Vec3::ZERO,
            contribution: Vec3::ZERO,
        });
    }

    fn hit(&mut self, info: HitInfo) {
        if let Some(n) = self.stack.last_mut() {
            n.hit = Some(info);
        }
    }

    fn miss(&mut self, info: MissInfo) {
        if let Some(n) = self.stack.last_mut() {
            n.miss = Some(info);
        }
    }

    fn begin_light(&mut self, index: usize, kind: &'static str) {
        if let Some(n) = self.stack.last_mut() {
            n.lights.push(LightNode {
                index,
                kind: kind.to_string(),
                samples: Vec::new(),
                bvh: TraversalStats::default(),
                diffuse: Vec3::ZERO,
                specular: Vec3::ZERO,
            });
        }
    }

    fn light_sample(&mut self, s: LightSample) {
        if self.listed >= LISTED_LIGHT_SAMPLES {
            self.not_listed += 1;
            return;
        }
        if let Some(l) = self.light() {
            l.samples.push(s);
            self.listed += 1;
        }
    }

    fn end_light(&mut self, diffuse: Vec3, specular: Vec3) {
        if let Some(l) = self.light() {
            l.diffuse = diffuse;
            l.specular = specular;
        }
    }

    fn emission(&mut self, e: Emission) {
        if let Some(n) = self.stack.last_mut() {
            n.emission = Some(e);
        }
    }

    fn bounce(&mut self, b: Bounce) {
        if let Some(n) = self.stack.last_mut() {
            n.bounce = Some(b);
        }
    }

    fn end_ray(&mut self, color: Vec3) {
        let Some(mut n) = self.stack.pop() else {
            return;
        };
        n.color = color;
        n.contribution = n.weight * color;
        match self.stack.last_mut() {
            Some(parent) => parent.children.push(n),
            None => self.done = Some(n),
        }
    }
}

/// Replays sample `k` of pixel `(x, y)` through the integrator with a tree recorder.
pub fn inspect_pixel(tracer: &Tracer, x: u32, y: u32, k: u32) -> PixelTree {
    let mut rec = TreeRecorder::default();
    let color = tracer.sample(x, y, k, &mut rec);
    let (offset, stratum, not_listed) = (rec.offset, rec.stratum, rec.not_listed);
    let root = rec.into_root().expect("every sample traces a camera ray");
    PixelTree {
        scene: tracer.scene.name.clone(),
        width: tracer.width,
        height: tracer.height,
        x,
        y,
        sample: k,
        seed: tracer.seed,
        offset,
        stratum,
        color,
        pixel_before_bloom: None,
        pixel_after_bloom: None,
        pixel_spp: None,
        root,
        light_samples_not_listed: not_listed,
    }
}

impl PixelTree {
    /// Takes the pixel's values before and after bloom from the image it
    /// belongs to (`shown`, made from a film of `spp` samples per pixel);
    /// nothing when bloom did not run.
    pub(crate) fn set_pixel(&mut self, shown: &Displayed, spp: u32) {
        let i = (self.y * self.width + self.x) as usize;
        if let (Some(before), Some(after)) = (
            shown.before_bloom.as_ref().and_then(|b| b.get(i)),
            shown.image.get(i),
        ) {
            self.pixel_before_bloom = Some(*before);
            self.pixel_after_bloom = Some(*after);
            self.pixel_spp = Some(spp);
        }
    }
}
