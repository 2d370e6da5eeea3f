//! Rays with a parametric interval.

use glam::{Vec3, Vec3A};

/// A ray `origin + t * dir` for `t` in `(0, tmax)`. `dir` need not be unit length.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            tmax: f32::INFINITY,
        }
    }

    pub fn segment(origin: Vec3, dir: Vec3, tmax: f32) -> Self {
        Self { origin, dir, tmax }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// Reciprocal direction for slab tests. Components below [`PARALLEL`]
    /// count as zero (as they do for the triangle test, see [`flush`]) and
    /// give ±inf; [`Aabb::hit`](super::Aabb::hit) reads the NaN of `0 * inf`
    /// (an origin on a slab plane) as inside the slab.
    ///
    /// One vector division (`Vec3::recip` makes three scalar ones: the same
    /// quotients, three times the divider's time), kept in a register.
    #[inline(always)]
    pub fn inv_dir(&self) -> Vec3A {
        Vec3A::ONE / Vec3A::from(flush(self.dir))
    }
}

/// Direction components smaller than this in magnitude are treated as
/// exactly zero by both the box and the triangle tests. A finite stand-in
/// reciprocal (or the triangle test seeing a slope the box test does not)
/// lets the two disagree on rays that graze a plane near the origin, and
/// then the BVH misses hits that brute force finds.
pub(crate) const PARALLEL: f32 = 1e-30;

/// `d` with components below [`PARALLEL`] replaced by zeros of their sign.
#[inline(always)]
pub(crate) fn flush(d: Vec3) -> Vec3 {
    Vec3::select(d.abs().cmplt(Vec3::splat(PARALLEL)), d * 0.0, d)
}
