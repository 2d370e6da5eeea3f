//! Rays with a parametric interval.

use glam::Vec3;

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

    /// Reciprocal direction for slab tests. Zero components become ±1e30
    /// rather than ±inf, so an origin lying on a slab plane gives `0 * 1e30 = 0`
    /// (inside the slab) instead of the NaN of `0 * inf`.
    #[inline(always)]
    pub fn inv_dir(&self) -> Vec3 {
        let tiny = Vec3::splat(1e-30);
        let d = self.dir;
        let safe = Vec3::select(d.abs().cmplt(tiny), tiny.copysign(d), d);
        safe.recip()
    }
}
