//! Pixels to terminal cells: two vertically stacked pixels per cell with the
//! upper half block (foreground = top pixel, background = bottom pixel), in
//! truecolor or quantized to the xterm 256-colour or the 16 ANSI colours.

use std::sync::OnceLock;

use glam::Vec3;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;
use rayon::prelude::*;

use crate::render::post::encode_srgb;

/// The upper half block: its foreground paints the top pixel of a cell.
pub const UPPER_HALF: &str = "▀";

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ColorMode {
    /// 24-bit colour.
    Truecolor,
    /// The xterm 256-colour palette (6x6x6 cube and grey ramp).
    #[value(name = "256")]
    Palette256,
    /// The 16 ANSI colours, with ordered dithering.
    #[value(name = "16")]
    Ansi16,
}

impl ColorMode {
    /// Truecolor when `COLORTERM` says the terminal has it, else 256 colours.
    pub fn detect(colorterm: Option<&str>) -> Self {
        match colorterm.map(str::to_ascii_lowercase).as_deref() {
            Some("truecolor" | "24bit") => ColorMode::Truecolor,
            _ => ColorMode::Palette256,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            ColorMode::Truecolor => "truecolor",
            ColorMode::Palette256 => "256 colours",
            ColorMode::Ansi16 => "16 colours",
        }
    }
}

/// Linear colour to 8-bit sRGB.
pub fn srgb(c: Vec3) -> [u8; 3] {
    [encode_srgb(c.x), encode_srgb(c.y), encode_srgb(c.z)]
}

/// Squared distance in sRGB with weights for the eye's sensitivity (green
/// most, red and blue less), for the 16-colour dither.
fn dist(a: [u8; 3], b: [u8; 3]) -> u32 {
    const W: [u32; 3] = [5, 8, 5];
    (0..3)
        .map(|i| W[i] * (a[i] as i32 - b[i] as i32).pow(2) as u32)
        .sum()
}

/// Channel levels of the 6x6x6 cube.
const CUBE: [u8; 6] = [0, 95, 135, 175, 215, 255];

/// RGB of palette entry `i` (16..=255) of the xterm 256-colour palette.
pub fn palette256(i: u8) -> [u8; 3] {
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

/// CIELAB (D65) of an sRGB colour: distances in it follow perceived
/// differences, which keeps hues right where the cube is coarse.
fn lab(c: [u8; 3]) -> [f32; 3] {
    let lin = |v: u8| {
        let v = v as f32 / 255.0;
        if v <= 0.040_45 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let [r, g, b] = c.map(lin);
    let x = (0.4124 * r + 0.3576 * g + 0.1805 * b) / 0.9505;
    let y = 0.2126 * r + 0.7152 * g + 0.0722 * b;
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

/// Bits per channel of the 256-colour lookup table's index.
const TABLE_BITS: u32 = 6;

/// The entry of the cube and grey ramp (16..=255; the first 16 vary between
/// terminals) nearest in CIELAB to `c`, by full search.
fn nearest256(c: [u8; 3], palette: &[[f32; 3]]) -> u8 {
    let l = lab(c);
    let d = |p: &[f32; 3]| (0..3).map(|i| (l[i] - p[i]).powi(2)).sum::<f32>();
    (0..palette.len())
        .min_by(|&a, &b| d(&palette[a]).total_cmp(&d(&palette[b])))
        .map_or(16, |i| 16 + i as u8)
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
        let palette: Vec<[f32; 3]> = (16..=255).map(|i| lab(palette256(i))).collect();
        (0..1usize << (3 * TABLE_BITS))
            .into_par_iter()
            .map(|k| nearest256(cell_colour(k), &palette))
            .collect()
    })
}

/// The 256-colour palette entry for `c`: the one nearest in CIELAB to the
/// middle of `c`'s table cell (at most 2 steps away in each channel).
pub fn quantize256(c: [u8; 3]) -> u8 {
    let s = 8 - TABLE_BITS;
    let k = ((c[0] as usize >> s) << (2 * TABLE_BITS))
        | ((c[1] as usize >> s) << TABLE_BITS)
        | (c[2] as usize >> s);
    table256()[k]
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

fn nearest16(c: [i32; 3]) -> usize {
    let c = c.map(|v| v.clamp(0, 255) as u8);
    (0..16).min_by_key(|&i| dist(c, ANSI16[i].1)).unwrap_or(0)
}

/// One of the 16 ANSI colours for pixel `c` at (x, y), ordered-dithered
/// between the nearest colour and the nearest one on the other side of the
/// pixel, in proportion to where the pixel lies between them. Colours in
/// the palette come out exactly.
pub fn quantize16(c: [u8; 3], x: u32, y: u32) -> Color {
    let p = c.map(i32::from);
    let a = nearest16(p);
    let ca = ANSI16[a].1.map(i32::from);
    let b = nearest16([0, 1, 2].map(|i| 2 * p[i] - ca[i]));
    let cb = ANSI16[b].1.map(i32::from);
    let ab: [i32; 3] = [0, 1, 2].map(|i| cb[i] - ca[i]);
    let len2: i32 = ab.iter().map(|v| v * v).sum();
    if len2 == 0 {
        return ANSI16[a].0;
    }
    let along: i32 = (0..3).map(|i| (p[i] - ca[i]) * ab[i]).sum();
    let ratio = (along as f32 / len2 as f32).clamp(0.0, 1.0);
    let threshold = (BAYER[y as usize % 4][x as usize % 4] as f32 + 0.5) / 16.0;
    ANSI16[if threshold < ratio { b } else { a }].0
}

/// The terminal colour of sRGB pixel `c` at image position (x, y).
pub fn to_color(c: [u8; 3], mode: ColorMode, x: u32, y: u32) -> Color {
    match mode {
        ColorMode::Truecolor => Color::Rgb(c[0], c[1], c[2]),
        ColorMode::Palette256 => Color::Indexed(quantize256(c)),
        ColorMode::Ansi16 => quantize16(c, x, y),
    }
}

/// Paints a `w x h` sRGB image into `area`, two pixels per cell. An image
/// of another size than the area's (during a resize) is scaled to fit.
pub fn paint(buf: &mut Buffer, area: Rect, img: &[[u8; 3]], w: u32, h: u32, mode: ColorMode) {
    if w == 0 || h == 0 || img.len() < (w * h) as usize {
        return;
    }
    let rows = area.height as u32 * 2;
    let px = |cx: u32, py: u32| {
        let x = cx * w / area.width.max(1) as u32;
        let y = py * h / rows.max(1);
        (x, y, img[(y * w + x) as usize])
    };
    for cy in 0..area.height {
        for cx in 0..area.width {
            let (tx, ty, top) = px(cx as u32, 2 * cy as u32);
            let (bx, by, bottom) = px(cx as u32, 2 * cy as u32 + 1);
            if let Some(cell) = buf.cell_mut((area.x + cx, area.y + cy)) {
                cell.set_symbol(UPPER_HALF);
                cell.fg = to_color(top, mode, tx, ty);
                cell.bg = to_color(bottom, mode, bx, by);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_block_puts_top_in_foreground() {
        let img = [[255, 0, 0], [0, 0, 255], [0, 255, 0], [10, 20, 30]];
        let mut buf = Buffer::empty(Rect::new(0, 0, 2, 1));
        paint(
            &mut buf,
            Rect::new(0, 0, 2, 1),
            &img,
            2,
            2,
            ColorMode::Truecolor,
        );
        let c = &buf[(0, 0)];
        assert_eq!(c.symbol(), UPPER_HALF);
        assert_eq!(c.fg, Color::Rgb(255, 0, 0));
        assert_eq!(c.bg, Color::Rgb(0, 255, 0));
        assert_eq!(buf[(1, 0)].fg, Color::Rgb(0, 0, 255));
        assert_eq!(buf[(1, 0)].bg, Color::Rgb(10, 20, 30));
    }

    #[test]
    fn linear_values_are_gamma_encoded() {
        // Linear 0.214 is sRGB mid-grey 128; 0 and >= 1 clamp to the ends.
        assert_eq!(srgb(Vec3::new(0.214_041_14, 0.0, 3.0)), [128, 0, 255]);
        assert_eq!(srgb(Vec3::NAN), [0, 0, 0]);
    }

    #[test]
    fn detection_reads_colorterm() {
        assert_eq!(ColorMode::detect(Some("truecolor")), ColorMode::Truecolor);
        assert_eq!(ColorMode::detect(Some("24bit")), ColorMode::Truecolor);
        assert_eq!(ColorMode::detect(None), ColorMode::Palette256);
        assert_eq!(ColorMode::detect(Some("")), ColorMode::Palette256);
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
        let palette: Vec<[f32; 3]> = (16..=255).map(|i| lab(palette256(i))).collect();
        let de = |a: [u8; 3], b: [u8; 3]| {
            let (a, b) = (lab(a), lab(b));
            (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f32>().sqrt()
        };
        for r in (0..=255).step_by(15) {
            for g in (0..=255).step_by(17) {
                for b in (0..=255).step_by(19) {
                    let c = [r as u8, g as u8, b as u8];
                    let q = palette256(quantize256(c));
                    let best = palette256(nearest256(c, &palette));
                    // The table answers for the middle m of c's cell, so by
                    // the triangle inequality it is at most 2 ΔE(c, m) worse.
                    let k = (r as usize >> 2) << 12 | (g as usize >> 2) << 6 | b as usize >> 2;
                    let m = cell_colour(k);
                    let slack = 2.0 * de(c, m) + 1e-3;
                    assert!(de(c, q) <= de(c, best) + slack, "{c:?}: {q:?} vs {best:?}");
                    // Cells' middles are answered exactly.
                    assert_eq!(quantize256(m), nearest256(m, &palette), "{m:?}");
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
}
