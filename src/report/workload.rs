//! The shared ray workload `primary+shadow` (version 1): one closest-hit ray
//! per pixel from the auto camera, then one any-hit ray from the light to
//! every primary hit. It is specified exactly so that rayterm and other
//! tracers (the Embree harness) trace the same rays and agree on a checksum.

use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::stats::median;
use crate::bvh::{self, Bvh, TraversalStats};
use crate::geometry::{Aabb, Ray};
use crate::scene::camera::CameraFrame;
use crate::scene::{Builder, Geometry};

/// Rows handed out together, as the harness does (interleaved chunks).
const ROW_CHUNK: usize = 4;

/// The far end of a shadow ray, just short of the primary hit.
pub const SHADOW_TMAX: f32 = (1.0 - 1e-4) as f32;

/// Camera and light of the workload for one mesh and image size.
#[derive(Clone, Copy, Debug)]
pub struct Workload {
    pub width: u32,
    pub height: u32,
    frame: CameraFrame,
    eye: Vec3,
    light: DVec3,
    light_f: Vec3,
}

impl Workload {
    /// The auto camera and light from the bounds of the mesh's triangles,
    /// computed in f64 like the specification.
    pub fn auto(bounds: &Aabb, width: u32, height: u32) -> Self {
        let lo = bounds.min.as_dvec3();
        let hi = bounds.max.as_dvec3();
        let c = (lo + hi) * 0.5;
        let r = (hi - lo).length() / 2.0;
        let eye = c + r * DVec3::new(1.2, 0.8, 2.0);
        let light = c + r * DVec3::new(-1.5, 3.0, 2.0);
        Workload {
            width,
            height,
            frame: CameraFrame::new(eye, c, DVec3::Y, 45.0, width, height),
            eye: eye.as_vec3(),
            light,
            light_f: light.as_vec3(),
        }
    }

    /// The primary ray of pixel `(x, y)`, `y = 0` the top row.
    #[inline]
    pub fn primary(&self, x: u32, y: u32) -> Ray {
        self.frame.ray(x as f64 + 0.5, y as f64 + 0.5)
    }

    /// The shadow ray toward the hit at `t` along `primary`: from the light,
    /// direction `P - light` unnormalised, with `P` computed in f64 from the
    /// f32 ray.
    #[inline]
    pub fn shadow(&self, primary: &Ray, t: f32) -> Ray {
        let p = self.eye.as_dvec3() + t as f64 * primary.dir.as_dvec3();
        Ray::segment(self.light_f, (p - self.light).as_vec3(), SHADOW_TMAX)
    }
}

/// `hits`, `occluded` and `sum_t`: summed per row, then over rows in order,
/// so they do not depend on the number of threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Checksum {
    pub hits: u64,
    pub occluded: u64,
    pub sum_t: f64,
}

/// Per-pixel hit distances (negative for a miss) and per-row sums.
pub struct Frame {
    t: Vec<f32>,
    rows: Vec<Checksum>,
}

impl Frame {
    pub fn new(w: &Workload) -> Self {
        Frame {
            t: vec![-1.0; w.width as usize * w.height as usize],
            rows: vec![Checksum::default(); w.height as usize],
        }
    }

    pub fn checksum(&self) -> Checksum {
        self.rows.iter().fold(Checksum::default(), |a, r| Checksum {
            hits: a.hits + r.hits,
            occluded: a.occluded + r.occluded,
            sum_t: a.sum_t + r.sum_t,
        })
    }
}

/// Traces every primary ray with `closest` (returning the hit distance) on
/// the current rayon pool; fills `frame` and returns the elapsed seconds.
/// Ray generation is inside the timed loop, as in the harness.
pub fn trace_primary(
    w: &Workload,
    frame: &mut Frame,
    closest: impl Fn(&Ray) -> Option<f32> + Sync,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    frame
        .t
        .par_chunks_mut(width * ROW_CHUNK)
        .zip(frame.rows.par_chunks_mut(ROW_CHUNK))
        .enumerate()
        .for_each(|(chunk, (ts, rows))| {
            // As the harness does: a row's rays first, then the row traced,
            // so the camera math does not sit in front of every ray.
            let mut rays = Vec::with_capacity(width);
            for (r, (trow, sums)) in ts.chunks_mut(width).zip(rows).enumerate() {
                let y = (chunk * ROW_CHUNK + r) as u32;
                rays.clear();
                rays.extend((0..w.width).map(|x| w.primary(x, y)));
                let (mut hits, mut sum_t) = (0, 0.0);
                for (t, ray) in trow.iter_mut().zip(&rays) {
                    *t = match closest(ray) {
                        Some(d) => {
                            hits += 1;
                            sum_t += d as f64;
                            d
                        }
                        None => -1.0,
                    };
                }
                sums.hits = hits;
                sums.sum_t = sum_t;
            }
        });
    start.elapsed().as_secs_f64()
}

/// Traces one shadow ray per primary hit with `occluded`; returns the
/// elapsed seconds.
pub fn trace_shadow(
    w: &Workload,
    frame: &mut Frame,
    occluded: impl Fn(&Ray) -> bool + Sync,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    frame
        .t
        .par_chunks(width * ROW_CHUNK)
        .zip(frame.rows.par_chunks_mut(ROW_CHUNK))
        .enumerate()
        .for_each(|(chunk, (ts, rows))| {
            let mut rays = Vec::with_capacity(width);
            for (r, (trow, sums)) in ts.chunks(width).zip(rows).enumerate() {
                let y = (chunk * ROW_CHUNK + r) as u32;
                rays.clear();
                rays.extend(
                    trow.iter()
                        .enumerate()
                        .filter(|(_, t)| **t >= 0.0)
                        .map(|(x, &t)| w.shadow(&w.primary(x as u32, y), t)),
                );
                sums.occluded = rays.iter().filter(|ray| occluded(ray)).count() as u64;
            }
        });
    start.elapsed().as_secs_f64()
}

/// Options of `rayterm bench rays`.
#[derive(Clone, Debug)]
pub struct RaysOptions {
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub builder: Builder,
    pub reps: usize,
}

/// The JSON line of the workload, with the fields the specification and the
/// Embree harness print.
#[derive(Clone, Debug, Serialize)]
pub struct RaysReport {
    pub mesh: String,
    pub triangles: usize,
    pub width: u32,
    pub height: u32,
    pub threads: usize,
    pub build_ms: f64,
    pub primary_rays: u64,
    pub hits: u64,
    pub sum_t: f64,
    pub primary_mrays_s: f64,
    pub shadow_rays: u64,
    pub occluded: u64,
    pub shadow_mrays_s: f64,
    pub engine: &'static str,
    pub builder: String,
    pub workload: &'static str,
    pub workload_version: u32,
    pub camera: &'static str,
    pub reps: usize,
    pub primary_ms: f64,
    pub shadow_ms: f64,
}

/// Runs the workload `o.reps` times (a fresh build each time) on the current
/// rayon pool and reports the medians. The checksum must be the same every
/// time; a warning on stderr says when it is not.
pub fn run(mesh: &str, geom: &Geometry, o: &RaysOptions) -> RaysReport {
    let w = Workload::auto(&geom.bounds(), o.width, o.height);
    let reps = o.reps.max(1);
    let mut frame = Frame::new(&w);
    let (mut build, mut prim, mut shad) = (Vec::new(), Vec::new(), Vec::new());
    let mut sum: Option<Checksum> = None;
    for _ in 0..reps {
        let start = Instant::now();
        let bvh = bvh::build(geom, o.builder);
        build.push(start.elapsed().as_secs_f64());
        prim.push(trace_primary(&w, &mut frame, |r| closest_t(&bvh, r)));
        shad.push(trace_shadow(&w, &mut frame, |r| occluded(&bvh, r)));
        let c = frame.checksum();
        if sum.is_some_and(|s| s != c) {
            eprintln!("warning: the checksum differs between repetitions");
        }
        sum = Some(c);
    }
    let c = sum.unwrap_or_default();
    let (b, p, s) = (median(&mut build), median(&mut prim), median(&mut shad));
    let primary_rays = o.width as u64 * o.height as u64;
    RaysReport {
        mesh: mesh.to_string(),
        triangles: geom.triangle_count(),
        width: o.width,
        height: o.height,
        threads: o.threads,
        build_ms: b * 1e3,
        primary_rays,
        hits: c.hits,
        sum_t: c.sum_t,
        primary_mrays_s: primary_rays as f64 / p.max(1e-12) / 1e6,
        shadow_rays: c.hits,
        occluded: c.occluded,
        shadow_mrays_s: c.hits as f64 / s.max(1e-12) / 1e6,
        engine: "rayterm",
        builder: o.builder.to_string(),
        workload: "primary+shadow",
        workload_version: 1,
        camera: "auto",
        reps,
        primary_ms: p * 1e3,
        shadow_ms: s * 1e3,
    }
}

#[inline]
fn closest_t(bvh: &Bvh, r: &Ray) -> Option<f32> {
    bvh.intersect::<false>(r, &mut TraversalStats::default())
        .map(|h| h.t)
}

#[inline]
fn occluded(bvh: &Bvh, r: &Ray) -> bool {
    bvh.occluded::<false>(r, &mut TraversalStats::default())
        .is_some()
}
