//! Terminal colours: truecolor, or sRGB quantized to the xterm 256-colour
//! palette or the 16 ANSI colours, with ordered dithering where it brings
//! the picture closer. `graphics::symbols`
//! turns pixels into cells with them.

use std::sync::OnceLock;

use ratatui::style::Color;
use rayon::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ColorMode {
    Truecolor,
    Palette256,
    Ansi16,
}

impl crate::choice::Choice for ColorMode {
    const ALL: &'static [Self] = &[
        ColorMode::Truecolor,
        ColorMode::Palette256,
        ColorMode::Ansi16,
    ];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            ColorMode::Truecolor => ("truecolor", "24-bit colour"),
            ColorMode::Palette256 => (
                "256",
                "The xterm 256-colour palette (6x6x6 cube and grey ramp), with ordered dithering",
            ),
            ColorMode::Ansi16 => ("16", "The 16 ANSI colours, with ordered dithering"),
        }
    }
}

impl ColorMode {
    /// Truecolor when `COLORTERM` says so or the terminal's terminfo entry
    /// declares it (`rgb`: `RGB` or `Tc`), else 256 colours.
    pub(crate) fn detect(colorterm: Option<&str>, rgb: bool) -> Self {
        match colorterm.map(str::to_ascii_lowercase).as_deref() {
            Some("truecolor" | "24bit") => ColorMode::Truecolor,
            _ if rgb => ColorMode::Truecolor,
            _ => ColorMode::Palette256,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            ColorMode::Truecolor => "truecolor",
            ColorMode::Palette256 => "256 colours",
            ColorMode::Ansi16 => "16 colours",
        }
    }
}

/// Weights of the channels in sRGB distances, for the eye's sensitivity
/// (green most, blue least).
const W: [u32; 3] = [3, 4, 2];

/// Squared distance in sRGB, weighted by [`W`].
fn dist(a: [u8; 3], b: [u8; 3]) -> u32 {
    (0..3)
        .map(|i| W[i] * (a[i] as i32 - b[i] as i32).pow(2) as u32)
        .sum()
}

/// Channel levels of the 6x6x6 cube.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// RGB of palette entry `i` (16..=255) of the xterm 256-colour palette.
pub(crate) fn palette256(i: u8) -> [u8; 3] {
    match i {
        16..=231 => {
            let j = i - 16;
            [
                CUBE[j as usize / 36],
                CUBE[j as usize / 6 % 6],
                CUBE[j as usize % 6],
            ]
        }
        232..=255 => [8 + 10 * (i - 232); 3],
        _ => ANSI16[i as usize].1,
    }
}

/// Bits per channel of the 256-colour lookup table's index.
const TABLE_BITS: u32 = 6;

/// The entry of the cube and grey ramp (16..=255; the first 16 vary between
/// terminals) nearest to `c` by [`dist`], by full search. (In CIELAB the
/// nearest entry often has a truer hue but is further off in lightness,
/// and the picture ends up further from the truecolor one.)
fn nearest256(c: [u8; 3]) -> u8 {
    (16..=255u8)
        .min_by_key(|&i| dist(c, palette256(i)))
        .unwrap_or(16)
}

/// Representative colour of a table cell: the middle of its range.
fn cell_colour(k: usize) -> [u8; 3] {
    let n = 1usize << TABLE_BITS;
    let mid = |v: usize| ((v << (8 - TABLE_BITS)) + (1 << (7 - TABLE_BITS))) as u8;
    [mid(k / (n * n)), mid(k / n % n), mid(k % n)]
}

/// The nearest palette entry for every cell of a 64x64x64 grid of colours,
/// computed once (in parallel) on first use.
fn table256() -> &'static [u8] {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..1usize << (3 * TABLE_BITS))
            .into_par_iter()
            .map(|k| nearest256(cell_colour(k)))
            .collect()
    })
}

/// The 256-colour palette entry for `c`: the one nearest to the
/// middle of `c`'s table cell (at most 2 steps away in each channel).
pub(crate) fn quantize256(c: [u8; 3]) -> u8 {
    table256()[table_cell(c)]
}

/// The cell of the 64x64x64 grid of colours `c` lies in.
fn table_cell(c: [u8; 3]) -> usize {
    let s = 8 - TABLE_BITS;
    ((c[0] as usize >> s) << (2 * TABLE_BITS))
        | ((c[1] as usize >> s) << TABLE_BITS)
        | (c[2] as usize >> s)
}

/// The 16 ANSI colours with xterm's default RGB.
const ANSI16: [(Color, [u8; 3]); 16] = [
    (Color::Black, [0, 0, 0]),
    (Color::Red, [205, 0, 0]),
    (Color::Green, [0, 205, 0]),
    (Color::Yellow, [205, 205, 0]),
    (Color::Blue, [0, 0, 238]),
    (Color::Magenta, [205, 0, 205]),
    (Color::Cyan, [0, 205, 205]),
    (Color::Gray, [229, 229, 229]),
    (Color::DarkGray, [127, 127, 127]),
    (Color::LightRed, [255, 0, 0]),
    (Color::LightGreen, [0, 255, 0]),
    (Color::LightYellow, [255, 255, 0]),
    (Color::LightBlue, [92, 92, 255]),
    (Color::LightMagenta, [255, 0, 255]),
    (Color::LightCyan, [0, 255, 255]),
    (Color::White, [255, 255, 255]),
];

/// 4x4 Bayer matrix: thresholds for ordered dithering.
const BAYER: [[u8; 4]; 4] = [[0, 8, 2, 10], [12, 4, 14, 6], [3, 11, 1, 9], [15, 7, 13, 5]];

/// How much a dithered pair's noise counts against the error it removes
/// (per unit of the spread between its two colours), for 16 colours;
/// chosen on the `env` scene (scripts/color-error.py).
const NOISE16: f32 = 0.35;

/// Where `p` lies between `a` and `b`: the share of `b` whose mix is
/// nearest to `p`, the mix's squared distance from `p`, and the pair's
/// squared spread (all weighted by [`W`]).
fn mix(p: [u8; 3], a: [u8; 3], b: [u8; 3]) -> (f32, f32, f32) {
    let (p, a, b) = (p.map(f32::from), a.map(f32::from), b.map(f32::from));
    let w = W.map(|v| v as f32);
    let ab = [0, 1, 2].map(|i| b[i] - a[i]);
    let len2: f32 = (0..3).map(|i| w[i] * ab[i] * ab[i]).sum();
    if len2 == 0.0 {
        return (0.0, (0..3).map(|i| w[i] * (p[i] - a[i]).powi(2)).sum(), 0.0);
    }
    let along: f32 = (0..3).map(|i| w[i] * (p[i] - a[i]) * ab[i]).sum();
    let r = (along / len2).clamp(0.0, 1.0);
    let off = (0..3)
        .map(|i| w[i] * (p[i] - a[i] - r * ab[i]).powi(2))
        .sum();
    (r, off, len2)
}

/// The pair of the 16 colours to dither `c` between (the same twice for
/// one colour alone): the one whose mix is nearest, counting the pattern's
/// noise ([`NOISE16`]). Any pair is a candidate, not only the nearest
/// entry and one beyond it, since the 16 colours lie far apart.
fn best_pair16(c: [u8; 3]) -> (u8, u8) {
    let nearest = (0..16).min_by_key(|&i| dist(c, ANSI16[i].1)).unwrap_or(0);
    let mut best = ((dist(c, ANSI16[nearest].1) as f32).sqrt(), nearest, nearest);
    for (a, (_, ca)) in ANSI16.iter().enumerate() {
        for (b, (_, cb)) in ANSI16.iter().enumerate().skip(a + 1) {
            let (r, off, len2) = mix(c, *ca, *cb);
            let cost = off.sqrt() + NOISE16 * (r * (1.0 - r) * len2).sqrt();
            if cost < best.0 {
                best = (cost, a, b);
            }
        }
    }
    (best.1 as u8, best.2 as u8)
}

/// [`best_pair16`] for every cell of the 64x64x64 grid, computed once (in
/// parallel) on first use.
fn pairs16() -> &'static [(u8, u8)] {
    static TABLE: OnceLock<Vec<(u8, u8)>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..1usize << (3 * TABLE_BITS))
            .into_par_iter()
            .map(|k| best_pair16(cell_colour(k)))
            .collect()
    })
}

/// Ordered dithering with any palette: pixel `c` at (x, y) becomes the
/// nearest entry or the nearest one on the other side of the pixel, in
/// proportion to where the pixel lies between them, so that a patch of
/// pixels averages to about its colour. Colours in the palette come out
/// exactly. The pattern depends only on the position and the colour, so a
/// picture that does not change does not shimmer.
pub(crate) fn dither(
    c: [u8; 3],
    x: u32,
    y: u32,
    nearest: impl Fn([i32; 3]) -> u8,
    rgb: impl Fn(u8) -> [u8; 3],
) -> u8 {
    let (a, b, ratio, _) = dither_pair(c, nearest, rgb);
    pick(a, b, ratio, x, y)
}

/// [`dither`] where it helps: only where mixing the two entries comes much
/// closer to the pixel than the nearest entry alone. Elsewhere (a colour
/// between entries of different hues, such as a brown between the cube's
/// olive and its red) a patch of the nearest entry is a truer picture
/// than a mosaic of two far ones.
fn dither_where_it_helps(
    c: [u8; 3],
    x: u32,
    y: u32,
    nearest: impl Fn([i32; 3]) -> u8,
    rgb: impl Fn(u8) -> [u8; 3],
) -> u8 {
    let (a, b, ratio, helps) = dither_pair(c, nearest, rgb);
    if helps {
        pick(a, b, ratio, x, y)
    } else {
        a
    }
}

/// The mix's residual must be at most this share of the nearest entry's
/// error (squared, in weighted sRGB) for dithering to be worth its noise;
/// chosen on the `env` scene (scripts/color-error.py).
const HELPS: f32 = 0.49;

/// The nearest entry `a`, the nearest one on the other side of `c`, the
/// share of `b` that mixes closest to `c`, and whether that mix is much
/// closer to `c` than `a`.
fn dither_pair(
    c: [u8; 3],
    nearest: impl Fn([i32; 3]) -> u8,
    rgb: impl Fn(u8) -> [u8; 3],
) -> (u8, u8, f32, bool) {
    let p = c.map(i32::from);
    let a = nearest(p);
    let ca = rgb(a);
    let b = nearest([0, 1, 2].map(|i| 2 * p[i] - ca[i] as i32));
    let (ratio, off, len2) = mix(c, ca, rgb(b));
    if len2 == 0.0 {
        return (a, a, 0.0, false);
    }
    (a, b, ratio, off <= HELPS * dist(c, ca) as f32)
}

/// `b` where the position's Bayer threshold is below `ratio`, else `a`.
fn pick(a: u8, b: u8, ratio: f32, x: u32, y: u32) -> u8 {
    let threshold = (BAYER[y as usize % 4][x as usize % 4] as f32 + 0.5) / 16.0;
    if threshold < ratio {
        b
    } else {
        a
    }
}

/// One of the 16 ANSI colours for pixel `c` at (x, y), ordered-dithered.
pub(crate) fn quantize16(c: [u8; 3], x: u32, y: u32) -> Color {
    ANSI16[dither16(c, x, y) as usize].0
}

/// The index (0..16) of [`quantize16`]'s colour.
pub(crate) fn dither16(c: [u8; 3], x: u32, y: u32) -> u8 {
    let (a, b) = pairs16()[table_cell(c)];
    if a == b {
        return a;
    }
    let (r, ..) = mix(c, ANSI16[a as usize].1, ANSI16[b as usize].1);
    pick(a, b, r, x, y)
}

/// The 256-colour entry for pixel `c` at (x, y), ordered-dithered between
/// cube and ramp entries, which breaks up the bands of smooth gradients.
pub(crate) fn dither256(c: [u8; 3], x: u32, y: u32) -> u8 {
    let clamp = |p: [i32; 3]| p.map(|v| v.clamp(0, 255) as u8);
    dither_where_it_helps(c, x, y, |p| quantize256(clamp(p)), palette256)
}

/// The terminal colour of sRGB pixel `c` at image position (x, y).
pub(crate) fn to_color(c: [u8; 3], mode: ColorMode, x: u32, y: u32) -> Color {
    match mode {
        ColorMode::Truecolor => Color::Rgb(c[0], c[1], c[2]),
        ColorMode::Palette256 => Color::Indexed(dither256(c, x, y)),
        ColorMode::Ansi16 => quantize16(c, x, y),
    }
}

/// The sRGB a terminal shows for `c` (xterm's defaults for the 16 colours).
#[cfg(test)]
pub(crate) fn shown(c: Color) -> Option<[u8; 3]> {
    match c {
        Color::Rgb(r, g, b) => Some([r, g, b]),
        Color::Indexed(i) => Some(palette256(i)),
        c => ANSI16.iter().find(|(a, _)| *a == c).map(|(_, rgb)| *rgb),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::{encode_srgb, srgb, srgb_to_linear, LUMA};
    use glam::Vec3;

    /// CIELAB (D65) of an sRGB colour: distances in it follow perceived
    /// differences, which keeps hues right where the cube is coarse.
    fn lab(c: [u8; 3]) -> [f32; 3] {
        let lin = |v: u8| srgb_to_linear(v as f32 / 255.0);
        let [r, g, b] = c.map(lin);
        let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.9505;
        let y = LUMA.dot(Vec3::new(r, g, b));
        let z = (0.0193 * r + 0.1192 * g + 0.9505 * b) / 1.089;
        let f = |t: f32| {
            if t > 0.008_856 {
                t.cbrt()
            } else {
                7.787 * t + 16.0 / 116.0
            }
        };
        let (fx, fy, fz) = (f(x), f(y), f(z));
        [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
    }

    #[test]
    fn linear_values_are_gamma_encoded() {
        // Linear 0.214 is sRGB mid-grey 128; 0 and >= 1 clamp to the ends.
        assert_eq!(srgb(Vec3::new(0.214_041_14, 0.0, 3.0)), [128, 0, 255]);
        assert_eq!(srgb(Vec3::NAN), [0, 0, 0]);
    }

    #[test]
    fn detection_reads_colorterm_and_terminfo() {
        assert_eq!(
            ColorMode::detect(Some("truecolor"), false),
            ColorMode::Truecolor
        );
        assert_eq!(
            ColorMode::detect(Some("24bit"), false),
            ColorMode::Truecolor
        );
        assert_eq!(ColorMode::detect(None, false), ColorMode::Palette256);
        assert_eq!(ColorMode::detect(Some(""), false), ColorMode::Palette256);
        assert_eq!(ColorMode::detect(None, true), ColorMode::Truecolor);
    }

    #[test]
    fn primaries_and_greys_quantize_sensibly() {
        assert_eq!(quantize256([255, 0, 0]), 196);
        assert_eq!(quantize256([0, 255, 0]), 46);
        assert_eq!(quantize256([0, 0, 255]), 21);
        assert_eq!(quantize256([0, 0, 0]), 16);
        assert_eq!(quantize256([255, 255, 255]), 231);
        // Mid greys go to the finer grey ramp, and stay grey.
        let g = quantize256([128, 128, 128]);
        assert!((232..=255).contains(&g), "{g}");
        assert_eq!(palette256(g), [128; 3]);
        let g = palette256(quantize256([60, 60, 60]));
        assert!(g[0] == g[1] && g[1] == g[2] && g[0].abs_diff(60) <= 5);
    }

    #[test]
    fn quantize256_is_the_nearest_entry() {
        let de = |a: [u8; 3], b: [u8; 3]| (dist(a, b) as f32).sqrt();
        for r in (0..=255).step_by(15) {
            for g in (0..=255).step_by(17) {
                for b in (0..=255).step_by(19) {
                    let c = [r as u8, g as u8, b as u8];
                    let q = palette256(quantize256(c));
                    let best = palette256(nearest256(c));
                    // The table answers for the middle m of c's cell, so by
                    // the triangle inequality it is at most 2 d(c, m) worse.
                    let k = (r as usize >> 2) << 12 | (g as usize >> 2) << 6 | b as usize >> 2;
                    let m = cell_colour(k);
                    let slack = 2.0 * de(c, m) + 1e-3;
                    assert!(de(c, q) <= de(c, best) + slack, "{c:?}: {q:?} vs {best:?}");
                    // Cells' middles are answered exactly.
                    assert_eq!(quantize256(m), nearest256(m), "{m:?}");
                }
            }
        }
    }

    #[test]
    fn sixteen_colours_keep_primaries_and_average_greys() {
        for x in 0..4 {
            for y in 0..4 {
                assert_eq!(quantize16([255, 0, 0], x, y), Color::LightRed);
                assert_eq!(quantize16([0, 0, 0], x, y), Color::Black);
                assert_eq!(quantize16([255, 255, 255], x, y), Color::White);
            }
        }
        // A dark grey between black (0) and dark grey (127) dithers between
        // the two, averaging close to itself.
        let rgb = |col: Color| ANSI16.iter().find(|(c, _)| *c == col).unwrap().1;
        let mut seen = std::collections::HashSet::new();
        let mut sum = 0u32;
        for x in 0..4 {
            for y in 0..4 {
                let col = quantize16([64, 64, 64], x, y);
                seen.insert(col);
                sum += rgb(col)[0] as u32;
            }
        }
        assert_eq!(seen, [Color::Black, Color::DarkGray].into());
        assert!((sum / 16).abs_diff(64) < 8, "{}", sum / 16);
    }

    /// Mean CIELAB ΔE between `a` and `b` after both are averaged over 4x4
    /// blocks in linear light, as the eye averages neighbouring pixels.
    fn blurred_delta_e(a: &[[u8; 3]], b: &[[u8; 3]], w: usize, rows: usize) -> f32 {
        let lin = |v: u8| srgb_to_linear(v as f32 / 255.0);
        let mean = |img: &[[u8; 3]], bx: usize, by: usize| {
            let mut s = [0f32; 3];
            for y in by * 4..by * 4 + 4 {
                for x in bx * 4..bx * 4 + 4 {
                    for c in 0..3 {
                        s[c] += lin(img[y * w + x][c]) / 16.0;
                    }
                }
            }
            s.map(encode_srgb)
        };
        let mut total = 0.0;
        let mut n = 0;
        for by in 0..rows / 4 {
            for bx in 0..w / 4 {
                let (p, q) = (lab(mean(a, bx, by)), lab(mean(b, bx, by)));
                total += (0..3).map(|i| (p[i] - q[i]).powi(2)).sum::<f32>().sqrt();
                n += 1;
            }
        }
        total / n as f32
    }

    #[test]
    fn dithering_brings_256_colours_closer_to_the_sky() {
        use crate::render::{post, Progressive, SceneRequest, Session};
        use crate::tui::graphics::symbols::{self, Symbols};
        use ratatui::buffer::Buffer;
        use ratatui::layout::Rect;
        // The env scene at the size of a 160x48 viewport in half blocks;
        // its top sixth is sky, a smooth gradient.
        let (w, h) = (160u32, 96u32);
        let req = SceneRequest {
            size: Some((w, h)),
            ..SceneRequest::new("env")
        };
        let (s, _) = Session::open(&req).unwrap();
        let film = Progressive::render(&s.tracer(), 1);
        let shown = post::display(film.image(), w, h, &s.plan, &s.scene.settings.bloom);
        let truth: Vec<[u8; 3]> = shown.image.iter().map(|c| srgb(*c)).collect();
        let area = Rect::new(0, 0, w as u16, (h / 2) as u16);
        let mut buf = Buffer::empty(area);
        symbols::paint(
            &mut buf,
            area,
            &truth,
            (w, h),
            Symbols::Half,
            ColorMode::Palette256,
        );
        let mut dithered = vec![[0u8; 3]; truth.len()];
        for cy in 0..area.height {
            for cx in 0..area.width {
                let c = &buf[(cx, cy)];
                let px = symbols::shown_cell(Symbols::Half, c.symbol(), c.fg, c.bg).unwrap();
                for (j, p) in px.iter().enumerate() {
                    dithered[(2 * cy as usize + j) * w as usize + cx as usize] = p.map(|v| v as u8);
                }
            }
        }
        let nearest: Vec<[u8; 3]> = truth.iter().map(|c| palette256(quantize256(*c))).collect();
        let sky = (h / 6) as usize / 4 * 4;
        let (d, n) = (
            blurred_delta_e(&dithered, &truth, w as usize, sky),
            blurred_delta_e(&nearest, &truth, w as usize, sky),
        );
        eprintln!("sky: mean ΔE {d:.3} dithered, {n:.3} nearest");
        assert!(d < 0.7 * n, "dithered {d} vs nearest {n}");
        // Over the whole picture too.
        let all = h as usize;
        let (d, n) = (
            blurred_delta_e(&dithered, &truth, w as usize, all),
            blurred_delta_e(&nearest, &truth, w as usize, all),
        );
        eprintln!("whole image: mean ΔE {d:.3} dithered, {n:.3} nearest");
        assert!(d < n, "dithered {d} vs nearest {n}");
        // Pixel by pixel the dither stays close too: it mixes only where
        // that helps (dithering everywhere gave 8.9 on the 0-255 scale).
        let mae = dithered
            .iter()
            .zip(&truth)
            .map(|(p, q)| (0..3).map(|c| p[c].abs_diff(q[c]) as f64).sum::<f64>())
            .sum::<f64>()
            / (3 * truth.len()) as f64;
        eprintln!("mean absolute error per channel: {mae:.2}");
        assert!(mae < 8.0, "{mae}");
    }
}
