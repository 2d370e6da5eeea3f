//! The `samples` view: a zoom of the pixel, where its samples fall (in
//! their strata) and their colours.

use glam::Vec3;

use super::{plural, Drawing, GRID, MARK};
use crate::geometry::sampling::PIXEL_GRID;
use crate::inspect::{inspect_pixel, PixelTree};

/// The most samples the zoom draws.
const MAX_ZOOM_SAMPLES: u32 = 1024;

impl Drawing<'_, '_> {
    /// A zoom of the pixel in a corner away from it: the strata, and each
    /// sample where its camera ray passes, in the sample's colour.
    pub(super) fn samples(&mut self, tree: &PixelTree, spp: u32) {
        let Some((x0, y0, side)) = self.zoom_box((tree.x, tree.y)) else {
            self.say(None, "the image is too small for the zoom");
            return;
        };
        let (px, py) = (tree.x as i32, tree.y as i32);
        // Lines from the pixel to the zoom's corners, then the zoom.
        let c = (px as f64 + 0.5, py as f64 + 0.5);
        for (cx, cy) in [
            (x0, y0),
            (x0 + side, y0),
            (x0, y0 + side),
            (x0 + side, y0 + side),
        ] {
            self.layer
                .line(c, (cx as f64, cy as f64), Some(GRID * 2.0), 1, Some((4, 4)));
        }
        self.layer
            .rect(x0 - 2, y0 - 2, x0 + side + 1, y0 + side + 1, Some(MARK));
        self.layer
            .rect(x0, y0, x0 + side - 1, y0 + side - 1, Some(Vec3::ZERO));
        self.layer.rect(px - 2, py - 2, px + 2, py - 2, Some(MARK));
        self.layer.rect(px - 2, py + 2, px + 2, py + 2, Some(MARK));
        self.layer.rect(px - 2, py - 2, px - 2, py + 2, Some(MARK));
        self.layer.rect(px + 2, py - 2, px + 2, py + 2, Some(MARK));
        let stratified = tree.stratum.is_some();
        if stratified {
            for k in 1..PIXEL_GRID as i32 {
                let o = side * k / PIXEL_GRID as i32;
                self.layer
                    .rect(x0 + o, y0, x0 + o, y0 + side - 1, Some(GRID));
                self.layer
                    .rect(x0, y0 + o, x0 + side - 1, y0 + o, Some(GRID));
            }
        }
        let shown = spp.clamp(1, MAX_ZOOM_SAMPLES);
        let r = (side / 60).max(1);
        let mut sum = Vec3::ZERO;
        for k in 0..shown {
            let t = if k == tree.sample {
                tree.clone()
            } else {
                inspect_pixel(self.tracer, tree.x, tree.y, k)
            };
            let (sx, sy) = (
                x0 + (t.offset.x * side as f32).floor() as i32,
                y0 + (t.offset.y * side as f32).floor() as i32,
            );
            self.layer.rect(
                sx - r - 1,
                sy - r - 1,
                sx + r + 1,
                sy + r + 1,
                Some(GRID * 2.0),
            );
            self.layer
                .rect(sx - r, sy - r, sx + r, sy + r, Some(t.color));
            sum += t.color;
        }
        let mean = sum / shown as f32;
        self.say(
            None,
            format!(
                "pixel ({}, {}): {shown} {} where each camera ray passes, in the sample's colour",
                tree.x,
                tree.y,
                plural(shown as usize, "sample")
            ),
        );
        if spp > shown {
            self.say(None, format!("the first {shown} of {spp} samples shown"));
        }
        self.say(
            Some(GRID),
            if stratified {
                "grey lines: the 4x4 strata; each run of 16 samples visits each once"
            } else if self.tracer.plan.supersampling {
                "uniform random positions (stratification off)"
            } else {
                "supersampling is off: every sample at the pixel's centre"
            },
        );
        self.say(
            Some(mean),
            format!(
                "their mean ({:.3}, {:.3}, {:.3}); white frame: the pixel and its zoom",
                mean.x, mean.y, mean.z
            ),
        );
    }
}
