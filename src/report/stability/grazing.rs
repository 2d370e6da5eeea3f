//! Grazing rays: rays along the planes of boxes and triangles, with
//! direction components of 0, -0 and tiny magnitudes (1e-30 and below),
//! starting on and off those planes. No result may be NaN, the BVH must
//! agree with brute force (both builders), and no box on the way to a
//! triangle the ray hits may be missed.

use anyhow::Result;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::{Options, Row};
use crate::bvh::{self, Bvh, TraversalStats};
use crate::geometry::sampling::Rng;
use crate::geometry::triangle::{intersect, RayShear};
use crate::geometry::Ray;
use crate::scene::{Builder, Geometry};

/// Components a grazing direction is made of: zeros of both signs and
/// magnitudes at, below and far below 1e-30 (the last one subnormal).
const TINY: [f32; 6] = [0.0, -0.0, 1e-30, -1e-30, 1e-35, -1e-40];
const PLAIN: [f32; 4] = [1.0, -1.0, 0.5, -0.25];

/// Every direction with at least one tiny and one plain component.
pub fn grazing_directions() -> Vec<Vec3> {
    let all: Vec<f32> = TINY.iter().chain(PLAIN.iter()).copied().collect();
    let tiny = |x: f32| x.abs() <= 1e-30;
    let mut out = Vec::new();
    for &x in &all {
        for &y in &all {
            for &z in &all {
                let c = [x, y, z];
                if c.iter().any(|&v| tiny(v)) && c.iter().any(|&v| !tiny(v)) {
                    out.push(Vec3::new(x, y, z));
                }
            }
        }
    }
    out
}

/// Unit cubes on a 3x3x3 lattice, every other one, so faces, edges and
/// BVH box planes coincide on the integer planes.
pub fn lattice() -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                if (i + j + k) % 2 == 1 {
                    continue;
                }
                let o = Vec3::new(i as f32, j as f32, k as f32);
                let c = |x: f32, y: f32, z: f32| o + Vec3::new(x, y, z);
                let faces = [
                    [c(0., 0., 0.), c(0., 1., 0.), c(1., 1., 0.), c(1., 0., 0.)],
                    [c(0., 0., 1.), c(1., 0., 1.), c(1., 1., 1.), c(0., 1., 1.)],
                    [c(0., 0., 0.), c(1., 0., 0.), c(1., 0., 1.), c(0., 0., 1.)],
                    [c(0., 1., 0.), c(0., 1., 1.), c(1., 1., 1.), c(1., 1., 0.)],
                    [c(0., 0., 0.), c(0., 0., 1.), c(0., 1., 1.), c(0., 1., 0.)],
                    [c(1., 0., 0.), c(1., 1., 0.), c(1., 1., 1.), c(1., 0., 1.)],
                ];
                for [a, b, cc, d] in faces {
                    tris.push([a, b, cc]);
                    tris.push([a, cc, d]);
                }
            }
        }
    }
    tris
}

/// Random triangles of assorted sizes and orientations beside the lattice.
pub(crate) fn slanted(rng: &mut Rng, n: usize) -> Vec<[Vec3; 3]> {
    let mut r = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
    (0..n)
        .map(|_| {
            let c = r() * 3.0 + Vec3::new(4.0, 0.0, 0.0);
            let s = 0.2 + r().x;
            [c, c + (r() - 0.5) * s, c + (r() - 0.5) * s]
        })
        .collect()
}

/// Nodes from the root to the leaf holding each triangle (in leaf order).
pub fn ancestors(b: &Bvh) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); b.triangle_count()];
    if b.nodes.is_empty() {
        return out;
    }
    let mut stack = vec![(0u32, Vec::new())];
    while let Some((i, mut path)) = stack.pop() {
        path.push(i);
        let n = &b.nodes[i as usize];
        if n.is_leaf() {
            for t in n.first..n.first + n.count {
                out[t as usize] = path.clone();
            }
        } else {
            stack.push((n.first, path.clone()));
            stack.push((n.first + 1, path));
        }
    }
    out
}

/// Problems found by one set of rays against one BVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Grazing {
    pub(crate) rays: u64,
    /// NaN or infinite t or barycentrics on a reported hit.
    pub nan: u64,
    /// Closest hits that differ from brute force, and any-hit answers that
    /// differ on segments ending beyond every hit or halfway to the first.
    pub disagree: u64,
    /// Boxes above a hit triangle that reject the ray even with `tmax`
    /// past the hit by its rounding bound.
    pub box_misses: u64,
    /// Any-hit answers that differ on segments ending exactly at the
    /// closest hit, and boxes that reject a hit only at its exact rounded
    /// `t`: both within the rounding of that `t`, shown for information.
    pub(crate) at_rounding: u64,
}

impl std::ops::AddAssign for Grazing {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.nan += o.nan;
        self.disagree += o.disagree;
        self.box_misses += o.box_misses;
        self.at_rounding += o.at_rounding;
    }
}

/// Checks every ray against the BVH, brute force and every box above each
/// triangle it hits.
///
/// The triangle test works in f32: a ray within f32 resolution of a
/// triangle's plane can be reported hitting it where, exactly, it crosses
/// the plane outside the triangle, and a hit's `t` carries a rounding error
/// that is large for big triangles seen edge-on. So each hit is also judged
/// exactly (in f64, where the ray meets the plane): it is *real* when that
/// point lies in the triangle's box. The BVH agrees when it returns brute
/// force's `t`; or when brute force's closer hit is not real, or lies,
/// exactly, beyond the `t` the BVH returned (its boxes then culled it by the
/// true geometry, while the triangle test's rounding put it first). A box
/// misses a hit when it rejects a real hit at `tmax` = its exact distance;
/// rejections at the rounded `t` only are counted apart.
pub fn check_rays(b: &Bvh, anc: &[Vec<u32>], rays: &[Ray]) -> Grazing {
    let mut leaf_of = vec![0; b.prim.len()];
    for (i, &p) in b.prim.iter().enumerate() {
        leaf_of[p as usize] = i;
    }
    rays.par_iter()
        .map(|ray| {
            let mut g = Grazing {
                rays: 1,
                ..Grazing::default()
            };
            let mut st = TraversalStats::default();
            let fast = b.intersect::<false>(ray, &mut st);
            let slow = b.intersect_brute(ray);
            let bad = |h: &Option<crate::bvh::Hit>| {
                h.is_some_and(|h| !(h.t.is_finite() && h.u.is_finite() && h.v.is_finite()))
            };
            g.nan += bad(&fast) as u64 + bad(&slow) as u64;
            let shear = RayShear::new(ray.origin, ray.dir);
            let inv = ray.inv_dir().into();
            let mut any_real = false;
            for (i, above) in (0..b.triangle_count()).zip(anc) {
                let t = &b.triangle(i);
                let Some(h) = intersect(&shear, &t[0], &t[1], &t[2], ray.tmax) else {
                    continue;
                };
                if !(h.t.is_finite() && h.u.is_finite() && h.v.is_finite()) {
                    g.nan += 1;
                    continue;
                }
                let (exact, real) = judge(t, ray, h.t);
                any_real |= real;
                let slack = (exact.max(h.t as f64) * (1.0 + 1e-6)) as f32;
                for &n in above {
                    let bx = b.nodes[n as usize].bounds();
                    if real && bx.hit(ray.origin, inv, slack).is_none() {
                        g.box_misses += 1;
                    } else if bx.hit(ray.origin, inv, h.t).is_none() {
                        g.at_rounding += 1;
                    }
                }
            }
            let judged =
                |h: &crate::bvh::Hit| judge(&b.triangle(leaf_of[h.prim as usize]), ray, h.t);
            let same = match (&fast, &slow) {
                (None, None) => true,
                (Some(f), Some(s)) if f.t == s.t => true,
                (Some(f), Some(s)) => {
                    let (x, real) = judged(s);
                    !real || x >= f.t as f64 * (1.0 - 1e-6)
                }
                (None, Some(s)) => !judged(s).1,
                (Some(_), None) => false,
            };
            g.disagree += !same as u64;
            let any = |tmax: f32| {
                let seg = Ray::segment(ray.origin, ray.dir, tmax);
                let mut st = TraversalStats::default();
                b.occluded::<false>(&seg, &mut st).is_some() != b.occluded_brute(&seg).is_some()
            };
            if any_real {
                g.disagree += any(1e4) as u64;
            }
            if let Some(h) = slow {
                g.disagree += any(h.t * 0.5) as u64;
                g.at_rounding += any(h.t) as u64;
            }
            g
        })
        .reduce(Grazing::default, |mut a, b| {
            a += b;
            a
        })
}

/// A hit at `t` on triangle `tri`, judged exactly: the distance at which the
/// ray meets the triangle's plane (computed in f64 from the exact inputs;
/// `t` itself when the ray runs in the plane), and whether that point lies in
/// the triangle's box.
fn judge(tri: &[[f32; 3]; 3], ray: &Ray, t: f32) -> (f64, bool) {
    let [a, b, c] = tri.map(|v| Vec3::from(v).as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let n = (b - a).cross(c - a);
    if n == DVec3::ZERO {
        return judge_segment([a, b, c], o, d);
    }
    let x = n.dot(a - o) / n.dot(d);
    if !x.is_finite() {
        return (t as f64, true);
    }
    let p = o + d * x;
    // The f64 rounding of p: of the sum, and of x, which grows as the ray
    // grazes the plane (1 / cos).
    let graze = n.length() * d.length() / n.dot(d).abs();
    let tol = (o.abs() + (d * x).abs()) * 1e-12 + d.abs() * (x.abs() * graze * 1e-14);
    let (lo, hi) = (a.min(b).min(c), a.max(b).max(c));
    (
        x,
        x > 0.0 && p.cmpge(lo - tol).all() && p.cmple(hi + tol).all(),
    )
}

/// [`judge`] for a triangle with no area (its corners on a line, or one
/// point): the ray meets it where it meets the segment between its two
/// farthest corners, judged by the closest approach of the two in f64.
fn judge_segment(v: [DVec3; 3], o: DVec3, d: DVec3) -> (f64, bool) {
    let pairs = [(v[0], v[1]), (v[1], v[2]), (v[2], v[0])];
    let (p, q) = pairs
        .into_iter()
        .max_by(|x, y| {
            (x.1 - x.0)
                .length_squared()
                .total_cmp(&(y.1 - y.0).length_squared())
        })
        .unwrap_or((v[0], v[0]));
    // Closest points of o + x d and p + u (q - p), u in [0, 1].
    let e = q - p;
    let w = o - p;
    let (dd, de, ee) = (d.dot(d), d.dot(e), e.dot(e));
    let (dw, ew) = (d.dot(w), e.dot(w));
    let den = dd * ee - de * de;
    let mut u = if den > 0.0 {
        (dd * ew - de * dw) / den
    } else {
        0.0
    };
    u = u.clamp(0.0, 1.0);
    let x = (e * u - w).dot(d) / dd;
    let gap = (o + d * x - (p + e * u)).length();
    let tol = (o.abs() + (d * x).abs() + p.abs() + q.abs()).max_element() * 1e-12;
    (x, x.is_finite() && x > 0.0 && gap <= tol)
}

/// Rays along the lattice's planes: from lattice points (on the planes) and
/// from points a few units back along the ray's main axis.
fn lattice_rays(n: u32, rng: &mut Rng) -> Vec<Ray> {
    let dirs = grazing_directions();
    let coords = [0.0, 0.5, 1.0, 2.0, 3.0];
    let mut pick = |k: usize| (rng.next_u32() as usize) % k;
    (0..n)
        .map(|i| {
            let d = dirs[pick(dirs.len())];
            let mut o = Vec3::new(coords[pick(5)], coords[pick(5)], coords[pick(5)]);
            if i % 2 == 1 {
                let a = d.abs().max_position();
                o[a] -= 4.0 * d[a].signum();
            }
            Ray::new(o, d)
        })
        .collect()
}

/// Rays in (or a hair off) the planes of the slanted triangles, through
/// their vertices, edges and interiors.
pub(crate) fn plane_rays(tris: &[[Vec3; 3]], n: u32, rng: &mut Rng) -> Vec<Ray> {
    let eps = [0.0, -0.0, 1e-30, -1e-30, 1e-7, -1e-7];
    (0..n)
        .map(|_| {
            let t = tris[rng.next_u32() as usize % tris.len()];
            let nrm = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
            let (a, b) = (rng.next_f32(), rng.next_f32());
            let p = match rng.next_u32() % 3 {
                0 => t[rng.next_u32() as usize % 3],
                1 => t[0].lerp(t[1], a),
                _ => t[0] + (t[1] - t[0]) * a * (1.0 - b) + (t[2] - t[0]) * a * b,
            };
            let along = (t[(rng.next_u32() % 3) as usize] - p + (t[1] - t[2]) * b)
                .normalize_or(nrm.any_orthonormal_vector());
            let in_plane = (along - nrm * nrm.dot(along)).normalize_or(along);
            let d = in_plane + nrm * eps[rng.next_u32() as usize % eps.len()];
            Ray::new(p - d * 2.0, d)
        })
        .collect()
}

/// The grazing rows: NaN results, BVH against brute force, box misses.
pub fn grazing(o: &Options) -> Result<Vec<Row>> {
    let mut rng = Rng::for_sample(0, 3, o.seed);
    let mut tris = lattice();
    let slant = slanted(&mut rng, 24);
    tris.extend_from_slice(&slant);
    let g = Geometry::from_triangles(&tris);
    let mut rays = lattice_rays(o.rays / 2, &mut rng);
    rays.extend(plane_rays(&slant, o.rays / 2, &mut rng));
    let mut total = Grazing::default();
    for builder in [Builder::Sah, Builder::Median] {
        let b = bvh::build(&g, builder);
        total += check_rays(&b, &ancestors(&b), &rays);
    }
    let of = format!(
        "in {} grazing rays x 2 builders over {} triangles",
        total.rays / 2,
        tris.len()
    );
    Ok(vec![
        Row::zero(
            "grazing: NaN results",
            total.nan,
            format!("{} NaN t or barycentrics {of}", total.nan),
        ),
        Row::zero(
            "grazing: BVH vs brute force",
            total.disagree,
            format!(
                "{} closest-hit or any-hit disagreements {of}",
                total.disagree
            ),
        ),
        Row::zero(
            "grazing: box test misses",
            total.box_misses,
            format!(
                "{} boxes missed above a triangle the ray hits {of} ({} more within the \
                 rounding of the hit's t)",
                total.box_misses, total.at_rounding
            ),
        ),
    ])
}
