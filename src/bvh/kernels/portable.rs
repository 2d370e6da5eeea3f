//! The kernels on any CPU: four lanes at a time (SSE on x86-64, whatever
//! the target has elsewhere).

use glam::Vec4;

use super::{
    box_planes, frustum_planes, lane, BoxRay, Kernels, PacketKernels, FAR_SCALE, MAX_TFAR,
};
use crate::bvh::packet::{Frustum, Lanes, Shears, PACKET_RAYS};
use crate::bvh::wide::{Node8, Packet, WIDTH};
use crate::geometry::triangle::{intersect8, lanes4, RayShear, TriHit8};

/// Bit `i` set when child `i`'s box is hit within `(0, tmax)`, and the entry
/// distances: the test of `Aabb::hit`, four boxes at a time.
#[inline(always)]
pub(in crate::bvh) fn hit_boxes(r: &BoxRay, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
    let mut mask = 0;
    let mut tnear = [0.0; WIDTH];
    for half in 0..WIDTH / 4 {
        let lanes = half * 4..half * 4 + 4;
        let slab = |a: usize| {
            let (o, inv) = (Vec4::splat(lane(r.o, a)), Vec4::splat(lane(r.inv, a)));
            let (i, j) = box_planes(r, a);
            let near = (Vec4::from_slice(&n.b[i][lanes.clone()]) - o) * inv;
            let far = (Vec4::from_slice(&n.b[j][lanes.clone()]) - o) * inv;
            (near, far)
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        // maxps/minps return the second operand when either is NaN: with the
        // running value second, the NaN of `0 * inf` (an origin on a slab
        // plane of a parallel ray) is passed over, as in `Aabb::hit`.
        let tn = nz.max(ny.max(nx.max(Vec4::ZERO)));
        let tf = fz.min(fy.min(fx.min(Vec4::splat(tmax.min(MAX_TFAR))))) * Vec4::splat(FAR_SCALE);
        mask |= tn.cmple(tf).bitmask() << (4 * half);
        tn.write_to_slice(&mut tnear[lanes]);
    }
    (mask, tnear)
}

/// The frustum's eight-box test: bit `i` set when some ray of the group may
/// hit child `i`'s box within `(0, tmax)`, and the least entry distance.
#[inline(always)]
pub(in crate::bvh) fn frustum_boxes(f: &Frustum, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
    let mut mask = 0;
    let mut tnear = [0.0; WIDTH];
    for half in 0..WIDTH / 4 {
        let lanes = half * 4..half * 4 + 4;
        let slab = |a: usize| {
            let o = Vec4::splat(f.o[a]);
            let (lo, hi) = (Vec4::splat(f.lo[a]), Vec4::splat(f.hi[a]));
            let (i, j) = frustum_planes(f, a);
            let dn = Vec4::from_slice(&n.b[i][lanes.clone()]) - o;
            let df = Vec4::from_slice(&n.b[j][lanes.clone()]) - o;
            ((dn * lo).min(dn * hi), (df * lo).max(df * hi))
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        // NaN (a NaN bound) is passed over as in the single-ray test.
        let tn = nz.max(ny.max(nx.max(Vec4::ZERO)));
        let tf = fz.min(fy.min(fx.min(Vec4::splat(tmax.min(MAX_TFAR))))) * Vec4::splat(FAR_SCALE);
        mask |= tn.cmple(tf).bitmask() << (4 * half);
        tn.write_to_slice(&mut tnear[lanes]);
    }
    (mask, tnear)
}

/// The single-ray box test of child `slot` of `n` for the rays in `active`,
/// four at a time: bit `i` set when ray `i` hits it.
#[inline(always)]
pub(in crate::bvh) fn rays_box(f: &Frustum, l: &Lanes, n: &Node8, slot: usize, active: u64) -> u64 {
    let d = |a: usize| {
        let (i, j) = frustum_planes(f, a);
        (
            Vec4::splat(n.b[i][slot] - f.o[a]),
            Vec4::splat(n.b[j][slot] - f.o[a]),
        )
    };
    let (dx, dy, dz) = (d(0), d(1), d(2));
    let mut hit = 0;
    for b in (0..PACKET_RAYS / 4).filter(|b| active & (0xf << (4 * b)) != 0) {
        let r = 4 * b..4 * b + 4;
        let inv = |a: usize| Vec4::from_slice(&l.inv[a][r.clone()]);
        let (ix, iy, iz) = (inv(0), inv(1), inv(2));
        let tn = (dz.0 * iz).max((dy.0 * iy).max((dx.0 * ix).max(Vec4::ZERO)));
        let tmax = Vec4::from_slice(&l.tmax[r.clone()]).min(Vec4::splat(MAX_TFAR));
        let tf = (dz.1 * iz).min((dy.1 * iy).min((dx.1 * ix).min(tmax))) * Vec4::splat(FAR_SCALE);
        hit |= (tn.cmple(tf).bitmask() as u64) << (4 * b);
    }
    hit & active
}

/// Four lanes at a time, on any CPU.
pub(in crate::bvh) struct Portable;

impl Kernels for Portable {
    #[inline(always)]
    fn boxes(&self, r: &BoxRay, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
        hit_boxes(r, n, tmax)
    }

    #[inline(always)]
    fn triangles<const UV: bool>(&self, s: &RayShear, p: &Packet, tmax: f32) -> TriHit8 {
        intersect8::<UV>(s, &p.p, tmax)
    }
}

impl PacketKernels for Portable {
    #[inline(always)]
    fn frustum(&self, f: &Frustum, n: &Node8, tmax: f32) -> (u32, [f32; WIDTH]) {
        frustum_boxes(f, n, tmax)
    }

    #[inline(always)]
    fn rays_box(&self, f: &Frustum, l: &Lanes, n: &Node8, slot: usize, active: u64) -> u64 {
        rays_box(f, l, n, slot, active)
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
        let mut h = TriHit8::NONE;
        let tri = p.p.map(|v| v.map(|a| Vec4::splat(a[j])));
        for half in 0..2 {
            let r = 8 * b + 4 * half..8 * b + 4 * half + 4;
            let at = 4 * half..4 * half + 4;
            let r4 = lanes4(
                sh.k,
                sh.k.map(|a| Vec4::splat(o[a])),
                sh.s.each_ref().map(|s| Vec4::from_slice(&s[r.clone()])),
                sh.k.map(|a| Vec4::from_slice(&l.inv[a][r.clone()])),
                &tri,
                Vec4::from_slice(&l.tmax[r.clone()]),
            );
            h.mask |= r4.mask << (4 * half);
            r4.t.write_to_slice(&mut h.t[at.clone()]);
            r4.u.write_to_slice(&mut h.u[at.clone()]);
            r4.v.write_to_slice(&mut h.v[at]);
        }
        h
    }
}
