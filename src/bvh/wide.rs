//! The 8-wide tree that traversal walks, collapsed from the binary tree the
//! builders make: each node holds its eight children's boxes in SIMD layout
//! (eight lanes per bound and axis) and leaves hold triangles in packets of
//! eight, so one instruction tests eight boxes or eight triangles (four
//! without AVX).

use rayon::prelude::*;

use super::Node;
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
    pub b: [[f32; WIDTH]; 6],
    /// An empty slot's child is [`EMPTY_LEAF`]: should a ray with NaN or
    /// infinite coordinates "hit" it, it finds nothing there, and no slot
    /// ever leads back up the tree.
    pub child: [u32; WIDTH],
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
    pub p: [[[f32; PACKET]; 3]; 3],
    /// Leaf-order index of each lane's triangle.
    pub idx: [u32; PACKET],
}

impl Packet {
    /// Lanes holding a triangle.
    pub fn lanes(&self) -> u32 {
        self.p[0][0].iter().filter(|x| !x.is_nan()).count() as u32
    }
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
    pub nodes: Vec<Node8>,
    pub packets: Vec<Packet>,
    /// Stack entries the deepest path can need, whatever the box tests
    /// answer: each node on it pushes at most all but one of its slots.
    pub stack: usize,
    /// Whether this CPU can test eight boxes at once (AVX).
    pub avx: bool,
    /// The binary node whose box each wide node is, and the binary leaf of
    /// each packet (`u32::MAX` for the empty packet): what a logged walk
    /// reports in the binary tree's terms.
    pub node_of: Vec<u32>,
    pub leaf_of: Vec<u32>,
    /// Where each triangle (in leaf order) lies: `packet << PACKET_BITS | lane`.
    pub slot: Vec<u32>,
}

impl Wide {
    /// Collapses the binary tree `bin` (leaves over `count` triangles in
    /// leaf order, `tri(i)` the `i`-th): each wide node takes the binary
    /// node's children and keeps opening the largest interior one until it
    /// has eight.
    pub fn collapse(
        bin: &[Node],
        count: usize,
        tri: impl Fn(usize) -> [[f32; 3]; 3] + Sync,
    ) -> Wide {
        Wide::plan(bin, count).fill(tri)
    }

    /// The walk of [`Wide::collapse`]: lays out the nodes and decides which
    /// triangles each packet holds, on this thread. The packets, where the
    /// time goes (a scattered read of every vertex), are left to
    /// [`Plan::fill`], on the rayon pool.
    pub fn plan(bin: &[Node], count: usize) -> Plan {
        let mut w = Wide {
            nodes: memory::room(bin.len() / 2 + 1),
            packets: Vec::new(),
            stack: 0,
            avx: avx_available(),
            node_of: Vec::with_capacity(bin.len() / 2 + 1),
            leaf_of: Vec::with_capacity(count / 3 + 2),
            // SAFETY: zero bytes are a u32.
            slot: unsafe { memory::zeroed(count) },
        };
        // Packet 0 holds no triangle: the empty slots' leaf.
        let mut runs: Vec<Run> = Vec::with_capacity(count / 3 + 2);
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
        Plan { wide: w, runs }
    }

    /// Wide node over the children of interior binary node `at` (at `c`
    /// and `c + 1`), opened up to eight; returns its index and the depth of
    /// its subtree in wide nodes.
    fn gather(&mut self, bin: &[Node], runs: &mut Vec<Run>, at: usize) -> (u32, usize) {
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

    fn node(
        &mut self,
        bin: &[Node],
        runs: &mut Vec<Run>,
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
    fn leaf(&mut self, runs: &mut Vec<Run>, owner: usize, first: usize, count: usize) -> u32 {
        let at = runs.len();
        for start in (first..first + count).step_by(PACKET) {
            let lanes = PACKET.min(first + count - start);
            let packet = (runs.len() as u32) << PACKET_BITS;
            for (lane, s) in self.slot[start..start + lanes].iter_mut().enumerate() {
                *s = packet | lane as u32;
            }
            runs.push((start as u32, lanes as u32));
            self.leaf_of.push(owner as u32);
        }
        let n = runs.len() - at;
        debug_assert!((1..=1 << PACKET_BITS).contains(&n));
        LEAF | (at as u32) << PACKET_BITS | (n as u32 - 1)
    }

    /// The triangle at leaf-order position `i`.
    #[inline]
    pub fn triangle(&self, i: usize) -> [[f32; 3]; 3] {
        let s = self.slot[i];
        let p = &self.packets[(s >> PACKET_BITS) as usize];
        let lane = (s & ((1 << PACKET_BITS) - 1)) as usize;
        p.p.map(|v| v.map(|axis| axis[lane]))
    }

    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.packets[..])
            + std::mem::size_of_val(&self.node_of[..])
            + std::mem::size_of_val(&self.leaf_of[..])
            + std::mem::size_of_val(&self.slot[..])
    }
}

/// A wide tree laid out, its packets still to be filled.
pub(crate) struct Plan {
    wide: Wide,
    /// The triangles of each packet.
    runs: Vec<Run>,
}

impl Plan {
    /// The wide tree, with its packets filled from `tri(i)`, the triangle
    /// at leaf-order position `i`.
    pub fn fill(self, tri: impl Fn(usize) -> [[f32; 3]; 3] + Sync) -> Wide {
        let Plan { wide: mut w, runs } = self;
        w.packets = memory::room(runs.len());
        runs.par_iter()
            .with_min_len(1024)
            .map(|&(first, lanes)| {
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
            })
            .collect_into_vec(&mut w.packets);
        w
    }
}

#[cfg(target_arch = "x86_64")]
fn avx_available() -> bool {
    std::is_x86_feature_detected!("avx")
}

#[cfg(not(target_arch = "x86_64"))]
fn avx_available() -> bool {
    false
}
