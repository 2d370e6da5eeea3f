//! Bounding volume hierarchy: builders, node layout, traversal, statistics.

pub(crate) mod build;
mod kernels;
pub(crate) mod node;
mod packet;
mod simd;
pub(crate) mod stats;
pub(crate) mod traverse;
mod wide;

pub use build::{build, build_full_sweep};
pub(crate) use node::Node;
pub(crate) use packet::PACKET_RAYS;
use simd::Detected;
pub use simd::Simd;
pub use stats::{BuildStats, TraversalStats};
pub(crate) use traverse::Hit;

/// A BVH over the triangles of a scene.
///
/// The builders make the binary tree `nodes` (what the statistics and debug
/// views describe) over the triangles in leaf order; `prim` maps each back
/// to its index in the scene's geometry. Traversal walks a wide tree
/// collapsed from it, with the same boxes and leaves, whose packets hold
/// the only copy of the triangles ([`Bvh::triangle`]).
pub struct Bvh {
    pub(crate) nodes: Vec<Node>,
    pub(crate) prim: Vec<u32>,
    pub(crate) stats: BuildStats,
    wide: wide::Wide,
    /// The largest coordinate magnitude of any triangle: rays test in f64
    /// beyond [`F32_REACH`](crate::geometry::triangle::F32_REACH).
    reach: f32,
}

impl Bvh {
    /// The SAH cost the SAH builder minimises: leaves cost one per packet of
    /// eight triangles, as traversal tests them. (`stats.sah_cost` counts
    /// every triangle.)
    pub fn packet_sah_cost(&self) -> f64 {
        build::sah_cost(&self.nodes, build::LEAF_BLOCK).2
    }

    /// The bytes its arrays hold: what `render --dry-run` reports.
    pub(crate) fn bytes(&self) -> u64 {
        fn of<T>(v: &[T]) -> u64 {
            std::mem::size_of_val(v) as u64
        }
        let w = &self.wide;
        of(&self.nodes)
            + of(&self.prim)
            + of(&w.nodes)
            + of(&w.packets)
            + of(&w.node_of)
            + of(&w.leaf_of)
            + of(&w.slot)
    }

    /// Triangles, as many as the scene has.
    pub fn triangle_count(&self) -> usize {
        self.prim.len()
    }

    /// The triangle at leaf-order position `i`, as traversal tests it.
    #[inline]
    pub fn triangle(&self, i: usize) -> [[f32; 3]; 3] {
        self.wide.triangle(i)
    }

    /// The binary tree the builder made, root first.
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// The triangle of each leaf slot, in leaf order.
    pub fn prims(&self) -> &[u32] {
        &self.prim
    }

    /// What the builder measured of its tree.
    pub fn stats(&self) -> &BuildStats {
        &self.stats
    }

    /// Edits every binary node with `f`, then collapses the traversal tree
    /// again from them (the stability tests break a box on purpose): the
    /// two trees never disagree.
    pub fn edit_nodes(&mut self, f: impl FnMut(&mut Node)) {
        self.nodes.iter_mut().for_each(f);
        let tris: Vec<_> = (0..self.triangle_count())
            .map(|i| self.triangle(i))
            .collect();
        self.wide = wide::Wide::collapse(&self.nodes, tris.len(), |i| tris[i]);
    }

    /// The SIMD kernels the walks use.
    pub fn simd(&self) -> Simd {
        self.wide.simd.level()
    }

    /// Walks with `most`'s kernels from now on, or the widest this CPU has
    /// if narrower: to compare them with the widest on the same machine.
    pub fn cap_simd(&mut self, most: Simd) {
        self.wide.simd = Detected::at_most(most);
    }

    /// Bytes held by the tree and its triangle packets.
    pub(crate) fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.prim[..])
            + self.wide.memory_bytes()
    }
}
