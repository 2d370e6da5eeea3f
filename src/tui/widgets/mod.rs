//! Drawing: one module per part of the screen, each placed by the layout
//! [`App::update`] computed. Widgets only read the app.

mod bars;
mod debug;
pub(crate) mod fit;
pub(crate) mod legend;
pub(crate) mod panels;
pub(crate) mod viewport;

use ratatui::Frame;

use super::app::App;

pub(crate) use viewport::paint_view;
pub use viewport::picture;

pub(crate) fn draw(f: &mut Frame, app: &App) {
    let l = &app.display.layout;
    if l.too_small {
        bars::too_small(f, l.area);
        return;
    }
    viewport::draw(f, l.view, app);
    if l.debug.height > 0 {
        debug::draw(f, l.debug, app);
    }
    if !app.display.arrangement.full_screen {
        panels::bvh(f, l.bvh, app);
        panels::features(
            f,
            l.features,
            panels::feature_lines(app, l.features.width, l.wrap_features),
        );
        panels::render(f, l.render, app);
    }
    if !bars::status(f, l.status, l.hints, app) {
        bars::hints(f, l.hints, app);
    }
    if let Some(p) = &app.popup {
        bars::popup(f, l.popup(p), p);
    }
}
