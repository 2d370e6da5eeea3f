//! The BVH's boxes over the image: the nodes of one level (stepping down
//! shows where the tree is deep), or every leaf.

use anyhow::{bail, Result};
use glam::Vec3;

use super::draw::{draw_box, Layer};
use crate::bvh::Bvh;
use crate::geometry::Aabb;
use crate::render::Tracer;

/// Boxes of the nodes exactly `level` edges below the root (level 0 is the
/// root); empty past the deepest level. Leaves above `level` are not
/// repeated, so stepping down shows where the tree is deep.
fn boxes_at_level(bvh: &Bvh, level: usize) -> Vec<Aabb> {
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
fn leaf_boxes(bvh: &Bvh) -> Vec<Aabb> {
    bvh.nodes
        .iter()
        .filter(|n| n.is_leaf())
        .map(|n| n.bounds())
        .collect()
}

/// Box outline colours, bright and far apart in hue so neighbours differ
/// (box `i` gets `BOX_COLORS[i % 6]`).
const BOX_COLORS: [Vec3; 6] = [
    Vec3::new(1.0, 0.85, 0.0),
    Vec3::new(0.0, 0.9, 1.0),
    Vec3::new(1.0, 0.1, 0.8),
    Vec3::new(0.3, 1.0, 0.1),
    Vec3::new(1.0, 0.35, 0.0),
    Vec3::new(0.45, 0.3, 1.0),
];

/// Outlines the boxes of level `k` on `layer`; says how many, or why there
/// is no such level.
pub(crate) fn level(layer: &mut Layer, tracer: &Tracer, k: usize) -> Result<String> {
    let bvh = tracer.bvh;
    let depth = bvh.stats.depth;
    if k >= depth {
        bail!(
            "bvh-level:{k}: this BVH has {}",
            match depth {
                0 => "no levels (the scene has no triangles)".to_string(),
                1 => "only level 0".to_string(),
                d => format!("levels 0 to {}", d - 1),
            }
        );
    }
    let b = boxes_at_level(bvh, k);
    outline(layer, tracer, &b);
    Ok(format!(
        "{} {} at level {k} of 0..{}",
        b.len(),
        if b.len() == 1 { "box" } else { "boxes" },
        depth - 1
    ))
}

/// Outlines the leaf boxes on `layer`; says how many and how full.
pub(crate) fn leaves(layer: &mut Layer, tracer: &Tracer) -> String {
    let bvh = tracer.bvh;
    let b = leaf_boxes(bvh);
    outline(layer, tracer, &b);
    format!(
        "{} leaf boxes, {:.2} triangles per leaf on average, {} at most",
        b.len(),
        bvh.stats.mean_leaf,
        bvh.stats.max_leaf
    )
}

fn outline(layer: &mut Layer, tracer: &Tracer, boxes: &[Aabb]) {
    for (i, b) in boxes.iter().enumerate() {
        let c = BOX_COLORS[i % BOX_COLORS.len()];
        draw_box(layer, &tracer.frame, b, Some(c));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{SceneRequest, Session};
    use crate::scene::{self, Builder};
    use crate::viz::View;

    fn teapot() -> Bvh {
        let s = scene::load::open("teapot:4", &Default::default())
            .unwrap()
            .scene;
        crate::bvh::build(&s.geometry, Builder::Sah)
    }

    fn session(w: u32, h: u32) -> Session {
        let mut req = SceneRequest::new("cornell");
        req.size = Some((w, h));
        Session::open(&req).unwrap().0
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
    fn level_past_the_deepest_is_an_error() {
        let s = session(16, 16);
        let (t, bvh) = (s.tracer(), &s.bvh);
        let e = crate::viz::draw(&t, View::Level(bvh.stats.depth))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("levels 0 to"), "{e}");
        let root = crate::viz::draw(&t, View::Level(0)).unwrap();
        assert_eq!(root.image.len(), 256);
        assert!(
            root.summary.starts_with("1 box at level 0"),
            "{}",
            root.summary
        );
    }
}
