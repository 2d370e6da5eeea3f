//! The `traversal` view: the BVH nodes one ray's walk visited (replayed by
//! `Bvh::walk_log`), those on the path to the hit triangle apart.

use glam::Vec3;

use super::super::draw::draw_box;
use super::{end_of, plural, Drawing, MARK};
use crate::inspect::TreeRay;

/// Boxes on the path to the hit triangle, and the others.
pub const ON_PATH: Vec3 = Vec3::new(0.0, 1.0, 0.0);
pub const OFF_PATH: Vec3 = Vec3::new(1.0, 0.0, 0.0);
/// The hit triangle's outline.
pub const TRIANGLE: Vec3 = Vec3::new(1.0, 1.0, 0.0);

impl Drawing<'_, '_> {
    pub(super) fn traversal(&mut self, i: usize, r: &TreeRay) {
        let bvh = self.tracer.bvh;
        self.say(None, format!("ray {i}: {}", r.label()));
        if !self.tracer.plan.bvh {
            self.say(
                None,
                "the BVH is off in this plan: rays test every triangle",
            );
            return;
        }
        let ray = r.ray();
        let log = bvh.walk_log(&ray, r.shadow.is_some());
        let path = log.found.map_or(Vec::new(), |t| bvh.path_to(t));
        let (on, off): (Vec<u32>, Vec<u32>) = log.visited.iter().partition(|n| path.contains(n));
        for &n in &off {
            draw_box(
                &mut self.layer,
                &self.tracer.frame,
                &bvh.nodes[n as usize].bounds(),
                Some(OFF_PATH),
            );
        }
        for &n in &on {
            draw_box(
                &mut self.layer,
                &self.tracer.frame,
                &bvh.nodes[n as usize].bounds(),
                Some(ON_PATH),
            );
        }
        let end = match r.shadow {
            Some((_, s)) => s.point,
            None => end_of(r.node, self.reach),
        };
        match log.found {
            Some(t) => {
                self.seg(ray.origin, end, MARK);
                let v = self.triangle(t);
                self.outline(v, TRIANGLE);
                self.say(
                    Some(ON_PATH),
                    format!(
                        "green: {} {} on the path to triangle {t}",
                        on.len(),
                        plural(on.len(), "box")
                    ),
                );
                self.say(
                    Some(OFF_PATH),
                    format!(
                        "red: {} {} entered off that path",
                        off.len(),
                        plural(off.len(), "box")
                    ),
                );
                self.say(
                    Some(TRIANGLE),
                    format!("yellow: triangle {t}, the hit; white: the ray"),
                );
            }
            None => {
                self.seg(ray.origin, end, OFF_PATH);
                let what = if r.shadow.is_some() {
                    "nothing blocks the shadow ray"
                } else {
                    "the ray hits nothing"
                };
                self.say(
                    Some(OFF_PATH),
                    format!(
                        "{what} (red); {} {} entered",
                        off.len(),
                        plural(off.len(), "box")
                    ),
                );
            }
        }
        let st = log.stats;
        self.say(
            None,
            format!(
                "{} visited, {}, {}",
                crate::words::count(st.nodes_visited, "wide node", "wide nodes"),
                crate::words::count(st.leaves, "leaf", "leaves"),
                crate::words::count(st.triangle_tests, "triangle test", "triangle tests"),
            ),
        );
    }
}
