//! Debug views of a BVH: the boxes of one level or of the leaves, the
//! traversal work of each camera ray (a heat map), and the heat colour map.
//!
//! The per-pixel heat of a [`Tracer`](crate::render::Tracer) is
//! `render::debug_view::heat`; this module stays free of shading.

use glam::Vec3;
use rayon::prelude::*;

use super::{Bvh, TraversalStats};
use crate::geometry::Aabb;
use crate::scene::camera::CameraFrame;

/// Boxes of the nodes exactly `level` edges below the root (level 0 is the
/// root); empty past the deepest level. Leaves above `level` are not
/// repeated, so stepping down shows where the tree is deep.
pub fn boxes_at_level(bvh: &Bvh, level: usize) -> Vec<Aabb> {
    let mut ids: Vec<u32> = if bvh.nodes.is_empty() {
        Vec::new()
    } else {
        vec![0]
    };
    for _ in 0..level {
        ids = ids
            .iter()
            .map(|&i| &bvh.nodes[i as usize])
            .filter(|n| !n.is_leaf())
            .flat_map(|n| [n.first, n.first + 1])
            .collect();
        if ids.is_empty() {
            break;
        }
    }
    ids.iter()
        .map(|&i| bvh.nodes[i as usize].bounds())
        .collect()
}

/// Boxes of every leaf, in node order.
pub fn leaf_boxes(bvh: &Bvh) -> Vec<Aabb> {
    bvh.nodes
        .iter()
        .filter(|n| n.is_leaf())
        .map(|n| n.bounds())
        .collect()
}

/// What a heat map counts per camera ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeatMeasure {
    NodesVisited,
    TriangleTests,
}

impl HeatMeasure {
    pub fn label(self) -> &'static str {
        match self {
            HeatMeasure::NodesVisited => "nodes visited",
            HeatMeasure::TriangleTests => "triangle tests",
        }
    }

    fn of(self, st: &TraversalStats) -> u32 {
        match self {
            HeatMeasure::NodesVisited => st.nodes_visited,
            HeatMeasure::TriangleTests => st.triangle_tests,
        }
    }
}

/// Per pixel (row-major), the closest-hit traversal work of the ray through
/// the pixel centre, rows in parallel.
pub fn heat_map(
    bvh: &Bvh,
    frame: &CameraFrame,
    width: u32,
    height: u32,
    measure: HeatMeasure,
) -> Vec<u32> {
    let mut out = vec![0u32; width as usize * height as usize];
    out.par_chunks_mut(width.max(1) as usize)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, v) in row.iter_mut().enumerate() {
                let ray = frame.ray(x as f64 + 0.5, y as f64 + 0.5);
                let mut st = TraversalStats::default();
                bvh.intersect::<true>(&ray, &mut st);
                *v = measure.of(&st);
            }
        });
    out
}

/// Largest value and mean of a heat map (0 and 0 when empty).
pub fn heat_summary(values: &[u32]) -> (u32, f64) {
    let max = values.iter().copied().max().unwrap_or(0);
    let sum: u64 = values.iter().map(|&v| v as u64).sum();
    (max, sum as f64 / values.len().max(1) as f64)
}

/// Viridis sampled at nine evenly spaced points, in sRGB: perceptually
/// uniform and readable by colour-blind viewers, dark for little work.
const VIRIDIS: [[u8; 3]; 9] = [
    [0x44, 0x01, 0x54],
    [0x47, 0x2d, 0x7b],
    [0x3b, 0x52, 0x8b],
    [0x2c, 0x72, 0x8e],
    [0x21, 0x91, 0x8c],
    [0x28, 0xae, 0x80],
    [0x5e, 0xc9, 0x62],
    [0xad, 0xdc, 0x30],
    [0xfd, 0xe7, 0x25],
];

/// Colour of `value` on a `0..=max` scale, in linear RGB (the image
/// buffers' space). Interpolation runs in sRGB, where the map is defined.
pub fn heat_color(value: u32, max: u32) -> Vec3 {
    let t = if max == 0 {
        0.0
    } else {
        (value as f32 / max as f32).min(1.0)
    };
    let x = t * (VIRIDIS.len() - 1) as f32;
    let i = (x as usize).min(VIRIDIS.len() - 2);
    let f = x - i as f32;
    let c = |k: usize| Vec3::from(VIRIDIS[k].map(|b| b as f32 / 255.0));
    let s = c(i).lerp(c(i + 1), f);
    Vec3::new(
        srgb_to_linear(s.x),
        srgb_to_linear(s.y),
        srgb_to_linear(s.z),
    )
}

fn srgb_to_linear(s: f32) -> f32 {
    if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{self, Builder};

    fn teapot() -> Bvh {
        let s = scene::load::open("teapot:4", &Default::default())
            .unwrap()
            .scene;
        super::super::build(&s.geometry, Builder::Sah)
    }

    #[test]
    fn level_zero_is_the_root_and_levels_nest_inside_it() {
        let bvh = teapot();
        let root = bvh.nodes[0].bounds();
        assert_eq!(boxes_at_level(&bvh, 0), vec![root]);
        let mut total = 0;
        for k in 0..bvh.stats.depth {
            let boxes = boxes_at_level(&bvh, k);
            assert!(!boxes.is_empty(), "level {k} of {}", bvh.stats.depth);
            let union = boxes.iter().fold(Aabb::EMPTY, |u, b| u.union(*b));
            assert!(root.contains(&union), "level {k}");
            total += boxes.len();
        }
        assert!(boxes_at_level(&bvh, bvh.stats.depth).is_empty());
        // Every node sits at exactly one level.
        assert_eq!(total, bvh.nodes.len());
        assert_eq!(boxes_at_level(&bvh, 1).len(), 2);
    }

    #[test]
    fn leaf_boxes_are_the_leaves() {
        let bvh = teapot();
        let leaves = leaf_boxes(&bvh);
        assert_eq!(leaves.len(), bvh.stats.leaves);
        let root = bvh.nodes[0].bounds();
        assert!(leaves.iter().all(|b| root.contains(b)));
    }

    #[test]
    fn heat_colour_runs_dark_to_bright_and_clamps() {
        let lum = |c: Vec3| c.dot(crate::render::film::LUMA);
        let steps: Vec<f32> = (0..=10).map(|v| lum(heat_color(v, 10))).collect();
        assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
        assert_eq!(heat_color(0, 0), heat_color(0, 10));
        assert_eq!(heat_color(20, 10), heat_color(10, 10));
        let top = heat_color(10, 10);
        assert!(top.x > 0.9 && top.y > 0.7 && top.z < 0.05, "{top}");
    }

    #[test]
    fn summary_of_values() {
        assert_eq!(heat_summary(&[1, 5, 3, 3]), (5, 3.0));
        assert_eq!(heat_summary(&[]), (0, 0.0));
    }
}
