//! Arbitrary output variables: what the camera's rays first hit, per
//! pixel, beside the picture in an EXR (`--aov`), for compositing and
//! denoisers. Read from the hit the integrator records, through the same
//! `Tracer::sample` as the picture (a recorder that keeps the camera ray's
//! hit, paths cut at the first hit), averaged over a few of the pixel's
//! own samples so that edges are antialiased as the picture's are.

use glam::Vec3;
use rayon::prelude::*;

use super::recorder::{HitInfo, Recorder};
use super::Tracer;
use crate::geometry::Ray;
use crate::interrupt::Cancel;

/// One output variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum Aov {
    Albedo,
    Normal,
    Depth,
}

impl crate::choice::Choice for Aov {
    const ALL: &'static [Self] = &[Aov::Albedo, Aov::Normal, Aov::Depth];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            Aov::Albedo => (
                "albedo",
                "The surface's colour: a Phong material's diffuse colour, a metallic-roughness one's base colour, textures and vertex colours applied; black where the ray leaves the scene",
            ),
            Aov::Normal => (
                "normal",
                "The shading normal in world space (after normal maps), each component -1 to 1; zero where the ray leaves the scene",
            ),
            Aov::Depth => (
                "depth",
                "The distance from the eye along the ray; infinite where the ray leaves the scene",
            ),
        }
    }
}

impl Aov {
    /// The EXR channels it is written as, in order.
    pub(crate) fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
            Aov::Normal => &["normal.X", "normal.Y", "normal.Z"],
            Aov::Depth => &["Z"],
        }
    }
}

/// Memory the variables take a pixel while they are made and written: a
/// pixel's first hit (28 bytes), its planes (7 channels of f32) and the
/// picture's three, and room for the encoded file.
pub(crate) const BYTES_PER_PIXEL: u64 = 28 + 28 + 12 + 40;

/// The samples of a pixel averaged for its variables (its first ones:
/// jittered over the pixel where supersampling runs).
pub(crate) const AOV_SAMPLES: u32 = 8;

/// The camera ray's first hit, as the variables need it.
#[derive(Default)]
struct FirstHit {
    nesting: u32,
    length: f32,
    hit: Option<(Vec3, Vec3, f32)>,
}

impl Recorder for FirstHit {
    const ACTIVE: bool = true;

    fn begin_ray(&mut self, _kind: super::recorder::RayKind, ray: &Ray, _weight: Vec3) {
        if self.nesting == 0 {
            self.length = ray.dir.length();
        }
        self.nesting += 1;
    }

    fn hit(&mut self, h: HitInfo) {
        if self.nesting == 1 {
            let normal = h
                .pbr
                .and_then(|p| p.normal_mapped)
                .unwrap_or(h.shading_normal);
            self.hit = Some((h.kd, normal, h.t * self.length));
        }
    }

    fn end_ray(&mut self, _color: Vec3) {
        self.nesting -= 1;
    }
}

/// The variables `which` of every pixel of `tracer`'s image, in the order
/// of their channels, each a plane of `width * height` values; `None` once
/// `cancel` says stop.
pub(crate) fn render(
    tracer: &Tracer,
    which: &[Aov],
    cancel: Cancel,
) -> Option<Vec<(&'static str, Vec<f32>)>> {
    // Only the first hit matters: no bounces after it.
    let plan = tracer.plan.clone().with_max_depth(0);
    let t = Tracer::new(tracer.scene, tracer.bvh, &plan, tracer.frame, tracer.seed);
    let (w, h) = (t.width as usize, t.height as usize);
    let n = if plan.supersampling { AOV_SAMPLES } else { 1 };
    let rows: Vec<Option<Vec<(Vec3, Vec3, f32)>>> = (0..h)
        .into_par_iter()
        .map(|y| {
            if cancel.is_set() {
                return None;
            }
            let row = (0..w)
                .map(|x| {
                    let (mut albedo, mut normal, mut depth, mut hits) =
                        (Vec3::ZERO, Vec3::ZERO, 0.0, 0);
                    for k in 0..n {
                        let mut rec = FirstHit::default();
                        t.sample(x as u32, y as u32, k, &mut rec);
                        if let Some((a, nn, d)) = rec.hit {
                            (albedo, normal, depth, hits) =
                                (albedo + a, normal + nn, depth + d, hits + 1);
                        }
                    }
                    // Misses count as black albedo and no normal; the
                    // depth is that of the hits, infinite without one.
                    let depth = if hits > 0 {
                        depth / hits as f32
                    } else {
                        f32::INFINITY
                    };
                    (albedo / n as f32, normal / n as f32, depth)
                })
                .collect();
            Some(row)
        })
        .collect();
    let px: Vec<(Vec3, Vec3, f32)> = rows.into_iter().collect::<Option<Vec<_>>>()?.concat();
    let mut out = Vec::new();
    for aov in which {
        let planes: Vec<Vec<f32>> = match aov {
            Aov::Albedo => (0..3)
                .map(|c| px.iter().map(|p| p.0[c]).collect())
                .collect(),
            Aov::Normal => (0..3)
                .map(|c| px.iter().map(|p| p.1[c]).collect())
                .collect(),
            Aov::Depth => vec![px.iter().map(|p| p.2).collect()],
        };
        out.extend(aov.channels().iter().copied().zip(planes));
    }
    Some(out)
}
