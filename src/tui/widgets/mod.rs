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
/// Height of a render panel with a readable chart.
const RENDER_WITH_CHART: u16 = 16;

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
    let side = (area.width * 2 / 7).clamp(32, 46);
    let [left, right] = Layout::horizontal([Constraint::Min(0), Constraint::Length(side)])
        .spacing(1)
        .areas(main);
    let [view, debug] = Layout::vertical([
        Constraint::Min(0),
        Constraint::Length((left.height * 3 / 10).max(6)),
    ])
    .areas(left);
    // Reasons get lines of their own when that leaves the render panel
    // room for its chart.
    let mut features = panels::feature_lines(app, right.width, true);
    if 5 + 1 + features.len() as u16 + RENDER_WITH_CHART > right.height {
        features = panels::feature_lines(app, right.width, false);
    }
    let [bvh, features_area, render] = Layout::vertical([
        Constraint::Length(5),
        Constraint::Length(1 + features.len() as u16),
        Constraint::Min(0),
    ])
    .areas(right);
    viewport::draw(f, view, app);
    debug::draw(f, debug, app);
    panels::bvh(f, bvh, app);
    panels::features(f, features_area, features);
    panels::render(f, render, app);
    bars::status(f, status, app);
    bars::hints(f, hints, app);
    if let Some(p) = &mut app.popup {
        bars::popup(f, main, p);
    }
}
