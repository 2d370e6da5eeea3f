//! The viewport: the newest pass in block symbols, with the BVH overlay and
//! the selected pixel's overlay the worker drew for this view, and the
//! pixel's mark.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use crate::tui::app::App;
use crate::tui::color::ColorMode;
use crate::tui::graphics::symbols::{self, Symbols};
use crate::tui::term::screen::make_hole;
use crate::tui::worker::Snapshot;

/// Colour of the marks around the selected pixel.
const MARK: [u8; 3] = [255, 0, 255];

/// The viewport's picture: the newest pass in sRGB with the BVH overlay,
/// the selected pixel's overlay and its mark when they are for this view,
/// and what the overlays say (their legends) for the title. The block symbols and the pixel
/// protocols show the same picture.
pub struct ViewPicture {
    pub px: Vec<[u8; 3]>,
    pub w: u32,
    pub h: u32,
    pub(crate) note: Option<String>,
}

pub fn picture(app: &App) -> Option<ViewPicture> {
    let frame = app.link.frame.as_deref()?;
    let (w, h) = (frame.width, frame.height);
    let mut note = None;
    // A film view (bloom, samples or error per pixel) replaces the
    // picture: it shows the pass itself.
    let mut img = match &frame.film_view {
        Some((v, view, legend)) if app.overlays.image == Some(*v) => {
            note = Some(legend.clone());
            view.clone()
        }
        _ => frame.image.clone(),
    };
    // Overlays and marks follow the current camera and size, so they wait
    // for a pass of that view.
    let current = app.link.current_frame().is_some() && (w, h) == app.display.view_size();
    if current {
        if let Some(o) = app.link.current_overlay() {
            match &o.layer {
                Ok((layer, summary)) if (layer.width, layer.height) == (w, h) => {
                    layer.over(&mut img);
                    note = Some(summary.to_string());
                }
                Ok(_) => {}
                Err(e) => note = Some(e.to_string()),
            }
        }
        if let Some(p) = app.link.current_pixel() {
            match &p.layer {
                Ok((layer, legend)) if (layer.width, layer.height) == (w, h) => {
                    layer.over(&mut img);
                    note = Some(match note {
                        Some(n) => format!("{n} · {legend}"),
                        None => legend.clone(),
                    });
                }
                Ok(_) => {}
                Err(e) => note = Some(e.clone()),
            }
        }
    }
    let mut px: Vec<[u8; 3]> = img.iter().map(|c| crate::color::srgb(*c)).collect();
    if let (true, Some(s)) = (current, app.inspector.selected) {
        mark(&mut px, w, h, s.x, s.y);
    }
    Some(ViewPicture { px, w, h, note })
}

pub(crate) fn draw(f: &mut Frame, area: Rect, app: &App) {
    let inner = app.display.layout.image;
    let shown = match &app.display.pixels {
        Some(m) => m.protocol.name().to_string(),
        None => format!(
            "{} · {}",
            app.display.symbols.name(),
            app.display.color.name()
        ),
    };
    let mut title = format!(
        " {} · {}x{} px · {shown}",
        app.session.scene.name,
        app.display.view_size().0,
        app.display.view_size().1,
    );
    if app.inspector.select_mode {
        title += " · SELECT";
    }
    let Some(pic) = picture(app) else {
        f.render_widget(Block::new().borders(Borders::TOP).title(title), area);
        f.render_widget(
            Paragraph::new("rendering the first pass...").style(Style::new().fg(Color::DarkGray)),
            inner,
        );
        return;
    };
    if let Some(note) = &pic.note {
        title += &format!(" · {note}");
    }
    title.push(' ');
    f.render_widget(Block::new().borders(Borders::TOP).title(title), area);
    // With a pixel protocol the cells are holes: the event loop sends the
    // picture as images over them.
    if app.display.pixels.is_some() {
        let buf = f.buffer_mut();
        for y in inner.top()..inner.bottom() {
            for x in inner.left()..inner.right() {
                if let Some(c) = buf.cell_mut((x, y)) {
                    make_hole(c);
                }
            }
        }
    } else {
        symbols::paint(
            f.buffer_mut(),
            inner,
            &pic.px,
            (pic.w, pic.h),
            app.display.symbols,
            app.display.color,
        );
    }
}

/// Paints a snapshot as the viewport does, without overlays (for the benchmark).
pub(crate) fn paint_view(buf: &mut Buffer, area: Rect, s: &Snapshot, mode: ColorMode) {
    let px: Vec<[u8; 3]> = s.image.iter().map(|c| crate::color::srgb(*c)).collect();
    symbols::paint(buf, area, &px, (s.width, s.height), Symbols::Half, mode);
}

/// Four short arms around pixel (x, y), leaving the pixel itself visible.
fn mark(px: &mut [[u8; 3]], w: u32, h: u32, x: u32, y: u32) {
    for d in 2..=3i64 {
        for (dx, dy) in [(d, 0), (-d, 0), (0, d), (0, -d)] {
            let (mx, my) = (x as i64 + dx, y as i64 + dy);
            if mx >= 0 && my >= 0 && mx < w as i64 && my < h as i64 {
                px[(my * w as i64 + mx) as usize] = MARK;
            }
        }
    }
}
