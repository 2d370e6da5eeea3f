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
        };
        assert_eq!(m.grid(100, 30), (10, 20));
        let (gx, gy) = m.grid(300, 100);
        assert!(300 * 100 * (gx * gy) as u64 <= PIXEL_BUDGET, "{gx}x{gy}");
        assert_eq!((gx, gy), (3, 6));
    }

    #[test]
    fn passthrough_doubles_escapes() {
        assert_eq!(
            passthrough(b"\x1b_Ga=q\x1b\\"),
            b"\x1bPtmux;\x1b\x1b_Ga=q\x1b\x1b\\\x1b\\"
        );
    }
}
