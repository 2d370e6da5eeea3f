//! BVH builders: SAH and object median on the largest axis. Both build a
//! binary tree, in parallel on the rayon pool; the 8-wide tree that
//! traversal uses is collapsed from it (`wide.rs`).
//!
//! The SAH builder bins centroids (Wald 2007; 32 bins near the root, 16
//! lower down), refines the chosen split near the root by sweeping the
//! triangles of the two bins beside it, and sweeps nodes of up to twelve
//! triangles exactly. Leaves cost one per packet of eight triangles, as
//! traversal tests them, so nodes of up to eight triangles are leaves.
//! `build_full_sweep` sweeps every node: the reference its cost is
//! measured against.

use std::mem::MaybeUninit;
use std::time::Instant;

use glam::{Vec3A, Vec4};
use rayon::prelude::*;

use super::{wide, BuildStats, Bvh, Node};
use crate::memory;
use crate::scene::{Builder, Geometry};

/// Nodes with at least this many triangles use 32 bins per axis, smaller
/// ones 16; the SAH cost stays within a few percent of a full sweep.
const BIG: usize = 1024;
/// The SAH builder splits any node with more triangles than this.
pub(super) const MAX_LEAF: usize = 8;
/// The median builder stops splitting at this many triangles.
const MEDIAN_LEAF: usize = 4;
/// Triangles tested together (one packet), for the SAH's leaf cost.
pub(super) const LEAF_BLOCK: usize = 8;
/// Cost of one node traversal relative to one triangle test, for the SAH.
pub(super) const TRAVERSAL_COST: f32 = 1.0;
/// Past this depth the SAH builder makes median splits, which bounds the
/// depth (and so the traversal stack) at about 40 + log2(n / 4).
const SAH_DEPTH: usize = 40;
/// Nodes with at least this many triangles refine the binned split (large
/// triangles such as ground planes, which binning handles badly, show up
/// near the root; lower down refining costs more than it gains).
const REFINE: usize = 1024;
/// Nodes of up to this many triangles are split by an exact sweep: bins
/// cannot separate triangles whose centroids coincide on an axis (a cube's
/// faces), a sweep can, and for so few it costs little more.
const SWEEP: usize = 12;
/// Subtrees smaller than this are built on one thread. Small enough that
/// a 16,000-triangle mesh makes a few dozen tasks, and a thread left idle
/// at the end waits on at most a fraction of a millisecond's work.
const PARALLEL_SUBTREE: usize = 1024;
/// Nodes with more triangles than this bin them and bound their centroids
/// on several threads: near the root, where fewer nodes are open than
/// there are threads, the other threads would idle.
const PARALLEL_BINNING: usize = 1 << 13;
/// Triangles per task of that work; a refined split sorts its triangles on
/// several threads when it has more than this.
const PARALLEL_BLOCK: usize = PARALLEL_BINNING / 4;

/// A triangle's bounds in 32 bytes: the triangle's index rides in the
/// fourth lanes, split into two halves stored as (exact, normal) floats so
/// SIMD arithmetic on those lanes never meets a denormal or NaN.
#[derive(Clone, Copy)]
struct PrimRef {
    lo: Vec4,
    hi: Vec4,
}

impl PrimRef {
    #[inline(always)]
    fn new(min: Vec3A, max: Vec3A, index: u32) -> Self {
        PrimRef {
            lo: min.extend((index & 0xffff) as f32),
            hi: max.extend((index >> 16) as f32),
        }
    }

    #[inline(always)]
    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    #[inline(always)]
    fn max(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }

    #[inline(always)]
    fn index(&self) -> u32 {
        (self.hi.w as u32) << 16 | self.lo.w as u32
    }

    /// Twice the centroid.
    #[inline(always)]
    fn c(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo + self.hi)
    }
}

/// Bounds as SIMD vectors, for the builder's inner loops.
#[derive(Clone, Copy)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: Vec3A::splat(f32::INFINITY),
        max: Vec3A::splat(f32::NEG_INFINITY),
    };

    #[inline(always)]
    fn grow(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    #[inline(always)]
    fn union(self, o: Box3) -> Box3 {
        Box3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    #[inline(always)]
    fn area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    fn of(refs: &[PrimRef]) -> (Box3, Box3) {
        refs.iter()
            .fold((Box3::EMPTY, Box3::EMPTY), |(mut b, mut c), r| {
                b.min = b.min.min(r.min());
                b.max = b.max.max(r.max());
                c.grow(r.c());
                (b, c)
            })
    }
}

/// One subtree to build: its triangles, their bounds and centroid bounds.
struct Task<'a> {
    refs: &'a mut [PrimRef],
    /// Index of `refs[0]` in the leaf order.
    first: usize,
    bounds: Box3,
    cbounds: Box3,
    depth: usize,
}

/// How nodes are split.
#[derive(Clone, Copy, PartialEq)]
enum Method {
    /// Binned SAH.
    Binned,
    /// SAH with a full sweep at every node: slow, the quality reference.
    Sweep,
    Median,
}

/// Builds a BVH over every triangle of `geom`.
pub fn build(geom: &Geometry, builder: Builder) -> Bvh {
    let method = match builder {
        Builder::Sah => Method::Binned,
        Builder::Median => Method::Median,
    };
    let mut bvh = build_with(geom, method);
    bvh.stats.builder = builder.to_string();
    bvh
}

/// The SAH tree with every split chosen by a full sweep over the sorted
/// centroids (no binning): the reference for the binned builder's quality.
/// O(n log² n); meant for tests and benchmarks.
pub fn build_full_sweep(geom: &Geometry) -> Bvh {
    let mut bvh = build_with(geom, Method::Sweep);
    bvh.stats.builder = "sah-full-sweep".to_string();
    bvh
}

fn build_with(geom: &Geometry, method: Method) -> Bvh {
    let start_time = Instant::now();
    let n = geom.indices.len();
    let vertices = |i: usize| geom.indices[i].map(|v| geom.positions[v as usize]);
    let mut refs: Vec<PrimRef> = memory::room(n);
    (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let [a, b, c] = vertices(i).map(Vec3A::from);
            if a.is_finite() && b.is_finite() && c.is_finite() {
                PrimRef::new(a.min(b).min(c), a.max(b).max(c), i as u32)
            } else {
                // Never hit (its edge functions or t are not finite). Its
                // box is a point at the origin: NaN in a bound would be
                // dropped or kept by min and max depending on the order,
                // and could cut the boxes of its neighbours short.
                PrimRef::new(Vec3A::ZERO, Vec3A::ZERO, i as u32)
            }
        })
        .collect_into_vec(&mut refs);
    // A binary tree over n triangles has at most 2n - 1 nodes. Each subtree
    // gets its own part of this room, so subtrees build in parallel without
    // locks; `compact` then copies the nodes out. The room is left
    // uninitialised: most of it is never written, and so never takes memory.
    let mut scratch: Vec<Node> = Vec::with_capacity((2 * n).saturating_sub(1));
    let room = &mut scratch.spare_capacity_mut()[..(2 * n).saturating_sub(1)];
    let mut depth = 0;
    let mut nodes = Vec::new();
    if let Some((root, rest)) = room.split_first_mut() {
        let (bounds, cbounds) = refs.par_chunks(PARALLEL_SUBTREE).map(Box3::of).reduce(
            || (Box3::EMPTY, Box3::EMPTY),
            |(a, b), (c, d)| (a.union(c), b.union(d)),
        );
        let task = Task {
            refs: &mut refs,
            first: 0,
            bounds,
            cbounds,
            depth: 1,
        };
        let part;
        (depth, part) = subtree(method, task, root, rest, 1, &mut Binning::new());
        nodes = compact(room, &part);
    }
    // Freed before the wide tree is laid out: with the walk overlapping the
    // freeing, primary rays on the 1M teapot measured 5-9 % slower.
    drop(scratch);
    let mut prim: Vec<u32> = memory::room(n);
    refs.par_iter()
        .map(PrimRef::index)
        .collect_into_vec(&mut prim);
    drop(refs);
    // The packets are the one copy of the triangles the BVH keeps, gathered
    // from the scene in leaf order. The statistics are taken meanwhile.
    let tri = |i: usize| vertices(prim[i] as usize).map(|p| p.to_array());
    let (wide, mut stats) = rayon::join(
        || wide::Wide::collapse(&nodes, n, tri),
        || stats(&nodes, n, depth),
    );
    stats.build_ms = start_time.elapsed().as_secs_f64() * 1e3;
    let reach = nodes.first().map_or(0.0, |r| {
        r.min
            .iter()
            .chain(&r.max)
            .fold(0.0, |m: f32, x| m.max(x.abs()))
    });
    Bvh {
        nodes,
        prim,
        stats,
        wide,
        reach,
    }
}

/// Builds the subtree of `t` into `me` (its root) and `desc` (room for its
/// descendants, which start at index `base`); returns the subtree's depth
/// and where its nodes lie. `bins` is scratch space for the binned SAH.
///
/// Each side of a split gets room for as many nodes as it could need, so
/// the two build in parallel; small subtrees are built on one thread
/// ([`packed`]) at the front of their room, so that the room they leave
/// unused is never touched (and never takes memory).
fn subtree(
    method: Method,
    t: Task,
    me: &mut MaybeUninit<Node>,
    desc: &mut [MaybeUninit<Node>],
    base: usize,
    bins: &mut Binning,
) -> (usize, Part) {
    // On one thread the whole tree is packed: its nodes fill the front of
    // the room, and no scratch is allocated per split.
    if t.refs.len() <= PARALLEL_SUBTREE || rayon::current_num_threads() == 1 {
        let (depth, len) = packed(method, t, me, desc, base, bins);
        return (depth, Part::Packed { at: base, len });
    }
    let (left, right) = match open(method, t, me, base, bins) {
        Ok(sides) => sides,
        Err(depth) => return (depth, Part::Packed { at: base, len: 0 }),
    };
    let m = left.refs.len();
    let (pair, rest) = desc.split_at_mut(2);
    let (l, r) = pair.split_at_mut(1);
    let (ldesc, rdesc) = rest.split_at_mut(2 * m - 2);
    let (lbase, rbase) = (base + 2, base + 2 + 2 * m - 2);
    let mut other = Binning::new();
    let ((da, a), (db, b)) = rayon::join(
        || subtree(method, left, &mut l[0], ldesc, lbase, bins),
        || subtree(method, right, &mut r[0], rdesc, rbase, &mut other),
    );
    let len = 2 + a.len() + b.len();
    let part = Part::Split {
        at: base,
        len,
        sides: Box::new([a, b]),
    };
    (da.max(db), part)
}

/// Where the descendants of a node lie in the builder's room, for
/// [`compact`]: what [`packed`] built, and the splits above it that
/// [`subtree`] made in parallel, each with room for all it could need.
enum Part {
    /// `len` nodes from `at`, depth-first, siblings adjacent.
    Packed { at: usize, len: usize },
    /// The two children at `at` and `at + 1`, their descendants elsewhere;
    /// `len` nodes in all.
    Split {
        at: usize,
        len: usize,
        sides: Box<[Part; 2]>,
    },
}

impl Part {
    fn at(&self) -> usize {
        match *self {
            Part::Packed { at, .. } | Part::Split { at, .. } => at,
        }
    }

    /// Nodes without the unused room.
    fn len(&self) -> usize {
        match *self {
            Part::Packed { len, .. } | Part::Split { len, .. } => len,
        }
    }
}

/// [`subtree`] on one thread, with the nodes in depth-first order from the
/// front of `desc` (siblings adjacent, the left child's subtree first);
/// returns the depth and the nodes of `desc` used.
fn packed(
    method: Method,
    t: Task,
    me: &mut MaybeUninit<Node>,
    desc: &mut [MaybeUninit<Node>],
    base: usize,
    bins: &mut Binning,
) -> (usize, usize) {
    let (left, right) = match open(method, t, me, base, bins) {
        Ok(sides) => sides,
        Err(depth) => return (depth, 0),
    };
    let (pair, rest) = desc.split_at_mut(2);
    let (l, r) = pair.split_at_mut(1);
    let (da, ua) = packed(method, left, &mut l[0], rest, base + 2, bins);
    let (db, ub) = packed(
        method,
        right,
        &mut r[0],
        &mut rest[ua..],
        base + 2 + ua,
        bins,
    );
    (da.max(db), 2 + ua + ub)
}

/// Makes `me` the node of `t`: a leaf (`Err` with its depth), or an
/// interior node whose children will be at `base` and `base + 1`, with
/// the tasks of its two sides.
fn open<'a>(
    method: Method,
    mut t: Task<'a>,
    me: &mut MaybeUninit<Node>,
    base: usize,
    bins: &mut Binning,
) -> Result<(Task<'a>, Task<'a>), usize> {
    let n = t.refs.len();
    let (min, max) = (t.bounds.min.to_array(), t.bounds.max.to_array());
    let cut = match method {
        Method::Binned if t.depth <= SAH_DEPTH => split_sah(&mut t, bins),
        Method::Sweep if t.depth <= SAH_DEPTH => split_full(&mut t),
        _ => split_median(&mut t),
    };
    let Some(cut) = cut else {
        me.write(Node {
            min,
            first: t.first as u32,
            max,
            count: n as u32,
        });
        return Err(t.depth);
    };
    me.write(Node {
        min,
        first: base as u32,
        max,
        count: 0,
    });
    let m = cut.at;
    let (a, b) = t.refs.split_at_mut(m);
    let side = |refs, first, s: Side| Task {
        refs,
        first,
        bounds: s.bounds,
        cbounds: s.cbounds,
        depth: t.depth + 1,
    };
    Ok((side(a, t.first, cut.left), side(b, t.first + m, cut.right)))
}

/// A split node: the left half is `refs[..at]` (partitioned in place).
struct Cut {
    at: usize,
    left: Side,
    right: Side,
}

/// One half of a split.
struct Side {
    bounds: Box3,
    cbounds: Box3,
}

impl Side {
    fn of(refs: &[PrimRef]) -> Side {
        let (bounds, cbounds) = Box3::of(refs);
        Side { bounds, cbounds }
    }
}

/// Splits at `m`, computing the halves' bounds.
fn halves(refs: &[PrimRef], m: usize) -> Option<Cut> {
    Some(Cut {
        at: m,
        left: Side::of(&refs[..m]),
        right: Side::of(&refs[m..]),
    })
}

/// Leaf cost of `n` triangles: traversal tests them in packets of eight.
#[inline(always)]
fn blocks(n: usize) -> f32 {
    n.div_ceil(LEAF_BLOCK) as f32
}

/// Most bins per axis.
const MAX_BINS: usize = 32;

/// Per-axis bins: bounds and triangle counts.
#[derive(Clone)]
struct Bins {
    bounds: [[Box3; MAX_BINS]; 3],
    count: [[u32; MAX_BINS]; 3],
}

impl Bins {
    fn new() -> Self {
        Bins {
            bounds: [[Box3::EMPTY; MAX_BINS]; 3],
            count: [[0; MAX_BINS]; 3],
        }
    }

    /// Empties the first `b` bins of each axis.
    #[inline(always)]
    fn clear(&mut self, b: usize) {
        for axis in 0..3 {
            self.bounds[axis][..b].fill(Box3::EMPTY);
            self.count[axis][..b].fill(0);
        }
    }

    #[inline(always)]
    fn add(&mut self, r: &PrimRef, b: [usize; 3]) {
        for (axis, &k) in b.iter().enumerate() {
            let slot = &mut self.bounds[axis][k];
            slot.min = slot.min.min(r.min());
            slot.max = slot.max.max(r.max());
            self.count[axis][k] += 1;
        }
    }

    /// Adds the first `b` bins of `o` to these.
    #[inline(always)]
    fn merge(&mut self, o: &Self, b: usize) {
        for axis in 0..3 {
            for k in 0..b {
                self.bounds[axis][k] = self.bounds[axis][k].union(o.bounds[axis][k]);
                self.count[axis][k] += o.count[axis][k];
            }
        }
    }
}

/// Two sets of bins, filled by alternate triangles and then merged.
/// Neighbouring triangles often fall in the same bins, and each update of
/// a bin waits for the previous one's store; alternating sets halves that
/// chain. One pair serves a whole subtree, cleared per node: building a
/// fresh one per node cost more than filling it.
#[derive(Clone)]
struct Binning {
    even: Bins,
    odd: Bins,
}

impl Binning {
    fn new() -> Box<Self> {
        Box::new(Binning {
            even: Bins::new(),
            odd: Bins::new(),
        })
    }

    /// Adds `refs` to the first `B` bins of each set.
    #[inline(always)]
    fn add_all<const B: usize>(&mut self, binner: &Binner<B>, refs: &[PrimRef]) {
        let mut pairs = refs.chunks_exact(2);
        for p in &mut pairs {
            self.even.add(&p[0], binner.bin(p[0].c()));
            self.odd.add(&p[1], binner.bin(p[1].c()));
        }
        for r in pairs.remainder() {
            self.even.add(r, binner.bin(r.c()));
        }
    }

    /// The sum of both sets' first `b` bins, in `even`.
    #[inline(always)]
    fn sum(&mut self, b: usize) -> &Bins {
        self.even.merge(&self.odd, b);
        &self.even
    }
}

/// Maps a doubled centroid to its bin (of `B`) on each axis.
#[derive(Clone, Copy)]
struct Binner<const B: usize> {
    origin: Vec3A,
    scale: Vec3A,
}

impl<const B: usize> Binner<B> {
    /// The bin on each axis. Adding 2^23 rounds to an integer held in the
    /// low mantissa bits: one SIMD add instead of three checked conversions.
    /// Rounding `x - 0.5` rather than truncating `x` moves a value exactly on
    /// a bin boundary at most one bin, the same way for binning and
    /// partitioning, which is all the SAH needs. NaN clamps to bin 0.
    #[inline(always)]
    fn bin(&self, c: Vec3A) -> [usize; 3] {
        const MAGIC: f32 = 8_388_608.0;
        let f = ((c - self.origin) * self.scale - Vec3A::splat(0.5))
            .max(Vec3A::ZERO)
            .min(Vec3A::splat(B as f32 - 1.0))
            + Vec3A::splat(MAGIC);
        // The mask changes nothing (the value is below B, a power of two)
        // but lets the compiler drop bounds checks on the bins.
        let lane = |x: f32| (x.to_bits() - MAGIC.to_bits()) as usize & (B - 1);
        [lane(f.x), lane(f.y), lane(f.z)]
    }

    /// The bin on one axis, the same as `bin(c)[axis]`.
    #[inline(always)]
    fn bin_on<const AXIS: usize>(&self, c: Vec3A) -> usize {
        self.bin(c)[AXIS]
    }
}

/// The best SAH split of `t`, partitioned; `None` makes a leaf.
fn split_sah(t: &mut Task, bins: &mut Binning) -> Option<Cut> {
    match t.refs.len() {
        // One packet costs less than any split of it.
        0..=LEAF_BLOCK => None,
        n if n <= SWEEP => split_sweep(t),
        // Fewer bins for mid-sized nodes: there evaluating the bins costs
        // as much as filling them, and the bins are still narrow.
        n if n < BIG => split_binned::<16>(t, bins),
        _ => split_binned::<MAX_BINS>(t, bins),
    }
}

/// The best split of `t` over `B` bins per axis, partitioned.
fn split_binned<const B: usize>(t: &mut Task, binning: &mut Binning) -> Option<Cut> {
    let n = t.refs.len();
    let ext = t.cbounds.max - t.cbounds.min;
    let binner = Binner::<B> {
        origin: t.cbounds.min,
        scale: Vec3A::select(
            ext.cmpgt(Vec3A::ZERO),
            Vec3A::splat(B as f32) / ext,
            Vec3A::ZERO,
        ),
    };
    let bins: &Bins = if n > PARALLEL_BINNING && rayon::current_num_threads() > 1 {
        *binning = *t
            .refs
            .par_chunks(PARALLEL_BLOCK)
            .fold(Binning::new, |mut b, chunk| {
                b.add_all(&binner, chunk);
                b
            })
            .reduce(Binning::new, |mut a, b| {
                a.even.merge(&b.even, B);
                a.odd.merge(&b.odd, B);
                a
            });
        binning.sum(B)
    } else {
        binning.even.clear(B);
        binning.odd.clear(B);
        binning.add_all(&binner, t.refs);
        binning.sum(B)
    };
    // Best (cost, axis, last bin of the left side). Empty bins are swept
    // like the others (a branch on them mispredicts more than it saves);
    // the strict comparison keeps the first of equal splits.
    let mut best = (f32::INFINITY, 0, 0);
    for axis in 0..3 {
        if ext[axis] <= 0.0 {
            continue;
        }
        let (bb, bc) = (&bins.bounds[axis], &bins.count[axis]);
        // Right-to-left sweep stores the suffix costs, left-to-right evaluates.
        let mut right_cost = [0.0f32; B];
        let (mut rb, mut rn) = (Box3::EMPTY, 0u32);
        for i in (1..B).rev() {
            rb = rb.union(bb[i]);
            rn += bc[i];
            right_cost[i] = rb.area() * blocks(rn as usize);
        }
        let (mut lb, mut ln) = (Box3::EMPTY, 0u32);
        for i in 0..B - 1 {
            lb = lb.union(bb[i]);
            ln += bc[i];
            let cost = lb.area() * blocks(ln as usize) + right_cost[i + 1];
            let cost = if ln > 0 && (ln as usize) < n {
                cost
            } else {
                f32::INFINITY
            };
            if cost < best.0 {
                best = (cost, axis, i);
            }
        }
    }
    let best = (best.0 < f32::INFINITY).then_some(best);
    let Some((cost, axis, bin)) = best else {
        // All centroids coincide: split by index so leaves stay bounded.
        return (n > MAX_LEAF).then(|| halves(t.refs, n / 2)).flatten();
    };
    let split_cost = TRAVERSAL_COST + cost / t.bounds.area().max(f32::MIN_POSITIVE);
    if split_cost >= blocks(n) && n <= MAX_LEAF {
        return None;
    }
    if n < REFINE {
        let at = match axis {
            0 => partition_by(t.refs, |c| binner.bin_on::<0>(c) <= bin),
            1 => partition_by(t.refs, |c| binner.bin_on::<1>(c) <= bin),
            _ => partition_by(t.refs, |c| binner.bin_on::<2>(c) <= bin),
        };
        let union = |r: &[Box3]| r.iter().fold(Box3::EMPTY, |a, b| a.union(*b));
        return Some(Cut {
            at,
            left: Side {
                bounds: union(&bins.bounds[axis][..=bin]),
                cbounds: centroids(&t.refs[..at]),
            },
            right: Side {
                bounds: union(&bins.bounds[axis][bin + 1..B]),
                cbounds: centroids(&t.refs[at..]),
            },
        });
    }
    // Refine: the triangles of the two bins beside the chosen boundary are
    // sorted and every split between them is tried. Bins cannot separate a
    // ground plane from the triangles just above it; this can, and it never
    // does worse than the binned split, which is one of those tried.
    // Three groups: left of the two bins, in them, right of them.
    let refs = &mut *t.refs;
    let lo = partition_by(refs, |c| binner.bin(c)[axis] < bin);
    let hi = lo + partition_by(&mut refs[lo..], |c| binner.bin(c)[axis] <= bin + 1);
    let (c_lo, c_hi) = rayon::join(|| centroids(&refs[..lo]), || centroids(&refs[hi..]));
    let union = |r: std::ops::Range<usize>| {
        bins.bounds[axis][r]
            .iter()
            .fold(Box3::EMPTY, |a, b| a.union(*b))
    };
    let (b_lo, b_hi) = (union(0..bin), union((bin + 2).min(B)..B));
    let mid = &mut refs[lo..hi];
    // Sort by centroid: keys computed once, with the position to gather by.
    let key = |(k, r): (usize, &PrimRef)| (sort_key(r, axis), k as u32);
    // The keys are distinct: the order is the same either way.
    let sorted: Vec<PrimRef> = if mid.len() > PARALLEL_BLOCK {
        let mut keys: Vec<(u64, u32)> = mid.par_iter().enumerate().map(key).collect();
        keys.par_sort_unstable();
        keys.par_iter().map(|&(_, k)| mid[k as usize]).collect()
    } else {
        let mut keys: Vec<(u64, u32)> = mid.iter().enumerate().map(key).collect();
        keys.sort_unstable();
        keys.iter().map(|&(_, k)| mid[k as usize]).collect()
    };
    mid.copy_from_slice(&sorted);
    let m = mid.len();
    let mut right = vec![0.0f32; m + 1];
    let mut rb = b_hi;
    for j in (0..=m).rev() {
        if j < m {
            rb = rb.union(Box3 {
                min: mid[j].min(),
                max: mid[j].max(),
            });
        }
        right[j] = rb.area() * blocks(n - lo - j);
    }
    let mut best_j = None;
    let mut lb = b_lo;
    for j in 0..=m {
        if j > 0 {
            lb = lb.union(Box3 {
                min: mid[j - 1].min(),
                max: mid[j - 1].max(),
            });
        }
        let at = lo + j;
        if at == 0 || at == n {
            continue;
        }
        let cost = lb.area() * blocks(at) + right[j];
        if best_j.is_none_or(|(c, _, _)| cost < c) {
            best_j = Some((cost, j, lb));
        }
    }
    let Some((_, j, lb)) = best_j else {
        return halves(t.refs, n / 2);
    };
    let rb = mid[j..].iter().fold(b_hi, |b, r| {
        b.union(Box3 {
            min: r.min(),
            max: r.max(),
        })
    });
    let lc = mid[..j].iter().fold(c_lo, |mut b, r| {
        b.grow(r.c());
        b
    });
    let rc = mid[j..].iter().fold(c_hi, |mut b, r| {
        b.grow(r.c());
        b
    });
    Some(Cut {
        at: lo + j,
        left: Side {
            bounds: lb,
            cbounds: lc,
        },
        right: Side {
            bounds: rb,
            cbounds: rc,
        },
    })
}

/// Moves the triangles whose centroid satisfies `left` to the front and
/// returns how many there are. Without branches: which side a triangle
/// goes to is a coin toss to the branch predictor. (Centroid bounds are
/// taken afterwards, by [`centroids`] over the halves while they are in
/// cache: cheaper than growing both sides under a mask here.)
#[inline(always)]
fn partition_by(refs: &mut [PrimRef], left: impl Fn(Vec3A) -> bool) -> usize {
    // `refs[..i]` are left, `refs[i..j]` right.
    let mut i = 0;
    for j in 0..refs.len() {
        let go = left(refs[j].c());
        refs.swap(i, j);
        i += go as usize;
    }
    i
}

/// Bounds of the (doubled) centroids, on the rayon pool for large nodes.
fn centroids(refs: &[PrimRef]) -> Box3 {
    let serial = |refs: &[PrimRef]| {
        refs.iter().fold(Box3::EMPTY, |mut b, p| {
            b.grow(p.c());
            b
        })
    };
    if refs.len() <= PARALLEL_BINNING {
        return serial(refs);
    }
    refs.par_chunks(PARALLEL_BLOCK)
        .map(serial)
        .reduce(|| Box3::EMPTY, Box3::union)
}

/// Orders triangles by centroid on `axis`, ties by triangle index, so every
/// sweep breaks ties the same way.
#[inline(always)]
fn sort_key(r: &PrimRef, axis: usize) -> u64 {
    (order_key(r.c().to_array()[axis]) as u64) << 32 | r.index() as u64
}

/// A float's bits in an order that sorts like the float (total order).
#[inline(always)]
fn order_key(x: f32) -> u32 {
    let b = x.to_bits();
    if b >> 31 == 1 {
        !b
    } else {
        b | 1 << 31
    }
}

/// The exact sweep for a node of at most `SWEEP` triangles, without
/// allocating.
fn split_sweep(t: &mut Task) -> Option<Cut> {
    let n = t.refs.len();
    let mut order = [[0usize; SWEEP]; 3];
    for (axis, o) in order.iter_mut().enumerate() {
        // Centroid above, position below: one integer sort, ties by position.
        let mut keys = [0u64; SWEEP];
        for (key, (k, r)) in keys.iter_mut().zip(t.refs.iter().enumerate()) {
            *key = (order_key(r.c().to_array()[axis]) as u64) << 32 | k as u64;
        }
        keys[..n].sort_unstable();
        for (x, key) in o.iter_mut().zip(&keys[..n]) {
            *x = *key as u32 as usize;
        }
    }
    let mut right = [0.0f32; SWEEP];
    let [a, b, c] = &order;
    let (axis, at) = best_sweep(t, [&a[..n], &b[..n], &c[..n]], &mut right[..n])?;
    let mut sorted = [t.refs[0]; SWEEP];
    for (s, &k) in sorted.iter_mut().zip(&order[axis][..n]) {
        *s = t.refs[k];
    }
    t.refs.copy_from_slice(&sorted[..n]);
    halves(t.refs, at)
}

/// The full sweep for any node: the reference the binned builder is
/// measured against.
fn split_full(t: &mut Task) -> Option<Cut> {
    let n = t.refs.len();
    if n <= 1 {
        return None;
    }
    let order: [Vec<usize>; 3] = [0, 1, 2].map(|axis| {
        let mut keys: Vec<(u64, usize)> = t
            .refs
            .iter()
            .enumerate()
            .map(|(k, r)| (sort_key(r, axis), k))
            .collect();
        keys.sort_unstable();
        keys.into_iter().map(|k| k.1).collect()
    });
    let [a, b, c] = &order;
    let (axis, at) = best_sweep(t, [a, b, c], &mut vec![0.0; n])?;
    let sorted: Vec<PrimRef> = order[axis].iter().map(|&k| t.refs[k]).collect();
    t.refs.copy_from_slice(&sorted);
    halves(t.refs, at)
}

/// Sweeps every split position of the sorted `order` on each axis; returns
/// the best axis and position, or `None` when a leaf is cheaper. `right` is
/// scratch space.
fn best_sweep(t: &Task, order: [&[usize]; 3], right: &mut [f32]) -> Option<(usize, usize)> {
    let n = t.refs.len();
    let bounds = |k: usize| Box3 {
        min: t.refs[k].min(),
        max: t.refs[k].max(),
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, o) in order.iter().enumerate() {
        let mut rb = Box3::EMPTY;
        for i in (1..n).rev() {
            rb = rb.union(bounds(o[i]));
            right[i] = rb.area() * blocks(n - i);
        }
        let mut lb = Box3::EMPTY;
        for i in 1..n {
            lb = lb.union(bounds(o[i - 1]));
            let cost = lb.area() * blocks(i) + right[i];
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, at) = best?;
    let split_cost = TRAVERSAL_COST + cost / t.bounds.area().max(f32::MIN_POSITIVE);
    if split_cost >= blocks(n) && n <= MAX_LEAF {
        return None;
    }
    Some((axis, at))
}

/// Splits at the object median of the largest centroid axis.
fn split_median(t: &mut Task) -> Option<Cut> {
    let n = t.refs.len();
    if n <= MEDIAN_LEAF {
        return None;
    }
    let axis = (t.cbounds.max - t.cbounds.min).max_position();
    let mid = n / 2;
    t.refs.select_nth_unstable_by(mid, |a, b| {
        a.c().to_array()[axis].total_cmp(&b.c().to_array()[axis])
    });
    halves(t.refs, mid)
}

/// The tree without unused room, in depth-first order, siblings adjacent:
/// the root (at 0) and its descendants (`part`), copied on the rayon pool.
fn compact(scratch: &[MaybeUninit<Node>], part: &Part) -> Vec<Node> {
    let mut out = memory::room(1 + part.len());
    let room = &mut out.spare_capacity_mut()[..1 + part.len()];
    let (root, desc) = room.split_at_mut(1);
    root[0].write(moved(scratch, 0, part.at(), 1));
    place(scratch, part, desc, 1);
    // SAFETY: `place` wrote every node of `desc`: a part's nodes are the
    // two children and both sides' nodes, or a packed run, `len` in all.
    unsafe { out.set_len(1 + part.len()) };
    out
}

/// The node at `i` of `scratch`, whose children (if it has any) are the
/// first nodes of the part at `from`, for a tree where that part starts at
/// `to`.
#[inline(always)]
fn moved(scratch: &[MaybeUninit<Node>], i: usize, from: usize, to: usize) -> Node {
    // SAFETY: the root and the children of every node read here were
    // written by `open` (a node is written before its children are made,
    // and an interior node's `first` names its two children).
    let mut n = unsafe { scratch[i].assume_init() };
    if !n.is_leaf() {
        n.first = (n.first as usize - from + to) as u32;
    }
    n
}

/// Copies the nodes of `part` to `out`, which starts at index `to`.
fn place(scratch: &[MaybeUninit<Node>], part: &Part, out: &mut [MaybeUninit<Node>], to: usize) {
    match part {
        &Part::Packed { at, len } => {
            for (k, o) in out[..len].iter_mut().enumerate() {
                o.write(moved(scratch, at + k, at, to));
            }
        }
        Part::Split { at, sides, .. } => {
            let [a, b] = &**sides;
            let (pair, rest) = out.split_at_mut(2);
            let (ra, rb) = rest.split_at_mut(a.len());
            let (ta, tb) = (to + 2, to + 2 + a.len());
            pair[0].write(moved(scratch, *at, a.at(), ta));
            pair[1].write(moved(scratch, at + 1, b.at(), tb));
            rayon::join(|| place(scratch, a, ra, ta), || place(scratch, b, rb, tb));
        }
    }
}

/// The tree's statistics; `build_ms` is left to the caller.
fn stats(nodes: &[Node], triangles: usize, depth: usize) -> BuildStats {
    let (leaves, max_leaf, sah) = sah_cost(nodes, 1);
    BuildStats {
        builder: String::new(),
        triangles,
        nodes: nodes.len(),
        leaves,
        depth,
        max_leaf,
        mean_leaf: triangles as f64 / leaves.max(1) as f64,
        sah_cost: sah,
        build_ms: 0.0,
    }
}

/// Leaves, largest leaf and SAH cost of a binary tree, with a node
/// traversal costing `TRAVERSAL_COST` and a leaf 1 per `block` triangles
/// (rounded up).
pub(super) fn sah_cost(nodes: &[Node], block: usize) -> (usize, usize, f64) {
    let root_area = nodes
        .first()
        .map_or(1.0, |r| r.bounds().area().max(f32::MIN_POSITIVE) as f64);
    let mut leaves = 0;
    let mut max_leaf = 0;
    let mut sah = 0.0;
    for node in nodes {
        let a = node.bounds().area() as f64 / root_area;
        if node.is_leaf() {
            leaves += 1;
            max_leaf = max_leaf.max(node.count as usize);
            sah += a * (node.count as usize).div_ceil(block) as f64;
        } else {
            sah += a * TRAVERSAL_COST as f64;
        }
    }
    (leaves, max_leaf, sah)
}
