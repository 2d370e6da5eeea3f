//! Axis-aligned bounding boxes.

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: growing it by any point gives that point.
    pub(crate) const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    #[inline]
    pub(crate) fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    #[inline]
    pub(crate) fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    pub(crate) fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Surface area; 0 for an empty box so empty bins cost nothing in the SAH.
    #[inline]
    pub(crate) fn area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.max - self.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    pub fn contains(&self, o: &Aabb) -> bool {
        o.min.cmpge(self.min).all() && o.max.cmple(self.max).all()
    }

    /// Slab test against a ray given by origin and reciprocal direction
    /// ([`Ray::inv_dir`](super::Ray::inv_dir)).
    ///
    /// Returns the entry distance when the box is hit within `(0, tmax)`.
    /// `tmax` is widened by 2γ₃ as in pbrt so rays that graze a box face are
    /// not lost to rounding. As in pbrt, the near and far planes are picked
    /// by the sign of the direction and a NaN distance never narrows the
    /// interval. A zero direction component (infinite reciprocal) gives a
    /// NaN (`0 * inf`) only when the origin lies on that slab's plane, and
    /// then the slab, closed, does not limit the ray: a ray lying in a face
    /// plane hits the box whatever the sign of its zero, as it hits the
    /// triangles on that face.
    #[inline(always)]
    pub fn hit(&self, origin: Vec3, inv_dir: Vec3, tmax: f32) -> Option<f32> {
        let neg = inv_dir.cmplt(Vec3::ZERO);
        let near = Vec3::select(neg, self.max, self.min);
        let far = Vec3::select(neg, self.min, self.max);
        let tn = (near - origin) * inv_dir;
        let tf = (far - origin) * inv_dir;
        // `if a > b { a } else { b }` keeps `b` when `a` is NaN (one maxss on
        // x86): with the running value as `b`, NaN distances are passed over.
        let max = |a: f32, b: f32| if a > b { a } else { b };
        let min = |a: f32, b: f32| if a < b { a } else { b };
        let tnear = max(tn.z, max(tn.y, max(tn.x, 0.0)));
        let tfar = min(tf.z, min(tf.y, min(tf.x, tmax))) * (1.0 + 2.0 * super::gamma(3));
        (tnear <= tfar && tnear < f32::INFINITY).then_some(tnear)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grazing_ray_along_face_hits() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        // Rays lying in a face plane, or inside the slab, with a zero (or
        // -0, or negligible) x component: inside the closed slab counts as
        // inside whatever the sign, outside misses, nothing is NaN.
        for dx in [0.0, -0.0, 1e-31, -1e-31, 1e-40, -1e-40] {
            let inv = crate::geometry::Ray::new(Vec3::ZERO, Vec3::new(dx, 0.0, 1.0))
                .inv_dir()
                .into();
            for x in [0.0, 1.0, 0.5, 1e-7, 1.0 - 1e-7] {
                assert_eq!(
                    b.hit(Vec3::new(x, 0.5, -1.0), inv, f32::INFINITY),
                    Some(1.0),
                    "x={x} dx={dx}"
                );
            }
            for x in [1.5, -1e-6, 1.0f32.next_up(), -1e-45] {
                assert!(
                    b.hit(Vec3::new(x, 0.5, -1.0), inv, f32::INFINITY).is_none(),
                    "x={x} dx={dx}"
                );
            }
        }
        // A flat box (all its triangles in one plane), the origin in it.
        let flat = Aabb {
            min: Vec3::new(0.0, 0.0, 2.0),
            max: Vec3::new(1.0, 1.0, 2.0),
        };
        let inv = crate::geometry::Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.0, -0.0))
            .inv_dir()
            .into();
        assert_eq!(flat.hit(Vec3::new(-1.0, 0.5, 2.0), inv, 5.0), Some(1.0));
        assert!(flat.hit(Vec3::new(-1.0, 0.5, 2.5), inv, 5.0).is_none());
        // Every direction component zero: inside hits at 0, outside misses.
        let inv = crate::geometry::Ray::new(Vec3::ZERO, Vec3::ZERO)
            .inv_dir()
            .into();
        assert_eq!(b.hit(Vec3::splat(0.5), inv, f32::INFINITY), Some(0.0));
        assert!(b.hit(Vec3::splat(2.0), inv, f32::INFINITY).is_none());
    }

    #[test]
    fn behind_and_beyond_tmax_miss() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let d = Vec3::new(0.0, 0.0, 1.0);
        assert!(b
            .hit(
                Vec3::new(0.5, 0.5, 2.0),
                crate::geometry::Ray::new(Vec3::ZERO, d).inv_dir().into(),
                10.0
            )
            .is_none());
        assert!(b
            .hit(
                Vec3::new(0.5, 0.5, -2.0),
                crate::geometry::Ray::new(Vec3::ZERO, d).inv_dir().into(),
                1.0
            )
            .is_none());
        assert_eq!(
            b.hit(
                Vec3::new(0.5, 0.5, -2.0),
                crate::geometry::Ray::new(Vec3::ZERO, d).inv_dir().into(),
                5.0
            ),
            Some(2.0)
        );
    }
}
