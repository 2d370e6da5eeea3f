//! The `environment` view: one ray that leaves the scene, in the colour
//! the environment gives it, and the cube face it reads.

use glam::Vec3;

use super::super::draw::clip_to_rect;
use super::{end_of, Drawing, MARK};
use crate::inspect::TreeRay;
use crate::raster::canvas::{text_width, GLYPH};

impl Drawing<'_, '_> {
    pub(super) fn environment(&mut self, i: usize, r: &TreeRay) {
        self.say(None, format!("ray {i}: {}", r.label()));
        let miss = match (&r.shadow, &r.node.miss) {
            (None, Some(m)) => m,
            _ => {
                self.say(
                    None,
                    "no ray of this sample leaves the scene here: choose one that misses",
                );
                return;
            }
        };
        let n = r.node;
        let end = end_of(n, self.reach);
        match &miss.face {
            Some(face) => {
                let uv = miss.uv.unwrap_or_default();
                self.say(
                    Some(miss.color),
                    format!(
                        "the ray in the colour found on face {face} at uv ({:.3}, {:.3})",
                        uv.x, uv.y
                    ),
                );
                // The face's name beside where the ray leaves the picture.
                let frame = &self.tracer.frame;
                let (w, h) = (self.layer.width as f64, self.layer.height as f64);
                let shown = frame
                    .project_clip(n.origin, end, 1e-6)
                    .and_then(|(p, q)| clip_to_rect(p, q, w, h));
                if let Some((_, q)) = shown {
                    let scale = (self.layer.height as i32 / 320).max(1);
                    let (tw, th) = (text_width(face, scale), GLYPH * scale);
                    let gap = 4 * self.dot_radius() + 4;
                    let x = (q.0 as i32 - tw / 2).clamp(0, (self.layer.width as i32 - tw).max(0));
                    let above = q.1 as i32 - th - gap;
                    let y = if above >= 0 { above } else { q.1 as i32 + gap };
                    self.layer
                        .rect(x - 2, y - 2, x + tw + 1, y + th + 1, Some(Vec3::ZERO));
                    self.layer.text(x, y, face, Some(MARK), scale);
                }
            }
            None => self.say(
                Some(miss.color),
                "the ray in the background colour (no environment map)",
            ),
        }
        self.seg(n.origin, end, miss.color);
        self.dot(end, miss.color);
    }
}
