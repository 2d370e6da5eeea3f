//! The SIMD kernels the walks are generic over, one file per instruction
//! set: a node's eight-box test and a leaf's eight-triangle test for one
//! ray ([`Kernels`]), and a packet's frustum, ray-box and ray-triangle tests
//! ([`PacketKernels`]). Static dispatch with forced inlining, so that a
//! walk compiled for an instruction set holds its kernels inline.
//!
//! A port to another instruction set is one more file here (its kernels,
//! for a token type made only where the CPU has them, as
//! [`Avx`](super::simd::Avx) is), its triangle lanes beside the others in
//! `geometry/triangle.rs` (where the bit-for-bit agreement tests run every
//! width), and its arm where the walks dispatch (`Bvh::traverse`,
//! `Bvh::group`).

#[cfg(target_arch = "x86_64")]
pub(super) mod avx;
pub(super) mod portable;

use glam::Vec3A;

pub(in crate::bvh) use portable::Portable;

use super::packet::{Frustum, Lanes, Shears};
use super::wide::{Node8, Packet, WIDTH};
use crate::geometry::triangle::{RayShear, TriHit8};
use crate::geometry::{gamma, Ray};

/// Widening of the far slab distance, as in [`crate::geometry::Aabb::hit`].
pub(in crate::bvh) const FAR_SCALE: f32 = 1.0 + 2.0 * gamma(3);
/// Exit distances are capped below infinity so that an entry distance of
/// infinity (a ray with no direction at all) never counts as a hit, as in
/// `Aabb::hit`.
pub(in crate::bvh) const MAX_TFAR: f32 = f32::MAX / 2.0;

/// A ray's constants for the slab tests.
#[derive(Clone, Copy)]
pub(in crate::bvh) struct BoxRay {
    /// Kept in registers: built as arrays, they cost a store-forwarding
    /// stall on every ray when the splats read them back.
    pub(super) o: Vec3A,
    pub(super) inv: Vec3A,
    /// Whether the ray runs toward -axis: the near plane of axis `a` is then
    /// `Node8::b[2a + 1]` (max), else `b[2a]` (min). Kept as a bool so the
    /// index is provably in bounds.
    pub(super) neg: [bool; 3],
}

impl BoxRay {
    #[inline(always)]
    pub(in crate::bvh) fn new(ray: &Ray) -> Self {
        let inv = ray.inv_dir();

        BoxRay {
            o: ray.origin.into(),
            inv,
            neg: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
        }
    }
}

/// Indices in `Node8::b` of the near and far planes of axis `a`.
#[inline(always)]
pub(super) fn box_planes(r: &BoxRay, a: usize) -> (usize, usize) {
    let n = r.neg[a] as usize;
    (2 * a + n, 2 * a + 1 - n)
}

/// Component `a` of `v`; a constant `a` folds to a register lane.
#[inline(always)]
pub(super) fn lane(v: Vec3A, a: usize) -> f32 {
    match a {
        0 => v.x,
        1 => v.y,
        _ => v.z,
    }
}

/// Indices in `Node8::b` of the near and far planes of axis `a`.
#[inline(always)]
pub(super) fn frustum_planes(f: &Frustum, a: usize) -> (usize, usize) {
    let n = f.neg[a] as usize;
    (2 * a + n, 2 * a + 1 - n)
}

/// The SIMD kernels of the walk: the eight-box test and the eight-triangle
/// test. Static dispatch with forced inlining, so the walk compiled for AVX
/// holds the AVX kernels inline.
pub(in crate::bvh) trait Kernels {
    fn boxes(&self, r: &BoxRay, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]);
    fn triangles<const UV: bool>(&self, s: &RayShear, p: &Packet, tmax: f32) -> TriHit8;
}

/// The kernels of a packet walk, beside those of the single-ray walk.
pub(in crate::bvh) trait PacketKernels: Kernels {
    fn frustum(&self, f: &Frustum, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]);
    fn rays_box(&self, f: &Frustum, l: &Lanes, n: &Node8, slot: usize, active: u64) -> u64;
    /// Triangle `j` of `p` against rays `8b..8b + 8` of the group, each
    /// computing what [`Kernels::triangles`] computes for that ray.
    fn rays_triangle<const UV: bool>(
        &self,
        t: (&Packet, usize),
        o: &[f32; 3],
        sh: &Shears,
        l: &Lanes,
        b: usize,
    ) -> TriHit8;
}
