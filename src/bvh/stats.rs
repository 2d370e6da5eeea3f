//! Build and traversal statistics shown in the TUI, the bench table and the inspector.

use serde::Serialize;

#[derive(Clone, Debug, Default, Serialize)]
pub struct BuildStats {
    pub(crate) builder: String,
    pub triangles: usize,
    pub(crate) nodes: usize,
    pub(crate) leaves: usize,
    /// Levels of the tree (a single leaf has depth 1).
    pub depth: usize,
    pub(crate) max_leaf: usize,
    pub(crate) mean_leaf: f64,
    /// Expected cost of a random ray, with node traversal and triangle test costing 1 each.
    pub sah_cost: f64,
    pub(crate) build_ms: f64,
}

impl BuildStats {
    pub(crate) fn triangles_per_second(&self) -> f64 {
        self.triangles as f64 / (self.build_ms.max(1e-6) * 1e-3)
    }
}

/// Work done by one traversal (or summed over many). Traversal walks the
/// 8-wide tree: `nodes_visited` counts its nodes, `boxes_hit`/`boxes_missed`
/// their child boxes, and `triangle_tests` the triangles in the leaf packets
/// tested (padding lanes not counted).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct TraversalStats {
    pub nodes_visited: u32,
    pub(crate) boxes_hit: u32,
    pub(crate) boxes_missed: u32,
    pub leaves: u32,
    pub(crate) triangle_tests: u32,
}

impl std::ops::AddAssign for TraversalStats {
    fn add_assign(&mut self, o: Self) {
        self.nodes_visited += o.nodes_visited;
        self.boxes_hit += o.boxes_hit;
        self.boxes_missed += o.boxes_missed;
        self.leaves += o.leaves;
        self.triangle_tests += o.triangle_tests;
    }
}
