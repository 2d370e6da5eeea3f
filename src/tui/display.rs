//! How the viewport reaches the screen: the colours, the block symbols or
//! the pixel protocol, the cell's size, and the layout with the view size
//! it gives.

use super::color::ColorMode;
use super::graphics::symbols::Symbols;
use super::graphics::PixelMode;
use super::layout::Layout;

/// The viewport's way to the screen and the view size it gives.
pub struct Display {
    pub(crate) color: ColorMode,
    /// Over a slow link, block symbols are painted in 256 colours until
    /// the view's first full picture is on screen (`tui::coarse_color`).
    pub(crate) coarse_color: bool,
    /// The block symbols the viewport is drawn with, unless a pixel
    /// protocol shows it.
    pub(crate) symbols: Symbols,
    pub pixels: Option<PixelMode>,
    /// A cell's size in screen pixels: what the terminal said, else 8x16.
    pub(crate) cell: (u32, u32),
    /// The layout of the last update.
    pub layout: Layout,
    /// What shares the screen with the view.
    pub(crate) arrangement: Arrangement,
    /// The viewport's size in pixels, from the layout.
    view_size: (u32, u32),
    /// A view pixel's width over its height on screen, as last sent.
    view_aspect: f64,
}

impl Display {
    pub(crate) fn new(color: ColorMode) -> Display {
        Display {
            color,
            coarse_color: false,
            symbols: Symbols::Half,
            pixels: None,
            cell: (8, 16),
            layout: Layout::default(),
            arrangement: Arrangement::default(),
            view_size: (0, 0),
            view_aspect: 1.0,
        }
    }

    /// The colours the viewport is painted in now.
    pub(crate) fn painted_color(&self) -> ColorMode {
        match (self.coarse_color, self.color) {
            (true, ColorMode::Truecolor) => ColorMode::Palette256,
            (_, c) => c,
        }
    }

    pub(crate) fn view_size(&self) -> (u32, u32) {
        self.view_size
    }

    pub(crate) fn view_aspect(&self) -> f64 {
        self.view_aspect
    }

    /// A view pixel's width over its height on screen: the cell's over the
    /// grid of pixels in it, so that every symbol set and pixel protocol
    /// shows the scene in the same proportions.
    fn pixel_aspect(&self) -> f64 {
        let (cw, ch) = self.pixels.map_or(self.cell, |m| m.cell);
        let (gx, gy) = self.layout.grid;
        (cw as f64 * gy as f64) / (ch.max(1) as f64 * gx.max(1) as f64)
    }

    /// Takes the view's size and aspect from the layout; the size before
    /// when either changed (the view must be rendered again).
    pub(crate) fn fit_view(&mut self) -> Option<(u32, u32)> {
        let (size, aspect) = (self.layout.view_size(), self.pixel_aspect());
        if self.view_size == size && self.view_aspect == aspect {
            return None;
        }
        self.view_aspect = aspect;
        Some(std::mem::replace(&mut self.view_size, size))
    }
}

/// What shares the screen with the viewport: everything (the panels and the
/// ray-tree pane, at one of its heights) or nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Arrangement {
    pub(crate) full_screen: bool,
    pub(crate) pane: Pane,
}

/// The ray-tree pane's height under the view.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Pane {
    /// About a third of the left column.
    #[default]
    Normal,
    /// Two thirds: long trees at small sizes.
    Tall,
    /// Its title line only.
    Hidden,
}

impl Pane {
    pub(crate) fn next(self) -> Pane {
        match self {
            Pane::Normal => Pane::Tall,
            Pane::Tall => Pane::Hidden,
            Pane::Hidden => Pane::Normal,
        }
    }

    pub(crate) fn name(self) -> &'static str {
        match self {
            Pane::Normal => "ray-tree pane: normal height",
            Pane::Tall => "ray-tree pane: tall",
            Pane::Hidden => "ray-tree pane: hidden (T shows it)",
        }
    }
}
