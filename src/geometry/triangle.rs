//! Watertight ray/triangle intersection (Woop, Benthin, Wald, JCGT 2013).
//!
//! The ray is sheared so it points along +z; the edge functions are then
//! evaluated in 2D, which makes a point on a shared edge land on exactly one
//! side for both neighbours: no cracks, no double misses. When an edge
//! function is exactly zero the test is redone in f64, as the paper requires.

use glam::Vec3;

use super::gamma;

/// Per-ray constants of the shear transform, computed once per ray.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    pub origin: [f32; 3],
    pub kx: usize,
    pub ky: usize,
    pub kz: usize,
    pub sx: f32,
    pub sy: f32,
    pub sz: f32,
}

impl RayShear {
    /// Direction components below [`PARALLEL`](super::ray::PARALLEL) count
    /// as zero, as in the box test, so the two agree on grazing rays.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let dir = super::ray::flush(dir);
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
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        let d = dir.to_array();
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        Self {
            origin: origin.to_array(),
            kx,
            ky,
            kz,
            sx: d[kx] / d[kz],
            sy: d[ky] / d[kz],
            sz: 1.0 / d[kz],
        }
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
        let (ax, ay, bx, by, cx, cy) = (
            ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64,
        );
        u = (cx * by - cy * bx) as f32;
        v = (ax * cy - ay * cx) as f32;
        w = (bx * ay - by * ax) as f32;
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
    if ts <= 0.0 || ts > tmax * d * (1.0 + 4.0 * f32::EPSILON) {
        return None;
    }
    let inv = 1.0 / det;
    let t = t_scaled * inv;
    // pbrt-v4's conservative bound on the rounding error of t: a hit closer
    // than it may be the ray's own surface, seen through rounding.
    let max_zt = az.abs().max(bz.abs()).max(cz.abs());
    let max_xt = ax.abs().max(bx.abs()).max(cx.abs());
    let max_yt = ay.abs().max(by.abs()).max(cy.abs());
    let delta_z = gamma(3) * max_zt;
    let delta_x = gamma(5) * (max_xt + max_zt);
    let delta_y = gamma(5) * (max_yt + max_zt);
    let delta_e = 2.0 * (gamma(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let delta_t =
        3.0 * (gamma(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * inv.abs();
    if t <= delta_t || !t.is_finite() || t > tmax {
        return None;
    }
    Some(TriHit {
        t,
        u: (v * inv).clamp(0.0, 1.0),
        v: (w * inv).clamp(0.0, 1.0),
    })
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
}
