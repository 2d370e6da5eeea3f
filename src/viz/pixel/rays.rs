//! The `rays` and `colour` views: every ray of the tree, in its kind's
//! colour or in the colour it adds to the pixel, with the shadow rays
//! (which the `lights` view draws too).

use glam::Vec3;

use super::{end_of, nodes, plural, Drawing};
use crate::inspect::rays::kind_name;
use crate::inspect::{PixelTree, RayNode};
use crate::render::recorder::RayKind;

/// Shadow ray colours, as the original renderer drew them.
const BLOCKED: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const CLEAR: Vec3 = Vec3::ONE;

/// The colour of a ray of `kind` in the `rays` view.
pub fn kind_color(k: RayKind) -> Vec3 {
    match k {
        RayKind::Camera => Vec3::new(1.0, 1.0, 0.0),
        RayKind::Reflection => Vec3::new(0.0, 1.0, 1.0),
        RayKind::Glossy => Vec3::new(0.3, 0.5, 1.0),
        RayKind::Transmission => Vec3::new(0.0, 1.0, 0.0),
        RayKind::Diffuse => Vec3::new(1.0, 0.5, 0.0),
    }
}

fn kind_color_name(k: RayKind) -> &'static str {
    match k {
        RayKind::Camera => "yellow",
        RayKind::Reflection => "cyan",
        RayKind::Glossy => "blue",
        RayKind::Transmission => "green",
        RayKind::Diffuse => "orange",
    }
}

impl Drawing<'_, '_> {
    pub(super) fn shadow_rays(&mut self, n: &RayNode) -> (usize, usize) {
        let (mut clear, mut blocked) = (0, 0);
        for s in n.lights.iter().flat_map(|l| &l.samples) {
            if let Some(r) = &s.shadow_ray {
                let c = if s.occluder.is_some() {
                    blocked += 1;
                    BLOCKED
                } else {
                    clear += 1;
                    CLEAR
                };
                self.seg(r.origin, s.point, c);
            }
        }
        (clear, blocked)
    }

    pub(super) fn shadow_legend(&mut self, (clear, blocked): (usize, usize)) {
        if clear > 0 {
            self.say(
                Some(CLEAR),
                format!(
                    "white: {}",
                    crate::words::count(clear as u64, "shadow ray clear", "shadow rays clear")
                ),
            );
        }
        if blocked > 0 {
            self.say(
                Some(BLOCKED),
                format!(
                    "red: {}",
                    crate::words::count(
                        blocked as u64,
                        "shadow ray blocked",
                        "shadow rays blocked"
                    )
                ),
            );
        }
    }

    pub(super) fn rays(&mut self, tree: &PixelTree, by_colour: bool) {
        let mut shadows = (0, 0);
        let mut kinds: Vec<(RayKind, usize)> = Vec::new();
        if by_colour {
            self.expose(nodes(tree).iter().map(|n| &n.contribution));
        }
        for n in nodes(tree) {
            let c = if by_colour {
                n.contribution * self.exposure
            } else {
                kind_color(n.kind)
            };
            let end = end_of(n, self.reach);
            self.seg(n.origin, end, c);
            let (a, b) = self.shadow_rays(n);
            shadows = (shadows.0 + a, shadows.1 + b);
            match kinds.iter_mut().find(|k| k.0 == n.kind) {
                Some(k) => k.1 += 1,
                None => kinds.push((n.kind, 1)),
            }
        }
        // The camera ray runs along the line of sight: a square where it
        // ends shows it.
        let root = &tree.root;
        let c = if by_colour {
            root.contribution * self.exposure
        } else {
            kind_color(root.kind)
        };
        self.dot(end_of(root, self.reach), c);
        if by_colour {
            let total: usize = kinds.iter().map(|k| k.1).sum();
            self.say(
                None,
                format!(
                    "{total} rays, each in the colour it adds to the pixel (weight x radiance)"
                ),
            );
        } else {
            for (k, count) in kinds {
                self.say(
                    Some(kind_color(k)),
                    format!(
                        "{}: {count} {} {}",
                        kind_color_name(k),
                        kind_name(k),
                        plural(count, "ray")
                    ),
                );
            }
        }
        self.shadow_legend(shadows);
    }
}
