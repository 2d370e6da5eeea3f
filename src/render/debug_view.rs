//! The BVH debug views of a rendered image: level or leaf boxes drawn over
//! the shaded image, or a heat map of each camera ray's traversal work.
//! `rayterm render --debug VIEW` writes them; the TUI draws the same data.

use std::fmt;
use std::str::FromStr;

use anyhow::{bail, Result};
use glam::Vec3;

use super::film::{Film, LUMA};
use super::overlay::{self, Layer, Legend};
use super::{post, Progressive, Tracer};
use crate::bvh::debug::HeatMeasure;
use crate::bvh::debug::{boxes_at_level, heat_color, heat_map, heat_summary, leaf_boxes};
use crate::raster::canvas::Canvas;
use crate::scene::BloomSettings;

/// Per pixel (row-major), the traversal work of the camera ray through the
/// pixel centre: what the heat map shows.
pub fn heat(tracer: &Tracer, measure: HeatMeasure) -> Vec<u32> {
    heat_map(
        tracer.bvh,
        &tracer.frame,
        tracer.width,
        tracer.height,
        measure,
    )
}

/// A debug view, as `--debug` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DebugView {
    /// `bvh-level:K`
    Level(usize),
    /// `bvh-leaves`
    Leaves,
    /// `bvh-heat` (nodes visited) or `bvh-heat:tests`
    Heat(HeatMeasure),
}

const VIEWS: &str = "bvh-level:K, bvh-leaves, bvh-heat or bvh-heat:tests";

impl FromStr for DebugView {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let (name, arg) = match s.split_once(':') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        match (name, arg) {
            ("bvh-level", Some(k)) => k.trim().parse().map(DebugView::Level).map_err(|_| {
                format!("'{s}': the level must be a whole number from 0, as in bvh-level:3")
            }),
            ("bvh-level", None) => Err("bvh-level needs a level, as in bvh-level:3".into()),
            ("bvh-leaves", None) => Ok(DebugView::Leaves),
            ("bvh-heat", None | Some("nodes")) => Ok(DebugView::Heat(HeatMeasure::NodesVisited)),
            ("bvh-heat", Some("tests")) => Ok(DebugView::Heat(HeatMeasure::TriangleTests)),
            ("bvh-heat", Some(m)) => Err(format!(
                "'{s}': unknown measure '{m}' (bvh-heat counts nodes; bvh-heat:tests counts triangle tests)"
            )),
            _ => Err(format!("unknown debug view '{s}': expected {VIEWS}")),
        }
    }
}

impl fmt::Display for DebugView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DebugView::Level(k) => write!(f, "bvh-level:{k}"),
            DebugView::Leaves => f.write_str("bvh-leaves"),
            DebugView::Heat(HeatMeasure::NodesVisited) => f.write_str("bvh-heat"),
            DebugView::Heat(HeatMeasure::TriangleTests) => f.write_str("bvh-heat:tests"),
        }
    }
}

/// A debug view drawn at the tracer's resolution, and what it shows in words.
pub struct DebugImage {
    /// Linear RGB, row-major.
    pub image: Vec<Vec3>,
    pub summary: String,
}

/// Box outline colours, bright and far apart in hue so neighbours differ
/// (box `i` gets `BOX_COLORS[i % 6]`).
pub const BOX_COLORS: [Vec3; 6] = [
    Vec3::new(1.0, 0.85, 0.0),
    Vec3::new(0.0, 0.9, 1.0),
    Vec3::new(1.0, 0.1, 0.8),
    Vec3::new(0.3, 1.0, 0.1),
    Vec3::new(1.0, 0.35, 0.0),
    Vec3::new(0.45, 0.3, 1.0),
];

/// `view` as a layer over the tracer's image (box outlines, or the heat map
/// with its legend covering everything), and what it shows in words.
pub fn layer(tracer: &Tracer, view: DebugView) -> Result<(Layer, String)> {
    let (w, h) = (tracer.width, tracer.height);
    let bvh = tracer.bvh;
    let mut layer = Canvas::new(w, h, None);
    let (boxes, summary) = match view {
        DebugView::Heat(measure) => {
            let values = heat(tracer, measure);
            let (max, mean) = heat_summary(&values);
            for (px, &v) in layer.pixels.iter_mut().zip(&values) {
                *px = Some(heat_color(v, max));
            }
            overlay::legend(&mut layer, max);
            let summary = format!(
                "{} per camera ray: max {max}, mean {mean:.2} per pixel",
                measure.label()
            );
            return Ok((layer, summary));
        }
        DebugView::Level(k) => {
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
            let summary = format!(
                "{} {} at level {k} of 0..{}",
                b.len(),
                if b.len() == 1 { "box" } else { "boxes" },
                depth - 1
            );
            (b, summary)
        }
        DebugView::Leaves => {
            let b = leaf_boxes(bvh);
            let summary = format!(
                "{} leaf boxes, {:.2} triangles per leaf on average, {} at most",
                b.len(),
                bvh.stats.mean_leaf,
                bvh.stats.max_leaf
            );
            (b, summary)
        }
    };
    for (i, b) in boxes.iter().enumerate() {
        let c = BOX_COLORS[i % BOX_COLORS.len()];
        overlay::draw_box(&mut layer, &tracer.frame, b, Some(c));
    }
    Ok((layer, summary))
}

/// Draws `view` over one shaded sample per pixel (with bloom where the plan
/// has it).
pub fn draw(tracer: &Tracer, view: DebugView) -> Result<DebugImage> {
    let (layer, summary) = layer(tracer, view)?;
    if let Some(image) = layer.pixels.iter().copied().collect::<Option<Vec<Vec3>>>() {
        // The heat map covers every pixel: nothing to render under it.
        return Ok(DebugImage { image, summary });
    }
    let film = Progressive::render(tracer, 1);
    let settings = &tracer.scene.settings.bloom;
    let (w, h) = (tracer.width, tracer.height);
    let mut image = post::display(film.image(), w, h, tracer.plan, settings).image;
    layer.over(&mut image);
    Ok(DebugImage { image, summary })
}

/// Pixels over bloom's threshold in the bloom view.
pub const BRIGHT: Vec3 = Vec3::new(0.0, 1.0, 1.0);
/// The glow bloom spreads, at its brightest, in the bloom view.
pub const GLOW: Vec3 = Vec3::new(1.0, 0.45, 0.0);

/// A view of the film the TUI draws from each pass in place of the
/// picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FilmView {
    /// [`bloom_view`].
    Bloom,
    /// [`spp_view`].
    Spp,
    /// [`error_view`].
    Error,
}

/// Steps of the colour scale of the film maps.
const SCALE_STEPS: u32 = 1000;

/// A colour of the heat scale at `t` in [0, 1].
fn scale_color(t: f64) -> Vec3 {
    heat_color(
        (t.clamp(0.0, 1.0) * SCALE_STEPS as f64).round() as u32,
        SCALE_STEPS,
    )
}

/// Each pixel's samples, on a log scale from the fewest (dark blue) to the
/// most (yellow), and the legend with the fewest, mean and most.
pub fn spp_view(film: &Film) -> (Vec<Vec3>, Legend) {
    let (min, mean, max) = film.spp_range();
    let span = (max.max(1) as f64 / min.max(1) as f64).log2();
    let image = (0..film.pixels_len())
        .map(|i| {
            let n = film.pixel_spp(i).max(1) as f64;
            scale_color(if span > 0.0 {
                (n / min.max(1) as f64).log2() / span
            } else {
                0.0
            })
        })
        .collect();
    let legend = if min == max {
        vec![(None, format!("samples per pixel: every pixel {min}"))]
    } else {
        vec![
            (
                Some(scale_color(0.0)),
                format!("samples per pixel: dark blue {min}"),
            ),
            (Some(scale_color(1.0)), format!("yellow {max} (log scale)")),
            (None, format!("mean {mean:.1}")),
        ]
    };
    (image, legend)
}

/// The smallest and largest estimated relative errors the error map
/// tells apart (0.1 % and 10 %).
const ERROR_SCALE: (f64, f64) = (1e-3, 1e-1);

/// Each pixel's estimated relative error (its standard error over
/// `√(lum² + 0.01)`, as the film's estimate counts it) on a log scale from
/// 0.1 % or less (dark blue) to 10 % or more (yellow), grey where unknown
/// (below two samples); and the legend.
pub fn error_view(film: &Film) -> (Vec<Vec3>, Legend) {
    let (lo, hi) = ERROR_SCALE;
    let image: Vec<Vec3> = film
        .pixels()
        .iter()
        .map(|p| match p.relative_error() {
            Some(e) => scale_color((e.max(lo) / lo).log10() / (hi / lo).log10()),
            None => UNKNOWN,
        })
        .collect();
    let mut legend = vec![
        (
            Some(scale_color(0.0)),
            "estimated relative error per pixel: dark blue 0.1 % or less".into(),
        ),
        (Some(scale_color(0.5)), "teal 1 %".into()),
        (
            Some(scale_color(1.0)),
            "yellow 10 % or more (log scale)".into(),
        ),
    ];
    if film.pixels().iter().any(|p| p.n < 2) {
        legend.push((Some(UNKNOWN), "grey unknown (below 2 samples)".into()));
    }
    (image, legend)
}

/// Pixels of the error map whose error is unknown.
const UNKNOWN: Vec3 = Vec3::splat(0.2);

/// What bloom does to `before` (an image before bloom): the pixels over the
/// threshold in cyan and the glow they spread in orange (brighter where it
/// adds more), over the image dimmed; and the legend with the threshold and
/// the kernel.
pub fn bloom_view(
    before: &[Vec3],
    width: u32,
    height: u32,
    s: &BloomSettings,
) -> (Vec<Vec3>, Legend) {
    let dim = |c: &Vec3| Vec3::splat(c.dot(LUMA).clamp(0.0, 1.0) * 0.25);
    let mut image: Vec<Vec3> = before.iter().map(dim).collect();
    let kernel = format!(
        "Gaussian sigma {} px, kernel {}x{} px, strength {}",
        s.sigma,
        2 * s.radius + 1,
        2 * s.radius + 1,
        s.strength
    );
    let Some(g) = post::glow(before, width as usize, height as usize, s) else {
        let legend = vec![
            (
                None,
                format!(
                    "no pixel is over the threshold (luminance > {})",
                    s.threshold
                ),
            ),
            (None, kernel),
        ];
        return (image, legend);
    };
    let most = g.glow.iter().map(|c| c.dot(LUMA)).fold(0.0f32, f32::max);
    for (px, glow) in image.iter_mut().zip(&g.glow) {
        let t = (glow.dot(LUMA) / most).clamp(0.0, 1.0);
        if t > 0.0 {
            *px = px.lerp(GLOW, t.sqrt());
        }
    }
    let mut bright = 0u32;
    for (px, b) in image.iter_mut().zip(&g.bright) {
        if *b != Vec3::ZERO {
            *px = BRIGHT;
            bright += 1;
        }
    }
    let legend = vec![
        (
            Some(BRIGHT),
            format!(
                "cyan: {} over the threshold (luminance > {})",
                crate::words::count(bright, "pixel", "pixels"),
                s.threshold
            ),
        ),
        (
            Some(GLOW),
            format!("orange: their glow, up to +{most:.3} luminance"),
        ),
        (None, kernel),
    ];
    (image, legend)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{SceneRequest, Session};

    fn session(w: u32, h: u32) -> Session {
        let mut req = SceneRequest::new("cornell");
        req.size = Some((w, h));
        Session::open(&req).unwrap().0
    }

    /// The maps colour by the film's own counts and errors: the fewest and
    /// most samples at the ends of the scale, 1 % error at its middle.
    #[test]
    fn the_film_maps_show_counts_and_errors() {
        let mut f = Film::new_adaptive(3, 1);
        // Pixel 0: 16 equal samples (no error); 1: 64 alternating 0.9 and
        // 1.1 (error 0.1 / √64 over √1.01); 2: one sample.
        for k in 0..16 {
            f.add(0, 0, k, None, Vec3::ONE);
        }
        for k in 0..64 {
            let v = if k % 2 == 0 { 0.9 } else { 1.1 };
            f.add(1, 0, k, None, Vec3::splat(v));
        }
        f.add(2, 0, 0, None, Vec3::ONE);
        let (img, legend) = spp_view(&f);
        assert_eq!(img[1], scale_color(1.0));
        assert_eq!(img[2], scale_color(0.0));
        assert!(img[0] != img[1] && img[0] != img[2]);
        let text = overlay::legend_line(&legend);
        assert!(
            text.contains("dark blue 1") && text.contains("yellow 64"),
            "{text}"
        );
        let (img, legend) = error_view(&f);
        assert_eq!(img[0], scale_color(0.0));
        assert_eq!(img[2], UNKNOWN);
        let e = f.pixels()[1].relative_error().unwrap();
        let want = 0.1 * (64.0f64 / 63.0).sqrt() / 8.0 / 1.01f64.sqrt();
        assert!((e - want).abs() < 1e-6, "{e} against {want}");
        let t = (e / 1e-3).log10() / 2.0;
        assert_eq!(img[1], scale_color(t));
        assert!(overlay::legend_line(&legend).contains("grey unknown"));
    }

    #[test]
    fn parses_every_view_and_rejects_bad_ones() {
        for s in ["bvh-level:3", "bvh-leaves", "bvh-heat", "bvh-heat:tests"] {
            let v: DebugView = s.parse().unwrap();
            assert_eq!(v.to_string(), s);
        }
        assert_eq!(
            "bvh-heat:nodes".parse(),
            Ok(DebugView::Heat(HeatMeasure::NodesVisited))
        );
        for bad in [
            "bvh-level:x",
            "bvh-level:-1",
            "bvh-level",
            "bvh",
            "bvh-heat:t",
        ] {
            let e = bad.parse::<DebugView>().unwrap_err();
            assert!(e.contains("bvh-"), "{bad}: {e}");
        }
        assert!("bvh-level:x"
            .parse::<DebugView>()
            .unwrap_err()
            .contains("whole number"));
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
    fn level_past_the_deepest_is_an_error() {
        let s = session(16, 16);
        let (t, bvh) = (s.tracer(), &s.bvh);
        let e = draw(&t, DebugView::Level(bvh.stats.depth))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("levels 0 to"), "{e}");
        let root = draw(&t, DebugView::Level(0)).unwrap();
        assert_eq!(root.image.len(), 256);
        assert!(
            root.summary.starts_with("1 box at level 0"),
            "{}",
            root.summary
        );
    }
}
