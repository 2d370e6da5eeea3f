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

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Symbols {
    #[default]
    Half,
    Quad,
    Sextant,
    Octant,
}

impl crate::choice::Choice for Symbols {
    const ALL: &'static [Self] = &[
        Symbols::Half,
        Symbols::Quad,
        Symbols::Sextant,
        Symbols::Octant,
    ];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            Symbols::Half => (
                "half",
                "Upper half blocks: 1x2 pixels per cell; every terminal has them",
            ),
            Symbols::Quad => ("quad", "Quadrants: 2x2 pixels per cell"),
            Symbols::Sextant => ("sextant", "Sextants (Unicode 13): 2x3 pixels per cell"),
            Symbols::Octant => ("octant", "Octants (Unicode 16): 2x4 pixels per cell"),
        }
    }
}

/// What `--symbols` asks for: a set, or the densest set the terminal is
/// known to draw (see `term::glyphs`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum SymbolsArg {
    #[default]
    Auto,
    Set(Symbols),
}

impl crate::choice::Choice for SymbolsArg {
    const ALL: &'static [Self] = &[
        SymbolsArg::Auto,
        SymbolsArg::Set(Symbols::Half),
        SymbolsArg::Set(Symbols::Quad),
        SymbolsArg::Set(Symbols::Sextant),
        SymbolsArg::Set(Symbols::Octant),
    ];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            SymbolsArg::Auto => (
                "auto",
                "The densest set the terminal is known to draw (half blocks elsewhere)",
            ),
            SymbolsArg::Set(s) => s.choice(),
        }
    }
}

impl Symbols {
    /// Sub-pixels per cell, across and down.
    pub(crate) fn grid(self) -> (u32, u32) {
        match self {
            Symbols::Half => (1, 2),
            Symbols::Quad => (2, 2),
            Symbols::Sextant => (2, 3),
            Symbols::Octant => (2, 4),
        }
    }

    pub(crate) fn name(self) -> &'static str {
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
    pub(crate) fn glyph(self, mask: u8) -> Option<char> {
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

/// What a cell's foreground covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Shape {
    /// The sub-pixels whose bits are set (`0`: none, one colour).
    Mask(u8),
    /// The upper half block on the sextant grid: the top row, half of the
    /// middle one. Every font has it, and a gradient across the cell is
    /// better served by it than by any two-colour sextant.
    UpperHalf,
}

/// Coverage of [`Shape::UpperHalf`] on the 2x3 sextant grid.
const UPPER_HALF_ON_SEXTANTS: [f32; 6] = [1.0, 1.0, 0.5, 0.5, 0.0, 0.0];

/// The fit of one cell: `fg` where `shape` covers, `bg` elsewhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Fit {
    pub(crate) shape: Shape,
    pub(crate) fg: [f32; 3],
    pub(crate) bg: [f32; 3],
    /// Sum of squared differences over the sub-pixels (sRGB, 0..255).
    pub(crate) error: f32,
}

impl Fit {
    /// What sub-pixel `j` shows.
    pub(crate) fn at(&self, j: usize) -> [f32; 3] {
        let a = coverage(self.shape, j);
        [0, 1, 2].map(|c| a * self.fg[c] + (1.0 - a) * self.bg[c])
    }
}

/// How much of sub-pixel `j` the foreground of `shape` covers.
fn coverage(shape: Shape, j: usize) -> f32 {
    match shape {
        Shape::Mask(m) => (m >> j & 1) as f32,
        Shape::UpperHalf => UPPER_HALF_ON_SEXTANTS[j],
    }
}

/// The least-squares fit of `px` (the cell's sub-pixels, up to 8, in mask
/// order) with the shapes of `symbols`: every two-colour partition, and on
/// the sextant grid also the upper half block.
pub(crate) fn fit(px: &[[f32; 3]], symbols: Symbols) -> Fit {
    let best = fit_partition(px);
    if symbols != Symbols::Sextant || px.len() != 6 {
        return best;
    }
    let half = fit_coverage(px, Shape::UpperHalf);
    if half.error < best.error {
        half
    } else {
        best
    }
}

/// The least-squares colours for a shape with partial coverage α: the 2x2
/// normal equations of `Σ|p - αF - (1-α)B|²`, per channel. Colours outside
/// 0..255 cannot be shown; the area means (what a coarser render would
/// give) are taken instead then.
fn fit_coverage(px: &[[f32; 3]], shape: Shape) -> Fit {
    let (mut a11, mut a12, mut a22) = (0f32, 0f32, 0f32);
    let (mut r1, mut r2) = ([0f32; 3], [0f32; 3]);
    for (j, p) in px.iter().enumerate() {
        let a = coverage(shape, j);
        a11 += a * a;
        a12 += a * (1.0 - a);
        a22 += (1.0 - a) * (1.0 - a);
        for c in 0..3 {
            r1[c] += a * p[c];
            r2[c] += (1.0 - a) * p[c];
        }
    }
    let det = a11 * a22 - a12 * a12;
    let mut fg = [0, 1, 2].map(|c| (a22 * r1[c] - a12 * r2[c]) / det);
    let mut bg = [0, 1, 2].map(|c| (a11 * r2[c] - a12 * r1[c]) / det);
    let in_range = |v: &[f32; 3]| v.iter().all(|x| (0.0..=255.0).contains(x));
    if !(in_range(&fg) && in_range(&bg)) {
        let (wf, wb) = (a11 + a12, a22 + a12);
        fg = r1.map(|v| v / wf);
        bg = r2.map(|v| v / wb);
    }
    let mut f = Fit {
        shape,
        fg,
        bg,
        error: 0.0,
    };
    f.error = px
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let q = f.at(j);
            (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f32>()
        })
        .sum();
    f
}

/// The least-squares two-colour fit of `px` (up to 8 sub-pixels). The error
/// of a partition into sets A and B around their means is
/// `Σ|c|² - |ΣA|²/|A| - |ΣB|²/|B|`, so the best partition maximises the last
/// two terms; partitions are visited in Gray-code order (one sub-pixel
/// moves per step) with the last sub-pixel always in B, since a partition
/// and its complement fit alike.
fn fit_partition(px: &[[f32; 3]]) -> Fit {
    let n = px.len();
    debug_assert!((1..=8).contains(&n));
    // In f64: the terms are large and close, and f32 would misjudge near ties.
    let mut total = [0f64; 3];
    let mut sq = 0f64;
    for p in px {
        for i in 0..3 {
            total[i] += p[i] as f64;
            sq += (p[i] as f64).powi(2);
        }
    }
    let norm2 = |v: [f64; 3]| v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    // The uniform cell (A empty) first.
    let mut best_score = norm2(total) / n as f64;
    let mut best_mask = 0u32;
    let mut sum_a = [0f64; 3];
    let mut count_a = 0u32;
    let mut gray = 0u32;
    for i in 1u32..(1 << (n - 1)) {
        let g = i ^ (i >> 1);
        let bit = (g ^ gray).trailing_zeros() as usize;
        let sign = if g & (1 << bit) != 0 { 1.0 } else { -1.0 };
        for c in 0..3 {
            sum_a[c] += sign * px[bit][c] as f64;
        }
        count_a = if sign > 0.0 { count_a + 1 } else { count_a - 1 };
        gray = g;
        let sum_b = [0, 1, 2].map(|c| total[c] - sum_a[c]);
        let score = norm2(sum_a) / count_a as f64 + norm2(sum_b) / (n as u32 - count_a) as f64;
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
        shape: Shape::Mask(best_mask as u8),
        fg,
        bg,
        error: (sq - best_score).max(0.0) as f32,
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
pub(crate) fn paint(
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
            let f = fit(&px[..n], symbols);
            // Dither each colour at the first sub-pixel it paints most, so
            // half blocks dither exactly as the pixels would.
            let first = |want: bool| {
                (0..n)
                    .find(|&j| (coverage(f.shape, j) >= 0.5) == want)
                    .map_or(pos[0], |j| pos[j])
            };
            let to = |c: [f32; 3], (x, y): (u32, u32)| {
                to_color(c.map(|v| v.round().clamp(0.0, 255.0) as u8), mode, x, y)
            };
            let bg = to(f.bg, first(false));
            let fg = if f.shape == Shape::Mask(0) {
                bg
            } else {
                to(f.fg, first(true))
            };
            let Some(cell) = buf.cell_mut((area.x + cx, area.y + cy)) else {
                continue;
            };
            let (straight, swapped) = match f.shape {
                Shape::Mask(m) => (symbols.glyph(m), symbols.glyph(!m & full)),
                Shape::UpperHalf => (Some('▀'), Some('▄')),
            };
            let (symbol, fg, bg) = match (f.shape, straight, swapped) {
                // One colour: a space on it, the foreground left as it was.
                (Shape::Mask(0), ..) => (' ', prev_fg, bg),
                (Shape::Mask(m), ..) if m == full => (' ', prev_fg, fg),
                _ if fg == bg => (' ', prev_fg, bg),
                (_, Some(g), Some(h)) => {
                    let (a, b) = ((g, fg, bg), (h, bg, fg));
                    let same =
                        |o: &(char, Color, Color)| (o.1 == prev_fg) as u8 + (o.2 == prev_bg) as u8;
                    if same(&b) > same(&a) {
                        b
                    } else {
                        a
                    }
                }
                (_, Some(g), None) => (g, fg, bg),
                (_, None, Some(h)) => (h, bg, fg),
                (_, None, None) => (' ', prev_fg, bg),
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

/// The sub-pixels a painted cell shows, in mask order (sRGB; a sub-pixel
/// half covered shows the mean of the two colours). For tests.
#[cfg(test)]
pub(crate) fn shown_cell(
    symbols: Symbols,
    symbol: &str,
    fg: Color,
    bg: Color,
) -> Option<Vec<[f32; 3]>> {
    let (gx, gy) = symbols.grid();
    let n = gx * gy;
    let full = ((1u32 << n) - 1) as u8;
    let ch = symbol.chars().next()?;
    let shape = match ch {
        ' ' => Shape::Mask(0),
        '▀' if symbols == Symbols::Sextant => Shape::UpperHalf,
        '▄' if symbols == Symbols::Sextant => {
            return shown_cell(symbols, "▀", bg, fg);
        }
        _ => Shape::Mask((1..=full).find(|&m| symbols.glyph(m) == Some(ch))?),
    };
    let f = Fit {
        shape,
        fg: crate::tui::color::shown(fg)
            .unwrap_or([0; 3])
            .map(f32::from),
        bg: crate::tui::color::shown(bg)?.map(f32::from),
        error: 0.0,
    };
    Some((0..n as usize).map(|j| f.at(j)).collect())
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
                let f = fit_partition(&px);
                let Shape::Mask(mask) = f.shape else {
                    panic!("{f:?}")
                };
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
                assert!((err(mask as u32) - f.error).abs() <= 1e-2 * best.max(1.0));
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
            assert_eq!(
                shown,
                vec![top.map(f32::from), bottom.map(f32::from)],
                "{c:?}"
            );
        }
    }

    /// The scene rendered at `w x h`, as sRGB.
    fn render(scene: &str, w: u32, h: u32) -> Vec<[f32; 3]> {
        use crate::render::{post, Progressive, SceneRequest, Session};
        let req = SceneRequest {
            size: Some((w, h)),
            ..SceneRequest::new(scene)
        };
        let (s, _) = Session::open(&req).unwrap();
        let film = Progressive::render(&s.tracer(), 2);
        let shown = post::display(film.image(), w, h, &s.plan, &s.scene.settings.bloom);
        shown
            .image
            .iter()
            .map(|c| crate::color::srgb(*c).map(f32::from))
            .collect()
    }

    fn sse(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| {
                (0..3)
                    .map(|c| (p[c] as f64 - q[c] as f64).powi(2))
                    .sum::<f64>()
            })
            .sum()
    }

    fn psnr(sse: f64, samples: usize) -> f64 {
        10.0 * (255.0f64.powi(2) / (sse / (3 * samples) as f64)).log10()
    }

    /// What half blocks at the same cell count show on a cell's `gx x gy`
    /// sub-pixels: the area means of its top and bottom halves, the middle
    /// row of an odd grid half of each.
    fn half_blocks(cell: &[[f32; 3]], gx: usize, gy: usize) -> Vec<[f32; 3]> {
        let cover = |r: usize| (gy as f32 / 2.0 - r as f32).clamp(0.0, 1.0);
        let (mut top, mut bottom, mut wt, mut wb) = ([0f32; 3], [0f32; 3], 0f32, 0f32);
        for (j, p) in cell.iter().enumerate() {
            let a = cover(j / gx);
            for c in 0..3 {
                top[c] += a * p[c];
                bottom[c] += (1.0 - a) * p[c];
            }
            wt += a;
            wb += 1.0 - a;
        }
        let (top, bottom) = (top.map(|v| v / wt), bottom.map(|v| v / wb));
        (0..cell.len())
            .map(|j| {
                let a = cover(j / gx);
                [0, 1, 2].map(|c| a * top[c] + (1.0 - a) * bottom[c])
            })
            .collect()
    }

    #[test]
    fn finer_symbols_beat_half_blocks_on_every_scene() {
        let (cols, rows) = (60u32, 20u32);
        for (scene, _) in crate::scene::load::builtin::SCENES {
            for symbols in [Symbols::Quad, Symbols::Sextant, Symbols::Octant] {
                let (gx, gy) = symbols.grid();
                let (w, h) = (cols * gx, rows * gy);
                let truth = render(scene, w, h);
                let (n, gxu) = ((gx * gy) as usize, gx as usize);
                let cell_px = |cx: u32, cy: u32, img: &[[f32; 3]]| -> Vec<[f32; 3]> {
                    (0..n)
                        .map(|j| {
                            let (x, y) = (cx * gx + j as u32 % gx, cy * gy + j as u32 / gx);
                            img[(y * w + x) as usize]
                        })
                        .collect()
                };
                // Painted in truecolor as the viewport paints, and read back.
                let u8s: Vec<[u8; 3]> = truth.iter().map(|p| p.map(|v| v as u8)).collect();
                let area = Rect::new(0, 0, cols as u16, rows as u16);
                let mut buf = Buffer::empty(area);
                paint(&mut buf, area, &u8s, (w, h), symbols, ColorMode::Truecolor);
                let (mut fitted, mut halves, mut worse) = (0.0, 0.0, 0);
                for cy in 0..rows {
                    for cx in 0..cols {
                        let px = cell_px(cx, cy, &truth);
                        let c = &buf[(cx as u16, cy as u16)];
                        let shown = shown_cell(symbols, c.symbol(), c.fg, c.bg).unwrap();
                        let half = half_blocks(&px, gxu, gy as usize);
                        // Half blocks show 8-bit colours too.
                        let half_u8: Vec<[f32; 3]> =
                            half.iter().map(|p| p.map(|v| v.round())).collect();
                        fitted += sse(&shown, &px);
                        halves += sse(&half_u8, &px);
                        // Per cell, the least-squares fit is never worse
                        // than half blocks (before either is rounded).
                        let f = fit(&px, symbols);
                        let fit_shown: Vec<[f32; 3]> = (0..n).map(|j| f.at(j)).collect();
                        let (e, eh) = (sse(&fit_shown, &px), sse(&half, &px));
                        if e > eh * (1.0 + 1e-4) + 1e-3 {
                            worse += 1;
                            eprintln!("{scene} {symbols:?} cell ({cx}, {cy}): {e} > {eh}");
                        }
                    }
                }
                let count = (w * h) as usize;
                let (p, ph) = (psnr(fitted, count), psnr(halves, count));
                eprintln!(
                    "{scene:14} {:11} PSNR {p:6.2} dB, half blocks {ph:6.2} dB",
                    symbols.name()
                );
                assert_eq!(worse, 0, "{scene} {symbols:?}");
                if symbols != Symbols::Quad {
                    assert!(p > ph, "{scene} {symbols:?}: {p} <= {ph}");
                }
            }
        }
    }
}
