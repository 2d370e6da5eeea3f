//! The selected pixel's ray tree drawn into the image: every ray as a
//! projected segment, shadow rays red when occluded and white when clear.

use glam::Vec3;

use crate::inspect::{PixelTree, RayNode};
use crate::render::overlay::{self, Layer};
use crate::render::recorder::RayKind;
use crate::scene::camera::CameraFrame;

const OCCLUDED: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const CLEAR: Vec3 = Vec3::ONE;

fn kind_color(k: RayKind) -> Vec3 {
    match k {
        RayKind::Camera => Vec3::new(1.0, 1.0, 0.0),
        RayKind::Reflection => Vec3::new(0.0, 1.0, 1.0),
        RayKind::Glossy => Vec3::new(0.3, 0.5, 1.0),
        RayKind::Transmission => Vec3::new(0.0, 1.0, 0.0),
    }
}

/// Draws every ray of `tree`; rays that miss are drawn `reach` long.
pub fn draw(layer: &mut Layer, frame: &CameraFrame, tree: &PixelTree, reach: f32) {
    let mut seg = |a: Vec3, b: Vec3, c: Vec3| overlay::draw_segment(layer, frame, a, b, Some(c));
    let mut stack: Vec<&RayNode> = vec![&tree.root];
    while let Some(n) = stack.pop() {
        let end = n
            .hit
            .as_ref()
            .map_or(n.origin + n.dir.normalize_or_zero() * reach, |h| h.point);
        seg(n.origin, end, kind_color(n.kind));
        for s in n.lights.iter().flat_map(|l| &l.samples) {
            if let Some(r) = &s.shadow_ray {
                let c = if s.occluder.is_some() {
                    OCCLUDED
                } else {
                    CLEAR
                };
                seg(r.origin, s.point, c);
            }
        }
        stack.extend(&n.children);
    }
}
