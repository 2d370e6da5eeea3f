//! The 8-wide tree that traversal walks, collapsed from the binary tree the
//! builders make: each node holds its eight children's boxes in SIMD layout
//! (eight lanes per bound and axis) and leaves hold triangles in packets of
//! eight, so one instruction tests eight boxes or eight triangles (four
//! without AVX).

use std::mem::MaybeUninit;

use rayon::prelude::*;

use super::simd::Detected;
use super::{Node, Simd};
use crate::memory;

/// Child references with this bit set are leaves:
/// `LEAF | first_packet << PACKET_BITS | (packets - 1)`.
pub(crate) const LEAF: u32 = 1 << 31;
const PACKET_BITS: u32 = 3;

/// Children per node.
pub(crate) const WIDTH: usize = 8;

#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Node8 {
    /// Min x, max x, min y, max y, min z, max z of the children, one lane
    /// each; an empty slot has min = +inf and max = -inf, which no finite
    /// ray hits.
    pub(crate) b: [[f32; WIDTH]; 6],
    /// An empty slot's child is [`EMPTY_LEAF`]: should a ray with NaN or
    /// infinite coordinates "hit" it, it finds nothing there, and no slot
    /// ever leads back up the tree.
    pub(crate) child: [u32; WIDTH],
}

/// The leaf of empty slots: packet 0, which holds no triangle.
pub(crate) const EMPTY_LEAF: u32 = LEAF;

/// Triangles per packet.
pub(crate) const PACKET: usize = 8;

/// Up to eight triangles of a leaf.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Packet {
    /// `p[vertex][axis][lane]`, one lane per triangle; padding lanes are NaN.
    pub(crate) p: [[[f32; PACKET]; 3]; 3],
    /// Leaf-order index of each lane's triangle.
    pub(crate) idx: [u32; PACKET],
}

impl Packet {
    /// Lanes holding a triangle.
    pub(crate) fn lanes(&self) -> u32 {
        self.p[0][0].iter().filter(|x| !x.is_nan()).count() as u32
    }
}

/// How a packet of rays tests a leaf's triangles: each ray against eight
/// triangles at a time, or each triangle against eight rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum LeafTest {
    /// Whichever makes fewer tests at this leaf.
    #[default]
    Chosen,
    /// Tests take one way at every leaf, to compare both on the same rays.
    #[cfg(test)]
    ByRay,
    #[cfg(test)]
    ByTriangle,
}

/// Packets of a leaf reference.
#[inline(always)]
pub(crate) fn leaf_packets(r: u32) -> std::ops::Range<usize> {
    let first = ((r & !LEAF) >> PACKET_BITS) as usize;
    first..first + (r & ((1 << PACKET_BITS) - 1)) as usize + 1
}

/// The triangles of one packet: the leaf-order position of the first, and
/// how many.
type Run = (u32, u32);

#[derive(Clone, Debug, Default)]
pub(crate) struct Wide {
    pub(crate) nodes: Vec<Node8>,
    pub(crate) packets: Vec<Packet>,
    /// Stack entries the deepest path can need, whatever the box tests
    /// answer: each node on it pushes at most all but one of its slots.
    pub(crate) stack: usize,
    /// The kernels the walks use: the widest this CPU has, unless capped.
    pub(super) simd: Detected,
    /// How packets test a leaf's triangles (chosen per leaf, except in
    /// tests that take each way on the same rays).
    pub(crate) leaf_test: LeafTest,
    /// The binary node whose box each wide node is, and the binary leaf of
    /// each packet (`u32::MAX` for the empty packet): what a logged walk
    /// reports in the binary tree's terms.
    pub(crate) node_of: Vec<u32>,
    pub(crate) leaf_of: Vec<u32>,
    /// Where each triangle (in leaf order) lies: `packet << PACKET_BITS | lane`.
    pub(crate) slot: Vec<u32>,
}

impl Wide {
    /// Collapses the binary tree `bin` (leaves over `count` triangles in
    /// leaf order, `tri(i)` the `i`-th): each wide node takes the binary
    /// node's children and keeps opening the largest interior one until it
    /// has eight.
    ///
    /// The walk that lays out the nodes runs on this thread; the packets,
    /// where the time goes (a scattered read of every vertex), are filled
    /// on the rayon pool in batches as the walk hands them out, so other
    /// threads fill while the walk goes on.
    pub(crate) fn collapse(bin: &[Node], count: usize, tri: impl Tri) -> Wide {
        let total = 1 + bin
            .par_iter()
            .with_min_len(4096)
            .filter(|n| n.is_leaf())
            .map(|n| (n.count as usize).div_ceil(PACKET))
            .sum::<usize>();
        let mut w = Wide {
            nodes: memory::room(bin.len() / 2 + 1),
            packets: memory::room(total),
            stack: 0,
            simd: Detected::at_most(Simd::Avx512),
            leaf_test: LeafTest::Chosen,
            node_of: Vec::with_capacity(bin.len() / 2 + 1),
            leaf_of: Vec::with_capacity(total),
            slot: memory::zeroed(count),
        };
        let mut packets = std::mem::take(&mut w.packets);
        rayon::scope(|s| {
            let mut runs = Runs {
                scope: s,
                tri: &tri,
                batch: Vec::with_capacity(BATCH),
                rest: &mut packets.spare_capacity_mut()[..total],
            };
            // Packet 0 holds no triangle: the empty slots' leaf.
            runs.push((0, 0));
            w.leaf_of.push(u32::MAX);
            if let Some(root) = bin.first() {
                // The root is always an interior wide node, even over one leaf.
                let depth = if root.is_leaf() {
                    w.node(bin, &mut runs, 0, &[0]).1
                } else {
                    w.gather(bin, &mut runs, 0).1
                };
                w.stack = depth * (WIDTH - 1);
            }
            runs.flush();
            assert!(runs.rest.is_empty(), "every packet is filled");
        });
        // SAFETY: the batches filled all `total` packets (checked above).
        unsafe { packets.set_len(total) };
        w.packets = packets;
        w
    }

    /// Wide node over the children of interior binary node `at` (at `c`
    /// and `c + 1`), opened up to eight; returns its index and the depth of
    /// its subtree in wide nodes.
    fn gather<F: Tri>(&mut self, bin: &[Node], runs: &mut Runs<F>, at: usize) -> (u32, usize) {
        let c = bin[at].first as usize;
        let mut kids = [0; WIDTH];
        kids[..2].copy_from_slice(&[c, c + 1]);
        let mut len = 2;
        while len < WIDTH {
            let open = (0..len)
                .filter(|&k| !bin[kids[k]].is_leaf())
                .max_by(|&a, &b| {
                    let area = |k: usize| bin[kids[k]].bounds().area();
                    area(a).total_cmp(&area(b))
                });
            let Some(k) = open else { break };
            let g = bin[kids[k]].first as usize;
            kids[k] = g;
            kids[len] = g + 1;
            len += 1;
        }
        self.node(bin, runs, at, &kids[..len])
    }

    fn node<F: Tri>(
        &mut self,
        bin: &[Node],
        runs: &mut Runs<F>,
        owner: usize,
        kids: &[usize],
    ) -> (u32, usize) {
        let at = self.nodes.len();
        self.node_of.push(owner as u32);
        let mut below = 0;
        let (inf, ninf) = (f32::INFINITY, f32::NEG_INFINITY);
        self.nodes.push(Node8 {
            b: [
                [inf; WIDTH],
                [ninf; WIDTH],
                [inf; WIDTH],
                [ninf; WIDTH],
                [inf; WIDTH],
                [ninf; WIDTH],
            ],
            child: [EMPTY_LEAF; WIDTH],
        });
        for (lane, &k) in kids.iter().enumerate() {
            let n = &bin[k];
            let r = if n.is_leaf() {
                self.leaf(runs, k, n.first as usize, n.count as usize)
            } else {
                let (r, need) = self.gather(bin, runs, k);
                below = below.max(need);
                r
            };
            let w = &mut self.nodes[at];
            for axis in 0..3 {
                w.b[2 * axis][lane] = n.min[axis];
                w.b[2 * axis + 1][lane] = n.max[axis];
            }
            w.child[lane] = r;
        }
        (at as u32, 1 + below)
    }

    /// Packets for the leaf over triangles `first..first + count`, to be
    /// filled from `runs`.
    fn leaf<F: Tri>(
        &mut self,
        runs: &mut Runs<F>,
        owner: usize,
        first: usize,
        count: usize,
    ) -> u32 {
        let at = self.leaf_of.len();
        for start in (first..first + count).step_by(PACKET) {
            let lanes = PACKET.min(first + count - start);
            let packet = (self.leaf_of.len() as u32) << PACKET_BITS;
            for (lane, s) in self.slot[start..start + lanes].iter_mut().enumerate() {
                *s = packet | lane as u32;
            }
            runs.push((start as u32, lanes as u32));
            self.leaf_of.push(owner as u32);
        }
        let n = self.leaf_of.len() - at;
        debug_assert!((1..=1 << PACKET_BITS).contains(&n));
        LEAF | (at as u32) << PACKET_BITS | (n as u32 - 1)
    }

    /// The triangle at leaf-order position `i`.
    #[inline]
    pub(crate) fn triangle(&self, i: usize) -> [[f32; 3]; 3] {
        let s = self.slot[i];
        let p = &self.packets[(s >> PACKET_BITS) as usize];
        let lane = (s & ((1 << PACKET_BITS) - 1)) as usize;
        p.p.map(|v| v.map(|axis| axis[lane]))
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.packets[..])
            + std::mem::size_of_val(&self.node_of[..])
            + std::mem::size_of_val(&self.leaf_of[..])
            + std::mem::size_of_val(&self.slot[..])
    }
}

/// Where the packets' triangles come from: the triangle at a leaf-order
/// position.
pub(crate) trait Tri: Fn(usize) -> [[f32; 3]; 3] + Sync {}
impl<F: Fn(usize) -> [[f32; 3]; 3] + Sync> Tri for F {}

/// Packets handed to the pool per batch: some hundred batches at a million
/// triangles, a few dozen at 70,000, so that a thread that finishes early
/// finds some left.
const BATCH: usize = 256;

/// The packets the walk has laid out and not yet handed to the pool, and
/// the room for them and those to come.
struct Runs<'a, 's, F> {
    scope: &'a rayon::Scope<'s>,
    tri: &'s F,
    batch: Vec<Run>,
    rest: &'s mut [MaybeUninit<Packet>],
}

impl<F: Tri> Runs<'_, '_, F> {
    fn push(&mut self, run: Run) {
        self.batch.push(run);
        if self.batch.len() == BATCH {
            self.flush();
        }
    }

    /// Fills the batch's packets on the pool (here, in order, when the pool
    /// has one thread: nothing to hand over, and the batches need not be
    /// held until the walk ends).
    fn flush(&mut self) {
        let (out, rest) = std::mem::take(&mut self.rest).split_at_mut(self.batch.len());
        self.rest = rest;
        let tri = self.tri;
        let fill = move |out: &mut [MaybeUninit<Packet>], batch: &[Run]| {
            for (o, &run) in out.iter_mut().zip(batch) {
                o.write(packet(run, tri));
            }
        };
        if rayon::current_num_threads() == 1 {
            fill(out, &self.batch);
            self.batch.clear();
        } else {
            let batch = std::mem::replace(&mut self.batch, Vec::with_capacity(BATCH));
            self.scope.spawn(move |_| fill(out, &batch));
        }
    }
}

/// The packet of the triangles of `run`, `tri(i)` the `i`-th.
fn packet((first, lanes): Run, tri: &impl Tri) -> Packet {
    let mut p = Packet {
        p: [[[f32::NAN; PACKET]; 3]; 3],
        idx: [u32::MAX; PACKET],
    };
    for lane in 0..lanes as usize {
        let i = first as usize + lane;
        for (pv, tv) in p.p.iter_mut().zip(&tri(i)) {
            for (pa, &x) in pv.iter_mut().zip(tv) {
                pa[lane] = x;
            }
        }
        p.idx[lane] = i as u32;
    }
    p
}
