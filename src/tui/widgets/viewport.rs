//! The viewport: the newest pass in half blocks, the selected pixel marked,
//! and the overlays (the selected pixel's rays, BVH views) drawn over it.

use glam::Vec3;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::style::{Color, Style};
use ratatui::widgets::{Block, Borders, Paragraph};
use ratatui::Frame;

use super::rays;
use crate::bvh::debug::{self, HeatMeasure};
use crate::render::debug_view::BOX_COLORS;
use crate::render::overlay;
use crate::scene::camera::CameraFrame;
use crate::tui::app::{App, Overlay};
use crate::tui::color::{self, ColorMode};
use crate::tui::worker::Snapshot;

/// Colour of the marks around the selected pixel.
const MARK: [u8; 3] = [255, 0, 255];

pub fn draw(f: &mut Frame, area: Rect, app: &mut App) {
    let inner = Block::new().borders(Borders::TOP).inner(area);
    app.viewport = inner;
    app.set_view_size(inner.width as u32, inner.height as u32 * 2);
    let mut title = format!(
        " {} · {}x{} px · {}",
        app.scene.name,
        app.view_size.0,
        app.view_size.1,
        app.color.name()
    );
    if app.select_mode {
        title += " · SELECT";
    }
    let Some(frame) = app.frame.take() else {
        f.render_widget(Block::new().borders(Borders::TOP).title(title), area);
        f.render_widget(
            Paragraph::new("rendering the first pass...").style(Style::new().fg(Color::DarkGray)),
            inner,
        );
        return;
    };
    let mut img = frame.image.clone();
    // Overlays and marks follow the current camera and size, so they wait
    // for a pass of that size.
    let matches = (frame.width, frame.height) == app.view_size;
    if matches {
        if let Some(legend) = draw_overlays(&mut img, frame.width, frame.height, app) {
            title += &format!(" · {legend}");
        }
    }
    title.push(' ');
    f.render_widget(Block::new().borders(Borders::TOP).title(title), area);
    let mut px: Vec<[u8; 3]> = img.iter().map(|c| color::srgb(*c)).collect();
    if let (true, Some(s)) = (matches, app.selected) {
        mark(&mut px, frame.width, frame.height, s.x, s.y);
    }
    color::paint(
        f.buffer_mut(),
        inner,
        &px,
        frame.width,
        frame.height,
        app.color,
    );
    app.frame = Some(frame);
}

/// Paints a snapshot as the viewport does, without overlays (for the benchmark).
pub fn paint_view(buf: &mut Buffer, area: Rect, s: &Snapshot, mode: ColorMode) {
    let px: Vec<[u8; 3]> = s.image.iter().map(|c| color::srgb(*c)).collect();
    color::paint(buf, area, &px, s.width, s.height, mode);
}

/// Draws the overlays into the linear image before it becomes cells;
/// returns a legend for the title.
fn draw_overlays(img: &mut [Vec3], w: u32, h: u32, app: &mut App) -> Option<String> {
    let camera = app.camera;
    let frame = camera.frame(w, h);
    let legend = draw_bvh(img, w, h, &frame, app);
    if app.show_rays {
        let reach = app.reach;
        if let Some(tree) = app.tree() {
            rays::draw(img, w, h, &frame, tree, reach);
        }
    }
    legend
}

/// The BVH overlay: box outlines of one level or of the leaves, or a heat map.
fn draw_bvh(img: &mut [Vec3], w: u32, h: u32, frame: &CameraFrame, app: &App) -> Option<String> {
    let measure = match app.overlay {
        Overlay::Off => return None,
        Overlay::Level | Overlay::Leaves => {
            let boxes = if app.overlay == Overlay::Level {
                debug::boxes_at_level(&app.bvh, app.level)
            } else {
                debug::leaf_boxes(&app.bvh)
            };
            for (i, b) in boxes.iter().enumerate() {
                overlay::draw_box(img, w, h, frame, b, BOX_COLORS[i % BOX_COLORS.len()]);
            }
            return Some(format!("{}: {} boxes", app.overlay_name(), boxes.len()));
        }
        Overlay::HeatNodes => HeatMeasure::NodesVisited,
        Overlay::HeatTests => HeatMeasure::TriangleTests,
    };
    let values = debug::heat_map(&app.bvh, frame, w, h, measure);
    let (max, mean) = debug::heat_summary(&values);
    for (px, v) in img.iter_mut().zip(&values) {
        *px = debug::heat_color(*v, max);
    }
    overlay::legend(img, w, h, max);
    Some(format!(
        "{}: max {max}, mean {mean:.1} per pixel",
        app.overlay_name()
    ))
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
