//! The `glossy` view: the glossy rays and their lobe's axis.

use glam::Vec3;

use super::{end_of, nodes, plural, Drawing};
use crate::inspect::{PixelTree, RayNode};
use crate::render::integrator::mirror;
use crate::render::recorder::RayKind;

/// The glossy lobe's axis.
pub const LOBE_AXIS: Vec3 = Vec3::new(1.0, 0.0, 1.0);

impl Drawing<'_, '_> {
    pub(super) fn glossy(&mut self, tree: &PixelTree) {
        let mut rays = 0;
        let all = nodes(tree);
        self.expose(
            all.iter()
                .filter(|n| n.kind == RayKind::Glossy)
                .map(|n| &n.contribution),
        );
        for n in all {
            let lobe: Vec<&RayNode> = n
                .children
                .iter()
                .filter(|c| c.kind == RayKind::Glossy)
                .collect();
            let Some(h) = n.hit.as_ref().filter(|_| !lobe.is_empty()) else {
                continue;
            };
            for c in &lobe {
                let end = end_of(c, self.reach);
                self.seg(c.origin, end, c.contribution * self.exposure);
            }
            rays += lobe.len();
            let axis = mirror(n.dir, h.shading_normal, h.geometric_normal);
            let len = lobe
                .iter()
                .map(|c| end_of(c, self.reach).distance(c.origin))
                .fold(f32::INFINITY, f32::min)
                .min(self.reach);
            self.seg(h.point, h.point + axis * len, LOBE_AXIS);
            self.say(
                Some(LOBE_AXIS),
                match &h.pbr {
                    None => format!(
                        "magenta: the lobe axis (mirror direction) at {} (Phong exponent {})",
                        h.mesh, h.ns
                    ),
                    Some(p) => format!(
                        "magenta: the lobe axis (mirror direction) at {} (GGX, roughness {:.3})",
                        h.mesh, p.roughness
                    ),
                },
            );
        }
        if rays == 0 {
            self.say(
                None,
                "no glossy rays in this sample (no glossy surface hit, or glossy reflection is off)",
            );
        } else {
            self.say(
                None,
                format!(
                    "{rays} glossy {}, each in the colour it adds to the pixel",
                    plural(rays, "ray")
                ),
            );
        }
    }
}
