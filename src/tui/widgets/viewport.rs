//! The viewport: the newest pass in block symbols, with the BVH overlay and
//! the selected pixel's overlay the worker drew for this view, and the
//! pixel's mark.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::text::Line;
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use super::fit;
use crate::tui::app::App;
use crate::tui::color::ColorMode;
use crate::tui::graphics::symbols::{self, Symbols};
use crate::tui::term::screen::make_hole;
use crate::tui::worker::Snapshot;
use crate::viz::draw::Layer;

/// Colour of the marks around the selected pixel.
const MARK: [u8; 3] = [255, 0, 255];

/// The viewport's picture: the newest pass in sRGB with the BVH overlay,
/// the selected pixel's overlay and its mark when they are for this view.
/// The block symbols and the pixel protocols show the same picture.
pub struct ViewPicture {
    pub px: Vec<[u8; 3]>,
    pub w: u32,
    pub h: u32,
}

/// What the view shows of the newest pass: the film view in place of the
/// image, the layers drawn over it, and what each says (its legend, one
/// item per line of it).
struct Shown<'a> {
    image: &'a [glam::Vec3],
    layers: Vec<&'a Layer>,
    legend: Vec<String>,
    /// The overlays and marks are for the current camera and size.
    current: bool,
}

fn shown(app: &App) -> Option<Shown<'_>> {
    let frame = app.link.frame.as_deref()?;
    let (w, h) = (frame.width, frame.height);
    let mut s = Shown {
        image: &frame.image,
        layers: Vec::new(),
        legend: Vec::new(),
        current: app.link.current_frame().is_some() && (w, h) == app.display.view_size(),
    };
    let mut say = |text: &str| s.legend.extend(text.split(" · ").map(str::to_string));
    // A film view (bloom, samples or error per pixel) replaces the
    // picture: it shows the pass itself.
    if let Some((v, view, legend)) = &frame.film_view {
        if app.overlays.image == Some(*v) {
            say(legend);
            s.image = view;
        }
    }
    // Overlays and marks follow the current camera and size, so they wait
    // for a pass of that view.
    if s.current {
        if let Some(o) = app.link.current_overlay() {
            match &o.layer {
                Ok((layer, summary)) if (layer.width, layer.height) == (w, h) => {
                    s.layers.push(layer);
                    say(summary);
                }
                Ok(_) => {}
                Err(e) => say(&e.to_string()),
            }
        }
        if let Some(p) = app.link.current_pixel() {
            match &p.layer {
                Ok((layer, legend)) if (layer.width, layer.height) == (w, h) => {
                    s.layers.push(layer);
                    say(legend);
                }
                Ok(_) => {}
                Err(e) => say(e),
            }
        }
    }
    Some(s)
}

/// What the overlays on the view say, one item per line of their legends.
pub(crate) fn legend(app: &App) -> Vec<String> {
    shown(app).map(|s| s.legend).unwrap_or_default()
}

pub fn picture(app: &App) -> Option<ViewPicture> {
    let frame = app.link.frame.as_deref()?;
    let (w, h) = (frame.width, frame.height);
    let shown = shown(app)?;
    let mut img = shown.image.to_vec();
    for layer in &shown.layers {
        layer.over(&mut img);
    }
    let mut px: Vec<[u8; 3]> = img.iter().map(|c| crate::color::srgb(*c)).collect();
    if let (true, Some(s)) = (shown.current, app.inspector.selected) {
        mark(&mut px, w, h, s.x, s.y);
    }
    Some(ViewPicture { px, w, h })
}

pub(crate) fn draw(f: &mut Frame, area: Rect, app: &App) {
    let inner = app.display.layout.image;
    let (w, h) = app.display.view_size();
    let shown = match &app.display.pixels {
        Some(m) => m.protocol.name().to_string(),
        None => format!(
            "{} · {}",
            app.display.symbols.name(),
            app.display.color.name()
        ),
    };
    // Narrow, the way the view is shown goes first, then its size.
    let mut parts = vec![
        (app.session.scene.name.clone(), 0),
        (format!("{w}x{h} px"), 1),
        (shown, 2),
    ];
    if app.inspector.select_mode {
        parts.push(("SELECT".into(), 0));
    }
    let room = (area.width as usize).saturating_sub(2);
    let title = format!(" {} ", fit::joined(&parts, " · ", room));
    fit::check("viewport title", &Line::raw(&title), area.width);
    f.render_widget(Block::new().borders(Borders::TOP).title(title), area);
    super::legend::draw(f, app.display.layout.legend, &legend(app));
    let Some(pic) = picture(app) else {
        f.render_widget(
            Paragraph::new("rendering the first pass...").style(Style::new().fg(Color::DarkGray)),
            inner,
        );
        return;
    };
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
            app.display.painted_color(),
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
