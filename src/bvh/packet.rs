//! Coherent rays in packets: up to [`PACKET_RAYS`] rays from one origin (a
//! camera's eye, a point light) walk the wide tree together.
//!
//! Rays are grouped by the signs of their directions; a group is a frustum,
//! its shared origin and, per axis, the range of its rays' reciprocal
//! directions. One eight-box test of the frustum per node stands for the
//! box tests of all its rays: a node it misses, every ray misses. Leaves
//! are entered by each ray whose own box test (the single-ray test, eight
//! rays per instruction) hits the leaf's box, and each such ray tests the
//! leaf's triangles exactly as [`Bvh::intersect`] would. The frustum only
//! ever lets more boxes through than the rays' own tests, and a ray passes
//! over a leaf only as its single walk would, when the leaf lies beyond the
//! nearest hit it has: every triangle that could be a ray's closest hit is
//! tested, and the closest hit (ties going to the lower triangle index) is
//! the same, bit for bit, whatever the order of the walk.
//!
//! At a leaf, the rays test its triangles one ray against eight triangles
//! a time, or, where that makes fewer tests (many rays, few triangles:
//! large triangles that whole tiles hit), one triangle against eight rays
//! a time. The second needs every ray of the group sheared onto the same
//! axes and tested in f32; each lane then computes exactly what the first
//! computes for its ray.
//!
//! Why the frustum test is conservative to the bit: with the origin shared,
//! a ray's slab distance is `(b - o) * inv`, the same `b - o` for every ray;
//! rounding is monotone, so over reciprocals in `[lo, hi]` the product lies
//! between `(b - o) * lo` and `(b - o) * hi` as rounded. The frustum's entry
//! distance is then at most every ray's, its exit distance at least every
//! ray's. Rays that break this (another origin, a direction component zero,
//! below [`PARALLEL`](crate::geometry::ray::PARALLEL) or not finite, a NaN
//! `tmax`) take the single-ray walk.

use std::mem::MaybeUninit;

use glam::{Vec3, Vec4};

use super::kernels::FAR_SCALE;
use super::kernels::{PacketKernels, Portable};
#[cfg(target_arch = "x86_64")]
use super::simd::Avx;
use super::traverse::{closer, STACK};
use super::wide::{leaf_packets, LeafTest, LEAF, PACKET};
use super::{Bvh, Hit, Simd, TraversalStats};
use crate::geometry::ray::PARALLEL;
use crate::geometry::triangle::{RayShear, TriHit8};
use crate::geometry::Ray;

/// The most rays one packet holds: an 8x8 tile of camera rays.
pub(crate) const PACKET_RAYS: usize = 64;

/// The rays of one group, one lane each, in the layout the kernels load
/// eight at a time: directions, their reciprocals and the current `tmax`.
#[repr(C, align(32))]
pub(super) struct Lanes {
    pub(super) dir: [[f32; PACKET_RAYS]; 3],
    pub(super) inv: [[f32; PACKET_RAYS]; 3],
    pub(super) tmax: [f32; PACKET_RAYS],
}

impl Lanes {
    fn new() -> Self {
        Lanes {
            dir: [[0.0; PACKET_RAYS]; 3],
            inv: [[0.0; PACKET_RAYS]; 3],
            tmax: [f32::NEG_INFINITY; PACKET_RAYS],
        }
    }
}

/// The shear constants ([`RayShear`]) of a group's rays, one lane each,
/// when they are all sheared onto the same axes `k` and in f32: then a
/// leaf's triangle can be tested against eight of them at once.
#[repr(C, align(32))]
pub(super) struct Shears {
    pub(super) k: [usize; 3],
    pub(super) s: [[f32; PACKET_RAYS]; 3],
}

impl Shears {
    /// The shears of the group's first `n` rays, exactly as
    /// [`RayShear::within`] makes each, or `None` when they may differ in
    /// their axes or need the f64 test.
    fn of(l: &Lanes, n: usize, f: &Frustum, reach: f32) -> Option<Shears> {
        if RayShear::needs_f64(Vec3::from_array(f.o), reach) {
            return None;
        }
        // Every ray's largest component is on axis `kz` when every
        // reciprocal on it is smaller than every other axis's: rounding a
        // reciprocal is monotone, so `|1/a| < |1/b|` as rounded means `|a| >
        // |b|`. (A group's rays have no component below `PARALLEL`, so
        // `within` flushes none.)
        let (near, far) = (Vec3::from(f.lo).abs(), Vec3::from(f.hi).abs());
        let (least, most) = (near.min(far), near.max(far));
        let kz = (0..3).find(|&a| (0..3).all(|b| b == a || most[a] < least[b]))?;
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let k = if f.neg[kz] {
            [ky, kx, kz]
        } else {
            [kx, ky, kz]
        };
        let mut sh = Shears {
            k,
            s: [[0.0; PACKET_RAYS]; 3],
        };
        for b in 0..n.div_ceil(4) {
            let r = 4 * b..4 * b + 4;
            let dk = |a: usize| Vec4::from_slice(&l.dir[k[a]][r.clone()]);
            let (dx, dy, dz) = (dk(0), dk(1), dk(2));
            (dx / dz).write_to_slice(&mut sh.s[0][r.clone()]);
            (dy / dz).write_to_slice(&mut sh.s[1][r.clone()]);
            (Vec4::ONE / dz).write_to_slice(&mut sh.s[2][r]);
        }
        // Lanes past the rays (0 / 0 above) get finite constants: NaN
        // would keep a test of eight lanes from seeing that all missed.
        for s in &mut sh.s {
            s[n..].fill(0.0);
        }
        Some(sh)
    }
}

/// A group's frustum: the shared origin and, per axis, the range of the
/// rays' reciprocal directions, all of one sign.
#[derive(Clone, Copy)]
pub(super) struct Frustum {
    pub(super) o: [f32; 3],
    pub(super) lo: [f32; 3],
    pub(super) hi: [f32; 3],
    pub(super) neg: [bool; 3],
}

/// What a packet walk finds for each ray of its group.
trait Found {
    /// Any hit will do: the walk drops a ray at its first hit.
    const ANY: bool;
    /// Ray `lane` (of the group) hit triangle `prim` at `t`, `(u, v)`.
    fn hit(&mut self, lane: usize, hit: Hit);
}

/// Closest hits, kept as [`Bvh::intersect`] keeps them.
struct Closest<'a>(&'a mut [Option<Hit>]);

impl Found for Closest<'_> {
    const ANY: bool = false;
    #[inline(always)]
    fn hit(&mut self, lane: usize, hit: Hit) {
        let best = &mut self.0[lane];
        if closer(&hit, best.as_ref()) {
            *best = Some(hit);
        }
    }
}

/// Whether each ray is blocked.
struct Blocked<'a>(&'a mut [bool]);

impl Found for Blocked<'_> {
    const ANY: bool = true;
    #[inline(always)]
    fn hit(&mut self, lane: usize, _: Hit) {
        self.0[lane] = true;
    }
}

/// Hands lane `lane` of `h`, a hit of ray `i` on triangle `prim`, to
/// `found`; then narrows the ray's `tmax` to it or, when any hit will do,
/// drops the ray from `left = (active, todo)`.
#[inline(always)]
fn take<F: Found>(
    found: &mut F,
    lanes: &[u8],
    l: &mut Lanes,
    left: &mut (u64, u64),
    i: usize,
    (h, lane, prim): (&TriHit8, usize, u32),
) {
    let hit = Hit {
        t: h.t[lane],
        u: h.u[lane],
        v: h.v[lane],
        prim,
    };
    found.hit(lanes[i] as usize, hit);
    if F::ANY {
        left.0 &= !(1 << i);
        left.1 &= !(1 << i);
        l.tmax[i] = f32::NEG_INFINITY;
    } else {
        l.tmax[i] = l.tmax[i].min(hit.t);
    }
}

impl Bvh {
    /// The closest hit of every ray of `rays` into `hits`: exactly what
    /// [`Bvh::intersect`] finds for each. The rays are taken
    /// [`PACKET_RAYS`] at a time; those that start where the first of them
    /// starts are traced together as frustums (see the module comment), the
    /// others one by one.
    ///
    /// # Panics
    /// When `hits` is not as long as `rays`.
    pub fn intersect_packet(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        for (r, h) in rays.chunks(PACKET_RAYS).zip(hits.chunks_mut(PACKET_RAYS)) {
            h.fill(None);
            self.packet(r, &mut Closest(h));
        }
    }

    /// Whether anything lies in `(0, tmax]` of every ray of `rays`, into
    /// `blocked`: exactly what [`Bvh::occluded`] says for each (which
    /// triangle blocks a ray is not asked for, so the walk may find another
    /// than the single ray's).
    ///
    /// # Panics
    /// When `blocked` is not as long as `rays`.
    pub fn occluded_packet(&self, rays: &[Ray], blocked: &mut [bool]) {
        assert_eq!(rays.len(), blocked.len(), "one answer per ray");
        for (r, b) in rays
            .chunks(PACKET_RAYS)
            .zip(blocked.chunks_mut(PACKET_RAYS))
        {
            b.fill(false);
            self.packet(r, &mut Blocked(b));
        }
    }

    /// Up to [`PACKET_RAYS`] rays: grouped by direction signs (in the order
    /// of the rays within each group), each group walked as a frustum, the
    /// rays that fit no frustum walked alone.
    fn packet<F: Found>(&self, rays: &[Ray], found: &mut F) {
        let n = rays.len();
        debug_assert!(n <= PACKET_RAYS);
        if self.wide.nodes.is_empty() || n == 0 {
            return;
        }
        let mut all = Lanes::new();
        // Rays from the first ray's origin (to the bit), with a `tmax`
        // that is a number.
        let o = rays[0].origin.to_array().map(f32::to_bits);
        let mut same = 0u64;
        for (i, r) in rays.iter().enumerate() {
            for a in 0..3 {
                all.dir[a][i] = r.dir[a];
            }
            all.tmax[i] = r.tmax;
            let fits = r.origin.to_array().map(f32::to_bits) == o && !r.tmax.is_nan();
            same |= (fits as u64) << i;
        }
        if !rays[0].origin.is_finite() {
            same = 0;
        }
        // The reciprocals as `Ray::inv_dir` makes them, four at a time;
        // `ok`: rays with every one finite and nonzero; `neg`: per axis,
        // rays running toward -axis; `lo`, `hi`: their range over all rays.
        let (mut ok, mut neg) = (0u64, [0u64; 3]);
        let mut lo = [Vec4::INFINITY; 3];
        let mut hi = [Vec4::NEG_INFINITY; 3];
        for b in 0..n.div_ceil(4) {
            let r = 4 * b..4 * b + 4;
            let mut fine = glam::BVec4A::splat(true);
            let real = glam::BVec4A::from_array(std::array::from_fn(|k| 4 * b + k < n));
            for a in 0..3 {
                let d = Vec4::from_slice(&all.dir[a][r.clone()]);
                let flat = d.abs().cmplt(Vec4::splat(PARALLEL));
                let inv = Vec4::ONE / Vec4::select(flat, d * 0.0, d);
                inv.write_to_slice(&mut all.inv[a][r.clone()]);
                fine &= inv.abs().cmplt(Vec4::INFINITY) & inv.cmpne(Vec4::ZERO);
                neg[a] |= (inv.cmplt(Vec4::ZERO).bitmask() as u64) << (4 * b);
                lo[a] = lo[a].min(Vec4::select(real, inv, Vec4::INFINITY));
                hi[a] = hi[a].max(Vec4::select(real, inv, Vec4::NEG_INFINITY));
            }
            ok |= (fine.bitmask() as u64) << (4 * b);
        }
        let every = if n == PACKET_RAYS { !0 } else { (1 << n) - 1 };
        ok &= every & same;
        if ok != every {
            self.one_by_one(rays, !ok & every, found);
        }
        let mut lanes = [0u8; PACKET_RAYS];
        let one_sign = |m: u64| m & ok == 0 || m & ok == ok;
        if ok == every && neg.iter().all(|&m| one_sign(m)) {
            lanes.iter_mut().enumerate().for_each(|(i, l)| *l = i as u8);
            let lo = lo.map(|v| v.min_element());
            let hi = hi.map(|v| v.max_element());
            self.group(rays, &mut all, &lanes[..n], (lo, hi), found);
            return;
        }
        for oct in 0..8 {
            let pick = |a: usize| if oct & (1 << a) != 0 { neg[a] } else { !neg[a] };
            let mut m = ok & pick(0) & pick(1) & pick(2);
            if m == 0 {
                continue;
            }
            let mut l = Lanes::new();
            let mut k = 0;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                for a in 0..3 {
                    l.dir[a][k] = all.dir[a][i];
                    l.inv[a][k] = all.inv[a][i];
                }
                l.tmax[k] = all.tmax[i];
                lanes[k] = i as u8;
                k += 1;
            }
            let range = |a: usize, f: fn(f32, f32) -> f32| {
                l.inv[a][1..k].iter().fold(l.inv[a][0], |m, &x| f(m, x))
            };
            let lo = [0, 1, 2].map(|a| range(a, f32::min));
            let hi = [0, 1, 2].map(|a| range(a, f32::max));
            self.group(rays, &mut l, &lanes[..k], (lo, hi), found);
        }
    }

    /// The rays `which` (bits), that fit no frustum, each walked alone.
    #[cold]
    fn one_by_one<F: Found>(&self, rays: &[Ray], which: u64, found: &mut F) {
        for (r, ray) in rays
            .iter()
            .enumerate()
            .filter(|(i, _)| which & (1 << i) != 0)
        {
            let mut st = TraversalStats::default();
            if F::ANY {
                if self.occluded::<false>(ray, &mut st).is_some() {
                    let none = Hit {
                        t: 0.0,
                        u: 0.0,
                        v: 0.0,
                        prim: 0,
                    };
                    found.hit(r, none);
                }
            } else if let Some(h) = self.intersect::<false>(ray, &mut st) {
                found.hit(r, h);
            }
        }
    }

    /// Walks one group: rays `lanes` of `rays`, one origin, one octant, with
    /// their reciprocal directions and `tmax` in `l` and the range of the
    /// reciprocals per axis in `(lo, hi)`.
    fn group<F: Found>(
        &self,
        rays: &[Ray],
        l: &mut Lanes,
        lanes: &[u8],
        (lo, hi): ([f32; 3], [f32; 3]),
        found: &mut F,
    ) {
        let f = Frustum {
            o: rays[lanes[0] as usize].origin.to_array(),
            lo,
            hi,
            neg: hi.map(|x| x < 0.0),
        };
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.wide.simd.avx() {
            return if self.wide.simd.level() == Simd::Avx512 {
                // SAFETY: the level was detected: this CPU has AVX-512.
                unsafe { self.group_avx512(rays, lanes, &f, l, found, k) }
            } else {
                // SAFETY: `k` exists: this CPU has AVX.
                unsafe { self.group_avx(rays, lanes, &f, l, found, k) }
            };
        }
        self.group_with(rays, lanes, &f, l, found, &Portable)
    }

    /// The AVX kernels compiled for AVX-512, as the single-ray walk's
    /// `traverse_avx512` compiles them.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,bmi1,popcnt")]
    fn group_avx512<F: Found>(
        &self,
        rays: &[Ray],
        lanes: &[u8],
        f: &Frustum,
        l: &mut Lanes,
        found: &mut F,
        k: Avx,
    ) {
        self.group_with(rays, lanes, f, l, found, &k);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    fn group_avx<F: Found>(
        &self,
        rays: &[Ray],
        lanes: &[u8],
        f: &Frustum,
        l: &mut Lanes,
        found: &mut F,
        k: Avx,
    ) {
        self.group_with(rays, lanes, f, l, found, &k);
    }

    #[inline(always)]
    fn group_with<F: Found, K: PacketKernels>(
        &self,
        rays: &[Ray],
        lanes: &[u8],
        f: &Frustum,
        l: &mut Lanes,
        found: &mut F,
        k: &K,
    ) {
        if self.wide.stack <= STACK {
            let mut stack = [MaybeUninit::uninit(); STACK];
            self.walk_group(rays, lanes, f, l, found, &mut stack, k);
        } else {
            let mut stack = vec![MaybeUninit::uninit(); self.wide.stack];
            self.walk_group(rays, lanes, f, l, found, &mut stack, k);
        }
    }

    /// The rays `todo` of `left = (active, todo)` against the triangles of
    /// `leaf`, one ray against eight triangles a test, each ray's shear
    /// made when first needed (`shear.0` has a bit for each made). Returns
    /// whether any ray hit.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn leaf_by_ray<F: Found, K: PacketKernels>(
        &self,
        leaf: u32,
        rays: &[Ray],
        (sheared, shear): (&mut u64, &mut [MaybeUninit<RayShear>; PACKET_RAYS]),
        l: &mut Lanes,
        lanes: &[u8],
        left: &mut (u64, u64),
        found: &mut F,
        k: &K,
    ) -> bool {
        let mut changed = false;
        for p in &self.wide.packets[leaf_packets(leaf)] {
            let mut m = left.1;
            while m != 0 {
                let i = m.trailing_zeros() as usize;
                m &= m - 1;
                if *sheared & (1 << i) == 0 {
                    let ray = &rays[lanes[i] as usize];
                    shear[i].write(RayShear::within(ray.origin, ray.dir, self.reach));
                    *sheared |= 1 << i;
                }
                // SAFETY: written above, once `sheared` has bit `i`.
                let s = unsafe { shear[i].assume_init_ref() };
                let h = if F::ANY {
                    k.triangles::<false>(s, p, l.tmax[i])
                } else {
                    k.triangles::<true>(s, p, l.tmax[i])
                };
                changed |= h.mask != 0;
                for lane in h.lanes() {
                    let prim = self.prim[p.idx[lane] as usize];
                    take(found, lanes, l, left, i, (&h, lane, prim));
                    if F::ANY {
                        break;
                    }
                }
            }
        }
        changed
    }

    /// [`Bvh::leaf_by_ray`] one triangle against eight rays a test, with the
    /// rays' shears in lanes and their shared origin `o`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn leaf_by_triangle<F: Found, K: PacketKernels>(
        &self,
        leaf: u32,
        (o, sh): (&[f32; 3], &Shears),
        l: &mut Lanes,
        lanes: &[u8],
        left: &mut (u64, u64),
        found: &mut F,
        k: &K,
    ) -> bool {
        let mut changed = false;
        for p in &self.wide.packets[leaf_packets(leaf)] {
            for j in (0..PACKET).take_while(|&j| p.idx[j] != u32::MAX) {
                let mut blocks = left.1;
                while blocks != 0 {
                    let b = blocks.trailing_zeros() as usize / 8;
                    blocks &= !(0xff << (8 * b));
                    let h = if F::ANY {
                        k.rays_triangle::<false>((p, j), o, sh, l, b)
                    } else {
                        k.rays_triangle::<true>((p, j), o, sh, l, b)
                    };
                    let mut m = h.mask as u64 & (left.1 >> (8 * b)) & 0xff;
                    changed |= m != 0;
                    let prim = self.prim[p.idx[j] as usize];
                    while m != 0 {
                        let lane = m.trailing_zeros() as usize;
                        m &= m - 1;
                        take(found, lanes, l, left, 8 * b + lane, (&h, lane, prim));
                    }
                }
            }
        }
        changed
    }

    /// Whether the rays `todo` test the triangles of `leaf` one triangle
    /// against eight rays at a time, rather than one ray against eight
    /// triangles: when that takes no more tests.
    #[inline(always)]
    fn by_triangle(&self, leaf: u32, todo: u64) -> bool {
        match self.wide.leaf_test {
            #[cfg(test)]
            LeafTest::ByRay => false,
            #[cfg(test)]
            LeafTest::ByTriangle => true,
            LeafTest::Chosen => {
                let packets = &self.wide.packets[leaf_packets(leaf)];
                let blocks = (0..PACKET_RAYS / 8)
                    .filter(|b| todo >> (8 * b) & 0xff != 0)
                    .count();
                let triangles: usize = packets
                    .iter()
                    .map(|p| p.idx.iter().filter(|&&i| i != u32::MAX).count())
                    .sum();
                triangles * blocks <= todo.count_ones() as usize * packets.len()
            }
        }
    }

    /// The walk of a group, nearest child first by the frustum's entry
    /// distance, for any-hit rays too (unlike a single any-hit ray): a
    /// group's blockers are found sooner, and the rays they block drop out.
    /// Stack entries hold a child, where its box is (`node << 3 | slot`,
    /// for the rays' own test at a leaf) and the frustum's entry distance.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn walk_group<F: Found, K: PacketKernels>(
        &self,
        rays: &[Ray],
        lanes: &[u8],
        f: &Frustum,
        l: &mut Lanes,
        found: &mut F,
        stack: &mut [MaybeUninit<(u32, u32, f32)>],
        k: &K,
    ) {
        let w = &self.wide;
        let n = lanes.len();
        let mut active: u64 = if n == 64 { !0 } else { (1 << n) - 1 };
        let mut sheared = 0u64;
        let mut shear = [MaybeUninit::<RayShear>::uninit(); PACKET_RAYS];
        // The rays' shears in lanes, made at the first leaf that asks.
        let (mut shears, mut asked) = (None, false);
        // The farthest `tmax` of the rays still walking (the others have
        // `-inf`, as the lanes past the group's rays).
        let far = |l: &Lanes| {
            let m = l
                .tmax
                .chunks_exact(4)
                .fold(Vec4::NEG_INFINITY, |m, t| m.max(Vec4::from_slice(t)));
            m.max_element()
        };
        let mut tmax = far(l);
        let mut sp = 0;
        let (mut cur, mut at) = (0u32, 0u32);
        loop {
            if cur & LEAF == 0 {
                let node = &w.nodes[cur as usize];
                let (mask, tnear) = k.frustum(f, node, tmax);
                if mask != 0 {
                    let from = cur << 3;
                    let mut near = mask.trailing_zeros() as usize;
                    let mut m = mask & (mask - 1);
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let other = if tnear[i] < tnear[near] {
                            std::mem::replace(&mut near, i)
                        } else {
                            i
                        };
                        stack[sp].write((node.child[other], from | other as u32, tnear[other]));
                        sp += 1;
                    }
                    (cur, at) = (node.child[near], from | near as u32);
                    continue;
                }
            } else {
                let node = &w.nodes[(at >> 3) as usize];
                let todo = k.rays_box(f, l, node, (at & 7) as usize, active);
                let sh = if todo != 0 && self.by_triangle(cur, todo) {
                    if !asked {
                        asked = true;
                        shears = Shears::of(l, n, f, self.reach);
                    }
                    shears.as_ref()
                } else {
                    None
                };
                let mut left = (active, todo);
                let changed = match sh {
                    Some(sh) => {
                        self.leaf_by_triangle(cur, (&f.o, sh), l, lanes, &mut left, found, k)
                    }
                    None => {
                        let shear = (&mut sheared, &mut shear);
                        self.leaf_by_ray(cur, rays, shear, l, lanes, &mut left, found, k)
                    }
                };
                active = left.0;
                if changed {
                    if active == 0 {
                        return;
                    }
                    tmax = far(l);
                }
            }
            // Pop, skipping nodes beyond every ray's closest hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: every entry below `sp` was written by a push.
                let (c, a, d) = unsafe { stack[sp].assume_init() };
                if d <= tmax * FAR_SCALE {
                    (cur, at) = (c, a);
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(target_arch = "x86_64")]
    use crate::bvh::kernels::avx::{frustum_boxes_avx, rays_box_avx};
    use crate::bvh::kernels::portable::{frustum_boxes, rays_box};
    use crate::bvh::wide::{Node8, WIDTH};
    use crate::geometry::sampling::Rng;
    use crate::scene::{self, Builder, Geometry};
    use glam::Vec3;

    /// The kernels this CPU can run, saying which it cannot.
    fn kernels() -> Vec<Simd> {
        let v = Simd::available();
        if !v.contains(&Simd::Avx512) {
            eprintln!("note: this CPU has no AVX-512: its packet kernels are not tested here");
        }
        v
    }

    /// Packets find exactly what single rays find, with either kernel and
    /// either way of testing leaves: the closest hit (distance,
    /// barycentrics, triangle) and whether a ray is blocked. Returns the
    /// number of hits.
    fn agree(b: &mut Bvh, rays: &[Ray]) -> usize {
        let mut hits = 0;
        let ways = [LeafTest::Chosen, LeafTest::ByRay, LeafTest::ByTriangle];
        let stack = b.wide.stack;
        for (simd, way) in kernels().into_iter().flat_map(|k| ways.map(|w| (k, w))) {
            b.cap_simd(simd);
            b.wide.leaf_test = way;
            let mut got = vec![None; rays.len()];
            let mut blocked = vec![false; rays.len()];
            b.intersect_packet(rays, &mut got);
            b.occluded_packet(rays, &mut blocked);
            // A tree deeper than the machine stack holds walks on the heap:
            // the same answers.
            b.wide.stack = STACK + 1;
            let mut heap = (vec![None; rays.len()], vec![false; rays.len()]);
            b.intersect_packet(rays, &mut heap.0);
            b.occluded_packet(rays, &mut heap.1);
            b.wide.stack = stack;
            assert_eq!(heap, (got.clone(), blocked.clone()), "{simd}, {way:?}");
            let mut st = TraversalStats::default();
            for (i, r) in rays.iter().enumerate() {
                let want = b.intersect::<false>(r, &mut st);
                assert_eq!(got[i].map(|h| h.t.to_bits()), want.map(|h| h.t.to_bits()));
                assert_eq!(got[i], want, "ray {i} {r:?}, {simd}, {way:?}");
                let any = b.occluded::<false>(r, &mut st).is_some();
                assert_eq!(blocked[i], any, "ray {i} {r:?}, {simd}, {way:?}");
                hits += want.is_some() as usize;
            }
        }
        hits
    }

    /// A ray far from a soup of large flat triangles, whose test rounds
    /// its hit on triangle 16 to `t` = 0.99999756, before the ray enters
    /// that triangle's box at 1.0, and hits triangle 7 at 0.99999917: the
    /// packet reached 7's leaf first and then skipped 16's, the single ray
    /// the reverse. Hits never nearer than where the ray enters the triangle's box
    /// (`triangle::intersect`) make the order irrelevant.
    #[test]
    fn a_hit_rounded_before_its_box_is_found_whatever_the_order() {
        let v = Vec3::new;
        let mut tris = vec![[Vec3::ZERO; 3]; 17];
        tris[1] = [v(0.0, 794912.06, 0.0), Vec3::ZERO, v(0.0, 794912.06, 0.0)];
        tris[6] = [
            v(5.552735, 0.0, 0.0),
            v(-9.903025, 0.0, 0.0),
            v(0.0, -5.733448, 0.0),
        ];
        tris[7] = [Vec3::ZERO, v(0.0, 0.0, 326390.38), v(-9.230016, 0.0, 0.0)];
        tris[9] = [
            v(0.0, 7.669358, 0.0),
            v(0.0, -5.943702, 0.0),
            v(0.0, 7.669358, 0.0),
        ];
        tris[10] = [Vec3::ZERO, v(-283069.44, 3.4950614, 0.0), Vec3::ZERO];
        tris[16] = [v(-8.654379, 0.0, 0.0), v(0.0, 0.0, 673145.56), Vec3::ZERO];
        let o = v(391467.97, 1.0, -575141.8);
        // Rays at 7's corners, and one across it.
        let t = tris[7];
        let rays: Vec<Ray> = (0..PACKET_RAYS)
            .map(|k| {
                let w = match k {
                    59 => [0.9243295, 1.0 - 0.9243295, 0.0],
                    _ if k % 8 < 3 => [0, 1, 2].map(|i| (i == k % 8) as u8 as f32),
                    _ if k % 8 == 3 => [0.0, 1.0, 0.0],
                    _ => [0.0, 0.0, 1.0],
                };
                Ray::new(o, t[0] * w[0] + t[1] * w[1] + t[2] * w[2] - o)
            })
            .collect();
        let mut b = super::super::build(&Geometry::from_triangles(&tris), Builder::Median);
        agree(&mut b, &rays);
        let hit = b.intersect::<false>(&rays[59], &mut TraversalStats::default());
        assert_eq!(hit.map(|h| (h.t, h.prim)), Some((1.0, 7)));
    }

    /// Camera rays in 8x8 tiles (and in tiles cut short at the frame's
    /// edges), and shadow rays from one light to every hit: on small
    /// triangles, and on a box of large ones that whole tiles hit.
    #[test]
    fn camera_tiles_and_shadow_rays_find_what_single_rays_find() {
        for scene in ["teapot:3", "cornell"] {
            camera_tiles_and_shadow_rays(scene);
        }
    }

    fn camera_tiles_and_shadow_rays(scene: &str) {
        let s = scene::load::open(scene, &Default::default()).unwrap().scene;
        let (w, h) = (60, 44);
        let frame = s.camera.frame(w, h);
        for builder in [Builder::Sah, Builder::Median] {
            let mut b = super::super::build(&s.geometry, builder);
            let (mut hits, mut points) = (0, Vec::new());
            for y0 in (0..h).step_by(8) {
                for x0 in (0..w).step_by(8) {
                    let rays: Vec<Ray> = (y0..(y0 + 8).min(h))
                        .flat_map(|y| (x0..(x0 + 8).min(w)).map(move |x| (x, y)))
                        .map(|(x, y)| frame.ray(x as f64 + 0.5, y as f64 + 0.5))
                        .collect();
                    hits += agree(&mut b, &rays);
                    let mut st = TraversalStats::default();
                    points.extend(
                        rays.iter()
                            .filter_map(|r| b.intersect::<false>(r, &mut st).map(|h| r.at(h.t))),
                    );
                }
            }
            assert!(hits > 200, "{hits} hits");
            // The scene's point light, else one above the teapot.
            let light = match s.lights.first() {
                Some(&scene::Light::Point { position, .. }) => position,
                _ => Vec3::new(3.0, 9.0, 5.0),
            };
            let shadow: Vec<Ray> = points
                .iter()
                .map(|&p| Ray::segment(light, p - light, 1.0 - 1e-4))
                .collect();
            let mut blocked = 0;
            for chunk in shadow.chunks(PACKET_RAYS) {
                agree(&mut b, chunk);
                let mut st = TraversalStats::default();
                blocked += chunk
                    .iter()
                    .filter(|r| b.occluded::<false>(r, &mut st).is_some())
                    .count();
            }
            assert!(blocked > 0 && blocked < shadow.len(), "{blocked}");
        }
    }

    /// Random rays from one origin in every direction: a packet splits
    /// into its octants, rays of one packet pointing opposite ways.
    #[test]
    fn random_rays_in_all_directions_find_what_single_rays_find() {
        let s = scene::load::open("teapot:3", &Default::default())
            .unwrap()
            .scene;
        let mut b = super::super::build(&s.geometry, Builder::Sah);
        let bounds = s.geometry.bounds();
        let mut r = Rng::for_sample(7, 0, 22);
        let mut hits = 0;
        for k in 0..60 {
            let u = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            let o = bounds.min + (bounds.max - bounds.min) * (u * 1.6 - 0.3);
            let n = 1 + (k * 7) % PACKET_RAYS;
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    let d = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 2.0 - 1.0;
                    let tmax = if k % 3 == 0 {
                        r.next_f32() * 4.0
                    } else {
                        f32::INFINITY
                    };
                    Ray::segment(o, d, tmax)
                })
                .collect();
            hits += agree(&mut b, &rays);
        }
        assert!(hits > 100, "{hits} hits");
    }

    /// Rays no frustum takes (other origins, zero, tiny, infinite and NaN
    /// components, a NaN `tmax`) mixed into packets, axis-parallel and
    /// grazing rays, coplanar and overlapping triangles (ties go to the
    /// lower index), empty packets and packets longer than one.
    #[test]
    fn adversarial_packets_find_what_single_rays_find() {
        let (inf, nan) = (f32::INFINITY, f32::NAN);
        let mut tris = Vec::new();
        for i in 0..200 {
            let p = Vec3::new((i % 10) as f32, (i / 10 % 5) as f32, (i / 50) as f32);
            tris.push([p, p + Vec3::X, p + Vec3::Y]);
            // The same triangle again, and one coplanar beside it.
            tris.push([p, p + Vec3::X, p + Vec3::Y]);
            tris.push([p + Vec3::X, p + Vec3::Y, p + Vec3::new(1.0, 1.0, 0.0)]);
        }
        let mut b = super::super::build(&Geometry::from_triangles(&tris), Builder::Sah);
        let o = Vec3::new(4.5, 2.5, 9.0);
        let mut rays = Vec::new();
        let mut r = Rng::for_sample(1, 2, 3);
        for i in 0..160 {
            let (x, y) = ((i % 13) as f32 * 0.77, (i / 13) as f32 * 0.41);
            // Through vertices and edges of the grid now and then.
            let target = if i % 4 == 0 {
                Vec3::new((i % 10) as f32, (i % 5) as f32, (i % 4) as f32)
            } else {
                Vec3::new(x, y, r.next_f32() * 4.0)
            };
            rays.push(Ray::new(o, target - o));
        }
        let odd = [
            Ray::new(o, Vec3::new(0.0, 0.0, -1.0)),
            Ray::new(o, Vec3::new(-0.0, 1e-31, -1.0)),
            Ray::new(o, Vec3::new(0.1, 0.2, -inf)),
            Ray::new(o, Vec3::new(nan, 0.2, -1.0)),
            Ray::segment(o, Vec3::new(0.1, 0.2, -1.0), nan),
            Ray::segment(o, Vec3::new(0.1, 0.2, -1.0), -1.0),
            Ray::new(Vec3::new(4.5, 2.5, nan), Vec3::new(0.1, 0.2, -1.0)),
            Ray::new(Vec3::new(4.5, 2.5, 8.0), Vec3::new(0.1, 0.2, -1.0)),
            Ray::new(o, Vec3::ZERO),
            // Grazing: in the plane z = 1 of a layer, along x, and along
            // the layer's diagonal edges.
            Ray::new(Vec3::new(-1.0, 0.5, 1.0), Vec3::new(1.0, 0.0, 0.0)),
            Ray::new(Vec3::new(-1.0, 2.0, 1.0), Vec3::new(1.0, -1.0, 1e-20)),
        ];
        for (i, ray) in odd.iter().enumerate() {
            rays.insert(i * 13 % rays.len(), *ray);
        }
        // Rays running in the plane z = 1 from one origin.
        let g = Vec3::new(-1.0, -1.0, 1.0);
        for i in 0..40 {
            let a = i as f32 * 0.04;
            rays.push(Ray::new(g, Vec3::new(a.cos(), a.sin() + 1e-3, 0.0)));
        }
        let mut hits = agree(&mut b, &rays);
        for chunk in rays.chunks(PACKET_RAYS) {
            hits += agree(&mut b, chunk);
        }
        for n in [1, 2, 7, 63] {
            hits += agree(&mut b, &rays[..n]);
        }
        agree(&mut b, &[]);
        assert!(hits > 100, "{hits} hits");
        // A tree over nothing: every ray misses.
        let mut empty = super::super::build(&Geometry::from_triangles(&[]), Builder::Sah);
        assert_eq!(agree(&mut empty, &rays[..PACKET_RAYS]), 0);
    }

    /// A box of large triangles some 1e13 across, seen from inside: its
    /// rays need the f64 triangle test, which no group takes eight rays at
    /// a time.
    #[test]
    fn packets_far_from_the_origin_find_what_single_rays_find() {
        let s = 1e13;
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) * s;
        let mut tris = Vec::new();
        for a in 0..3 {
            for side in [-1.0, 1.0] {
                let p = |u: f32, v: f32| {
                    let mut q = [0.0; 3];
                    q[a] = side;
                    q[(a + 1) % 3] = u;
                    q[(a + 2) % 3] = v;
                    c(q[0], q[1], q[2])
                };
                tris.push([p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0)]);
                tris.push([p(-1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)]);
            }
        }
        let mut b = super::super::build(&Geometry::from_triangles(&tris), Builder::Sah);
        let o = c(0.1, 0.2, 0.3);
        let rays: Vec<Ray> = (0..PACKET_RAYS)
            .map(|i| {
                let (x, y) = ((i % 8) as f32 * 0.05, (i / 8) as f32 * 0.05);
                Ray::new(o, Vec3::new(x - 0.2, y - 0.2, -1.0))
            })
            .collect();
        // Every ray hits a wall, in each of the three ways of every kernel.
        assert_eq!(agree(&mut b, &rays), kernels().len() * 3 * PACKET_RAYS);
    }

    /// The frustum's box test lets through every box a ray of the group
    /// hits, at an entry distance no greater than the ray's, and the rays'
    /// own test at a leaf is the single-ray test, bit for bit, with either
    /// kernel.
    #[test]
    fn frustum_test_is_conservative_and_ray_tests_are_the_single_ray_test() {
        use crate::bvh::kernels::BoxRay;
        let mut r = Rng::for_sample(5, 5, 5);
        let mut f = |s: f32| (r.next_f32() * 2.0 - 1.0) * s;
        for k in 0..3000 {
            let mut node = Node8 {
                b: [[0.0; WIDTH]; 6],
                child: [0; WIDTH],
            };
            for lane in 0..WIDTH {
                for a in 0..3 {
                    let (p, q) = (f(4.0), f(4.0));
                    node.b[2 * a][lane] = p.min(q);
                    node.b[2 * a + 1][lane] = p.max(q);
                }
            }
            let o = Vec3::new(f(6.0), f(6.0), f(6.0));
            let sign = Vec3::new(f(1.0), f(1.0), f(1.0)).signum();
            let n = 1 + k % PACKET_RAYS;
            let rays: Vec<Ray> = (0..n)
                .map(|_| {
                    let d = (Vec3::new(f(1.0), f(1.0), f(1.0)).abs() + 1e-3) * sign;
                    Ray::segment(o, d, if k % 2 == 0 { inf() } else { f(8.0).abs() })
                })
                .collect();
            let mut l = Lanes::new();
            for (i, ray) in rays.iter().enumerate() {
                let inv = ray.inv_dir();
                for a in 0..3 {
                    l.inv[a][i] = inv[a];
                }
                l.tmax[i] = ray.tmax;
            }
            let (lo, hi) = (0..3).fold(([0.0; 3], [0.0; 3]), |(mut lo, mut hi), a| {
                lo[a] = l.inv[a][..n].iter().copied().fold(inf(), f32::min);
                hi[a] = l.inv[a][..n].iter().copied().fold(-inf(), f32::max);
                (lo, hi)
            });
            let fr = Frustum {
                o: o.to_array(),
                lo,
                hi,
                neg: hi.map(|x| x < 0.0),
            };
            let tmax = rays.iter().map(|r| r.tmax).fold(-inf(), f32::max);
            let (fmask, ftn) = frustum_boxes(&fr, &node, tmax);
            let active = if n == 64 { !0 } else { (1u64 << n) - 1 };
            for slot in 0..WIDTH {
                let mut want = 0u64;
                for (i, ray) in rays.iter().enumerate() {
                    let br = BoxRay::new(ray);
                    let (m, tn) = super::super::kernels::portable::hit_boxes(&br, &node, ray.tmax);
                    if m & (1 << slot) != 0 {
                        want |= 1 << i;
                        assert!(
                            fmask & (1 << slot) != 0,
                            "frustum misses a box ray {i} hits"
                        );
                        assert!(ftn[slot] <= tn[slot]);
                    }
                }
                assert_eq!(rays_box(&fr, &l, &node, slot, active), want);
                #[cfg(target_arch = "x86_64")]
                if std::is_x86_feature_detected!("avx") {
                    // SAFETY: AVX is present.
                    unsafe {
                        assert_eq!(rays_box_avx(&fr, &l, &node, slot, active), want);
                        let (m, t) = frustum_boxes_avx(&fr, &node, tmax);
                        assert_eq!(m, fmask);
                        assert_eq!(t.map(f32::to_bits), ftn.map(f32::to_bits));
                    }
                }
            }
        }
    }

    fn inf() -> f32 {
        f32::INFINITY
    }
}
