//! Drawing: the layout and one module per part of the screen. Widgets read
//! the app's state; the viewport and the debug pane also record their areas
//! and sizes in it (for mouse clicks, scrolling and the render size).

mod bars;
mod debug;
mod panels;
mod rays;
mod viewport;

use ratatui::layout::{Constraint, Layout};
use ratatui::Frame;

use super::app::App;

/// Below this the layout cannot show every panel.
pub const MIN_SIZE: (u16, u16) = (80, 24);

pub use viewport::paint_view;

pub fn draw(f: &mut Frame, app: &mut App) {
    let area = f.area();
    if area.width < MIN_SIZE.0 || area.height < MIN_SIZE.1 {
        bars::too_small(f, area);
        return;
    }
    let [main, status, hints] = Layout::vertical([
        Constraint::Min(0),
        Constraint::Length(1),
        Constraint::Length(1),
    ])
    .areas(area);
    let side = (area.width / 4).clamp(32, 44);
    let [left, right] =
        Layout::horizontal([Constraint::Min(0), Constraint::Length(side)]).areas(main);
    let [view, debug] = Layout::vertical([
        Constraint::Min(0),
        Constraint::Length((left.height * 3 / 10).max(6)),
    ])
    .areas(left);
    let [bvh, features, render] = Layout::vertical([
        Constraint::Length(5),
        Constraint::Length(12),
        Constraint::Min(0),
    ])
    .areas(right);
    viewport::draw(f, view, app);
    debug::draw(f, debug, app);
    panels::bvh(f, bvh, app);
    panels::features(f, features, app);
    panels::render(f, render, app);
    bars::status(f, status, app);
    bars::hints(f, hints, app);
    if let Some(p) = &mut app.popup {
        bars::popup(f, main, p);
    }
}
