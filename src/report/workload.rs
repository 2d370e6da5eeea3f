//! The shared ray workload `primary+shadow+diffuse` (version 2): one
//! closest-hit ray per pixel from the auto camera, one any-hit ray from the
//! light to every primary hit, and one incoherent closest-hit ray from every
//! primary hit, cosine-distributed about the hit triangle's normal. It is
//! specified exactly (in f64, to the bit) so that rayterm and other tracers
//! (the Embree harness) trace the same rays and agree on a checksum.

use std::ops::Range;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::stats::median;
use crate::bvh::{self, Bvh, Simd, TraversalStats};
use crate::geometry::{Aabb, Ray};
use crate::scene::camera::{CameraFrame, Projection};
use crate::scene::{Builder, Geometry};

/// Rows handed out together, as the harness does (interleaved chunks).
/// Every chunk of rows, and every band of tiles, is a job of its own
/// (`with_max_len(1)`): the mesh fills the middle rows, and a run of rows
/// that rayon no longer splits once a thread has begun it left the other
/// thread idle at the end.
const ROW_CHUNK: usize = 4;

/// The far end of a shadow ray, just short of the primary hit.
pub(crate) const SHADOW_TMAX: f32 = (1.0 - 1e-4) as f32;

/// Camera and light of the workload for one mesh and image size.
#[derive(Clone, Copy, Debug)]
pub struct Workload {
    pub width: u32,
    pub height: u32,
    frame: CameraFrame,
    eye: Vec3,
    light: DVec3,
    light_f: Vec3,
    /// Half the bounding box's diagonal: diffuse origins are lifted off
    /// the surface by 1e-4 of it.
    radius: f64,
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
            frame: CameraFrame::new(
                eye,
                c,
                DVec3::Y,
                Projection::perspective(45.0),
                width,
                height,
            ),
            eye: eye.as_vec3(),
            light,
            light_f: light.as_vec3(),
            radius: r,
        }
    }

    /// The primary ray of pixel `(x, y)`, `y = 0` the top row.
    #[inline]
    pub fn primary(&self, x: u32, y: u32) -> Ray {
        self.frame.ray(x as f64 + 0.5, y as f64 + 0.5)
    }

    /// The offsets of the image's columns ([`CameraFrame::sx`] of their
    /// centres): made once per pass, they save every ray a division.
    pub(crate) fn columns(&self) -> Vec<f64> {
        (0..self.width)
            .map(|x| self.frame.sx(x as f64 + 0.5))
            .collect()
    }

    /// The shadow ray toward the hit at `t` along `primary`: from the light,
    /// direction `P - light` unnormalised, with `P` computed in f64 from the
    /// f32 ray.
    #[inline]
    pub fn shadow(&self, primary: &Ray, t: f32) -> Ray {
        let p = self.eye.as_dvec3() + t as f64 * primary.dir.as_dvec3();
        Ray::segment(self.light_f, (p - self.light).as_vec3(), SHADOW_TMAX)
    }

    /// The diffuse ray from the hit at `t` along the primary ray of pixel
    /// index `pixel` on triangle `tri`: every step in f64 as written in the
    /// specification (no fused operations, left to right), rounded to f32
    /// at the end.
    pub fn diffuse(&self, primary: &Ray, t: f32, tri: [Vec3; 3], pixel: u32) -> Ray {
        let d = primary.dir.as_dvec3();
        let p = self.eye.as_dvec3() + t as f64 * d;
        let [v0, v1, v2] = tri.map(|v| v.as_dvec3());
        let (a, b) = (v1 - v0, v2 - v0);
        let c = DVec3::new(
            a.y * b.z - a.z * b.y,
            a.z * b.x - a.x * b.z,
            a.x * b.y - a.y * b.x,
        );
        let dot = |a: DVec3, b: DVec3| (a.x * b.x + a.y * b.y) + a.z * b.z;
        let len = dot(c, c).sqrt();
        let mut n = DVec3::new(c.x / len, c.y / len, c.z / len);
        if dot(n, d) > 0.0 {
            n = -n;
        }
        let lift = 1e-4 * self.radius;
        let origin = p + n * lift;
        let unit = |v: u32| (pcg(v) >> 8) as f64 * (1.0 / (1u64 << 24) as f64);
        let (u1, u2) = (
            unit(pixel.wrapping_mul(2)),
            unit(pixel.wrapping_mul(2).wrapping_add(1)),
        );
        let phi = std::f64::consts::TAU * u1;
        let s = u2.sqrt();
        let local = DVec3::new(s * phi.cos(), s * phi.sin(), (1.0 - u2).sqrt());
        // Duff et al. 2017; copysign keeps -0 apart from +0.
        let sign = 1f64.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let t1 = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t2 = DVec3::new(b, sign + n.y * n.y * a, -n.y);
        let dir = (local.x * t1 + local.y * t2) + local.z * n;
        Ray::new(origin.as_vec3(), dir.as_vec3())
    }
}

/// The PCG hash of Jarzynski and Olano (2020), as the workload defines it.
fn pcg(v: u32) -> u32 {
    let s = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let w = ((s >> ((s >> 28) + 4)) ^ s).wrapping_mul(277_803_737);
    (w >> 22) ^ w
}

/// `hits`, `occluded` and `sum_t`: summed per row, then over rows in order,
/// so they do not depend on the number of threads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Checksum {
    pub hits: u64,
    pub occluded: u64,
    pub sum_t: f64,
    pub diffuse_hits: u64,
    pub diffuse_sum_t: f64,
}

/// Per-pixel hit distances (negative for a miss) and triangles, and per-row
/// sums.
pub struct HitImage {
    t: Vec<f32>,
    tri: Vec<u32>,
    rows: Vec<Checksum>,
}

impl HitImage {
    pub fn new(w: &Workload) -> Self {
        let n = w.width as usize * w.height as usize;
        HitImage {
            t: vec![-1.0; n],
            tri: vec![0; n],
            rows: vec![Checksum::default(); w.height as usize],
        }
    }

    pub fn checksum(&self) -> Checksum {
        self.rows.iter().fold(Checksum::default(), |a, r| Checksum {
            hits: a.hits + r.hits,
            occluded: a.occluded + r.occluded,
            sum_t: a.sum_t + r.sum_t,
            diffuse_hits: a.diffuse_hits + r.diffuse_hits,
            diffuse_sum_t: a.diffuse_sum_t + r.diffuse_sum_t,
        })
    }
}

/// What a timed loop makes its primary and shadow rays with: the same
/// rays as [`Workload::primary`] and [`Workload::shadow`], a column's and a
/// row's offsets computed once each and the camera math done four rays at
/// a time ([`CameraFrame::rays_through`]).
pub(crate) struct Maker<'a> {
    w: &'a Workload,
    /// [`Workload::columns`].
    cols: &'a [f64],
    sx: Vec<f64>,
    sy: Vec<f64>,
    /// The row of the last shadow ray asked for, and its offset.
    row: Option<(usize, f64)>,
    /// The hit distances of the shadow rays asked for.
    t: Vec<f32>,
    primary: Vec<Ray>,
}

impl<'a> Maker<'a> {
    pub(crate) fn new(w: &'a Workload, cols: &'a [f64]) -> Self {
        Maker {
            w,
            cols,
            sx: Vec::new(),
            sy: Vec::new(),
            row: None,
            t: Vec::new(),
            primary: Vec::new(),
        }
    }

    /// The primary rays of the pixels `xs` x `ys`, rows in order, appended
    /// to `rays`.
    pub(crate) fn primary(&mut self, xs: Range<usize>, ys: Range<usize>, rays: &mut Vec<Ray>) {
        debug_assert!(self.t.is_empty(), "shadow rays asked for and not made");
        self.sx.clear();
        self.sy.clear();
        for y in ys {
            let sy = self.w.frame.sy(y as f64 + 0.5);
            self.sx.extend_from_slice(&self.cols[xs.clone()]);
            self.sy.extend(std::iter::repeat_n(sy, xs.len()));
        }
        self.w.frame.rays_through(&self.sx, &self.sy, rays);
    }

    /// Asks for the shadow ray toward the hit at `t` in pixel `(x, y)`;
    /// [`Maker::shadows`] makes it.
    #[inline]
    pub(crate) fn ask_shadow(&mut self, x: usize, y: usize, t: f32) {
        let sy = match self.row {
            Some((row, sy)) if row == y => sy,
            _ => self.w.frame.sy(y as f64 + 0.5),
        };
        self.row = Some((y, sy));
        self.sx.push(self.cols[x]);
        self.sy.push(sy);
        self.t.push(t);
    }

    /// The shadow rays asked for since the last call, in that order,
    /// appended to `rays`.
    #[inline(never)]
    pub(crate) fn shadows(&mut self, rays: &mut Vec<Ray>) {
        self.primary.clear();
        self.w
            .frame
            .rays_through(&self.sx, &self.sy, &mut self.primary);
        let w = self.w;
        rays.extend(
            self.primary
                .iter()
                .zip(&self.t)
                .map(|(p, &t)| w.shadow(p, t)),
        );
        self.sx.clear();
        self.sy.clear();
        self.t.clear();
    }
}

/// Where a phase's rays come from: made row by row inside the timed loop
/// (as the Embree harness does), or made before it, one `Vec` per row (as
/// the tinybvh harness does).
#[derive(Clone, Copy)]
pub enum Rows<'a> {
    Make,
    Made(&'a [Vec<Ray>]),
}

/// Traces every primary ray with `closest` (returning the hit distance and
/// triangle) on the current rayon pool; fills `frame` and returns the
/// elapsed seconds. With [`Rows::Make`] ray generation is inside the timed
/// loop, as in the Embree harness.
pub fn trace_primary(
    w: &Workload,
    frame: &mut HitImage,
    source: Rows,
    closest: impl Fn(&Ray) -> Option<(f32, u32)> + Sync,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    let cols = w.columns();
    frame
        .t
        .par_chunks_mut(width * ROW_CHUNK)
        .zip(frame.tri.par_chunks_mut(width * ROW_CHUNK))
        .zip(frame.rows.par_chunks_mut(ROW_CHUNK))
        .enumerate()
        .with_max_len(1)
        .for_each(|(chunk, ((ts, tris), rows))| {
            // As the harness does: a row's rays first, then the row traced,
            // so the camera math does not sit in front of every ray.
            let mut rays = Vec::with_capacity(width);
            let mut maker = Maker::new(w, &cols);
            let rows_of = ts.chunks_mut(width).zip(tris.chunks_mut(width));
            for (r, ((trow, tri_row), sums)) in rows_of.zip(rows).enumerate() {
                let y = (chunk * ROW_CHUNK + r) as u32;
                let row = match source {
                    Rows::Made(made) => &made[y as usize][..],
                    Rows::Make => {
                        rays.clear();
                        let y = y as usize;
                        maker.primary(0..width, y..y + 1, &mut rays);
                        &rays[..]
                    }
                };
                let (mut hits, mut sum_t) = (0, 0.0);
                for ((t, tri), ray) in trow.iter_mut().zip(tri_row).zip(row) {
                    *t = match closest(ray) {
                        Some((d, k)) => {
                            hits += 1;
                            sum_t += d as f64;
                            *tri = k;
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
    frame: &mut HitImage,
    source: Rows,
    occluded: impl Fn(&Ray) -> bool + Sync,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    let cols = w.columns();
    frame
        .t
        .par_chunks(width * ROW_CHUNK)
        .zip(frame.rows.par_chunks_mut(ROW_CHUNK))
        .enumerate()
        .with_max_len(1)
        .for_each(|(chunk, (ts, rows))| {
            let mut rays = Vec::with_capacity(width);
            let mut maker = Maker::new(w, &cols);
            for (r, (trow, sums)) in ts.chunks(width).zip(rows).enumerate() {
                let y = (chunk * ROW_CHUNK + r) as u32;
                let row = match source {
                    Rows::Made(made) => &made[y as usize][..],
                    Rows::Make => {
                        for (x, &t) in trow.iter().enumerate().filter(|(_, t)| **t >= 0.0) {
                            maker.ask_shadow(x, y as usize, t);
                        }
                        rays.clear();
                        maker.shadows(&mut rays);
                        &rays[..]
                    }
                };
                sums.occluded = row.iter().filter(|ray| occluded(ray)).count() as u64;
            }
        });
    start.elapsed().as_secs_f64()
}

/// The shadow rays of row `y` (one per primary hit, in pixel order) into
/// `rays`, from the row's hit distances `trow` (negative for a miss).
fn shadow_row(w: &Workload, trow: &[f32], y: u32, rays: &mut Vec<Ray>) {
    rays.clear();
    rays.extend(
        trow.iter()
            .enumerate()
            .filter(|(_, t)| **t >= 0.0)
            .map(|(x, &t)| w.shadow(&w.primary(x as u32, y), t)),
    );
}

/// Pixels per side of the square tiles whose rays `--packets` traces
/// together: 64 camera rays of a tile, or the shadow rays of its hits.
pub(crate) const TILE: usize = 8;

/// [`trace_primary`] in packets: the camera rays of each tile of
/// [`TILE`] x [`TILE`] pixels (left to right in bands of [`TILE`] rows, the
/// rays of a tile in pixel order) traced together by
/// [`Bvh::intersect_packet`]. The checksum is summed per row in pixel order,
/// as there.
pub(crate) fn trace_primary_packets(
    w: &Workload,
    frame: &mut HitImage,
    source: Rows,
    bvh: &Bvh,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    let cols = w.columns();
    frame
        .t
        .par_chunks_mut(width * TILE)
        .zip(frame.tri.par_chunks_mut(width * TILE))
        .zip(frame.rows.par_chunks_mut(TILE))
        .enumerate()
        .with_max_len(1)
        .for_each(|(band, ((ts, tris), rows))| {
            let mut rays = Vec::with_capacity(TILE * TILE);
            let mut maker = Maker::new(w, &cols);
            let mut hits = [None; TILE * TILE];
            for x0 in (0..width).step_by(TILE) {
                let xs = x0..(x0 + TILE).min(width);
                rays.clear();
                let ys = band * TILE..band * TILE + rows.len();
                match source {
                    Rows::Made(made) => {
                        for y in ys {
                            rays.extend_from_slice(&made[y][xs.clone()]);
                        }
                    }
                    Rows::Make => maker.primary(xs.clone(), ys, &mut rays),
                }
                let hits = &mut hits[..rays.len()];
                bvh.intersect_packet(&rays, hits);
                let at = (0..rows.len()).flat_map(|r| xs.clone().map(move |x| r * width + x));
                for (i, h) in at.zip(hits.iter()) {
                    (ts[i], tris[i]) = h.map_or((-1.0, 0), |h| (h.t, h.prim));
                }
            }
            for (sums, trow) in rows.iter_mut().zip(ts.chunks(width)) {
                let hit = trow.iter().filter(|t| **t >= 0.0);
                sums.hits = hit.clone().count() as u64;
                sums.sum_t = hit.map(|&t| t as f64).sum();
            }
        });
    start.elapsed().as_secs_f64()
}

/// [`trace_shadow`] in packets: the shadow rays of each tile's hits (as
/// [`trace_primary_packets`] tiles the frame, in pixel order within the
/// tile) traced together by [`Bvh::occluded_packet`].
pub(crate) fn trace_shadow_packets(
    w: &Workload,
    frame: &mut HitImage,
    source: Rows,
    bvh: &Bvh,
) -> f64 {
    let width = w.width as usize;
    let start = Instant::now();
    let cols = w.columns();
    frame
        .t
        .par_chunks(width * TILE)
        .zip(frame.rows.par_chunks_mut(TILE))
        .enumerate()
        .with_max_len(1)
        .for_each(|(band, (ts, rows))| {
            let mut rays = Vec::with_capacity(TILE * TILE);
            let mut maker = Maker::new(w, &cols);
            let mut row_of = Vec::with_capacity(TILE * TILE);
            let mut blocked = [false; TILE * TILE];
            // Where each row's next ray lies among its rays made first.
            let mut next = [0; TILE];
            for sums in rows.iter_mut() {
                sums.occluded = 0;
            }
            for x0 in (0..width).step_by(TILE) {
                let xs = x0..(x0 + TILE).min(width);
                rays.clear();
                row_of.clear();
                for (r, trow) in ts.chunks(width).enumerate() {
                    let y = band * TILE + r;
                    for x in xs.clone().filter(|&x| trow[x] >= 0.0) {
                        match source {
                            Rows::Made(made) => rays.push(made[y][next[r]]),
                            Rows::Make => maker.ask_shadow(x, y, trow[x]),
                        }
                        next[r] += 1;
                        row_of.push(r);
                    }
                }
                maker.shadows(&mut rays);
                let blocked = &mut blocked[..rays.len()];
                bvh.occluded_packet(&rays, blocked);
                for (&r, &b) in row_of.iter().zip(blocked.iter()) {
                    rows[r].occluded += b as u64;
                }
            }
        });
    start.elapsed().as_secs_f64()
}

/// The primary rays of every row, made before they are timed.
pub(crate) fn primary_rays(w: &Workload) -> Vec<Vec<Ray>> {
    (0..w.height)
        .into_par_iter()
        .map(|y| (0..w.width).map(|x| w.primary(x, y)).collect())
        .collect()
}

/// The shadow rays of every row, made before they are timed.
pub(crate) fn shadow_rays(w: &Workload, frame: &HitImage) -> Vec<Vec<Ray>> {
    frame
        .t
        .par_chunks(w.width as usize)
        .enumerate()
        .map(|(y, trow)| {
            let mut rays = Vec::new();
            shadow_row(w, trow, y as u32, &mut rays);
            rays
        })
        .collect()
}

/// The diffuse rays of every row (one per primary hit, in pixel order),
/// made before they are timed, as in the harness.
pub fn diffuse_rays(w: &Workload, frame: &HitImage, geom: &Geometry) -> Vec<Vec<Ray>> {
    let width = w.width as usize;
    (0..w.height as usize)
        .into_par_iter()
        .map(|y| {
            let row = y * width..(y + 1) * width;
            frame.t[row.clone()]
                .iter()
                .zip(&frame.tri[row])
                .enumerate()
                .filter(|(_, (t, _))| **t >= 0.0)
                .map(|(x, (&t, &tri))| {
                    let p = w.primary(x as u32, y as u32);
                    let pixel = (y * width + x) as u32;
                    w.diffuse(&p, t, geom.triangle(tri as usize), pixel)
                })
                .collect()
        })
        .collect()
}

/// Traces the diffuse rays of every row with `closest`; returns the
/// elapsed seconds.
pub fn trace_diffuse(
    frame: &mut HitImage,
    rays: &[Vec<Ray>],
    closest: impl Fn(&Ray) -> Option<(f32, u32)> + Sync,
) -> f64 {
    let start = Instant::now();
    frame
        .rows
        .par_chunks_mut(ROW_CHUNK)
        .zip(rays.par_chunks(ROW_CHUNK))
        .with_max_len(1)
        .for_each(|(sums, rows)| {
            for (s, row) in sums.iter_mut().zip(rows) {
                let (mut hits, mut sum_t) = (0, 0.0);
                for t in row.iter().filter_map(&closest) {
                    hits += 1;
                    sum_t += t.0 as f64;
                }
                s.diffuse_hits = hits;
                s.diffuse_sum_t = sum_t;
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
    /// Make the primary and shadow rays before the timer and trace every
    /// set once untimed before the timed pass, as the tinybvh harness
    /// does; otherwise they are made in the timed loop, as the Embree
    /// harness makes them.
    pub rays_first: bool,
    /// Primary and shadow rays in packets of a tile
    /// ([`trace_primary_packets`], [`trace_shadow_packets`]).
    pub packets: bool,
    /// The widest SIMD kernels the walks may use.
    pub simd: Simd,
}

/// The JSON line of the workload, with the fields the specification and the
/// Embree harness print.
#[derive(Clone, Debug, Serialize)]
pub struct RaysReport {
    pub(crate) mesh: String,
    pub(crate) triangles: usize,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) threads: usize,
    pub(crate) build_ms: f64,
    pub(crate) primary_rays: u64,
    pub hits: u64,
    pub sum_t: f64,
    pub(crate) primary_mrays_s: f64,
    pub(crate) shadow_rays: u64,
    pub occluded: u64,
    pub(crate) shadow_mrays_s: f64,
    pub(crate) diffuse_rays: u64,
    pub diffuse_hits: u64,
    pub diffuse_sum_t: f64,
    pub(crate) diffuse_mrays_s: f64,
    pub(crate) engine: &'static str,
    pub(crate) builder: String,
    pub(crate) workload: &'static str,
    pub(crate) workload_version: u32,
    pub(crate) camera: &'static str,
    pub(crate) reps: usize,
    /// `"timed"`: primary and shadow rays made in the timed loop;
    /// `"untimed"`: made before it, each set traced once untimed first.
    pub ray_generation: &'static str,
    /// How each ray set was traced: `"single"` (one ray at a time) or
    /// `"packets of 8x8 tiles"`.
    pub primary_traversal: &'static str,
    pub shadow_traversal: &'static str,
    pub diffuse_traversal: &'static str,
    /// The SIMD kernels the walks used.
    pub simd: Simd,
    pub(crate) primary_ms: f64,
    pub(crate) shadow_ms: f64,
    pub(crate) diffuse_ms: f64,
}

/// Runs the workload `o.reps` times (a fresh build each time) on the current
/// rayon pool and reports the medians. The checksum must be the same every
/// time; a warning on stderr says when it is not.
pub fn run(mesh: &str, geom: &Geometry, o: &RaysOptions) -> RaysReport {
    let w = Workload::auto(&geom.bounds(), o.width, o.height);
    let reps = o.reps.max(1);
    let mut frame = HitImage::new(&w);
    let (mut build, mut prim, mut shad, mut diff) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut sum: Option<Checksum> = None;
    let mut simd = o.simd;
    for _ in 0..reps {
        let start = Instant::now();
        let mut bvh = bvh::build(geom, o.builder);
        build.push(start.elapsed().as_secs_f64());
        bvh.cap_simd(o.simd);
        simd = bvh.simd();
        let (closest, occluded) = (|r: &Ray| closest(&bvh, r), |r: &Ray| occluded(&bvh, r));
        let primary = |frame: &mut HitImage, rows| match o.packets {
            true => trace_primary_packets(&w, frame, rows, &bvh),
            false => trace_primary(&w, frame, rows, closest),
        };
        if o.rays_first {
            let rays = primary_rays(&w);
            primary(&mut frame, Rows::Made(&rays));
            prim.push(primary(&mut frame, Rows::Made(&rays)));
        } else {
            prim.push(primary(&mut frame, Rows::Make));
        }
        let shadow = |frame: &mut HitImage, rows| match o.packets {
            true => trace_shadow_packets(&w, frame, rows, &bvh),
            false => trace_shadow(&w, frame, rows, occluded),
        };
        if o.rays_first {
            let rays = shadow_rays(&w, &frame);
            shadow(&mut frame, Rows::Made(&rays));
            shad.push(shadow(&mut frame, Rows::Made(&rays)));
        } else {
            shad.push(shadow(&mut frame, Rows::Make));
        }
        let rays = diffuse_rays(&w, &frame, geom);
        if o.rays_first {
            trace_diffuse(&mut frame, &rays, closest);
        }
        diff.push(trace_diffuse(&mut frame, &rays, closest));
        let c = frame.checksum();
        if sum.is_some_and(|s| s != c) {
            crate::noteln!("warning: the checksum differs between repetitions");
        }
        sum = Some(c);
    }
    let c = sum.unwrap_or_default();
    let (b, p, s) = (median(&mut build), median(&mut prim), median(&mut shad));
    let d = median(&mut diff);
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
        diffuse_rays: c.hits,
        diffuse_hits: c.diffuse_hits,
        diffuse_sum_t: c.diffuse_sum_t,
        diffuse_mrays_s: c.hits as f64 / d.max(1e-12) / 1e6,
        engine: "rayterm",
        builder: o.builder.to_string(),
        workload: "primary+shadow+diffuse",
        workload_version: 2,
        camera: "auto",
        reps,
        ray_generation: if o.rays_first { "untimed" } else { "timed" },
        primary_traversal: traversal(o.packets),
        shadow_traversal: traversal(o.packets),
        // Diffuse rays share no origin: packets would trace them one by one.
        diffuse_traversal: "single",
        simd,
        primary_ms: p * 1e3,
        shadow_ms: s * 1e3,
        diffuse_ms: d * 1e3,
    }
}

fn traversal(packets: bool) -> &'static str {
    if packets {
        "packets of 8x8 tiles"
    } else {
        "single"
    }
}

#[inline]
fn closest(bvh: &Bvh, r: &Ray) -> Option<(f32, u32)> {
    bvh.intersect::<false>(r, &mut TraversalStats::default())
        .map(|h| (h.t, h.prim))
}

#[inline]
fn occluded(bvh: &Bvh, r: &Ray) -> bool {
    bvh.occluded::<false>(r, &mut TraversalStats::default())
        .is_some()
}
