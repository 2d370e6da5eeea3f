//! The viewport's picture on the terminal: `symbols` fits block symbols
//! and two colours to each cell; with a pixel protocol (`kitty`, `sixel`,
//! `iterm2`) the picture is sent as images, in bands of cell rows
//! (`bands`) so that only what changed is sent again and the output can be
//! paced between them, encoded off the event loop (`encoder`).

pub(crate) mod bands;
pub(crate) mod encoder;
pub(crate) mod iterm2;
pub(crate) mod kitty;
pub(crate) mod sixel;
pub mod symbols;

/// What `--graphics` asks for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum GraphicsArg {
    #[default]
    Auto,
    Kitty,
    Sixel,
    Iterm2,
    Symbols,
}

impl crate::choice::Choice for GraphicsArg {
    const ALL: &'static [Self] = &[
        GraphicsArg::Auto,
        GraphicsArg::Kitty,
        GraphicsArg::Sixel,
        GraphicsArg::Iterm2,
        GraphicsArg::Symbols,
    ];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            GraphicsArg::Auto => (
                "auto",
                "Ask the terminal; block symbols when it has no pixel protocol",
            ),
            GraphicsArg::Kitty => (
                "kitty",
                "The kitty graphics protocol (kitty, Ghostty, WezTerm, Konsole)",
            ),
            GraphicsArg::Sixel => (
                "sixel",
                "Sixel (xterm -ti vt340, foot, mlterm, WezTerm, Windows Terminal)",
            ),
            GraphicsArg::Iterm2 => ("iterm2", "iTerm2 inline images (iTerm2, WezTerm)"),
            GraphicsArg::Symbols => ("symbols", "Block symbols (`--symbols`) only"),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Protocol {
    Kitty,
    Sixel,
    Iterm2,
}

impl Protocol {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Protocol::Kitty => "kitty graphics",
            Protocol::Sixel => "sixel",
            Protocol::Iterm2 => "iTerm2 images",
        }
    }
}

/// Most pixels rendered for the viewport: beyond this a pass takes too
/// long to be progressive, and the picture is rendered smaller and scaled.
pub(crate) const PIXEL_BUDGET: u64 = 640_000;

/// A pixel protocol and what it needs to know of the terminal.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelMode {
    pub protocol: Protocol,
    /// A cell's size in pixels.
    pub cell: (u32, u32),
    /// Colour registers for sixel images.
    pub colours: usize,
    /// Inside tmux with `allow-passthrough`: images are wrapped for it.
    pub passthrough: bool,
    /// Inside tmux: the pane's top-left cell (column, row) in the terminal
    /// tmux runs in. Images sent through passthrough are placed from it,
    /// with the cursor saved and restored around them, since tmux moves
    /// that terminal's cursor only when it next draws.
    pub pane: Option<(u16, u16)>,
    /// The largest image the terminal draws, in its pixels (sixel, where
    /// it says): the picture is kept within it.
    pub max: Option<(u32, u32)>,
}

impl PixelMode {
    /// Rendered pixels per cell for an image of `cols x rows` cells: the
    /// cell's size, divided by the smallest whole factor that keeps the
    /// picture within [`PIXEL_BUDGET`].
    pub(crate) fn grid(&self, cols: u16, rows: u16) -> (u32, u32) {
        let (cw, ch) = (self.cell.0.max(1), self.cell.1.max(1));
        let cells = cols as u64 * rows as u64;
        let mut k = 1u32;
        while cells * (cw / k).max(1) as u64 * (ch / k).max(1) as u64 > PIXEL_BUDGET
            && (cw / k > 1 || ch / k > 1)
        {
            k += 1;
        }
        ((cw / k).max(1), (ch / k).max(1))
    }
}

/// Over a slow link the first picture of a view is sent coarse, to be on
/// screen within about this long (the text around it takes a little more:
/// 8 kB at 160x48 in 256 colours), and the sharp one follows.
const COARSE_WITHIN: f64 = 0.8;
/// Bytes a coarse image takes per pixel sent, about: kitty's
/// zlib-compressed RGB in base64 takes 1.2 to 1.5 once shrunk (a sharp one
/// 0.8 to 1); sixel about 3 per block of one colour (measured in xterm at
/// 160x48: 40 kB for 13,400 blocks), its lines of six pixel rows being
/// written once per colour they hold.
const BYTES_PER_PIXEL: f64 = 1.5;
const SIXEL_BYTES_PER_BLOCK: f64 = 3.0;
/// The link's rate assumed before it is measured: the first picture's.
const UNMEASURED_RATE: f64 = 32e3;
/// Bytes a cell of block symbols takes in 24-bit colour where neighbours
/// differ, as in a first pass's noise: 15 to 21 (`bench tui`'s
/// `first_frame_bytes` over 160x48 cells, `cornell` and `env`); in 256
/// colours it takes 3 to 4.
const TRUECOLOR_BYTES_PER_CELL: f64 = 16.0;

/// Whether `cols x rows` cells of block symbols in 24-bit colour would
/// take longer than [`COARSE_WITHIN`] over a link of `rate` bytes per
/// second (`None`: not measured yet).
pub(crate) fn truecolor_is_slow((cols, rows): (u16, u16), rate: Option<f64>) -> bool {
    let bytes = cols as f64 * rows as f64 * TRUECOLOR_BYTES_PER_CELL;
    bytes > rate.unwrap_or(UNMEASURED_RATE) * COARSE_WITHIN
}

/// By how much to shrink (each way) the `w x h` picture for `cols x rows`
/// cells so that it reaches the terminal within [`COARSE_WITHIN`] over a
/// link of `rate` bytes per second (`None`: not measured yet); 1 where the
/// link is fast enough. Never below one pixel per cell.
pub(crate) fn coarse_factor(
    mode: &PixelMode,
    (w, h): (u32, u32),
    (cols, rows): (u16, u16),
    rate: Option<f64>,
) -> u32 {
    let per_pixel = match mode.protocol {
        Protocol::Sixel => SIXEL_BYTES_PER_BLOCK,
        Protocol::Kitty | Protocol::Iterm2 => BYTES_PER_PIXEL,
    };
    let bytes = w as f64 * h as f64 * per_pixel;
    let budget = rate.unwrap_or(UNMEASURED_RATE) * COARSE_WITHIN;
    let k = (bytes / budget.max(1.0)).sqrt().ceil().max(1.0) as u32;
    let most = (w / cols.max(1) as u32).min(h / rows.max(1) as u32).max(1);
    k.min(most)
}

/// The `w x h` picture shrunk `k` times each way (the mean of each block;
/// those at the right and bottom edges may be smaller), and its size.
pub(crate) fn downscale(px: &[[u8; 3]], w: u32, h: u32, k: u32) -> (Vec<[u8; 3]>, u32, u32) {
    let (cw, ch) = (w.div_ceil(k), h.div_ceil(k));
    let mut out = Vec::with_capacity((cw * ch) as usize);
    for cy in 0..ch {
        for cx in 0..cw {
            let mut sum = [0u32; 3];
            let mut n = 0;
            for y in cy * k..((cy + 1) * k).min(h) {
                for x in cx * k..((cx + 1) * k).min(w) {
                    let p = px[(y * w + x) as usize];
                    for c in 0..3 {
                        sum[c] += p[c] as u32;
                    }
                    n += 1;
                }
            }
            out.push(sum.map(|s| ((s + n / 2) / n.max(1)) as u8));
        }
    }
    (out, cw, ch)
}

/// `seq` wrapped for tmux's passthrough: inside `DCS tmux; ... ST` with
/// every ESC doubled.
pub(crate) fn passthrough(seq: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(seq.len() + seq.len() / 64 + 16);
    out.extend_from_slice(b"\x1bPtmux;");
    for &b in seq {
        if b == 0x1b {
            out.push(0x1b);
        }
        out.push(b);
    }
    out.extend_from_slice(b"\x1b\\");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_scales_large_views_down() {
        let m = PixelMode {
            protocol: Protocol::Kitty,
            cell: (10, 20),
            colours: 256,
            passthrough: false,
            pane: None,
            max: None,
        };
        assert_eq!(m.grid(100, 30), (10, 20));
        let (gx, gy) = m.grid(300, 100);
        assert!(300 * 100 * (gx * gy) as u64 <= PIXEL_BUDGET, "{gx}x{gy}");
        assert_eq!((gx, gy), (3, 6));
    }

    /// 24-bit colour is slow where its cells would take over 0.8 s: a
    /// 120x46 viewport (88 kB) at 32 kB/s or before the link is measured,
    /// not at 1 MB/s; a 20x10 one (3.2 kB) never at 32 kB/s.
    #[test]
    fn truecolor_is_slow_where_its_cells_outlast_the_budget() {
        assert!(truecolor_is_slow((120, 46), Some(32e3)));
        assert!(truecolor_is_slow((120, 46), None));
        assert!(!truecolor_is_slow((120, 46), Some(1e6)));
        assert!(!truecolor_is_slow((20, 10), Some(32e3)));
    }

    #[test]
    fn a_slow_link_gets_a_coarse_picture_that_fits_its_second() {
        let kitty = PixelMode {
            protocol: Protocol::Kitty,
            cell: (6, 13),
            colours: 256,
            passthrough: false,
            pane: None,
            max: None,
        };
        let (pic, cells) = ((684, 416), (114, 32));
        // 285k pixels: shrunk 5 times each way for 32 kB/s (17 kB, with
        // 26 kB in 0.8 s), not at all for 1 MB/s.
        assert_eq!(coarse_factor(&kitty, pic, cells, Some(32e3)), 5);
        assert_eq!(coarse_factor(&kitty, pic, cells, None), 5);
        assert_eq!(coarse_factor(&kitty, pic, cells, Some(1e6)), 1);
        // Never below a pixel per cell, however slow.
        assert_eq!(coarse_factor(&kitty, pic, cells, Some(10.0)), 6);
        // Sixel takes more bytes per block.
        let sixel = PixelMode {
            protocol: Protocol::Sixel,
            ..kitty
        };
        assert_eq!(coarse_factor(&sixel, pic, cells, Some(32e3)), 6);
        assert_eq!(coarse_factor(&sixel, (342, 208), cells, Some(32e3)), 3);
        // Blocks are averaged; the edges' smaller ones too.
        let px: Vec<[u8; 3]> = (0..15).map(|i| [i as u8 * 10, 0, 255]).collect();
        let (small, w, h) = downscale(&px, 5, 3, 2);
        assert_eq!((w, h), (3, 2));
        assert_eq!(small[0], [30, 0, 255]);
        assert_eq!(small[2], [65, 0, 255]);
        assert_eq!(small[5], [140, 0, 255]);
    }

    #[test]
    fn passthrough_doubles_escapes() {
        assert_eq!(
            passthrough(b"\x1b_Ga=q\x1b\\"),
            b"\x1bPtmux;\x1b\x1b_Ga=q\x1b\x1b\\\x1b\\"
        );
    }
}
