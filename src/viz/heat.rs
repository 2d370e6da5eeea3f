//! The heat maps: each camera ray's traversal work (nodes visited or
//! triangle tests) as a colour, with a colour bar for a legend; and the
//! heat colour map, which the film views' scales use too.

use glam::Vec3;
use rayon::prelude::*;

use super::draw::Layer;
use crate::bvh::{Bvh, TraversalStats};
use crate::raster::canvas::{text_width, GLYPH};
use crate::render::Tracer;
use crate::scene::camera::CameraFrame;

/// What a heat map counts per camera ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HeatMeasure {
    NodesVisited,
    TriangleTests,
}

impl HeatMeasure {
    fn label(self) -> &'static str {
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

/// Per pixel (row-major), the traversal work of the camera ray through the
/// pixel centre: what the heat map shows.
pub(crate) fn heat(tracer: &Tracer, measure: HeatMeasure) -> Vec<u32> {
    heat_map(
        tracer.bvh,
        &tracer.frame,
        tracer.width,
        tracer.height,
        measure,
    )
}

/// Per pixel (row-major), the closest-hit traversal work of the ray through
/// the pixel centre, rows in parallel.
fn heat_map(
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
pub(crate) fn heat_summary(values: &[u32]) -> (u32, f64) {
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
pub(crate) fn heat_color(value: u32, max: u32) -> Vec3 {
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
        crate::color::srgb_to_linear(s.x),
        crate::color::srgb_to_linear(s.y),
        crate::color::srgb_to_linear(s.z),
    )
}

/// Steps of the colour scale of the film maps.
const SCALE_STEPS: u32 = 1000;

/// A colour of the heat scale at `t` in [0, 1].
pub(crate) fn scale_color(t: f64) -> Vec3 {
    heat_color(
        (t.clamp(0.0, 1.0) * SCALE_STEPS as f64).round() as u32,
        SCALE_STEPS,
    )
}

/// Fills `layer` with the heat map of `measure` and its colour bar; says
/// what it shows. The colours run from the least work in the view to the
/// most, so that a small tree's few levels still differ; where every ray
/// did the same work there is nothing to tell apart, and it says so.
pub(crate) fn draw(layer: &mut Layer, tracer: &Tracer, measure: HeatMeasure) -> String {
    let values = heat(tracer, measure);
    let (max, mean) = heat_summary(&values);
    let min = values.iter().copied().min().unwrap_or(0);
    if min == max {
        let mid = heat_color(1, 2);
        layer.pixels.iter_mut().for_each(|px| *px = Some(mid));
        let why = match measure {
            HeatMeasure::NodesVisited => {
                " (the whole tree fits in one wide node; bvh-heat:tests differs)"
            }
            HeatMeasure::TriangleTests => "",
        };
        return format!(
            "{} per camera ray: {max} for every pixel{why}",
            measure.label()
        );
    }
    for (px, &v) in layer.pixels.iter_mut().zip(&values) {
        *px = Some(heat_color(v - min, max - min));
    }
    legend(layer, min, max);
    format!(
        "{} per camera ray: {min} (dark) to {max} (bright), mean {mean:.2} per pixel",
        measure.label()
    )
}

/// Draws a vertical colour bar for a `min..=max` heat map at the right
/// edge, labelled with `min` at the bottom and `max` at the top.
fn legend(c: &mut Layer, min: u32, max: u32) {
    let (w, h) = (c.width as i32, c.height as i32);
    if w < 16 || h < 16 {
        return;
    }
    let scale = (h / 320).max(1);
    let bar_w = (w / 40).max(3);
    let margin = (w / 80).max(2);
    let (top, bottom) = (h / 8, h - h / 8);
    let x0 = w - margin - bar_w;
    c.rect(x0 - 1, top - 1, x0 + bar_w, bottom, Some(Vec3::ZERO));
    let span = (bottom - top - 1).max(1);
    let range = max - min;
    for y in top..bottom {
        // The top row is `max`, the bottom row `min`.
        let t = (bottom - 1 - y) as f64 / span as f64;
        let col = heat_color((t * range as f64).round() as u32, range);
        c.rect(x0, y, x0 + bar_w - 1, y, Some(col));
    }
    let mut label = |text: &str, y: i32| {
        let tw = text_width(text, scale);
        let x = (x0 + bar_w - tw).max(0);
        c.rect(x - 1, y - 1, x + tw, y + GLYPH * scale, Some(Vec3::ZERO));
        c.text(x, y, text, Some(Vec3::ONE), scale);
    };
    label(&max.to_string(), (top - GLYPH * scale - 2).max(0));
    label(&min.to_string(), bottom + 2);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::canvas::Canvas;
    use crate::render::{SceneRequest, Session};

    fn session(w: u32, h: u32) -> Session {
        let mut req = SceneRequest::new("cornell");
        req.size = Some((w, h));
        Session::open(&req).unwrap().0
    }

    #[test]
    fn heat_colour_runs_dark_to_bright_and_clamps() {
        let lum = |c: Vec3| c.dot(crate::color::LUMA);
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

    #[test]
    fn heat_counts_the_work_of_each_camera_ray() {
        let s = session(24, 24);
        let (t, bvh) = (s.tracer(), &s.bvh);
        let nodes = heat(&t, HeatMeasure::NodesVisited);
        let tests = heat(&t, HeatMeasure::TriangleTests);
        assert_eq!(nodes.len(), 24 * 24);
        let (max, mean) = heat_summary(&nodes);
        // The box fills the (square) view, so every ray enters the root; no
        // ray visits more than every node.
        assert!(max >= 1 && (max as usize) <= bvh.nodes.len(), "{max}");
        assert!(nodes.iter().all(|&n| n >= 1), "a ray skipped the root");
        assert!(mean >= 1.0 && mean <= max as f64, "{mean}");
        assert!(heat_summary(&tests).0 >= 1);
        // The same count the traversal reports for that ray.
        let mut st = crate::bvh::TraversalStats::default();
        bvh.intersect::<true>(&t.frame.ray(5.5, 7.5), &mut st);
        assert_eq!(nodes[7 * 24 + 5], st.nodes_visited);
        assert_eq!(tests[7 * 24 + 5], st.triangle_tests);
    }

    #[test]
    fn legend_runs_from_dark_at_the_bottom_to_bright_at_the_top() {
        let (w, h) = (200u32, 160u32);
        let mut layer: Layer = Canvas::new(w, h, None);
        legend(&mut layer, 10, 52);
        let col = w - (w / 80).max(2) - 1;
        let at = |y: u32| layer.get(col, y).flatten();
        assert_eq!(at(h / 8), Some(heat_color(42, 42)));
        assert_eq!(at(h - h / 8 - 1), Some(heat_color(0, 42)));
        // The left half of the image is untouched.
        assert!(layer
            .pixels
            .chunks(w as usize)
            .all(|row| row[..(w / 2) as usize].iter().all(Option::is_none)));
    }

    #[test]
    fn a_map_where_every_ray_does_the_same_work_says_so() {
        // The Cornell box's tree is one wide node: every ray visits 1.
        let s = session(24, 16);
        let t = s.tracer();
        let mut layer: Layer = Canvas::new(24, 16, None);
        let said = draw(&mut layer, &t, HeatMeasure::NodesVisited);
        assert!(said.contains("1 for every pixel"), "{said}");
        assert!(said.contains("one wide node"), "{said}");
        let mut layer: Layer = Canvas::new(24, 16, None);
        let said = draw(&mut layer, &t, HeatMeasure::TriangleTests);
        assert!(said.contains("(dark) to"), "{said}");
    }
}
