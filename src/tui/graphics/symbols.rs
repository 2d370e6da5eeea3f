//! Pixels to cells with block symbols: each cell covers a grid of sub-pixels
//! (1x2 for half blocks, 2x2 quadrants, 2x3 sextants, 2x4 octants) and shows
//! two colours, foreground where its glyph is inked. Per cell the two
//! colours and the glyph are the least-squares fit of the sub-pixels: the
//! partition of the sub-pixels into two sets that leaves the least squared
//! error around the two sets' means.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::Color;

use crate::tui::color::{to_color, ColorMode};

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Symbols {
    /// Upper half blocks: 1x2 pixels per cell; every terminal has them.
    #[default]
    Half,
    /// Quadrants: 2x2 pixels per cell.
    Quad,
    /// Sextants (Unicode 13): 2x3 pixels per cell.
    Sextant,
    /// Octants (Unicode 16): 2x4 pixels per cell.
    Octant,
}

impl Symbols {
    /// Sub-pixels per cell, across and down.
    pub fn grid(self) -> (u32, u32) {
        match self {
            Symbols::Half => (1, 2),
            Symbols::Quad => (2, 2),
            Symbols::Sextant => (2, 3),
            Symbols::Octant => (2, 4),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Symbols::Half => "half blocks",
            Symbols::Quad => "quadrants",
            Symbols::Sextant => "sextants",
            Symbols::Octant => "octants",
        }
    }

    /// The glyph whose inked sub-pixels are the bits of `mask` (bit `i` is
    /// sub-pixel `i`, row by row from the top left), if the symbol set has
    /// one. `0` and the full mask are a space (background only).
    pub fn glyph(self, mask: u8) -> Option<char> {
        let (gx, gy) = self.grid();
        let full = ((1u32 << (gx * gy)) - 1) as u8;
        if mask == 0 || mask == full {
            return Some(' ');
        }
        match self {
            // Bit 0 is the top pixel.
            Symbols::Half => Some(if mask == 1 { '▀' } else { '▄' }),
            Symbols::Quad => Some(QUADRANTS[mask as usize]),
            Symbols::Sextant => Some(sextant(mask)),
            Symbols::Octant => octant(mask),
        }
    }
}

/// Quadrant glyphs by mask (bit 0 top left, 1 top right, 2 bottom left, 3
/// bottom right).
const QUADRANTS: [char; 16] = [
    ' ', '▘', '▝', '▀', '▖', '▌', '▞', '▛', '▗', '▚', '▐', '▜', '▄', '▙', '▟', '█',
];

/// Sextants are U+1FB00.. in mask order, less the two halves that Block
/// Elements already has.
fn sextant(mask: u8) -> char {
    const LEFT: u8 = 0b01_0101;
    const RIGHT: u8 = 0b10_1010;
    match mask {
        LEFT => '▌',
        RIGHT => '▐',
        m => {
            let skipped = (m > LEFT) as u32 + (m > RIGHT) as u32;
            char::from_u32(0x1FB00 + m as u32 - 1 - skipped).unwrap_or(' ')
        }
    }
}

/// Octant patterns that Unicode encodes outside the octant block (Block
/// Elements' halves, quadrants and quarter blocks, and Symbols for Legacy
/// Computing's quarter blocks), with the glyph where it is a Block Element.
const OCTANT_ELSEWHERE: [(u8, Option<char>); 24] = [
    (0b0000_0001, None),
    (0b0000_0010, None),
    (0b0100_0000, None),
    (0b1000_0000, None),
    (0b0000_0011, None),
    (0b0011_1111, None),
    (0b0001_0100, None),
    (0b0010_1000, None),
    (0b1100_0000, Some('▂')),
    (0b1111_1100, Some('▆')),
    (0b0000_1111, Some('▀')),
    (0b1111_0000, Some('▄')),
    (0b0101_0101, Some('▌')),
    (0b1010_1010, Some('▐')),
    (0b0000_0101, Some('▘')),
    (0b0000_1010, Some('▝')),
    (0b0101_0000, Some('▖')),
    (0b1010_0000, Some('▗')),
    (0b1010_0101, Some('▚')),
    (0b0101_1010, Some('▞')),
    (0b0101_1111, Some('▛')),
    (0b1010_1111, Some('▜')),
    (0b1111_0101, Some('▙')),
    (0b1111_1010, Some('▟')),
];

/// Octants are U+1CD00..=U+1CDE5 in mask order, less the patterns encoded
/// elsewhere. Those outside Block Elements are left out (`None`): their
/// complements are octants, and Legacy Computing fonts are rarer.
fn octant(mask: u8) -> Option<char> {
    if let Some((_, g)) = OCTANT_ELSEWHERE.iter().find(|(m, _)| *m == mask) {
        return *g;
    }
    let below = OCTANT_ELSEWHERE.iter().filter(|(m, _)| *m < mask).count() as u32;
    char::from_u32(0x1CD00 + mask as u32 - 1 - below)
}

/// The fit of one cell: the sub-pixels in `mask` take `fg`, the others `bg`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fit {
    pub mask: u8,
    pub fg: [f32; 3],
    pub bg: [f32; 3],
    /// Sum of squared differences over the sub-pixels (sRGB, 0..255).
    pub error: f32,
}

/// The least-squares two-colour fit of `px` (up to 8 sub-pixels). The error
/// of a partition into sets A and B around their means is
/// `Σ|c|² - |ΣA|²/|A| - |ΣB|²/|B|`, so the best partition maximises the last
/// two terms; partitions are visited in Gray-code order (one sub-pixel
/// moves per step) with the last sub-pixel always in B, since a partition
/// and its complement fit alike.
pub fn fit(px: &[[f32; 3]]) -> Fit {
    let n = px.len();
    debug_assert!((1..=8).contains(&n));
    let mut total = [0f32; 3];
    let mut sq = 0f32;
    for p in px {
        for i in 0..3 {
            total[i] += p[i];
            sq += p[i] * p[i];
        }
    }
    let norm2 = |v: [f32; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    // The uniform cell (A empty) first.
    let mut best_score = norm2(total) / n as f32;
    let mut best_mask = 0u32;
    let mut sum_a = [0f32; 3];
    let mut count_a = 0u32;
    let mut gray = 0u32;
    for i in 1u32..(1 << (n - 1)) {
        let g = i ^ (i >> 1);
        let bit = (g ^ gray).trailing_zeros() as usize;
        let sign = if g & (1 << bit) != 0 { 1.0 } else { -1.0 };
        for c in 0..3 {
            sum_a[c] += sign * px[bit][c];
        }
        count_a = if sign > 0.0 { count_a + 1 } else { count_a - 1 };
        gray = g;
        let sum_b = [0, 1, 2].map(|c| total[c] - sum_a[c]);
        let score = norm2(sum_a) / count_a as f32 + norm2(sum_b) / (n as u32 - count_a) as f32;
        if score > best_score {
            best_score = score;
            best_mask = g;
        }
    }
    let mean = |mask: u32, want: bool| {
        let mut s = [0f32; 3];
        let mut k = 0;
        for (j, p) in px.iter().enumerate() {
            if (mask >> j & 1 == 1) == want {
                for c in 0..3 {
                    s[c] += p[c];
                }
                k += 1;
            }
        }
        s.map(|v| v / k.max(1) as f32)
    };
    let bg = mean(best_mask, false);
    let fg = if best_mask == 0 {
        bg
    } else {
        mean(best_mask, true)
    };
    Fit {
        mask: best_mask as u8,
        fg,
        bg,
        error: (sq - best_score).max(0.0),
    }
}

/// The sub-pixels of cell (cx, cy) of an image `w` wide, in mask order.
/// An image of another size than the grid's (during a resize) is sampled
/// to fit.
struct Grid {
    w: u32,
    h: u32,
    /// The grid's size in sub-pixels.
    gw: u32,
    gh: u32,
}

impl Grid {
    /// The image pixel under sub-pixel (sx, sy) of the grid.
    fn at(&self, sx: u32, sy: u32) -> (u32, u32) {
        if (self.w, self.h) == (self.gw, self.gh) {
            (sx, sy)
        } else {
            (sx * self.w / self.gw.max(1), sy * self.h / self.gh.max(1))
        }
    }
}

/// Fits every cell of `area` to the `w x h` sRGB image laid over it and
/// writes the glyphs and colours into `buf`. Of the two ways to show a fit
/// (a glyph, or its complement with the colours swapped) the one that
/// repeats the previous cell's colours is taken, which saves bytes.
pub fn paint(
    buf: &mut Buffer,
    area: Rect,
    img: &[[u8; 3]],
    (w, h): (u32, u32),
    symbols: Symbols,
    mode: ColorMode,
) {
    if w == 0 || h == 0 || img.len() < (w * h) as usize {
        return;
    }
    let (gx, gy) = symbols.grid();
    let n = (gx * gy) as usize;
    let full = ((1u32 << n) - 1) as u8;
    let grid = Grid {
        w,
        h,
        gw: area.width as u32 * gx,
        gh: area.height as u32 * gy,
    };
    let mut px = [[0f32; 3]; 8];
    let mut pos = [(0u32, 0u32); 8];
    for cy in 0..area.height {
        let (mut prev_fg, mut prev_bg) = (Color::Reset, Color::Reset);
        for cx in 0..area.width {
            for j in 0..n {
                let (sx, sy) = (
                    cx as u32 * gx + j as u32 % gx,
                    cy as u32 * gy + j as u32 / gx,
                );
                let (x, y) = grid.at(sx, sy);
                pos[j] = (sx, sy);
                px[j] = img[(y * w + x) as usize].map(f32::from);
            }
            let f = fit(&px[..n]);
            // Dither each colour at the first sub-pixel it paints, so half
            // blocks dither exactly as the pixels would.
            let first = |want: bool| {
                (0..n)
                    .find(|&j| (f.mask >> j & 1 == 1) == want)
                    .map_or(pos[0], |j| pos[j])
            };
            let to = |c: [f32; 3], (x, y): (u32, u32)| {
                to_color(c.map(|v| v.round().clamp(0.0, 255.0) as u8), mode, x, y)
            };
            let bg = to(f.bg, first(false));
            let fg = if f.mask == 0 {
                bg
            } else {
                to(f.fg, first(true))
            };
            let Some(cell) = buf.cell_mut((area.x + cx, area.y + cy)) else {
                continue;
            };
            let (symbol, fg, bg) = if fg == bg || f.mask == 0 || f.mask == full {
                // One colour: a space on it, the foreground left as it was.
                (' ', prev_fg, if f.mask == full { fg } else { bg })
            } else {
                let straight = symbols.glyph(f.mask).map(|g| (g, fg, bg));
                let swapped = symbols.glyph(!f.mask & full).map(|g| (g, bg, fg));
                match (straight, swapped) {
                    (Some(a), Some(b)) => {
                        let same = |o: &(char, Color, Color)| {
                            (o.1 == prev_fg) as u8 + (o.2 == prev_bg) as u8
                        };
                        if same(&b) > same(&a) {
                            b
                        } else {
                            a
                        }
                    }
                    (Some(a), None) | (None, Some(a)) => a,
                    (None, None) => (' ', prev_fg, bg),
                }
            };
            let mut utf8 = [0u8; 4];
            cell.set_symbol(symbol.encode_utf8(&mut utf8));
            cell.fg = symbol_fg(symbol, fg, prev_fg);
            cell.bg = bg;
            (prev_fg, prev_bg) = (cell.fg, cell.bg);
        }
    }
}

/// A space shows no foreground: keep the previous one so that no escape is
/// sent for it.
fn symbol_fg(symbol: char, fg: Color, prev: Color) -> Color {
    if symbol == ' ' {
        prev
    } else {
        fg
    }
}

/// The sub-pixels a painted cell shows, as sRGB in mask order (for tests
/// and the benchmark's error figures).
pub fn shown_cell(symbols: Symbols, symbol: &str, fg: Color, bg: Color) -> Option<Vec<[u8; 3]>> {
    let (gx, gy) = symbols.grid();
    let n = gx * gy;
    let full = ((1u32 << n) - 1) as u8;
    let ch = symbol.chars().next()?;
    let mask = if ch == ' ' {
        0
    } else {
        (0..=full).find(|&m| symbols.glyph(m) == Some(ch) && m != 0)?
    };
    let (f, b) = (
        crate::tui::color::shown(fg).unwrap_or([0; 3]),
        crate::tui::color::shown(bg)?,
    );
    Some(
        (0..n)
            .map(|j| if mask >> j & 1 == 1 { f } else { b })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_pattern_has_a_glyph_or_a_complement() {
        for s in [
            Symbols::Half,
            Symbols::Quad,
            Symbols::Sextant,
            Symbols::Octant,
        ] {
            let (gx, gy) = s.grid();
            let full = ((1u32 << (gx * gy)) - 1) as u8;
            let mut seen = std::collections::HashSet::new();
            for m in 0..=full {
                assert!(
                    s.glyph(m).is_some() || s.glyph(!m & full).is_some(),
                    "{s:?} {m:08b}"
                );
                if let Some(g) = s.glyph(m).filter(|&g| g != ' ') {
                    assert!(seen.insert(g), "{s:?}: {g} twice");
                }
            }
        }
        // The blocks' ends: 60 sextants, 230 octants.
        assert_eq!(Symbols::Sextant.glyph(0b11_1110), Some('\u{1FB3B}'));
        assert_eq!(Symbols::Sextant.glyph(1), Some('\u{1FB00}'));
        assert_eq!(Symbols::Octant.glyph(0b100), Some('\u{1CD00}'));
        assert_eq!(Symbols::Octant.glyph(0b1111_1110), Some('\u{1CDE5}'));
    }

    #[test]
    fn the_fit_is_the_best_partition() {
        // Brute force over every partition and compare.
        let mut rng = 12345u32;
        let mut next = || {
            rng = rng.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (rng >> 24) as f32
        };
        for n in [2usize, 4, 6, 8] {
            for _ in 0..50 {
                let px: Vec<[f32; 3]> = (0..n).map(|_| [next(), next(), next()]).collect();
                let f = fit(&px);
                let err = |mask: u32| {
                    let mean = |want: bool| {
                        let v: Vec<_> = px
                            .iter()
                            .enumerate()
                            .filter(|(j, _)| (mask >> j & 1 == 1) == want)
                            .map(|(_, p)| *p)
                            .collect();
                        let k = v.len().max(1) as f32;
                        let s = v
                            .iter()
                            .fold([0f32; 3], |a, p| [a[0] + p[0], a[1] + p[1], a[2] + p[2]]);
                        s.map(|x| x / k)
                    };
                    let (a, b) = (mean(true), mean(false));
                    px.iter()
                        .enumerate()
                        .map(|(j, p)| {
                            let m = if mask >> j & 1 == 1 { a } else { b };
                            (0..3).map(|c| (p[c] - m[c]).powi(2)).sum::<f32>()
                        })
                        .sum::<f32>()
                };
                let best = (0..1u32 << n).map(err).fold(f32::INFINITY, f32::min);
                assert!(
                    (f.error - best).abs() <= 1e-2 * best.max(1.0),
                    "{n}: {} vs {best}",
                    f.error
                );
                assert!((err(f.mask as u32) - f.error).abs() <= 1e-2 * best.max(1.0));
            }
        }
    }

    #[test]
    fn half_blocks_are_exact() {
        let img = [[255, 0, 0], [0, 0, 255], [0, 255, 0], [10, 20, 30]];
        let mut buf = Buffer::empty(Rect::new(0, 0, 2, 1));
        paint(
            &mut buf,
            Rect::new(0, 0, 2, 1),
            &img,
            (2, 2),
            Symbols::Half,
            ColorMode::Truecolor,
        );
        for (x, top, bottom) in [(0, img[0], img[2]), (1, img[1], img[3])] {
            let c = &buf[(x, 0)];
            let shown = shown_cell(Symbols::Half, c.symbol(), c.fg, c.bg).unwrap();
            assert_eq!(shown, vec![top, bottom], "{c:?}");
        }
    }
}
