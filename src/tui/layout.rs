//! Where everything goes on screen, computed in the event loop before each
//! draw: the view size the worker renders, the debug pane's height and the
//! popup's rows follow from it, so drawing only reads.

use ratatui::layout::{Constraint, Layout as Split, Rect};
use ratatui::widgets::{Block, Borders};

use super::app::App;
use super::display::Pane;
use super::popup::Popup;
use super::widgets::{legend, panels, viewport};

/// Below this the layout cannot show every panel.
pub(crate) const MIN_SIZE: (u16, u16) = (80, 24);
/// Height of a render panel with a readable chart.
const RENDER_WITH_CHART: u16 = 16;
/// The keys every popup takes, on its bottom edge.
pub(crate) const POPUP_HINT: &str = " ↑↓ PgUp PgDn scroll · Esc q close ";
/// Rows the legend takes from a full-screen view while an overlay is on
/// (fixed, so that the view's size does not follow the legend's).
const LEGEND_FULL: u16 = 3;
/// Height of the BVH panel.
const BVH_PANEL: u16 = 5;

/// The render panel's title and its first line, the samples and error.
const RENDER_LEAST: u16 = 3;

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Layout {
    pub(crate) area: Rect,
    /// The terminal is smaller than [`MIN_SIZE`]: only a message is shown.
    pub(crate) too_small: bool,
    /// Everything above the status line (popups centre on it).
    pub(crate) main: Rect,
    /// The viewport panel and, inside its title line, the image.
    pub(crate) view: Rect,
    pub image: Rect,
    /// The overlays' legend, beneath the view.
    pub(crate) legend: Rect,
    /// The debug pane and its text.
    pub(crate) debug: Rect,
    pub(crate) debug_text: Rect,
    pub(crate) bvh: Rect,
    pub(crate) features: Rect,
    /// Whether feature reasons get lines of their own.
    pub(crate) wrap_features: bool,
    pub(crate) render: Rect,
    /// Pixels per cell of the image, across and down: the symbols' grid,
    /// or with a pixel protocol the cell's size (within the budget).
    pub(crate) grid: (u32, u32),
    pub(crate) status: Rect,
    pub(crate) hints: Rect,
}

impl Layout {
    pub(crate) fn compute(area: Rect, app: &App) -> Layout {
        let mut l = Layout {
            area,
            ..Layout::default()
        };
        if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
            l.too_small = true;
            return l;
        }
        [l.main, l.status, l.hints] = Split::vertical([
            Constraint::Min(0),
            Constraint::Length(1),
            Constraint::Length(1),
        ])
        .areas(area);
        let arrangement = app.display.arrangement;
        let left = if arrangement.full_screen {
            l.main
        } else {
            let side = (area.width * 2 / 7).clamp(32, 46);
            let [left, right] = Split::horizontal([Constraint::Min(0), Constraint::Length(side)])
                .spacing(1)
                .areas(l.main);
            l.side(right, app);
            left
        };
        // The legend takes its rows from the ray-tree pane while that keeps
        // a few lines (the view's size stays); else a few from the view.
        let overlay = app.overlays.pixel.is_some() || app.overlays.image.is_some();
        let pane = match (arrangement.full_screen, arrangement.pane) {
            (true, _) => 0,
            (false, Pane::Normal) => (left.height * 3 / 10).max(6),
            (false, Pane::Tall) => left.height * 6 / 10,
            (false, Pane::Hidden) => 1,
        };
        let (legend, pane) = if pane >= 6 {
            let want = legend::rows(&viewport::legend(app), left.width as usize).len() as u16;
            let rows = if overlay { want.clamp(1, pane - 3) } else { 0 };
            (rows, pane - rows)
        } else {
            (if overlay { LEGEND_FULL } else { 0 }, pane)
        };
        [l.view, l.legend, l.debug] = Split::vertical([
            Constraint::Min(0),
            Constraint::Length(legend),
            Constraint::Length(pane),
        ])
        .areas(left);
        let titled = Block::new().borders(Borders::TOP);
        l.image = titled.inner(l.view);
        // A terminal that draws no image wider than it says gets a picture
        // that narrow, centred in the view.
        if let Some(m) = &app.display.pixels {
            if let Some((w, _)) = m.max {
                let most = (w / m.cell.0.max(1)).clamp(1, u16::MAX as u32) as u16;
                let cut = l.image.width.saturating_sub(most);
                l.image.x += cut / 2;
                l.image.width -= cut;
            }
        }
        l.grid = match &app.display.pixels {
            Some(m) => m.grid(l.image.width, l.image.height),
            None => app.display.symbols.grid(),
        };
        l.debug_text = titled.inner(l.debug);
        l
    }

    /// The right column: the BVH, features and render panels.
    fn side(&mut self, right: Rect, app: &App) {
        // Reasons get lines of their own when that leaves the render panel
        // room for its chart.
        self.wrap_features = true;
        let mut n = panels::feature_lines(app, right.width, true).len() as u16;
        if BVH_PANEL + 1 + n + RENDER_WITH_CHART > right.height {
            self.wrap_features = false;
            n = panels::feature_lines(app, right.width, false).len() as u16;
        }
        // Where even that leaves the render panel no line under its title
        // (80x24), the BVH panel gives up its last lines first, down to
        // its first: the samples and error matter more than the tree's
        // figures.
        let bvh = BVH_PANEL.min(right.height.saturating_sub(1 + n + RENDER_LEAST).max(2));
        [self.bvh, self.features, self.render] = Split::vertical([
            Constraint::Length(bvh),
            Constraint::Length(1 + n),
            Constraint::Min(0),
        ])
        .areas(right);
    }

    /// The view's size in pixels: the symbols' grid in every cell.
    pub(crate) fn view_size(&self) -> (u32, u32) {
        let (gx, gy) = self.grid;
        (self.image.width as u32 * gx, self.image.height as u32 * gy)
    }

    /// The top left pixel under a terminal cell, when it lies in the image.
    pub(crate) fn pixel_at(&self, column: u16, row: u16) -> Option<(u32, u32)> {
        let r = self.image;
        let (gx, gy) = self.grid;
        let inside = column >= r.x && column < r.x + r.width && row >= r.y && row < r.y + r.height;
        inside.then(|| ((column - r.x) as u32 * gx, (row - r.y) as u32 * gy))
    }

    /// Whether a terminal cell lies in the debug pane.
    pub(crate) fn in_debug(&self, column: u16, row: u16) -> bool {
        let r = self.debug;
        column >= r.x && column < r.x + r.width && row >= r.y && row < r.y + r.height
    }

    /// Where `p` is drawn: centred on the main area, as large as its text.
    pub(crate) fn popup(&self, p: &Popup) -> Rect {
        let area = self.main;
        let width = p
            .header
            .iter()
            .chain(&p.lines)
            .map(|l| l.chars().count())
            .max()
            .unwrap_or(0)
            .max(p.title.chars().count())
            .max(POPUP_HINT.chars().count()) as u16
            + 4;
        let w = width.min(area.width.saturating_sub(2));
        let rows = (p.header.len() + p.lines.len()) as u16;
        let h = (rows + 2).min(area.height.saturating_sub(2));
        Rect::new(
            area.x + (area.width - w) / 2,
            area.y + (area.height - h) / 2,
            w,
            h,
        )
    }
}
