//! Watertight ray/triangle intersection (Woop, Benthin, Wald, JCGT 2013).
//!
//! The ray is sheared so it points along +z; the edge functions are then
//! evaluated in 2D, which makes a point on a shared edge land on exactly one
//! side for both neighbours: no cracks, no double misses. When an edge
//! function is exactly zero the test is redone in f64, as the paper requires.
//!
//! A hit is kept only when every vertex lies ahead of the origin beyond
//! the rounding of its `z` (then `t`, a mean of the vertices' `z` weighted
//! by edge functions of one sign, is positive however those weights are
//! rounded), or else when its `t` exceeds a conservative bound on the
//! rounding error of `t` (pbrt-v4's `IntersectTriangle`). That bound grows
//! as a triangle turns edge-on to the ray, and alone it rejected true hits
//! of grazing shadow rays on small triangles far from the light (45 of the
//! 101438 shadow rays of a 1M-triangle teapot). The bound is derived term by
//! term in the sheared space of this ray, where `x` and `y` are lengths and
//! the scaled `z` (divided by the direction's largest component) is in units
//! of `t`. A sheared `x = (p.x - o.x) - s_x (p.z - o.z)` is three roundings
//! from exact: its error is at most `γ₂ |p.x - o.x| + γ₃ |s_x z|`, with `z`
//! the translated, unscaled coordinate, and so at most `γ₃ (|x_t| + 2 |s_x
//! z|)` (`γ₅` covers taking the bound from the rounded values). Edge functions (`x y` products, length²) then carry `δe`, the
//! scaled `z` `δz = γ₃ |z_t|`, and `t = Σ e z_t / Σ e` the sum of both.
//! Every term is thus a length, a length² or a `t`, at any scale and for any
//! length of the direction (shadow rays are not normalised): adding the
//! scaled `z` to the lengths instead would make the bound depend on the
//! scene's size and reject true hits in tiny scenes.
//!
//! The f32 test forms products of three coordinates (`t_scaled`, length² ·
//! t): beyond [`F32_REACH`] from the ray's origin they can overflow, and a
//! scene some 1e13 across went black. Rays that can meet such coordinates
//! run the whole test in f64 instead ([`RayShear::wide`]), every triangle
//! alike, so neighbours still agree on their shared edges.

use glam::{Vec3, Vec4};

use super::gamma;

/// While the ray's origin and the triangles' coordinates stay within this
/// magnitude, every product of the f32 test is finite: translated
/// coordinates are below 2^40, sheared ones below 2^41, edge functions
/// (length²) below 2^83 and `t_scaled` (length² · t) below 2^128 for
/// directions at least 1/4 long (camera and reflection rays are unit
/// vectors) and for triangles within a shadow ray's segment (others lie
/// beyond its end and are rejected whatever their `t`).
pub(crate) const F32_REACH: f32 = (1u64 << 39) as f32;

/// Per-ray constants of the shear transform, computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub(crate) origin: [f32; 3],
    pub(crate) kx: usize,
    pub(crate) ky: usize,
    pub(crate) kz: usize,
    pub(crate) sx: f32,
    pub(crate) sy: f32,
    pub(crate) sz: f32,
    /// The reciprocal direction on the axes `kx`, `ky`, `kz` (the last is
    /// `sz`), as [`Ray::inv_dir`](super::Ray::inv_dir) makes it: where the
    /// ray enters a triangle's box ([`box_entry`]).
    pub(crate) inv: [f32; 3],
    /// The ray may meet coordinates beyond [`F32_REACH`] of its origin:
    /// every test of it runs in f64.
    pub(crate) wide: bool,
}

impl RayShear {
    /// For triangles whose coordinates are at most as large as the origin's
    /// (see [`RayShear::within`]).
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self::within(origin, dir, 0.0)
    }

    /// For triangles whose coordinates are at most `reach` in magnitude
    /// (a BVH's bounds). Direction components below
    /// [`PARALLEL`](super::ray::PARALLEL) count as zero, as in the box
    /// test, so the two agree on grazing rays.
    #[inline]
    pub(crate) fn within(origin: Vec3, dir: Vec3, reach: f32) -> Self {
        let dir = super::ray::flush(dir);
        let [kx, ky, kz] = Self::axes(dir);
        let d = dir.to_array();
        // The three quotients in one vector division: a third of the
        // divider's time, the same values.
        let q = (glam::Vec4::from((dir, 1.0)) / glam::Vec4::splat(d[kz])).to_array();
        let inv = (Vec4::ONE / Vec4::from((dir, 1.0))).to_array();
        Self {
            origin: origin.to_array(),
            kx,
            ky,
            kz,
            sx: q[kx],
            sy: q[ky],
            sz: q[3],
            inv: [inv[kx], inv[ky], inv[kz]],
            wide: Self::needs_f64(origin, reach),
        }
    }

    /// The axes `[kx, ky, kz]` a ray along `dir` (flushed) is sheared
    /// onto: `kz` its largest component's, `kx` and `ky` the others in an
    /// order that keeps a triangle's winding.
    #[inline]
    pub(crate) fn axes(dir: Vec3) -> [usize; 3] {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        if dir[kz] < 0.0 {
            [ky, kx, kz]
        } else {
            [kx, ky, kz]
        }
    }

    /// Whether rays from `origin` may meet coordinates beyond
    /// [`F32_REACH`] among triangles at most `reach` in magnitude: the same
    /// for every ray from one origin. NaN (a broken origin or bound) takes
    /// the f64 path too.
    #[inline]
    pub(crate) fn needs_f64(origin: Vec3, reach: f32) -> bool {
        (origin.abs().max_element() + reach)
            .partial_cmp(&F32_REACH)
            .is_none_or(|o| o.is_gt())
    }
}

/// A hit: distance and the barycentric weights of vertices 1 and 2
/// (vertex 0 has `1 - u - v`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Slack of the undivided `t <= tmax` pre-check, a few roundings wide, so it
/// never rejects a `t` the exact check after the division accepts.
const LOOSE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Intersects the ray with triangle `(p0, p1, p2)` for `t` in `(0, tmax]`.
/// Both faces are hit.
#[inline(always)]
pub fn intersect(
    s: &RayShear,
    p0: &[f32; 3],
    p1: &[f32; 3],
    p2: &[f32; 3],
    tmax: f32,
) -> Option<TriHit> {
    if s.wide {
        return intersect_wide(s, [p0, p1, p2], tmax);
    }
    let (kx, ky, kz) = (s.kx, s.ky, s.kz);
    let o = &s.origin;
    let a = [p0[kx] - o[kx], p0[ky] - o[ky], p0[kz] - o[kz]];
    let b = [p1[kx] - o[kx], p1[ky] - o[ky], p1[kz] - o[kz]];
    let c = [p2[kx] - o[kx], p2[ky] - o[ky], p2[kz] - o[kz]];
    let ax = a[0] - s.sx * a[2];
    let ay = a[1] - s.sy * a[2];
    let bx = b[0] - s.sx * b[2];
    let by = b[1] - s.sy * b[2];
    let cx = c[0] - s.sx * c[2];
    let cy = c[1] - s.sy * c[2];
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        [u, v, w] = edges_exact([ax, ay, bx, by, cx, cy]);
    }
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = s.sz * a[2];
    let bz = s.sz * b[2];
    let cz = s.sz * c[2];
    let t_scaled = u * az + v * bz + w * cz;
    // t = t_scaled / det must lie in (0, tmax]; a first check without
    // dividing, loose by a few roundings so it never rejects a t that the
    // exact check below accepts (that made the closest hit depend on the
    // order triangles are tested in).
    let (ts, d) = if det < 0.0 {
        (-t_scaled, -det)
    } else {
        (t_scaled, det)
    };
    if ts <= 0.0 || ts > tmax * LOOSE * d {
        return None;
    }
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    // The conservative bound on the rounding error of t (see the module
    // comment): a hit closer than it may be the ray's own surface, seen
    // through rounding.
    let max_z = a[2].abs().max(b[2].abs()).max(c[2].abs());
    let max_zt = az.abs().max(bz.abs()).max(cz.abs());
    let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
    let max_yt = ay.abs().max(by.abs()).max(cy.abs());
    let delta_z = gamma(3) * max_zt;
    let delta_x = gamma(5) * (max_xt + 2.0 * (s.sx.abs() * max_z));
    let delta_y = gamma(5) * (max_yt + 2.0 * (s.sy.abs() * max_z));
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let delta_t =
        3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv.abs();
    if t <= delta_t && !ahead(az, bz, cz, delta_z) {
        return None;
    }
    let t = at_least(box_entry([a, b, c], s.inv), t);
    if !t.is_finite() || t > tmax {
        return None;
    }
    Some(TriHit {
        t,
        u: (v * inv).clamp(0.0, 1.0),
        v: (w * inv).clamp(0.0, 1.0),
    })
}

/// Where the ray enters the triangle's bounding box, as the box tests of
/// the BVH round it ([`Aabb::hit`](super::Aabb::hit)): the larger of 0 and
/// each axis's distance to the box's near plane, NaN (a parallel ray on
/// that plane) passed over. `v`: the vertices less the ray's origin, on
/// the axes `inv` is given for (`min(p) - o` is `min(p - o)`, rounding
/// being monotone).
///
/// A hit is never nearer than this ([`at_least`]). The triangle test
/// rounds `t` its own way, and on a large triangle far from the origin it
/// came out a few ulps before the ray even entered the box (a hit at
/// 0.99999756 in a flat box entered at 1.0). A BVH walk that already held
/// a hit between the two then skipped every box holding that triangle, so
/// the closest hit depended on the order the walk reached the leaves in:
/// a packet's walk and a single ray's disagreed. A box's entry distance is
/// at most that of any box inside it, so with hits raised to their own
/// box's, a box skipped as lying beyond the closest hit holds no nearer
/// one, whatever the order of the walk or the tree.
#[inline(always)]
fn box_entry(v: [[f32; 3]; 3], inv: [f32; 3]) -> f32 {
    let mut tn = 0.0f32;
    for a in 0..3 {
        let (x, y, z) = (v[0][a], v[1][a], v[2][a]);
        let near = if inv[a] < 0.0 {
            x.max(y).max(z)
        } else {
            x.min(y).min(z)
        };
        let d = near * inv[a];
        if d > tn {
            tn = d;
        }
    }
    tn
}

/// `t`, or `entry` where that is larger; a NaN `t` stays NaN.
#[inline(always)]
fn at_least(entry: f32, t: f32) -> f32 {
    if entry > t {
        entry
    } else {
        t
    }
}

/// Whether every vertex lies ahead of the origin by more than its scaled
/// `z`'s rounding error `delta_z`: then `t`, a weighted mean of the
/// vertices' `z` with weights of one sign, is positive however uncertain the
/// weights are, and no error bound on `t` need be met.
#[inline(always)]
fn ahead(az: f32, bz: f32, cz: f32, delta_z: f32) -> bool {
    az.min(bz).min(cz) > delta_z
}

/// pbrt's γₙ for f64 arithmetic.
const fn gamma64(n: i32) -> f64 {
    let nu = n as f64 * f64::EPSILON * 0.5;
    nu / (1.0 - nu)
}

/// [`intersect`] in f64, for rays that may meet coordinates beyond
/// [`F32_REACH`]: the same steps and the same conservative bound on `t`,
/// with f64's rounding (and one more rounding for the translation, which
/// f64 need not hold exactly). Out of line: such scenes are rare, and the
/// packet tests call it lane by lane.
#[cold]
#[inline(never)]
pub(crate) fn intersect_wide(s: &RayShear, p: [&[f32; 3]; 3], tmax: f32) -> Option<TriHit> {
    let (kx, ky, kz) = (s.kx, s.ky, s.kz);
    let o = s.origin.map(f64::from);
    let [a, b, c] = p.map(|p| {
        [
            p[kx] as f64 - o[kx],
            p[ky] as f64 - o[ky],
            p[kz] as f64 - o[kz],
        ]
    });
    let (sx, sy, sz) = (s.sx as f64, s.sy as f64, s.sz as f64);
    let (ax, ay) = (a[0] - sx * a[2], a[1] - sy * a[2]);
    let (bx, by) = (b[0] - sx * b[2], b[1] - sy * b[2]);
    let (cx, cy) = (c[0] - sx * c[2], c[1] - sy * c[2]);
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let (az, bz, cz) = (sz * a[2], sz * b[2], sz * c[2]);
    let t = (u * az + v * bz + w * cz) / det;
    let max_z = a[2].abs().max(b[2].abs()).max(c[2].abs());
    let max_zt = az.abs().max(bz.abs()).max(cz.abs());
    let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
    let max_yt = ay.abs().max(by.abs()).max(cy.abs());
    let delta_z = gamma64(4) * max_zt;
    let delta_x = gamma64(6) * (max_xt + 2.0 * (sx.abs() * max_z));
    let delta_y = gamma64(6) * (max_yt + 2.0 * (sy.abs() * max_z));
    let delta_e = 2.0 * (gamma64(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    // Far from the origin, rounding can collapse a small triangle's sheared
    // corners onto one line: its edge functions are then rounding alone,
    // and their signs say nothing. A triangle whose area in the ray's view
    // is within their error bound is edge-on to the ray, and missed.
    if det.abs() <= 3.0 * delta_e {
        return None;
    }
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let delta_t =
        3.0 * (gamma64(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) / det.abs();
    let ahead = az.min(bz).min(cz) > delta_z;
    // `t <= tmax` as rounded to f32, as the f32 test checks it: a `t` just
    // past `tmax` in f64 that rounds to it is a tie with the hit that set
    // `tmax`, which the lower triangle index must win whichever was found
    // first.
    if !(t > delta_t || ahead) {
        return None;
    }
    // Raised to the triangle's box as the f32 box tests round it.
    let corners = p.map(|p| [kx, ky, kz].map(|k| p[k] - s.origin[k]));
    let t32 = at_least(box_entry(corners, s.inv), t as f32);
    if t32 > tmax {
        return None;
    }
    (t32 > 0.0 && t32.is_finite()).then(|| TriHit {
        t: t32,
        u: ((v / det) as f32).clamp(0.0, 1.0),
        v: ((w / det) as f32).clamp(0.0, 1.0),
    })
}

/// [`intersect_wide`] on the lanes of a packet `p[vertex][axis][lane]`.
#[cold]
#[inline(never)]
fn wide_lanes<const N: usize>(
    s: &RayShear,
    p: &[[[f32; N]; 3]; 3],
    tmax: f32,
) -> [Option<TriHit>; N] {
    std::array::from_fn(|lane| {
        let v = p.map(|v| v.map(|a| a[lane]));
        intersect_wide(s, [&v[0], &v[1], &v[2]], tmax)
    })
}

/// [`RayShear`] with every constant splatted across four lanes, for
/// [`intersect4`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct RayShear4 {
    pub(crate) k: [usize; 3],
    pub(crate) o: [Vec4; 3],
    pub(crate) s: [Vec4; 3],
    pub(crate) inv: [Vec4; 3],
    /// The ray itself, for [`RayShear::wide`] rays.
    pub(crate) ray: RayShear,
}

impl RayShear4 {
    #[inline(always)]
    pub(crate) fn new(s: &RayShear) -> Self {
        let k = [s.kx, s.ky, s.kz];
        RayShear4 {
            ray: *s,
            k,
            o: [
                Vec4::splat(s.origin[k[0]]),
                Vec4::splat(s.origin[k[1]]),
                Vec4::splat(s.origin[k[2]]),
            ],
            s: [Vec4::splat(s.sx), Vec4::splat(s.sy), Vec4::splat(s.sz)],
            inv: s.inv.map(Vec4::splat),
        }
    }
}

/// Four results of [`intersect4`]: `mask` has bit `i` set when lane `i` hit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TriHit4 {
    pub(crate) mask: u32,
    pub(crate) t: Vec4,
    pub(crate) u: Vec4,
    pub(crate) v: Vec4,
}

/// [`intersect`] on four triangles at once: `p[vertex][axis]` holds one
/// triangle per lane. Every lane computes exactly what the scalar test
/// computes, operation for operation (no fused multiply-adds), so results
/// agree bit for bit, watertightness and the conservative t bound included.
/// Lanes with NaN coordinates (padding) never hit.
#[inline(always)]
pub(crate) fn intersect4(r: &RayShear4, p: &[[Vec4; 3]; 3], tmax: f32) -> TriHit4 {
    if r.ray.wide {
        let h = wide_lanes(&r.ray, &p.map(|v| v.map(|a| a.to_array())), tmax);
        let get = |f: fn(&TriHit) -> f32, none: f32| {
            Vec4::from_array(h.map(|x| x.as_ref().map_or(none, f)))
        };
        return TriHit4 {
            mask: (0..4).filter(|&i| h[i].is_some()).map(|i| 1 << i).sum(),
            t: get(|x| x.t, f32::INFINITY),
            u: get(|x| x.u, 0.0),
            v: get(|x| x.v, 0.0),
        };
    }
    lanes4(r.k, r.o, r.s, r.inv, p, Vec4::splat(tmax))
}

/// [`intersect4`] past its f64 check, every lane with its own ray
/// constants (`o`, `s` and `recip`, [`RayShear4`]'s `inv`, one ray per lane or
/// one in all), its own triangle and its own `tmax`: eight rays against one
/// triangle compute the same as one ray against eight.
#[inline(always)]
pub(crate) fn lanes4(
    [kx, ky, kz]: [usize; 3],
    [ox, oy, oz]: [Vec4; 3],
    [sx, sy, sz]: [Vec4; 3],
    recip: [Vec4; 3],
    p: &[[Vec4; 3]; 3],
    tmax: Vec4,
) -> TriHit4 {
    let (az, bz, cz) = (p[0][kz] - oz, p[1][kz] - oz, p[2][kz] - oz);
    let ax = (p[0][kx] - ox) - sx * az;
    let ay = (p[0][ky] - oy) - sy * az;
    let bx = (p[1][kx] - ox) - sx * bz;
    let by = (p[1][ky] - oy) - sy * bz;
    let cx = (p[2][kx] - ox) - sx * cz;
    let cy = (p[2][ky] - oy) - sy * cz;
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut w = bx * ay - by * ax;
    let zero = Vec4::ZERO;
    let on_edge = (u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero)).bitmask();
    if on_edge != 0 {
        for i in (0..4).filter(|i| on_edge & (1 << i) != 0) {
            [u[i], v[i], w[i]] = edges_exact([ax[i], ay[i], bx[i], by[i], cx[i], cy[i]]);
        }
    }
    let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
    let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
    let none = TriHit4 {
        mask: 0,
        t: Vec4::INFINITY,
        u: zero,
        v: zero,
    };
    // Every lane outside an edge: coherent rays mostly miss a triangle
    // all together. (The AVX test takes this branch only for them.)
    if (neg & pos).bitmask() == 0xf {
        return none;
    }
    let det = u + v + w;
    let (az0, bz0, cz0) = (az, bz, cz);
    let (az, bz, cz) = (sz * az, sz * bz, sz * cz);
    let t_scaled = u * az + v * bz + w * cz;
    let flip = det.cmplt(zero);
    let ts = Vec4::select(flip, -t_scaled, t_scaled);
    let d = Vec4::select(flip, -det, det);
    // `d > 0`: a determinant neither zero nor NaN. Padding lanes (NaN)
    // fail here, so that a packet with no hit ends here, padding or not.
    let mut ok = !(neg & pos) & d.cmpgt(zero) & !ts.cmple(zero) & !ts.cmpgt(tmax * LOOSE * d);
    if ok.bitmask() == 0 {
        return none;
    }
    let inv = Vec4::ONE / det;
    let t = t_scaled * inv;
    let max_zt = az.abs().max(bz.abs()).max(cz.abs());
    let g = |n| Vec4::splat(gamma(n));
    let delta_z = g(3) * max_zt;
    let ahead = az.min(bz).min(cz).cmpgt(delta_z);
    // A lane whose vertices all lie ahead of the origin beyond the rounding
    // of their `z` is never too near to tell: the bound on `t`'s rounding
    // is needed only where some passing lane is not (a ray leaving a
    // surface through its own triangle), so most hits skip it.
    if (ok & !ahead).any() {
        let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
        let max_yt = ay.abs().max(by.abs()).max(cy.abs());
        let max_z = az0.abs().max(bz0.abs()).max(cz0.abs());
        let delta_x = g(5) * (max_xt + 2.0 * (sx.abs() * max_z));
        let delta_y = g(5) * (max_yt + 2.0 * (sy.abs() * max_z));
        let delta_e = 2.0 * (g(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
        let max_e = u.abs().max(v.abs()).max(w.abs());
        let delta_t =
            3.0 * (g(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv.abs();
        ok &= !t.cmple(delta_t) | ahead;
    }
    // Raised to the triangle's box ([`box_entry`]), lane by lane alike.
    let mut entry = zero;
    for (a, inv) in recip.into_iter().enumerate() {
        let [x, y, z] = [0, 1, 2].map(|v| p[v][[kx, ky, kz][a]] - [ox, oy, oz][a]);
        let near = Vec4::select(inv.cmplt(zero), x.max(y).max(z), x.min(y).min(z));
        let d = near * inv;
        entry = Vec4::select(d.cmpgt(entry), d, entry);
    }
    let t = Vec4::select(entry.cmpgt(t), entry, t);
    ok &= t.abs().cmplt(Vec4::INFINITY) & !t.cmpgt(tmax);
    TriHit4 {
        mask: ok.bitmask(),
        t: Vec4::select(ok, t, Vec4::INFINITY),
        u: (v * inv).clamp(zero, Vec4::ONE),
        v: (w * inv).clamp(zero, Vec4::ONE),
    }
}

/// Eight results of [`intersect8`]: bit `i` of `mask` set when lane `i`
/// hit; `t` is infinite in the other lanes; `u` and `v` are filled only
/// when asked for (any-hit traversal needs none).
#[derive(Clone, Copy, Debug)]
pub struct TriHit8 {
    pub(crate) mask: u32,
    pub(crate) t: [f32; 8],
    pub(crate) u: [f32; 8],
    pub(crate) v: [f32; 8],
}

impl TriHit8 {
    /// No lane hit.
    pub(crate) const NONE: TriHit8 = TriHit8 {
        mask: 0,
        t: [f32::INFINITY; 8],
        u: [0.0; 8],
        v: [0.0; 8],
    };

    /// The lanes that hit, lowest first. One step per hit rather than a
    /// test of all eight lanes: the eight tests' outcomes change from
    /// packet to packet, and the closest-hit walk mispredicted about two of
    /// them per ray that hits, as simulated (BENCHMARKS.md).
    #[inline(always)]
    pub(crate) fn lanes(&self) -> impl Iterator<Item = usize> {
        let mut m = self.mask;
        std::iter::from_fn(move || {
            (m != 0).then(|| {
                let lane = m.trailing_zeros() as usize;
                m &= m - 1;
                lane
            })
        })
    }
}

/// [`intersect`] on eight triangles, `p[vertex][axis][lane]`, as two runs of
/// [`intersect4`]; barycentrics only with `UV`.
#[inline(always)]
pub fn intersect8<const UV: bool>(s: &RayShear, p: &[[[f32; 8]; 3]; 3], tmax: f32) -> TriHit8 {
    let s4 = RayShear4::new(s);
    let mut h = TriHit8::NONE;
    for half in 0..2 {
        let lanes = 4 * half..4 * half + 4;
        let q = p.map(|v| v.map(|a| Vec4::from_slice(&a[lanes.clone()])));
        let r = intersect4(&s4, &q, tmax);
        h.mask |= r.mask << (4 * half);
        r.t.write_to_slice(&mut h.t[lanes.clone()]);
        if UV {
            r.u.write_to_slice(&mut h.u[lanes.clone()]);
            r.v.write_to_slice(&mut h.v[lanes]);
        }
    }
    h
}

/// The edge functions of the lanes in `lanes` redone in f64 from the sheared
/// vertices `[ax, ay, bx, by, cx, cy]`; the others kept. Rare, so kept out
/// of line where it does not stop the packet test from being inlined.
#[cold]
#[inline(never)]
fn edges_f64(lanes: i32, p: [[f32; 8]; 6], mut e: [[f32; 8]; 3]) -> [[f32; 8]; 3] {
    for i in (0..8).filter(|i| lanes & (1 << i) != 0) {
        [e[0][i], e[1][i], e[2][i]] = edges_exact(p.map(|c| c[i]));
    }
    e
}

/// The edge functions `u`, `v`, `w` of the sheared vertices `[ax, ay, bx,
/// by, cx, cy]` in f64, where products of f32 are exact and so is each
/// sign, rounded to f32 keeping that sign: a value too small for f32 becomes
/// its smallest subnormal rather than a zero, which would read as "on the
/// edge". (A ray passing 3e-11 above a vertex of a triangle lying in the
/// ray's plane had two edge functions round to zero, and hit the vertex.)
#[inline]
fn edges_exact(p: [f32; 6]) -> [f32; 3] {
    let [ax, ay, bx, by, cx, cy] = p.map(f64::from);
    [cx * by - cy * bx, ax * cy - ay * cx, bx * ay - by * ax].map(|e| {
        let f = e as f32;
        if f == 0.0 && e != 0.0 {
            f32::from_bits(1).copysign(f)
        } else {
            f
        }
    })
}

/// [`intersect8`] with AVX: all eight lanes per instruction, computing
/// exactly what [`intersect4`] computes, operation for operation.
///
/// Not a `#[target_feature]` function, which could not be forced inline:
/// traversal calls it from its AVX build, where it is inlined and every
/// intrinsic compiles to one instruction.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) unsafe fn intersect8_avx<const UV: bool>(
    s: &RayShear,
    p: &[[[f32; 8]; 3]; 3],
    tmax: f32,
) -> TriHit8 {
    use std::arch::x86_64::*;
    if s.wide {
        let h = wide_lanes(s, p, tmax);
        let mut out = TriHit8::NONE;
        for (lane, hit) in h.iter().enumerate() {
            if let Some(hit) = hit {
                out.mask |= 1 << lane;
                out.t[lane] = hit.t;
                if UV {
                    out.u[lane] = hit.u;
                    out.v[lane] = hit.v;
                }
            }
        }
        return out;
    }
    // Macros, not closures: a closure here would be compiled on its own,
    // without AVX, and called.
    macro_rules! ld {
        ($v:expr) => {
            [
                _mm256_loadu_ps(p[$v][s.kx].as_ptr()),
                _mm256_loadu_ps(p[$v][s.ky].as_ptr()),
                _mm256_loadu_ps(p[$v][s.kz].as_ptr()),
            ]
        };
    }
    let set = _mm256_set1_ps;
    let (kx, ky, kz) = (s.kx, s.ky, s.kz);
    lanes8_avx::<UV, false>(
        [ld!(0), ld!(1), ld!(2)],
        [set(s.origin[kx]), set(s.origin[ky]), set(s.origin[kz])],
        [set(s.sx), set(s.sy), set(s.sz)],
        [set(s.inv[0]), set(s.inv[1]), set(s.inv[2])],
        set(tmax),
    )
}

/// [`intersect8_avx`] past its f64 check, every lane with its own ray
/// constants, triangle and `tmax`, as [`lanes4`]. The vertices come as
/// `p[vertex]` = its coordinates on the ray's axes `kx`, `ky`, `kz`, and
/// the origin's likewise. With `EARLY`, the test stops as soon as every
/// lane is outside an edge, which pays for eight coherent rays against one
/// triangle; one ray against eight triangles takes that branch seldom
/// enough that the single-ray walks measured no faster with it.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) unsafe fn lanes8_avx<const UV: bool, const EARLY: bool>(
    p: [[std::arch::x86_64::__m256; 3]; 3],
    [ox, oy, oz]: [std::arch::x86_64::__m256; 3],
    [sx, sy, sz]: [std::arch::x86_64::__m256; 3],
    recip: [std::arch::x86_64::__m256; 3],
    tmax: std::arch::x86_64::__m256,
) -> TriHit8 {
    use std::arch::x86_64::*;
    macro_rules! st {
        ($x:expr) => {{
            let mut a = [0.0f32; 8];
            _mm256_storeu_ps(a.as_mut_ptr(), $x);
            a
        }};
    }
    macro_rules! cmp {
        ($op:ident, $a:expr, $b:expr) => {
            _mm256_cmp_ps::<$op>($a, $b)
        };
    }
    let set = _mm256_set1_ps;
    let (sub, mul, add) = (_mm256_sub_ps, _mm256_mul_ps, _mm256_add_ps);
    let (or, and, max) = (_mm256_or_ps, _mm256_and_ps, _mm256_max_ps);
    let (az, bz, cz) = (sub(p[0][2], oz), sub(p[1][2], oz), sub(p[2][2], oz));
    let ax = sub(sub(p[0][0], ox), mul(sx, az));
    let ay = sub(sub(p[0][1], oy), mul(sy, az));
    let bx = sub(sub(p[1][0], ox), mul(sx, bz));
    let by = sub(sub(p[1][1], oy), mul(sy, bz));
    let cx = sub(sub(p[2][0], ox), mul(sx, cz));
    let cy = sub(sub(p[2][1], oy), mul(sy, cz));
    let mut u = sub(mul(cx, by), mul(cy, bx));
    let mut v = sub(mul(ax, cy), mul(ay, cx));
    let mut w = sub(mul(bx, ay), mul(by, ax));
    let zero = _mm256_setzero_ps();
    let sign = set(-0.0);
    let on_edge = _mm256_movemask_ps(or(
        or(cmp!(_CMP_EQ_OQ, u, zero), cmp!(_CMP_EQ_OQ, v, zero)),
        cmp!(_CMP_EQ_OQ, w, zero),
    ));
    if on_edge != 0 {
        let e = edges_f64(
            on_edge,
            [st!(ax), st!(ay), st!(bx), st!(by), st!(cx), st!(cy)],
            [st!(u), st!(v), st!(w)],
        );
        u = _mm256_loadu_ps(e[0].as_ptr());
        v = _mm256_loadu_ps(e[1].as_ptr());
        w = _mm256_loadu_ps(e[2].as_ptr());
    }
    let neg = or(
        or(cmp!(_CMP_LT_OQ, u, zero), cmp!(_CMP_LT_OQ, v, zero)),
        cmp!(_CMP_LT_OQ, w, zero),
    );
    let pos = or(
        or(cmp!(_CMP_GT_OQ, u, zero), cmp!(_CMP_GT_OQ, v, zero)),
        cmp!(_CMP_GT_OQ, w, zero),
    );
    // As in `lanes4`: every lane outside an edge.
    if EARLY && _mm256_movemask_ps(and(neg, pos)) == 0xff {
        return TriHit8::NONE;
    }
    let det = add(add(u, v), w);
    let (az0, bz0, cz0) = (az, bz, cz);
    let (az, bz, cz) = (mul(sz, az), mul(sz, bz), mul(sz, cz));
    let t_scaled = add(add(mul(u, az), mul(v, bz)), mul(w, cz));
    let flip = cmp!(_CMP_LT_OQ, det, zero);
    let ts = _mm256_blendv_ps(t_scaled, _mm256_xor_ps(t_scaled, sign), flip);
    let d = _mm256_blendv_ps(det, _mm256_xor_ps(det, sign), flip);
    // `!(a <= b)` and `!(a > b)` as in the scalar test, NaN included.
    let le0 = cmp!(_CMP_LE_OQ, ts, zero);
    let beyond = cmp!(_CMP_GT_OQ, ts, mul(mul(tmax, set(LOOSE)), d));
    let ok = _mm256_andnot_ps(
        or(and(neg, pos), or(le0, beyond)),
        // Neither zero nor NaN: padding lanes fail here, as in `lanes4`.
        cmp!(_CMP_NEQ_OQ, det, zero),
    );
    if _mm256_movemask_ps(ok) == 0 {
        return TriHit8::NONE;
    }
    let inv = _mm256_div_ps(set(1.0), det);
    let t = mul(t_scaled, inv);
    let (aaz, abz, acz) = (
        _mm256_andnot_ps(sign, az),
        _mm256_andnot_ps(sign, bz),
        _mm256_andnot_ps(sign, cz),
    );
    let max_zt = max(max(aaz, abz), acz);
    let delta_z = mul(set(gamma(3)), max_zt);
    let ahead = cmp!(
        _CMP_GT_OQ,
        _mm256_min_ps(_mm256_min_ps(az, bz), cz),
        delta_z
    );
    // A lane whose vertices all lie ahead of the origin beyond the rounding
    // of their `z` is never too near to tell: the bound on `t`'s rounding
    // is needed only where some passing lane is not (a ray leaving a
    // surface through its own triangle), so most hits skip it.
    let near = if _mm256_movemask_ps(_mm256_andnot_ps(ahead, ok)) == 0 {
        zero
    } else {
        let (au, av, aw) = (
            _mm256_andnot_ps(sign, u),
            _mm256_andnot_ps(sign, v),
            _mm256_andnot_ps(sign, w),
        );
        let (aax, abx, acx) = (
            _mm256_andnot_ps(sign, ax),
            _mm256_andnot_ps(sign, bx),
            _mm256_andnot_ps(sign, cx),
        );
        let (aay, aby, acy) = (
            _mm256_andnot_ps(sign, ay),
            _mm256_andnot_ps(sign, by),
            _mm256_andnot_ps(sign, cy),
        );
        let max_xt = max(max(aax, abx), acx);
        let max_yt = max(max(aay, aby), acy);
        let (g2, g3, g5) = (set(gamma(2)), set(gamma(3)), set(gamma(5)));
        let max_z = max(
            max(_mm256_andnot_ps(sign, az0), _mm256_andnot_ps(sign, bz0)),
            _mm256_andnot_ps(sign, cz0),
        );
        let two = set(2.0);
        let shear_x = mul(two, mul(_mm256_andnot_ps(sign, sx), max_z));
        let shear_y = mul(two, mul(_mm256_andnot_ps(sign, sy), max_z));
        let delta_x = mul(g5, add(max_xt, shear_x));
        let delta_y = mul(g5, add(max_yt, shear_y));
        let delta_e = mul(
            set(2.0),
            add(
                add(mul(mul(g2, max_xt), max_yt), mul(delta_y, max_xt)),
                mul(delta_x, max_yt),
            ),
        );
        let max_e = max(max(au, av), aw);
        let delta_t = mul(
            mul(
                set(3.0),
                add(
                    add(mul(mul(g3, max_e), max_zt), mul(delta_e, max_zt)),
                    mul(delta_z, max_e),
                ),
            ),
            _mm256_andnot_ps(sign, inv),
        );
        _mm256_andnot_ps(ahead, cmp!(_CMP_LE_OQ, t, delta_t))
    };
    // Raised to the triangle's box ([`box_entry`]), as in `lanes4`.
    let mut entry = zero;
    for (a, o) in [ox, oy, oz].into_iter().enumerate() {
        let [x, y, z] = [sub(p[0][a], o), sub(p[1][a], o), sub(p[2][a], o)];
        let far = cmp!(_CMP_LT_OQ, recip[a], zero);
        let near = _mm256_blendv_ps(
            _mm256_min_ps(_mm256_min_ps(x, y), z),
            max(max(x, y), z),
            far,
        );
        // `max_ps` keeps its second operand where the first is NaN.
        entry = max(mul(near, recip[a]), entry);
    }
    let t = max(entry, t);
    let finite = and(
        cmp!(_CMP_LT_OQ, _mm256_andnot_ps(sign, t), set(f32::INFINITY)),
        cmp!(_CMP_LE_OQ, t, tmax),
    );
    let ok = and(_mm256_andnot_ps(near, ok), finite);
    let (u, v) = if UV {
        let one = set(1.0);
        (
            st!(_mm256_min_ps(_mm256_max_ps(mul(v, inv), zero), one)),
            st!(_mm256_min_ps(_mm256_max_ps(mul(w, inv), zero), one)),
        )
    } else {
        ([0.0; 8], [0.0; 8])
    };
    TriHit8 {
        mask: _mm256_movemask_ps(ok) as u32,
        t: st!(_mm256_blendv_ps(set(f32::INFINITY), t, ok)),
        u,
        v,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(o: Vec3, d: Vec3, tri: [[f32; 3]; 3]) -> Option<TriHit> {
        intersect(
            &RayShear::new(o, d),
            &tri[0],
            &tri[1],
            &tri[2],
            f32::INFINITY,
        )
    }

    const TRI: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

    /// A ray from 3.6e16 away passes a triangle some 9 across by 1.3e16;
    /// in its sheared view the triangle's corners round onto one line, and
    /// the edge functions' signs, rounding alone, said it hit.
    #[test]
    fn a_triangle_collapsed_by_rounding_is_not_hit() {
        let o = Vec3::new(3.5845402e16, -0.2, 2.5853504e16);
        let d = Vec3::new(-7.1690804e16, 0.2, -2.5853504e16);
        let tri = [
            [-8.433532, -0.0, -1.6558007],
            [-0.0, -0.0, 0.0],
            [-4.155766, -0.0, -0.8159239],
        ];
        let s = RayShear::new(o, d);
        assert!(s.wide);
        assert_eq!(
            intersect(&s, &tri[0], &tri[1], &tri[2], f32::INFINITY),
            None
        );
        // A triangle 2e15 across where the ray crosses x = 0 is hit there.
        let big = [
            [0.0, -1e15, 1.19e16],
            [0.0, 1e15, 1.19e16],
            [0.0, 0.0, 1.39e16],
        ];
        let h = intersect(&s, &big[0], &big[1], &big[2], f32::INFINITY).unwrap();
        assert!((h.t - 0.5).abs() < 1e-6, "{h:?}");
    }

    #[test]
    fn hits_interior_with_barycentrics() {
        let h = hit(Vec3::new(0.25, 0.5, 1.0), Vec3::NEG_Z, TRI).unwrap();
        assert_eq!(h.t, 1.0);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6);
        // Back face too.
        assert!(hit(Vec3::new(0.25, 0.5, -1.0), Vec3::Z, TRI).is_some());
    }

    #[test]
    fn misses_outside_and_behind() {
        assert!(hit(Vec3::new(0.6, 0.6, 1.0), Vec3::NEG_Z, TRI).is_none());
        assert!(hit(Vec3::new(0.25, 0.25, 1.0), Vec3::Z, TRI).is_none());
        assert!(hit(Vec3::new(-0.1, 0.5, 1.0), Vec3::NEG_Z, TRI).is_none());
    }

    /// A ray 3.3e-11 above a vertex of a triangle that lies (to within
    /// 1e-38) in a plane holding the ray: two of its edge functions are
    /// below f32's range, and rounded to zero they put the ray on the
    /// vertex. Every kernel misses it, as the ray does.
    #[test]
    fn edge_functions_below_f32_keep_their_sign() {
        let t = [
            [0.0, 0.0, 0.0],
            [8.101901, 1.0, 0.0],
            [2.9311085, 0.36178035, 1e-38],
        ];
        let (o, d) = (
            Vec3::new(-4.4815583, 1.0, 0.0),
            Vec3::new(99225.93, 2.6193533e-7, 0.0),
        );
        let s = RayShear::new(o, d);
        assert_eq!(intersect(&s, &t[0], &t[1], &t[2], f32::INFINITY), None);
        check_lanes(o, d, &[t; 4], 0, f32::INFINITY);
        // Below the vertex, it is a hit.
        let up = Vec3::new(d.x, -d.y, 0.0);
        assert!(intersect(&RayShear::new(o, up), &t[0], &t[1], &t[2], f32::INFINITY).is_some());
        check_lanes(o, up, &[t; 4], 0, f32::INFINITY);
    }

    /// No hit is nearer than where its ray enters the triangle's box as
    /// the box test rounds it, on axis-aligned triangles (whose box is
    /// flat) and far, large ones, in every kernel.
    #[test]
    fn hits_lie_no_nearer_than_the_triangles_box() {
        let mut r = crate::geometry::sampling::Rng::for_sample(9, 2, 5);
        let mut f = || r.next_f32() * 2.0 - 1.0;
        let mut raised = 0;
        for k in 0..4000 {
            let scale = if k % 2 == 0 { 1.0 } else { 4e5 };
            let mut t =
                [[f(), f(), f()], [f(), f(), f()], [f(), f(), f()]].map(|v| v.map(|x| x * scale));
            if k % 3 == 0 {
                // Flat on an axis: the box has no depth there.
                let (a, x) = (k % 3, f() * scale);
                t.iter_mut().for_each(|v| v[a] = x);
            }
            let o = Vec3::new(f(), f(), f()) * scale * 3.0;
            let target = (Vec3::from(t[0]) + Vec3::from(t[1]) + Vec3::from(t[2])) / 3.0;
            let d = target - o + Vec3::new(f(), f(), f()) * scale * 0.1;
            let s = RayShear::new(o, d);
            let Some(h) = intersect(&s, &t[0], &t[1], &t[2], f32::INFINITY) else {
                continue;
            };
            let bx = super::super::Aabb {
                min: Vec3::from(t[0]).min(t[1].into()).min(t[2].into()),
                max: Vec3::from(t[0]).max(t[1].into()).max(t[2].into()),
            };
            let inv = super::super::Ray::new(o, d).inv_dir().into();
            let entry = bx
                .hit(o, inv, f32::INFINITY)
                .expect("the box holds the hit");
            assert!(
                h.t >= entry,
                "{h:?} before the box at {entry}: {t:?} from {o} along {d}"
            );
            raised += (h.t == entry) as u32;
            check_lanes(o, d, &[t; 4], 0, f32::INFINITY);
        }
        assert!(raised > 0, "no hit was at its box's entry");
    }

    #[test]
    fn tmax_is_respected() {
        let s = RayShear::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
        assert!(intersect(&s, &TRI[0], &TRI[1], &TRI[2], 0.999).is_none());
        assert!(intersect(&s, &TRI[0], &TRI[1], &TRI[2], 1.0).is_some());
    }

    #[test]
    fn shared_edge_and_vertex_hit_exactly_once_or_twice_never_zero() {
        // Two triangles sharing the diagonal of the unit square, and a fan of
        // six triangles around a shared vertex.
        let t1 = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
        let t2 = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        for i in 0..=1000 {
            let x = i as f32 / 1000.0;
            for d in [
                Vec3::new(0.013, -0.007, -1.0),
                Vec3::NEG_Z,
                Vec3::new(-0.3, 0.1, -1.0),
            ] {
                // Passes through (x, x, 0) on the shared diagonal, up to rounding.
                let o = Vec3::new(x, x, 0.0) - d;
                let n = hit(o, d, t1).is_some() as u32 + hit(o, d, t2).is_some() as u32;
                if x > 0.0 && x < 1.0 {
                    assert!(n >= 1, "crack at x = {x}, d = {d}");
                }
            }
        }
        let c = [0.3f32, 0.7, 0.0];
        let fan: Vec<[[f32; 3]; 3]> = (0..6)
            .map(|k| {
                let a0 = k as f32 * std::f32::consts::TAU / 6.0;
                let a1 = (k + 1) as f32 * std::f32::consts::TAU / 6.0;
                [
                    c,
                    [c[0] + a0.cos(), c[1] + a0.sin(), 0.0],
                    [c[0] + a1.cos(), c[1] + a1.sin(), 0.0],
                ]
            })
            .collect();
        for d in [
            Vec3::NEG_Z,
            Vec3::new(0.3, -0.2, -1.0),
            Vec3::new(-1e-3, 1e-3, -1.0),
        ] {
            let o = Vec3::from(c) - d;
            let n = fan.iter().filter(|t| hit(o, d, **t).is_some()).count();
            assert!(n >= 1, "ray through shared vertex missed all six triangles");
        }
    }

    #[test]
    fn hits_never_lie_beyond_tmax_and_do_not_depend_on_order() {
        // Two triangles crossing the ray one ulp of t apart (from a property
        // test): each must be accepted exactly when its t is within tmax.
        let o = Vec3::new(1894893.9, 1.7716894, -0.9);
        let d = Vec3::new(-1894893.9, -2.7575336, 1.4);
        let a = [
            [0.0, 0.0, 873712.44],
            [0.0, -0.16328001, 0.0],
            [0.0, -407915.78, 0.0],
        ];
        let b = [
            [947446.8, 5.173792e-7, -0.0],
            [-0.0, -0.0, 0.0],
            [0.0, -1.9716884, 1.0],
        ];
        let s = RayShear::new(o, d);
        let ta = intersect(&s, &a[0], &a[1], &a[2], f32::INFINITY).unwrap().t;
        let tb = intersect(&s, &b[0], &b[1], &b[2], f32::INFINITY).unwrap().t;
        assert!(tb < ta, "{tb} {ta}");
        assert!(intersect(&s, &a[0], &a[1], &a[2], tb).is_none());
        assert_eq!(
            intersect(&s, &b[0], &b[1], &b[2], ta).map(|h| h.t),
            Some(tb)
        );
    }

    #[test]
    fn degenerate_triangle_never_hits_or_nans() {
        let line = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 2.0, 0.0]];
        let point = [[0.5, 0.5, 0.0]; 3];
        for d in [
            Vec3::NEG_Z,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1e-30, 0.0, -1.0),
        ] {
            let o = Vec3::new(0.5, 0.5, 1.0);
            assert!(hit(o, d, line).is_none());
            assert!(hit(o, d, point).is_none());
        }
    }

    /// Lane `i` of `intersect4` against the scalar test on the same triangle.
    fn check_lanes(o: Vec3, d: Vec3, tris: &[[[f32; 3]; 3]; 4], pad: usize, tmax: f32) {
        check_lanes_with(RayShear::new(o, d), o, d, tris, pad, tmax);
        // The same in f64, as for rays that may meet huge coordinates.
        check_lanes_with(RayShear::within(o, d, f32::MAX), o, d, tris, pad, tmax);
    }

    fn check_lanes_with(
        s: RayShear,
        o: Vec3,
        d: Vec3,
        tris: &[[[f32; 3]; 3]; 4],
        pad: usize,
        tmax: f32,
    ) {
        let mut p = [[[f32::NAN; 4]; 3]; 3];
        for (lane, t) in tris.iter().enumerate().take(4 - pad) {
            for v in 0..3 {
                for a in 0..3 {
                    p[v][a][lane] = t[v][a];
                }
            }
        }
        let h = intersect4(
            &RayShear4::new(&s),
            &p.map(|v| v.map(Vec4::from_array)),
            tmax,
        );
        for (lane, t) in tris.iter().enumerate() {
            let want = (lane < 4 - pad)
                .then(|| intersect(&s, &t[0], &t[1], &t[2], tmax))
                .flatten();
            let got = (h.mask & (1 << lane) != 0).then(|| TriHit {
                t: h.t.to_array()[lane],
                u: h.u.to_array()[lane],
                v: h.v.to_array()[lane],
            });
            assert_eq!(got, want, "lane {lane}, ray {o} {d}, triangle {t:?}");
        }
        // Eight lanes: these four, then the same in reverse order.
        let mut p8 = [[[f32::NAN; 8]; 3]; 3];
        for v in 0..3 {
            for a in 0..3 {
                for lane in 0..4 {
                    p8[v][a][lane] = p[v][a][lane];
                    p8[v][a][7 - lane] = p[v][a][lane];
                }
            }
        }
        let mut results = vec![intersect8::<true>(&s, &p8, tmax)];
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx") {
            // SAFETY: AVX is present.
            results.push(unsafe { intersect8_avx::<true>(&s, &p8, tmax) });
        }
        for h8 in results {
            for lane in 0..8 {
                let k = if lane < 4 { lane } else { 7 - lane };
                let want = (h.mask & (1 << k) != 0)
                    .then(|| (h.t.to_array()[k], h.u.to_array()[k], h.v.to_array()[k]));
                let got =
                    (h8.mask & (1 << lane) != 0).then(|| (h8.t[lane], h8.u[lane], h8.v[lane]));
                assert_eq!(got, want, "eight lanes: lane {lane}, ray {o} {d}");
            }
        }
    }

    /// The shear's and the slab test's quotients, each set made in one
    /// vector division, are the scalar divisions' bit for bit, on every
    /// sign, on magnitudes from subnormal to huge, and on zero components.
    #[test]
    fn vector_divisions_give_the_scalar_quotients() {
        let mut r = crate::geometry::sampling::Rng::for_sample(2, 7, 1);
        let mut f = || {
            let m = [0.0, 1e-38, 1e-30, 1.0, 3e7, 1e30][(r.next_u32() % 6) as usize];
            (r.next_f32() * 2.0 - 1.0) * m
        };
        let same = |a: f32, b: f32| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        for _ in 0..100_000 {
            let dir = Vec3::new(f(), f(), f());
            let s = RayShear::new(Vec3::ZERO, dir);
            let d = crate::geometry::ray::flush(dir).to_array();
            let want = [d[s.kx] / d[s.kz], d[s.ky] / d[s.kz], 1.0 / d[s.kz]];
            for (got, want) in [s.sx, s.sy, s.sz].into_iter().zip(want) {
                assert!(same(got, want), "{dir:?}: {got} against {want}");
            }
            let inv = crate::geometry::Ray::new(Vec3::ZERO, dir).inv_dir();
            for a in 0..3 {
                assert!(
                    same(inv[a], 1.0 / d[a]),
                    "{dir:?}: {} against {}",
                    inv[a],
                    1.0 / d[a]
                );
            }
        }
    }

    /// The f64 test finds the f32 test's hits, at the same `t` up to
    /// rounding, and its misses, on triangles the ray does not graze.
    #[test]
    fn the_f64_test_agrees_with_the_f32_test() {
        let mut r = crate::geometry::sampling::Rng::for_sample(5, 7, 9);
        let mut f = || r.next_f32() * 2.0 - 1.0;
        let mut hits = 0;
        for _ in 0..100_000 {
            let o = Vec3::new(f(), f(), f()) * 3.0;
            let d = Vec3::new(f(), f(), f());
            let t = [[f(), f(), f()], [f(), f(), f()], [f(), f(), f()]];
            let narrow = intersect(&RayShear::new(o, d), &t[0], &t[1], &t[2], f32::INFINITY);
            let wide = intersect(
                &RayShear::within(o, d, f32::MAX),
                &t[0],
                &t[1],
                &t[2],
                f32::INFINITY,
            );
            let near_edge = narrow
                .or(wide)
                .is_some_and(|h| h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-4 || h.t < 1e-4);
            if near_edge {
                continue;
            }
            match (narrow, wide) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!((a.t - b.t).abs() <= 1e-5 * a.t, "{a:?} {b:?}");
                }
                (None, None) => {}
                (a, b) => panic!("f32 {a:?}, f64 {b:?}, ray {o} {d}, triangle {t:?}"),
            }
        }
        assert!(hits > 250, "{hits} hits");
    }

    /// Small triangles nearly edge-on to a long ray far from its origin (a
    /// shadow ray grazing a fine mesh toward the light): wherever the ray
    /// crosses a triangle well inside its edges (by Möller-Trumbore in f64
    /// on the same float vertices), every test finds the hit.
    /// The conservative bound on `t` alone exceeded `t` on most of these.
    #[test]
    fn grazing_hits_far_from_the_origin_are_found() {
        let o = Vec3::new(0.3, -0.2, 0.1);
        let mut checked = 0;
        for (scale, size, slope) in [
            (1.0f32, 0.01f32, 1e-4f32),
            (1.0, 0.003, 3e-4),
            (1.0, 0.001, 1e-3),
            (3.0, 0.01, 3e-4),
            (3.0, 0.003, 1e-3),
            (10.0, 0.01, 1e-3),
            (10.0, 0.003, 3e-3),
        ] {
            let d = Vec3::new(3.0, 2.4, 1.8) * scale;
            let along = d.normalize();
            let across = along.any_orthonormal_vector();
            let c = o + 0.99 * d;
            let u = (along + slope * along.cross(across)) * size;
            let b = across * size;
            let tri = [c - u - b, c + u - b, c + b].map(|v| v.to_array());
            let Some((t, margin)) = crossing_f64(o, d, tri) else {
                continue;
            };
            if margin < 0.05 {
                continue;
            }
            checked += 1;
            let case = format!("distance {scale}, size {size}, slope {slope}");
            // Edge-on, the crossing moves along the ray with the vertices'
            // rounding; it stays within the triangle's span along the ray.
            let along_ray = |v: [f32; 3]| {
                (Vec3::from(v) - o).as_dvec3().dot(d.as_dvec3()) / d.as_dvec3().length_squared()
            };
            let span = tri.map(along_ray);
            let (lo, hi) = (
                span[0].min(span[1]).min(span[2]),
                span[0].max(span[1]).max(span[2]),
            );
            let within = |x: f32| (lo - 1e-6..=hi + 1e-6).contains(&(x as f64));
            assert!(
                within(t as f32),
                "{case}: f64 crossing {t} outside {lo}..{hi}"
            );
            let h = hit(o, d, tri).unwrap_or_else(|| panic!("{case}: missed"));
            assert!(within(h.t), "{case}: t {} outside {lo}..{hi}", h.t);
            let wide = intersect(
                &RayShear::within(o, d, f32::MAX),
                &tri[0],
                &tri[1],
                &tri[2],
                1.0,
            );
            assert!(wide.is_some_and(|w| within(w.t)), "{case}: f64 {wide:?}");
            check_lanes(o, d, &[tri; 4], checked % 4, 1.0);
        }
        assert!(checked >= 5, "{checked} cases well inside");
    }

    /// Where the ray crosses the triangle, in f64, and how far inside its
    /// edges (the least barycentric weight).
    fn crossing_f64(o: Vec3, d: Vec3, tri: [[f32; 3]; 3]) -> Option<(f64, f64)> {
        let [a, b, c] = tri.map(|v| Vec3::from(v).as_dvec3());
        let (o, d) = (o.as_dvec3(), d.as_dvec3());
        let (e1, e2) = (b - a, c - a);
        let p = d.cross(e2);
        let det = e1.dot(p);
        let s = o - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        (det != 0.0).then(|| (e2.dot(q) / det, u.min(v).min(1.0 - u - v)))
    }

    /// A hit of the f64 test stays a hit when `tmax` is its own `t`: a
    /// `t` past `tmax` in f64 that rounds to it ties with the hit that set
    /// `tmax`, and the tie must go to the lower triangle index whichever
    /// leaf was walked first.
    #[test]
    fn the_f64_test_keeps_a_hit_at_its_own_t() {
        let o = Vec3::new(-749451.94, -8.488897, -6.9230987e-7);
        let tri = [[0.0, -4.5481553, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]];
        let mut kept = 0;
        for k in 0..64 {
            let w = (k as f32) / 64.0;
            let target = Vec3::new(0.0, 1.0 - w * 0.5, w * 0.25);
            let s = RayShear::within(o, target - o, 4.8e16);
            assert!(s.wide);
            if let Some(h) = intersect(&s, &tri[0], &tri[1], &tri[2], f32::INFINITY) {
                let again = intersect(&s, &tri[0], &tri[1], &tri[2], h.t);
                assert_eq!(again, Some(h), "ray {k}");
                kept += 1;
            }
        }
        assert!(kept > 32, "{kept} hits");
    }

    /// Eight rays from one origin against one triangle, each lane its own
    /// ray (as a packet's leaves test them), compute what each ray computes
    /// alone.
    #[test]
    fn eight_rays_against_one_triangle_agree_bit_for_bit_with_the_scalar_test() {
        let mut r = crate::geometry::sampling::Rng::for_sample(3, 1, 4);
        let mut f = || r.next_f32() * 2.0 - 1.0;
        let mut hits = 0;
        for k in 0..20_000 {
            let o = Vec3::new(f(), f(), f()) * 3.0;
            let mut t = [[f(), f(), f()], [f(), f(), f()], [f(), f(), f()]];
            if k % 5 == 0 {
                t = t.map(|v| v.map(|x| (x * 4.0).round() / 4.0));
            }
            // Rays toward the triangle: through its vertices, the middle of
            // an edge, and points about it, some from a snapped origin.
            let [a, b, c] = t.map(Vec3::from);
            let o = if k % 7 == 0 { o.round() } else { o };
            let aim = [a, b, c, (a + b) * 0.5, (a + b + c) / 3.0];
            let dirs: [Vec3; 8] = std::array::from_fn(|i| {
                let p = aim[i % 5] + Vec3::new(f(), f(), f()) * if i < 5 { 0.0 } else { 0.3 };
                p - o
            });
            let shears = dirs.map(|d| RayShear::new(o, d));
            let axes = |s: &RayShear| [s.kx, s.ky, s.kz];
            if shears.iter().any(|s| axes(s) != axes(&shears[0])) {
                continue;
            }
            let tmax: [f32; 8] = std::array::from_fn(|i| {
                if i % 3 == 0 {
                    f().abs() * 4.0
                } else {
                    f32::INFINITY
                }
            });
            let want: [Option<TriHit>; 8] =
                std::array::from_fn(|i| intersect(&shears[i], &t[0], &t[1], &t[2], tmax[i]));
            hits += want.iter().flatten().count();
            let k3 = axes(&shears[0]);
            let lane = |i: usize, x: [f32; 3]| [x[k3[0]], x[k3[1]], x[k3[2]]][i];
            let s8 = |f: fn(&RayShear) -> f32| shears.map(|s| f(&s));
            let (sx, sy, sz) = (s8(|s| s.sx), s8(|s| s.sy), s8(|s| s.sz));
            let inv: [[f32; 8]; 3] = [0, 1, 2].map(|a| shears.map(|s| s.inv[a]));
            let tri4 = t.map(|v| v.map(Vec4::splat));
            let o4 = k3.map(|a| Vec4::splat(o[a]));
            let mut got = Vec::new();
            for half in 0..2 {
                let r = 4 * half..4 * half + 4;
                let v4 = |x: &[f32; 8]| Vec4::from_slice(&x[r.clone()]);
                let (s4, inv4) = ([v4(&sx), v4(&sy), v4(&sz)], inv.each_ref().map(v4));
                let h = lanes4(k3, o4, s4, inv4, &tri4, v4(&tmax));
                got.extend((0..4).map(|i| {
                    (h.mask & (1 << i) != 0).then(|| TriHit {
                        t: h.t[i],
                        u: h.u[i],
                        v: h.v[i],
                    })
                }));
            }
            assert_eq!(got, want, "case {k}");
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx") {
                use std::arch::x86_64::*;
                // SAFETY: AVX is present.
                let h = unsafe {
                    let ld = |x: &[f32; 8]| _mm256_loadu_ps(x.as_ptr());
                    let set = |x: f32| _mm256_set1_ps(x);
                    lanes8_avx::<true, true>(
                        t.map(|v| [0, 1, 2].map(|i| set(lane(i, v)))),
                        [0, 1, 2].map(|i| set(lane(i, o.to_array()))),
                        [ld(&sx), ld(&sy), ld(&sz)],
                        inv.each_ref().map(ld),
                        ld(&tmax),
                    )
                };
                let got: Vec<_> = (0..8)
                    .map(|i| {
                        (h.mask & (1 << i) != 0).then(|| TriHit {
                            t: h.t[i],
                            u: h.u[i],
                            v: h.v[i],
                        })
                    })
                    .collect();
                assert_eq!(got, want, "case {k}, AVX");
            }
        }
        assert!(hits > 10_000, "{hits} hits");
    }

    #[test]
    fn four_and_eight_lane_tests_agree_bit_for_bit_with_the_scalar_test() {
        let mut r = crate::geometry::sampling::Rng::for_sample(9, 9, 9);
        let mut f = || r.next_f32() * 2.0 - 1.0;
        for k in 0..20_000 {
            let o = Vec3::new(f(), f(), f()) * 3.0;
            let d = Vec3::new(f(), f(), f());
            let mut tris = [[[0.0f32; 3]; 3]; 4];
            for t in &mut tris {
                *t = [[f(), f(), f()], [f(), f(), f()], [f(), f(), f()]];
            }
            // Shared edges and vertices, a ray through a vertex, snapped
            // coordinates (exact zeros in the edge functions), degenerate
            // triangles and padding lanes.
            tris[1][0] = tris[0][1];
            tris[1][1] = tris[0][0];
            if k % 3 == 0 {
                let v = Vec3::from(tris[2][0]);
                let o2 = v - d * 2.0;
                check_lanes(o2, d, &tris, 0, f32::INFINITY);
            }
            if k % 5 == 0 {
                for t in &mut tris {
                    for v in t.iter_mut() {
                        *v = v.map(|x| (x * 4.0).round() / 4.0);
                    }
                }
                tris[3] = [[0.5, 0.5, 0.5]; 3];
            }
            check_lanes(
                o,
                d,
                &tris,
                k % 4,
                if k % 2 == 0 { 2.0 } else { f32::INFINITY },
            );
            // From a point on triangle 0 (its own surface, up to rounding):
            // hits there are decided by the conservative t bound.
            let [a, b, c] = tris[0].map(Vec3::from);
            let (u, v) = (f().abs() * 0.5, f().abs() * 0.5);
            let on = a + u * (b - a) + v * (c - a);
            check_lanes(on, d, &tris, 0, f32::INFINITY);
            check_lanes(on + d * 1e-6 * f(), -d, &tris, 0, f32::INFINITY);
            let axis = Vec3::new((f() * 4.0).round() / 4.0, (f() * 4.0).round() / 4.0, 2.0);
            check_lanes(axis, Vec3::NEG_Z, &tris, 0, f32::INFINITY);
        }
    }
}
