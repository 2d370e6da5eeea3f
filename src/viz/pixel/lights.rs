//! The `lights` view: the points sampled on lights, in the light's colour
//! there, and the shadow rays to them.

use super::{nodes, plural, Drawing};
use crate::inspect::PixelTree;

impl Drawing<'_, '_> {
    pub(super) fn lights(&mut self, tree: &PixelTree) {
        let mut points = 0;
        let mut shadows = (0, 0);
        let mut lights: Vec<(usize, String)> = Vec::new();
        for n in nodes(tree) {
            let (a, b) = self.shadow_rays(n);
            shadows = (shadows.0 + a, shadows.1 + b);
            for l in &n.lights {
                if !lights.iter().any(|(i, _)| *i == l.index) {
                    lights.push((l.index, l.kind.clone()));
                }
                for s in &l.samples {
                    self.dot(s.point, s.color);
                    points += 1;
                }
            }
        }
        if points == 0 {
            self.say(
                None,
                "no light was sampled: no ray of this sample hit a surface",
            );
            return;
        }
        let kinds: Vec<String> = lights
            .iter()
            .map(|(i, k)| format!("light {i} ({k})"))
            .collect();
        self.say(
            None,
            format!(
                "squares: {points} {} on {}, each in the light's colour there",
                plural(points, "point"),
                kinds.join(", ")
            ),
        );
        self.shadow_legend(shadows);
    }
}
