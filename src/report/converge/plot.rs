//! The log-log plot of relative error against time, drawn on the project's
//! canvas (a plotting crate would need a font stack): one line per
//! strategy, the slope -0.5 reference dashed, the target dotted.

use image::{Rgb, RgbImage};

use crate::raster::canvas::{text_width, Canvas, Dash};

use super::Study;

const WIDTH: u32 = 960;
const HEIGHT: u32 = 640;
/// Plot area inside the image; the legend sits to the right.
const LEFT: i32 = 90;
const RIGHT: i32 = 690;
const TOP: i32 = 60;
const BOTTOM: i32 = 570;

const WHITE: Rgb<u8> = Rgb([255, 255, 255]);
const BLACK: Rgb<u8> = Rgb([20, 20, 20]);
const GRID: Rgb<u8> = Rgb([225, 225, 225]);
const GREY: Rgb<u8> = Rgb([110, 110, 110]);
const PALETTE: [Rgb<u8>; 8] = [
    Rgb([31, 119, 180]),
    Rgb([214, 39, 40]),
    Rgb([44, 160, 44]),
    Rgb([255, 127, 14]),
    Rgb([148, 103, 189]),
    Rgb([140, 86, 75]),
    Rgb([227, 119, 194]),
    Rgb([23, 190, 207]),
];

const DASHED: Dash = Some((10, 6));
const DOTTED: Dash = Some((2, 4));

/// A logarithmic axis from `lo` to `hi` (data units) onto pixels `p0..p1`.
struct Axis {
    lo: f64,
    hi: f64,
    p0: f64,
    p1: f64,
}

impl Axis {
    /// Spans `values` with a little room on both sides.
    fn fit(values: impl Iterator<Item = f64>, p0: i32, p1: i32) -> Self {
        let (mut lo, mut hi) = values
            .filter(|v| *v > 0.0 && v.is_finite())
            .fold((f64::INFINITY, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
        if !lo.is_finite() {
            (lo, hi) = (0.1, 1.0);
        }
        // At least a factor of ten, centred, so ticks exist.
        let span = (hi / lo).max(10.0);
        let mid = (hi * lo).sqrt();
        Self {
            lo: mid / span.sqrt() / 1.15,
            hi: mid * span.sqrt() * 1.15,
            p0: p0 as f64,
            p1: p1 as f64,
        }
    }

    fn map(&self, v: f64) -> f64 {
        self.p0 + (v / self.lo).ln() / (self.hi / self.lo).ln() * (self.p1 - self.p0)
    }

    /// Ticks at 1, 2, 5 times powers of ten (only 1 over wide ranges).
    fn ticks(&self) -> Vec<(f64, String)> {
        let mantissas: &[f64] = if (self.hi / self.lo).log10() > 3.0 {
            &[1.0]
        } else {
            &[1.0, 2.0, 5.0]
        };
        let mut out = Vec::new();
        for k in self.lo.log10().floor() as i32..=self.hi.log10().ceil() as i32 {
            for &m in mantissas {
                let v = m * 10f64.powi(k);
                if v >= self.lo && v <= self.hi {
                    let digits = (-k).max(0) as usize;
                    out.push((v, format!("{v:.digits$}")));
                }
            }
        }
        out
    }
}

/// Draws the study's error-against-time plot.
pub fn draw(study: &Study) -> RgbImage {
    let mut c = Canvas::new(WIDTH, HEIGHT, WHITE);
    let points = || study.series.iter().flat_map(|s| s.points.iter());
    let x = Axis::fit(points().map(|p| p.seconds), LEFT, RIGHT);
    let target = 100.0 * study.target;
    let y = Axis::fit(
        points()
            .map(|p| 100.0 * p.rel_err())
            .chain(std::iter::once(target)),
        BOTTOM,
        TOP,
    );
    c.text(
        LEFT,
        18,
        &format!(
            "{} {}x{}: relative error against time",
            study.scene, study.width, study.height
        ),
        BLACK,
        2,
    );
    for (v, label) in x.ticks() {
        let px = x.map(v);
        c.line((px, TOP as f64), (px, BOTTOM as f64), GRID, 1, None);
        c.line(
            (px, BOTTOM as f64),
            (px, BOTTOM as f64 + 5.0),
            BLACK,
            1,
            None,
        );
        let lx = px as i32 - text_width(&label, 1) / 2;
        c.text(lx, BOTTOM + 10, &label, BLACK, 1);
    }
    for (v, label) in y.ticks() {
        let py = y.map(v);
        c.line((LEFT as f64, py), (RIGHT as f64, py), GRID, 1, None);
        c.line((LEFT as f64 - 5.0, py), (LEFT as f64, py), BLACK, 1, None);
        c.text(
            LEFT - 10 - text_width(&label, 1),
            py as i32 - 4,
            &label,
            BLACK,
            1,
        );
    }
    let xl = "time (s)";
    c.text(
        (LEFT + RIGHT) / 2 - text_width(xl, 2) / 2,
        BOTTOM + 32,
        xl,
        BLACK,
        2,
    );
    c.text(8, TOP - 22, "rel. error (%)", BLACK, 1);
    let frame = [
        (LEFT, TOP),
        (RIGHT, TOP),
        (RIGHT, BOTTOM),
        (LEFT, BOTTOM),
        (LEFT, TOP),
    ];
    for w in frame.windows(2) {
        let p = |(a, b): (i32, i32)| (a as f64, b as f64);
        c.line(p(w[0]), p(w[1]), BLACK, 1, None);
    }

    c.clip = (LEFT + 1, TOP + 1, RIGHT - 1, BOTTOM - 1);
    let ty = y.map(target);
    c.line((LEFT as f64, ty), (RIGHT as f64, ty), GREY, 1, DOTTED);
    if let Some(p) = study.series.first().and_then(|s| s.points.first()) {
        // Slope -0.5 through the scene's first point.
        let (t0, e0) = (p.seconds, 100.0 * p.rel_err());
        if t0 > 0.0 && e0 > 0.0 {
            let at = |t: f64| (x.map(t), y.map(e0 * (t / t0).powf(-0.5)));
            c.line(at(x.lo), at(x.hi), GREY, 2, DASHED);
        }
    }
    for (i, s) in study.series.iter().enumerate() {
        let col = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.seconds > 0.0 && p.rel_err() > 0.0)
            .map(|p| (x.map(p.seconds), y.map(100.0 * p.rel_err())))
            .collect();
        for w in pts.windows(2) {
            c.line(w[0], w[1], col, 2, None);
        }
        for &(px, py) in &pts {
            let (px, py) = (px.round() as i32, py.round() as i32);
            c.rect(px - 3, py - 3, px + 3, py + 3, col);
        }
    }

    c.unclip();
    let lx = RIGHT + 20;
    let mut ly = TOP + 4;
    let mut entry = |c: &mut Canvas<Rgb<u8>>, label: &str, col: Rgb<u8>, width: i32, dash: Dash| {
        let yy = ly as f64 + 4.0;
        c.line((lx as f64, yy), (lx as f64 + 30.0, yy), col, width, dash);
        c.text(lx + 40, ly, label, BLACK, 1);
        ly += 20;
    };
    for (i, s) in study.series.iter().enumerate() {
        let suffix = if i == 0 { " (scene)" } else { "" };
        entry(
            &mut c,
            &format!("{}{suffix}", s.label),
            PALETTE[i % PALETTE.len()],
            3,
            None,
        );
    }
    entry(&mut c, "slope -0.5", GREY, 2, DASHED);
    entry(
        &mut c,
        &format!("target {} %", super::report::short(target)),
        GREY,
        1,
        DOTTED,
    );
    RgbImage::from_fn(WIDTH, HEIGHT, |x, y| c.get(x, y).unwrap_or(WHITE))
}
