//! The kernels with AVX: eight lanes per instruction. The walks compiled
//! for AVX-512 (F, VL, DQ, BW) use them too, in their EVEX forms.

use super::{
    box_planes, frustum_planes, lane, BoxRay, Kernels, PacketKernels, FAR_SCALE, MAX_TFAR,
};
use crate::bvh::packet::{Frustum, Lanes, Shears};
use crate::bvh::simd::Avx;
use crate::bvh::wide::{Node8, Packet, WIDTH};
use crate::geometry::triangle::{lanes8_avx, RayShear, TriHit8};

/// The same test on all eight boxes at once with AVX (not a
/// `#[target_feature]` function so that it can be forced inline).
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
pub(in crate::bvh) unsafe fn hit_boxes_avx(
    r: &BoxRay,
    n: &Node8,
    tmax: f32,
) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    // Macros, not closures: a closure here would be compiled on its own,
    // without AVX, and called.
    // `Node8` is 32-byte aligned and each plane is eight f32 at the start of
    // a 32-byte row.
    macro_rules! slab {
        ($a:expr) => {{
            let (o, inv) = (
                _mm256_set1_ps(lane(r.o, $a)),
                _mm256_set1_ps(lane(r.inv, $a)),
            );
            let (i, j) = box_planes(r, $a);
            let near = _mm256_load_ps(n.b[i].as_ptr());
            let far = _mm256_load_ps(n.b[j].as_ptr());
            (
                _mm256_mul_ps(_mm256_sub_ps(near, o), inv),
                _mm256_mul_ps(_mm256_sub_ps(far, o), inv),
            )
        }};
    }
    let (nx, fx) = slab!(0);
    let (ny, fy) = slab!(1);
    let (nz, fz) = slab!(2);
    slab_hits_avx([nx, ny, nz], [fx, fy, fz], tmax)
}

/// Eight boxes' hits from their slabs' entry (`near`) and exit (`far`)
/// distances per axis: entered no later than left (the exit widened by
/// [`FAR_SCALE`]) and within `[0, tmax]`; with the entry distances.
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
unsafe fn slab_hits_avx(
    near: [std::arch::x86_64::__m256; 3],
    far: [std::arch::x86_64::__m256; 3],
    tmax: f32,
) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    let tn = _mm256_max_ps(
        near[2],
        _mm256_max_ps(near[1], _mm256_max_ps(near[0], _mm256_setzero_ps())),
    );
    let tf = _mm256_mul_ps(
        _mm256_min_ps(
            far[2],
            _mm256_min_ps(
                far[1],
                _mm256_min_ps(far[0], _mm256_set1_ps(tmax.min(MAX_TFAR))),
            ),
        ),
        _mm256_set1_ps(FAR_SCALE),
    );
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
    let mut tnear = [0.0; WIDTH];
    _mm256_storeu_ps(tnear.as_mut_ptr(), tn);
    (mask, tnear)
}

/// [`frustum_boxes`](super::portable::frustum_boxes) with AVX.
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
pub(in crate::bvh) unsafe fn frustum_boxes_avx(
    f: &Frustum,
    n: &Node8,
    tmax: f32,
) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    macro_rules! slab {
        ($a:expr) => {{
            let o = _mm256_set1_ps(f.o[$a]);
            let (lo, hi) = (_mm256_set1_ps(f.lo[$a]), _mm256_set1_ps(f.hi[$a]));
            let (i, j) = frustum_planes(f, $a);
            let dn = _mm256_sub_ps(_mm256_load_ps(n.b[i].as_ptr()), o);
            let df = _mm256_sub_ps(_mm256_load_ps(n.b[j].as_ptr()), o);
            (
                _mm256_min_ps(_mm256_mul_ps(dn, lo), _mm256_mul_ps(dn, hi)),
                _mm256_max_ps(_mm256_mul_ps(df, lo), _mm256_mul_ps(df, hi)),
            )
        }};
    }
    let (nx, fx) = slab!(0);
    let (ny, fy) = slab!(1);
    let (nz, fz) = slab!(2);
    slab_hits_avx([nx, ny, nz], [fx, fy, fz], tmax)
}

/// [`rays_box`](super::portable::rays_box) with AVX, eight rays at a time.
///
/// # Safety
/// The CPU must support AVX.
#[inline(always)]
pub(in crate::bvh) unsafe fn rays_box_avx(
    f: &Frustum,
    l: &Lanes,
    n: &Node8,
    slot: usize,
    active: u64,
) -> u64 {
    use std::arch::x86_64::*;
    macro_rules! d {
        ($a:expr) => {{
            let (i, j) = frustum_planes(f, $a);
            (
                _mm256_set1_ps(n.b[i][slot] - f.o[$a]),
                _mm256_set1_ps(n.b[j][slot] - f.o[$a]),
            )
        }};
    }
    let (dx, dy, dz) = (d!(0), d!(1), d!(2));
    let (zero, maxt, scale) = (
        _mm256_setzero_ps(),
        _mm256_set1_ps(MAX_TFAR),
        _mm256_set1_ps(FAR_SCALE),
    );
    let mut hit = 0;
    let mut blocks = active;
    while blocks != 0 {
        let b = blocks.trailing_zeros() as usize / 8;
        blocks &= !(0xff << (8 * b));
        let r = 8 * b;
        // `Lanes` is 32-byte aligned and each row holds 64 f32.
        let ix = _mm256_load_ps(l.inv[0].as_ptr().add(r));
        let iy = _mm256_load_ps(l.inv[1].as_ptr().add(r));
        let iz = _mm256_load_ps(l.inv[2].as_ptr().add(r));
        let tn = _mm256_max_ps(
            _mm256_mul_ps(dz.0, iz),
            _mm256_max_ps(
                _mm256_mul_ps(dy.0, iy),
                _mm256_max_ps(_mm256_mul_ps(dx.0, ix), zero),
            ),
        );
        let tmax = _mm256_min_ps(_mm256_load_ps(l.tmax.as_ptr().add(r)), maxt);
        let tf = _mm256_mul_ps(
            _mm256_min_ps(
                _mm256_mul_ps(dz.1, iz),
                _mm256_min_ps(
                    _mm256_mul_ps(dy.1, iy),
                    _mm256_min_ps(_mm256_mul_ps(dx.1, ix), tmax),
                ),
            ),
            scale,
        );
        let m = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u64;
        hit |= m << r;
    }
    hit & active
}

impl Kernels for Avx {
    #[inline(always)]
    fn boxes(&self, r: &BoxRay, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
        // SAFETY: an `Avx` exists only where the CPU has AVX.
        unsafe { hit_boxes_avx(r, n, tmax) }
    }

    #[inline(always)]
    fn triangles<const UV: bool>(&self, s: &RayShear, p: &Packet, tmax: f32) -> TriHit8 {
        // SAFETY: as above.
        unsafe { crate::geometry::triangle::intersect8_avx::<UV>(s, &p.p, tmax) }
    }
}

impl PacketKernels for Avx {
    #[inline(always)]
    fn frustum(&self, f: &Frustum, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
        // SAFETY: an `Avx` exists only where the CPU has AVX.
        unsafe { frustum_boxes_avx(f, n, tmax) }
    }

    #[inline(always)]
    fn rays_box(&self, f: &Frustum, l: &Lanes, n: &Node8, slot: usize, active: u64) -> u64 {
        // SAFETY: as above.
        unsafe { rays_box_avx(f, l, n, slot, active) }
    }

    #[inline(always)]
    fn rays_triangle<const UV: bool>(
        &self,
        (p, j): (&Packet, usize),
        o: &[f32; 3],
        sh: &Shears,
        l: &Lanes,
        b: usize,
    ) -> TriHit8 {
        use std::arch::x86_64::*;
        let [kx, ky, kz] = sh.k;
        let r = 8 * b;
        // Macros, not closures, as in `intersect8_avx`.
        macro_rules! ld {
            ($s:expr) => {
                _mm256_loadu_ps($s.as_ptr().add(r))
            };
        }
        macro_rules! v {
            ($v:expr) => {
                [
                    _mm256_set1_ps(p.p[$v][kx][j]),
                    _mm256_set1_ps(p.p[$v][ky][j]),
                    _mm256_set1_ps(p.p[$v][kz][j]),
                ]
            };
        }
        // SAFETY: as above; every row of `Shears` and `Lanes` holds 64 f32.
        unsafe {
            lanes8_avx::<UV, true>(
                [v!(0), v!(1), v!(2)],
                [
                    _mm256_set1_ps(o[kx]),
                    _mm256_set1_ps(o[ky]),
                    _mm256_set1_ps(o[kz]),
                ],
                [ld!(sh.s[0]), ld!(sh.s[1]), ld!(sh.s[2])],
                [ld!(l.inv[kx]), ld!(l.inv[ky]), ld!(l.inv[kz])],
                ld!(l.tmax),
            )
        }
    }
}
