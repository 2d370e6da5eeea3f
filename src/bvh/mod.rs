//! Bounding volume hierarchy: builders, node layout, traversal, statistics.

pub mod build;
pub mod node;
pub mod stats;
pub mod traverse;

pub use build::build;
pub use node::Node;
pub use stats::{BuildStats, TraversalStats};
pub use traverse::Hit;

/// A binary BVH over the triangles of a scene.
///
/// Triangles are copied in leaf order (`tris`) so a leaf reads contiguous
/// memory; `prim` maps each back to its index in the scene's geometry.
pub struct Bvh {
    pub nodes: Vec<Node>,
    pub tris: Vec<[[f32; 3]; 3]>,
    pub prim: Vec<u32>,
    pub stats: BuildStats,
}

impl Bvh {
    /// Bytes held by the tree and its leaf-order triangle copies.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.tris[..])
            + std::mem::size_of_val(&self.prim[..])
    }
}
