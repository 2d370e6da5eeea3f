//! Scale-aware origins for spawned rays (pbrt-v4, "Robust spawned ray origins").
//!
//! A hit point computed from barycentrics carries a rounding error bounded by
//! γ₇ times the magnitudes of the weighted vertices. Moving the origin by that
//! bound along the geometric normal, and rounding away from the surface, puts
//! it on the correct side whatever the scene's scale or distance from the origin.

use glam::Vec3;

const GAMMA7: f32 = super::gamma(7);

/// Point on a triangle from barycentrics, with its absolute error bound.
#[inline]
pub fn hit_point(p: [Vec3; 3], u: f32, v: f32) -> (Vec3, Vec3) {
    let b0 = 1.0 - u - v;
    let point = b0 * p[0] + u * p[1] + v * p[2];
    let err = GAMMA7 * ((b0 * p[0]).abs() + (u * p[1]).abs() + (v * p[2]).abs());
    (point, err)
}

/// Unit geometric normal of a triangle (zero when it has no area), from a
/// cross product in f64: in f32 the cross product of a long, thin triangle
/// can point well away from the true normal, and spawned rays are offset
/// along it.
#[inline]
pub fn geometric_normal(p: [Vec3; 3]) -> Vec3 {
    // Converted one by one: `map` over the array was a call whose result
    // came back through memory in pieces the loads then straddled.
    let [a, b, c] = [p[0].as_dvec3(), p[1].as_dvec3(), p[2].as_dvec3()];
    (b - a).cross(c - a).normalize_or_zero().as_vec3()
}

/// Origin for a ray leaving `p` (error `err`) in direction `w`, on the side of
/// the geometric normal `ng` that `w` points to. The side is decided in f64:
/// for a `w` nearly in the plane the f32 dot product can get its sign wrong,
/// and the ray then starts on the far side and crosses back through the
/// surface.
pub fn offset_origin(p: Vec3, err: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let d = ng.abs().dot(err);
    let mut off = d * ng;
    if w.as_dvec3().dot(ng.as_dvec3()) < 0.0 {
        off = -off;
    }
    let po = p + off;
    let bump = |x: f32, o: f32| {
        if o > 0.0 {
            x.next_up()
        } else if o < 0.0 {
            x.next_down()
        } else {
            x
        }
    };
    Vec3::new(bump(po.x, off.x), bump(po.y, off.y), bump(po.z, off.z))
}

/// Fraction of a shadow segment kept before its end, so the segment stops
/// short of the surface that holds the light sample.
pub(crate) const SHADOW_EPSILON: f32 = 1e-4;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_is_relative_to_magnitude() {
        for scale in [1e-6f32, 1.0, 1e6] {
            let tri = [Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale]
                .map(|v| v + Vec3::splat(3.0 * scale));
            let (p, e) = hit_point(tri, 0.3, 0.3);
            let o = offset_origin(p, e, Vec3::Z, Vec3::Z);
            assert!(o.z > p.z);
            assert!(o.z - p.z < scale * 1e-5, "offset too big at scale {scale}");
        }
    }
}
