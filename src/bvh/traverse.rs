//! Closest-hit and any-hit traversal of the 8-wide tree, nearest child first.
//!
//! `STATS` is a compile-time switch: with `false` the counters vanish from
//! the generated code, so the fast path pays nothing for the inspector.

use std::mem::MaybeUninit;

use super::kernels::{BoxRay, Kernels, Portable, FAR_SCALE};
#[cfg(target_arch = "x86_64")]
use super::simd::Avx;
use super::wide::{leaf_packets, LEAF, PACKET};
use super::{Bvh, Simd, TraversalStats};
use crate::geometry::triangle::{intersect, RayShear, TriHit8};
use crate::geometry::Ray;

/// A closest hit: distance, barycentrics of vertices 1 and 2, and the
/// triangle's index in the scene geometry. Aligned to 16 bytes, so that an
/// `Option<Hit>` copied in 16-byte moves holds the hit in one of them:
/// packed after the tag, a hit handed to the shading (a camera ray's from
/// its packet) was read across two fresh stores, which the CPU cannot
/// forward, and the read waited for both to reach the cache (2 to 3 % of
/// a frame).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(align(16))]
pub struct Hit {
    pub t: f32,
    pub(crate) u: f32,
    pub(crate) v: f32,
    pub prim: u32,
}

/// Traversal stack entries on the machine stack (2 kB, left uninitialised):
/// enough for trees 36 wide levels deep (a level pushes at most seven).
/// The builders' trees are at most about 40 + log2(n) binary levels deep,
/// fewer wide ones; deeper trees get a stack on the heap. Either way the
/// stack holds [`Wide::stack`](super::wide::Wide) entries, the most any
/// ray can push, whatever its coordinates: empty slots lead to an empty
/// leaf, so the walk only goes down the tree.
pub(super) const STACK: usize = 256;

/// Whether `hit` replaces `best`: nearer, or as near and of a lower scene
/// triangle index. A ray through a shared edge or vertex then picks the
/// same triangle whatever the tree or the order of the tests.
#[inline(always)]
pub(super) fn closer(hit: &Hit, best: Option<&Hit>) -> bool {
    best.is_none_or(|b| hit.t < b.t || (hit.t == b.t && hit.prim < b.prim))
}

/// What a walk reports when `STATS` is on: the counts of
/// [`TraversalStats`], or the nodes themselves ([`WalkLog`]).
trait Tally {
    /// Wide node `at` was visited; `hit` of its child boxes were hit.
    fn node(&mut self, at: u32, hit: u32, missed: u32);
    /// The leaf reference `r` was visited.
    fn leaf(&mut self, r: u32);
    fn tests(&mut self, n: u32);
}

impl Tally for TraversalStats {
    #[inline(always)]
    fn node(&mut self, _at: u32, hit: u32, missed: u32) {
        self.nodes_visited += 1;
        self.boxes_hit += hit;
        self.boxes_missed += missed;
    }

    #[inline(always)]
    fn leaf(&mut self, _r: u32) {
        self.leaves += 1;
    }

    #[inline(always)]
    fn tests(&mut self, n: u32) {
        self.triangle_tests += n;
    }
}

/// One walk of one ray, as the debug views draw it: the binary nodes whose
/// boxes it visited, in order, and what it found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WalkLog {
    pub stats: TraversalStats,
    /// Binary node indices (`Bvh::nodes`), each once, in visiting order.
    pub visited: Vec<u32>,
    /// The scene triangle found: the closest hit, or any blocker.
    pub found: Option<u32>,
    /// Wide node indices and leaf references (with the `LEAF` bit).
    walked: Vec<u32>,
}

impl Tally for WalkLog {
    fn node(&mut self, at: u32, hit: u32, missed: u32) {
        self.stats.node(at, hit, missed);
        self.walked.push(at);
    }

    fn leaf(&mut self, r: u32) {
        self.stats.leaf(r);
        self.walked.push(r);
    }

    fn tests(&mut self, n: u32) {
        self.stats.tests(n);
    }
}

impl Bvh {
    /// The walk `intersect` (or, with `any`, `occluded`) makes for `ray`,
    /// logged node by node: the same code, counting into a log.
    pub fn walk_log(&self, ray: &Ray, any: bool) -> WalkLog {
        let mut log = WalkLog::default();
        if any {
            let mut found = None;
            self.traverse::<true, true>(ray, &mut log, |h, idx| {
                found = Some(self.prim[idx[h.mask.trailing_zeros() as usize] as usize]);
                0.0
            });
            log.found = found;
        } else {
            let mut best: Option<Hit> = None;
            self.traverse::<false, true>(ray, &mut log, self.keep_closest(&mut best));
            log.found = best.map(|h| h.prim);
        }
        let w = &self.wide;
        let mut seen = std::collections::HashSet::new();
        log.visited = log
            .walked
            .iter()
            .map(|&r| match r & LEAF {
                0 => w.node_of[r as usize],
                _ => w.leaf_of[leaf_packets(r).start],
            })
            .filter(|&n| n != u32::MAX && seen.insert(n))
            .collect();
        log
    }

    /// Binary nodes from the root down to the leaf holding scene triangle
    /// `prim` (empty when no leaf holds it).
    pub fn path_to(&self, prim: u32) -> Vec<u32> {
        let Some(slot) = self.prim.iter().position(|&p| p == prim) else {
            return Vec::new();
        };
        let slot = slot as u32;
        let mut parent = vec![u32::MAX; self.nodes.len()];
        let mut leaf = None;
        for (i, n) in self.nodes.iter().enumerate() {
            if n.is_leaf() {
                if (n.first..n.first + n.count).contains(&slot) {
                    leaf = Some(i as u32);
                }
            } else {
                parent[n.first as usize] = i as u32;
                parent[n.first as usize + 1] = i as u32;
            }
        }
        let mut path: Vec<u32> = std::iter::successors(leaf, |&n| {
            Some(parent[n as usize]).filter(|&p| p != u32::MAX)
        })
        .collect();
        path.reverse();
        path
    }

    /// Nearest hit in `(0, ray.tmax]`.
    #[inline]
    pub fn intersect<const STATS: bool>(&self, ray: &Ray, st: &mut TraversalStats) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        self.traverse::<false, STATS>(ray, st, self.keep_closest(&mut best));
        best
    }

    /// The closest-hit `on_hit`: keeps the closest of a packet's hits in
    /// `best` and returns its `t` as the new `tmax`.
    #[inline(always)]
    fn keep_closest<'b>(
        &'b self,
        best: &'b mut Option<Hit>,
    ) -> impl FnMut(&TriHit8, &[u32; PACKET]) -> f32 + 'b {
        move |h, idx| {
            for lane in h.lanes() {
                let hit = Hit {
                    t: h.t[lane],
                    u: h.u[lane],
                    v: h.v[lane],
                    prim: self.prim[idx[lane] as usize],
                };
                if closer(&hit, best.as_ref()) {
                    *best = Some(hit);
                }
            }
            best.map_or(f32::INFINITY, |b| b.t)
        }
    }

    /// Whether anything lies in `(0, ray.tmax]`; stops at the first hit found
    /// and returns that triangle.
    #[inline]
    pub fn occluded<const STATS: bool>(&self, ray: &Ray, st: &mut TraversalStats) -> Option<u32> {
        let mut found = None;
        self.traverse::<true, STATS>(ray, st, |h, idx| {
            found = Some(self.prim[idx[h.mask.trailing_zeros() as usize] as usize]);
            0.0
        });
        found
    }

    /// Walks the wide tree nearest child first. `on_hit` gets every packet
    /// with a hit and returns the new `tmax`; with `ANY` the walk stops at
    /// the first hit.
    #[inline(always)]
    fn traverse<const ANY: bool, const STATS: bool>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
    ) {
        if self.wide.nodes.is_empty() {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(k) = self.wide.simd.avx() {
            return if self.wide.simd.level() == Simd::Avx512 {
                // SAFETY: the level was detected: this CPU has AVX-512.
                unsafe { self.traverse_avx512::<ANY, STATS>(ray, st, on_hit, k) }
            } else {
                // SAFETY: `k` exists: this CPU has AVX.
                unsafe { self.traverse_avx::<ANY, STATS>(ray, st, on_hit, k) }
            };
        }
        self.traverse_with::<ANY, STATS, _>(ray, st, on_hit, &Portable)
    }

    /// The traversal with the AVX kernels, compiled for AVX-512 (F, VL, DQ,
    /// BW). The same tests in their EVEX forms have 32 vector registers
    /// instead of 16: the box test keeps a ray's splatted constants in them,
    /// where the AVX build reloads them from the stack at every node, and
    /// broadcasts fold into loads. They stay eight lanes wide, as a node and
    /// a leaf packet are: sixteen rays of a packet in a 512-bit register per
    /// box test measured no faster (BENCHMARKS.md).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512vl,avx512dq,avx512bw,bmi1,popcnt")]
    #[inline]
    fn traverse_avx512<const ANY: bool, const STATS: bool>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
        k: Avx,
    ) {
        self.traverse_with::<ANY, STATS, _>(ray, st, on_hit, &k);
    }

    /// The traversal compiled for AVX: eight boxes or eight triangles per
    /// instruction.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    fn traverse_avx<const ANY: bool, const STATS: bool>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
        k: Avx,
    ) {
        self.traverse_with::<ANY, STATS, _>(ray, st, on_hit, &k);
    }

    #[inline(always)]
    fn traverse_with<const ANY: bool, const STATS: bool, K: Kernels>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
        k: &K,
    ) {
        if self.wide.stack <= STACK {
            // Left uninitialised: clearing it would cost a ray that misses
            // as much as testing a node.
            let mut stack = [MaybeUninit::uninit(); STACK];
            self.walk::<ANY, STATS, K>(ray, st, &mut stack, on_hit, k);
        } else {
            self.walk_deep::<ANY, STATS, K>(ray, st, on_hit, k);
        }
    }

    #[cold]
    #[inline(never)]
    fn walk_deep<const ANY: bool, const STATS: bool, K: Kernels>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
        k: &K,
    ) {
        let mut stack = vec![MaybeUninit::uninit(); self.wide.stack];
        self.walk::<ANY, STATS, K>(ray, st, &mut stack, on_hit, k);
    }

    /// The walk itself; `stack` has room for the tree's deepest path.
    #[inline(always)]
    fn walk<const ANY: bool, const STATS: bool, K: Kernels>(
        &self,
        ray: &Ray,
        st: &mut impl Tally,
        stack: &mut [MaybeUninit<(u32, f32)>],
        mut on_hit: impl FnMut(&TriHit8, &[u32; PACKET]) -> f32,
        k: &K,
    ) {
        let w = &self.wide;
        let setup = || RayShear::within(ray.origin, ray.dir, self.reach);
        let boxes = BoxRay::new(ray);
        let mut tmax = ray.tmax;
        let mut sp = 0;
        // Tests wide node `at`'s boxes; the child to visit next, with the
        // others hit pushed, or `None` when no box is hit.
        macro_rules! visit {
            ($at:expr) => {{
                let at: u32 = $at;
                let node = &w.nodes[at as usize];
                let (mask, tnear) = k.boxes(&boxes, node, tmax);
                if STATS {
                    let slots = node.b[0].iter().filter(|x| x.is_finite()).count() as u32;
                    st.node(at, mask.count_ones(), slots - mask.count_ones());
                }
                if mask == 0 {
                    None
                } else if mask & (mask - 1) == 0 {
                    Some(node.child[mask.trailing_zeros() as usize])
                } else if ANY {
                    // Any hit will do: no ordering, the first lane next.
                    let mut m = mask & (mask - 1);
                    while m != 0 {
                        stack[sp].write((node.child[m.trailing_zeros() as usize], 0.0));
                        sp += 1;
                        m &= m - 1;
                    }
                    Some(node.child[mask.trailing_zeros() as usize])
                } else {
                    // Two or more hits: the nearest next, the others pushed
                    // (unsorted: sorting mispredicts more than it saves).
                    let mut near = mask.trailing_zeros() as usize;
                    let mut m = mask & (mask - 1);
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let far = if tnear[i] < tnear[near] {
                            std::mem::replace(&mut near, i)
                        } else {
                            i
                        };
                        stack[sp].write((node.child[far], tnear[far]));
                        sp += 1;
                    }
                    Some(node.child[near])
                }
            }};
        }
        // The root first, outside the loop: most camera rays that miss end
        // here, before what the compiler hoists out of the loop (the
        // triangle test's set-up, constants spilled for the leaves).
        let Some(mut cur) = visit!(0) else {
            return;
        };
        // Closest-hit rays set up the triangle test at their first leaf:
        // most of them (camera rays past the object) never reach one. Shadow
        // rays nearly always do.
        let mut shear = if ANY { Some(setup()) } else { None };
        loop {
            if cur & LEAF == 0 {
                if let Some(next) = visit!(cur) {
                    cur = next;
                    continue;
                }
            } else {
                if STATS {
                    st.leaf(cur);
                }
                for p in &w.packets[leaf_packets(cur)] {
                    if STATS {
                        st.tests(p.lanes());
                    }
                    let shear = shear.get_or_insert_with(setup);
                    // Any-hit traversal needs no barycentrics.
                    let h = if ANY {
                        k.triangles::<false>(shear, p, tmax)
                    } else {
                        k.triangles::<true>(shear, p, tmax)
                    };
                    if h.mask != 0 {
                        tmax = on_hit(&h, &p.idx);
                        if ANY {
                            return;
                        }
                    }
                }
            }
            // Pop, skipping nodes that now lie beyond the closest hit.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: every entry below `sp` was written by a push.
                let (c, d) = unsafe { stack[sp].assume_init() };
                if ANY || d <= tmax * FAR_SCALE {
                    cur = c;
                    break;
                }
            }
        }
    }

    /// Closest hit by testing every triangle: the reference the BVH is checked
    /// against, and the "no BVH" column of the benchmark.
    pub fn intersect_brute(&self, ray: &Ray) -> Option<Hit> {
        let shear = RayShear::within(ray.origin, ray.dir, self.reach);
        let mut tmax = ray.tmax;
        let mut best = None;
        for i in 0..self.triangle_count() {
            let t = self.triangle(i);
            if let Some(h) = intersect(&shear, &t[0], &t[1], &t[2], tmax) {
                let hit = Hit {
                    t: h.t,
                    u: h.u,
                    v: h.v,
                    prim: self.prim[i],
                };
                if closer(&hit, best.as_ref()) {
                    tmax = h.t;
                    best = Some(hit);
                }
            }
        }
        best
    }

    /// Any hit by testing every triangle.
    pub fn occluded_brute(&self, ray: &Ray) -> Option<u32> {
        let shear = RayShear::within(ray.origin, ray.dir, self.reach);
        (0..self.triangle_count())
            .find(|&i| {
                let t = self.triangle(i);
                intersect(&shear, &t[0], &t[1], &t[2], ray.tmax).is_some()
            })
            .map(|i| self.prim[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(target_arch = "x86_64")]
    use crate::bvh::kernels::avx::hit_boxes_avx;
    use crate::bvh::kernels::portable::hit_boxes;
    use crate::bvh::wide::{Node8, WIDTH};
    use crate::scene::{self, Builder, Geometry};

    /// Both eight-box tests agree with `Aabb::hit` lane by lane, bit for bit,
    /// grazing rays and rays starting inside a box included; empty slots
    /// (which `Aabb::hit`, swapping the slabs, would call hit) never hit.
    #[test]
    fn eight_box_tests_agree_with_the_scalar_slab_test() {
        use crate::geometry::sampling::Rng;
        use crate::geometry::Aabb;
        use glam::Vec3;
        let mut r = Rng::for_sample(3, 1, 4);
        let mut f = || {
            (r.next_f32() * 8.0 - 4.0).round() / 2.0
                + if r.next_u32().is_multiple_of(2) {
                    0.0
                } else {
                    r.next_f32()
                }
        };
        for k in 0..5000 {
            let mut node = Node8 {
                b: [[0.0; WIDTH]; 6],
                child: [0; WIDTH],
            };
            let mut boxes = [Aabb::EMPTY; WIDTH];
            for (lane, bx) in boxes.iter_mut().enumerate() {
                if (k + lane) % 5 != 0 {
                    let (a, b) = (Vec3::new(f(), f(), f()), Vec3::new(f(), f(), f()));
                    *bx = Aabb {
                        min: a.min(b),
                        max: a.max(b),
                    };
                }
                for axis in 0..3 {
                    node.b[2 * axis][lane] = bx.min[axis];
                    node.b[2 * axis + 1][lane] = bx.max[axis];
                }
            }
            let o = Vec3::new(f(), f(), f());
            // Rays through a box corner (where rounding decides), and zero
            // direction components, now and then.
            let mut d = Vec3::new(f(), f(), f());
            if k % 3 == 0 {
                d[k % 3] = 0.0;
            }
            if let Some(c) = boxes
                .iter()
                .filter(|b| !b.is_empty())
                .nth(k % 4)
                .filter(|_| k % 4 != 0)
            {
                d = Vec3::new(c.max.x, c.min.y, c.max.z) - o;
            }
            let ray = Ray::segment(o, d, if k % 2 == 0 { f32::INFINITY } else { 1.5 });
            let br = BoxRay::new(&ray);
            let inv = ray.inv_dir();
            let want: u32 = (0..WIDTH)
                .filter(|&i| {
                    !boxes[i].is_empty() && boxes[i].hit(o, inv.into(), ray.tmax).is_some()
                })
                .map(|i| 1 << i)
                .sum();
            let (mask, tnear) = hit_boxes(&br, &node, ray.tmax);
            assert_eq!(mask, want, "ray {ray:?}");
            for i in (0..WIDTH).filter(|i| want & (1 << i) != 0) {
                assert_eq!(Some(tnear[i]), boxes[i].hit(o, inv.into(), ray.tmax));
            }
            #[cfg(target_arch = "x86_64")]
            if std::is_x86_feature_detected!("avx") {
                // SAFETY: AVX is present.
                let (m, t) = unsafe { hit_boxes_avx(&br, &node, ray.tmax) };
                assert_eq!(m, mask);
                for i in (0..WIDTH).filter(|i| mask & (1 << i) != 0) {
                    assert_eq!(t[i], tnear[i]);
                }
            }
        }
    }

    /// Traversal is memory-safe whatever the floats: huge, infinite and NaN
    /// coordinates in the tree, NaN, infinite and zero rays. The stack
    /// cannot overflow (the 1e20 triangle once pushed past 128 entries:
    /// empty slots led back to the root), and where the answer is defined
    /// the BVH agrees with brute force.
    #[test]
    fn any_float_in_the_tree_or_the_ray_is_walked_safely() {
        use glam::Vec3;
        let (inf, nan) = (f32::INFINITY, f32::NAN);
        let mut tris = vec![
            [
                Vec3::ZERO,
                Vec3::new(1e20, 0.0, 0.0),
                Vec3::new(0.0, 1e20, 0.0),
            ],
            [
                Vec3::ZERO,
                Vec3::new(3e38, 0.0, 0.0),
                Vec3::new(0.0, 3e38, 1.0),
            ],
            [
                Vec3::ZERO,
                Vec3::new(inf, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            [Vec3::splat(-inf), Vec3::splat(inf), Vec3::ONE],
            [Vec3::new(nan, 0.0, 0.0), Vec3::ONE, Vec3::Y],
            [Vec3::splat(nan); 3],
        ];
        // Enough ordinary triangles for several levels of the tree.
        for i in 0..300 {
            let p = Vec3::new((i % 17) as f32, (i / 17) as f32, (i % 5) as f32);
            tris.push([p, p + Vec3::X, p + Vec3::Y]);
        }
        let origins = [
            Vec3::new(0.3, 0.2, 5.0),
            Vec3::ZERO,
            Vec3::splat(1e20),
            Vec3::splat(-3e38),
            Vec3::new(inf, 0.0, 0.0),
            Vec3::splat(nan),
        ];
        let dirs = [
            Vec3::new(0.01, 0.02, -1.0),
            Vec3::ZERO,
            Vec3::splat(inf),
            Vec3::new(nan, 1.0, 0.0),
            Vec3::new(-1.0, 1e-38, 0.0),
        ];
        let mut hits = 0;
        for builder in [Builder::Sah, Builder::Median] {
            let b = super::super::build(&Geometry::from_triangles(&tris), builder);
            let mut st = TraversalStats::default();
            for o in origins {
                for d in dirs {
                    for tmax in [f32::INFINITY, 1.0, nan] {
                        let ray = Ray::segment(o, d, tmax);
                        let hit = b.intersect::<true>(&ray, &mut st);
                        let any = b.occluded::<true>(&ray, &mut st);
                        if o.is_finite() && d.is_finite() && !tmax.is_nan() {
                            assert_eq!(hit, b.intersect_brute(&ray), "{ray:?}");
                            assert_eq!(any.is_some(), hit.is_some(), "{ray:?}");
                            hits += hit.is_some() as u32;
                        }
                    }
                }
            }
        }
        assert!(hits >= 4, "{hits} hits");
    }

    /// Every SIMD level this CPU has finds exactly what the portable walk
    /// finds, closest hits to the bit and any hits, on camera rays and on
    /// random rays (some parallel to an axis, some short), with the stack
    /// on the machine stack and on the heap.
    #[test]
    fn every_simd_level_finds_what_the_portable_walk_finds() {
        use crate::geometry::sampling::Rng;
        use glam::Vec3;
        let levels = Simd::available();
        if !levels.contains(&Simd::Avx512) {
            eprintln!("note: this CPU has no AVX-512: its walk is not tested here");
        }
        let s = scene::load::open("teapot:4", &Default::default())
            .unwrap()
            .scene;
        let mut b = super::super::build(&s.geometry, Builder::Sah);
        let frame = s.camera.frame(48, 32);
        let mut rays: Vec<Ray> = (0..48 * 32)
            .map(|i| frame.ray((i % 48) as f64 + 0.5, (i / 48) as f64 + 0.5))
            .collect();
        let bounds = s.geometry.bounds();
        let mut r = Rng::for_sample(5, 2, 7);
        for k in 0..4000 {
            let mut p = || {
                Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * (bounds.max - bounds.min)
                    + bounds.min
            };
            let (o, to) = (p(), p());
            let mut d = to - o;
            if k % 5 == 0 {
                d[k % 3] = 0.0;
            }
            let tmax = if k % 3 == 0 { 0.5 } else { f32::INFINITY };
            rays.push(Ray::segment(o, d, tmax));
        }
        let mut st = TraversalStats::default();
        b.cap_simd(Simd::Portable);
        let want: Vec<_> = rays
            .iter()
            .map(|r| {
                (
                    b.intersect::<false>(r, &mut st),
                    b.occluded::<false>(r, &mut st),
                )
            })
            .collect();
        let hits = want.iter().filter(|w| w.0.is_some()).count();
        assert!(hits > 1000, "{hits} hits");
        let stack = b.wide.stack;
        for heap in [false, true] {
            // A tree deeper than the machine stack holds walks on the heap.
            b.wide.stack = if heap { STACK + 1 } else { stack };
            for &level in &levels {
                b.cap_simd(level);
                for (r, (hit, any)) in rays.iter().zip(&want) {
                    let got = b.intersect::<false>(r, &mut st);
                    assert_eq!(got.map(|h| h.t.to_bits()), hit.map(|h| h.t.to_bits()));
                    assert_eq!(got, *hit, "{level}, heap {heap}, {r:?}");
                    let blocked = b.occluded::<false>(r, &mut st).is_some();
                    assert_eq!(blocked, any.is_some(), "{level}, heap {heap}, {r:?}");
                }
            }
        }
    }

    /// The walk with a heap stack, which trees too deep for the machine stack
    /// take, and the box test without AVX find the same hits as the usual
    /// walk.
    #[test]
    fn deep_walk_agrees_with_the_usual_walk() {
        let s = scene::load::open("teapot:4", &Default::default())
            .unwrap()
            .scene;
        let b = super::super::build(&s.geometry, Builder::Sah);
        let frame = s.camera.frame(48, 32);
        let mut hits = 0;
        for y in 0..32 {
            for x in 0..48 {
                let ray = frame.ray(x as f64 + 0.5, y as f64 + 0.5);
                let mut st = TraversalStats::default();
                let want = b.intersect::<false>(&ray, &mut st);
                let mut got = None;
                b.walk_deep::<false, false, _>(&ray, &mut st, b.keep_closest(&mut got), &Portable);
                assert_eq!(got, want);
                hits += want.is_some() as u32;
            }
        }
        assert!(hits > 100);
    }
}
