//! The views' drawing kit over [`Canvas`]'s primitives: world-space
//! segments and boxes projected through the camera and clipped, at any
//! size, and legends (swatches and lines of text).

use glam::Vec3;

use crate::geometry::Aabb;
use crate::raster::canvas::{text_width, Canvas, GLYPH};
use crate::scene::camera::CameraFrame;

/// A transparent layer drawn over an image.
pub type Layer = Canvas<Option<Vec3>>;

/// A debug view's legend: per line, a colour swatch (none for plain text)
/// and what it means.
pub(crate) type Legend = Vec<(Option<Vec3>, String)>;

/// Distance in front of the eye where segments are cut. Tiny, because the
/// projection runs in f64 and the 2D clip handles the huge coordinates of
/// points just in front of the eye.
const NEAR: f64 = 1e-6;

/// Draws the world-space segment `a`–`b` one pixel wide. The part behind the
/// camera is cut away before projecting, and the rest is clipped to the image.
pub(crate) fn draw_segment<P: Copy>(
    c: &mut Canvas<P>,
    frame: &CameraFrame,
    a: Vec3,
    b: Vec3,
    color: P,
) {
    let Some((p, q)) = frame.project_clip(a, b, NEAR) else {
        return;
    };
    let Some((p, q)) = clip_to_rect(p, q, c.width as f64, c.height as f64) else {
        return;
    };
    // DDA: consecutive samples are at most one pixel apart on each axis, so
    // the pixels form an 8-connected line.
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let steps = dx.abs().max(dy.abs()).ceil().max(1.0) as u64;
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        let (x, y) = ((p.0 + dx * t).floor(), (p.1 + dy * t).floor());
        c.put(x as i32, y as i32, color);
    }
}

/// Draws the 12 edges of `b`.
pub(crate) fn draw_box<P: Copy>(c: &mut Canvas<P>, frame: &CameraFrame, b: &Aabb, color: P) {
    if b.is_empty() {
        return;
    }
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    // Corners differing in exactly one bit share an edge.
    for i in 0..8 {
        for bit in [1, 2, 4] {
            if i & bit == 0 {
                draw_segment(c, frame, corner(i), corner(i | bit), color);
            }
        }
    }
}

/// Writes the legend in the top left corner of `layer` (bottom left with
/// `bottom`): a swatch and a line of text per entry, on black, each entry
/// wrapped at spaces to stay inside the image.
pub(crate) fn draw_legend(layer: &mut Layer, legend: &Legend, bottom: bool) {
    let scale = (layer.height as i32 / 400).max(1);
    let line = (GLYPH + 4) * scale;
    let pad = 4 * scale;
    let tx = pad + (GLYPH + 4) * scale;
    let room = layer.width as i32 - tx - pad;
    let mut rows: Vec<(Option<Vec3>, String)> = legend
        .iter()
        .flat_map(|(swatch, text)| {
            wrap_to(text, room, scale)
                .into_iter()
                .enumerate()
                .map(move |(i, row)| (swatch.filter(|_| i == 0), row))
        })
        .collect();
    // On a small image the legend keeps to its top (or bottom) part, so as
    // not to hide what it explains; the command prints it whole.
    let most = ((layer.height as i32 * 2 / 5 - pad) / line).max(1) as usize;
    if rows.len() > most {
        rows.truncate(most - 1);
        rows.push((None, "...".into()));
    }
    let top = if bottom {
        layer.height as i32 - pad - rows.len() as i32 * line
    } else {
        pad
    };
    for (i, (swatch, text)) in rows.iter().enumerate() {
        let y = top + i as i32 * line;
        layer.rect(
            pad - 2,
            y - 2,
            tx + text_width(text, scale) + 2,
            y + GLYPH * scale + 1,
            Some(Vec3::ZERO),
        );
        if let Some(c) = swatch {
            layer.rect(
                pad,
                y,
                pad + GLYPH * scale - 1,
                y + GLYPH * scale - 1,
                Some(*c),
            );
        }
        layer.text(tx, y, text, Some(Vec3::ONE), scale);
    }
}

/// `text` broken at spaces into rows at most `room` pixels wide (a word
/// wider than that alone on its row).
fn wrap_to(text: &str, room: i32, scale: i32) -> Vec<String> {
    let mut rows = vec![String::new()];
    for word in text.split(' ') {
        let row = rows.last_mut().expect("one row at least");
        let joined = if row.is_empty() {
            word.to_string()
        } else {
            format!("{row} {word}")
        };
        if row.is_empty() || text_width(&joined, scale) <= room {
            *row = joined;
        } else {
            rows.push(word.to_string());
        }
    }
    rows
}

/// The legend as one line, for the TUI's title.
pub fn legend_line(legend: &Legend) -> String {
    legend
        .iter()
        .map(|(_, t)| t.as_str())
        .collect::<Vec<_>>()
        .join(" · ")
}

/// Clips segment `p`–`q` to `[0, w] x [0, h]` (Liang–Barsky).
pub(crate) fn clip_to_rect(
    p: (f64, f64),
    q: (f64, f64),
    w: f64,
    h: f64,
) -> Option<((f64, f64), (f64, f64))> {
    if ![p.0, p.1, q.0, q.1].iter().all(|v| v.is_finite()) {
        return None;
    }
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (den, num) in [(-dx, p.0), (dx, w - p.0), (-dy, p.1), (dy, h - p.1)] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some((
        (p.0 + t0 * dx, p.1 + t0 * dy),
        (p.0 + t1 * dx, p.1 + t1 * dy),
    ))
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_long_legend_wraps_inside_the_image() {
        let legend: Legend = vec![(
            Some(Vec3::X),
            "a legend line far too long for a small image".into(),
        )];
        let mut layer: Layer = crate::raster::canvas::Canvas::new(120, 100, None);
        draw_legend(&mut layer, &legend, false);
        let rows = wrap_to(&legend[0].1, 120 - 16 - 4, 1);
        assert!(rows.len() > 1, "{rows:?}");
        assert!(rows.iter().all(|r| text_width(r, 1) <= 100), "{rows:?}");
        assert_eq!(rows.join(" "), legend[0].1);
        // Nothing is drawn in the last column: the text stopped short.
        assert!((0..100).all(|y| layer.get(119, y).flatten().is_none()));
        // Nor below two fifths of the image, however long the legend.
        let long: Legend = (0..20).map(|i| (None, format!("line {i}"))).collect();
        let mut layer: Layer = crate::raster::canvas::Canvas::new(120, 100, None);
        draw_legend(&mut layer, &long, false);
        assert!((40..100).all(|y| (0..120).all(|x| layer.get(x, y).flatten().is_none())));
    }

    use super::*;
    use crate::scene::{Camera, Projection};

    const W: u32 = 64;
    const H: u32 = 48;

    /// Camera at the origin looking down -z.
    fn frame() -> CameraFrame {
        Camera {
            eye: Vec3::ZERO,
            target: Vec3::NEG_Z,
            up: Vec3::Y,
            projection: Projection::perspective(60.0),
        }
        .frame(W, H)
    }

    fn drawn(img: &[Vec3]) -> Vec<(u32, u32)> {
        (0..W * H)
            .filter(|&i| img[i as usize] != Vec3::ZERO)
            .map(|i| (i % W, i / W))
            .collect()
    }

    #[test]
    fn segment_behind_the_camera_draws_nothing() {
        let mut img = Canvas::new(W, H, Vec3::ZERO);
        let f = frame();
        draw_segment(
            &mut img,
            &f,
            Vec3::new(-1.0, 0.2, 2.0),
            Vec3::new(1.0, -0.3, 5.0),
            Vec3::ONE,
        );
        // Lying in the eye's own plane, it is not in front either.
        draw_segment(
            &mut img,
            &f,
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::ONE,
        );
        assert!(drawn(&img.pixels).is_empty());
    }

    #[test]
    fn segment_crossing_the_eye_plane_stays_on_its_side() {
        // Left of the camera, from in front to behind: projecting the far
        // end naively would mirror it to the right half.
        let mut img = Canvas::new(W, H, Vec3::ZERO);
        draw_segment(
            &mut img,
            &frame(),
            Vec3::new(-0.5, 0.1, -4.0),
            Vec3::new(-0.5, 0.1, 3.0),
            Vec3::ONE,
        );
        let px = drawn(&img.pixels);
        assert!(!px.is_empty());
        assert!(px.iter().all(|&(x, _)| x < W / 2), "{px:?}");
    }

    #[test]
    fn segment_across_the_image_is_a_connected_line() {
        let mut img = Canvas::new(W, H, Vec3::ZERO);
        // From far left to far right, rising: both ends off-screen.
        draw_segment(
            &mut img,
            &frame(),
            Vec3::new(-10.0, -1.0, -5.0),
            Vec3::new(10.0, 1.5, -5.0),
            Vec3::X,
        );
        let px = drawn(&img.pixels);
        // Every column is crossed, and each pixel touches the next.
        let mut by_x = px.clone();
        by_x.sort();
        let mut cols: Vec<u32> = by_x.iter().map(|p| p.0).collect();
        cols.dedup();
        assert_eq!(cols, (0..W).collect::<Vec<_>>());
        for pair in by_x.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            assert!(
                b.0 - a.0 <= 1 && a.1.abs_diff(b.1) <= 1,
                "gap between {a:?} and {b:?}"
            );
        }
        assert!(img.pixels.iter().all(|&c| c == Vec3::ZERO || c == Vec3::X));
    }

    #[test]
    fn box_outline_projects_its_corners() {
        let f = frame();
        let b = Aabb {
            min: Vec3::new(-1.0, -0.5, -6.0),
            max: Vec3::new(1.0, 0.5, -4.0),
        };
        let mut img = Canvas::new(W, H, Vec3::ZERO);
        draw_box(&mut img, &f, &b, Vec3::ONE);
        let px = drawn(&img.pixels);
        // The front face's corners are the extremes of the outline.
        let (x0, y0) = f.project(Vec3::new(-1.0, 0.5, -4.0)).unwrap();
        let (x1, y1) = f.project(Vec3::new(1.0, -0.5, -4.0)).unwrap();
        let xs = (px.iter().map(|p| p.0).min(), px.iter().map(|p| p.0).max());
        let ys = (px.iter().map(|p| p.1).min(), px.iter().map(|p| p.1).max());
        assert_eq!(xs, (Some(x0 as u32), Some(x1 as u32)));
        assert_eq!(ys, (Some(y0 as u32), Some(y1 as u32)));
        // The inside of the back face is not filled.
        let c = f.project(Vec3::new(0.0, 0.0, -6.0)).unwrap();
        assert_eq!(img.get(c.0 as u32, c.1 as u32), Some(Vec3::ZERO));
    }
}
