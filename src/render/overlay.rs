//! Drawing world-space lines and boxes, and a heat-map legend, into a
//! linear RGB image: the BVH debug views at full resolution.

use glam::Vec3;

use crate::bvh::debug::heat_color;
use crate::geometry::Aabb;
use crate::scene::camera::CameraFrame;

/// Distance in front of the eye where segments are cut. Tiny, because the
/// projection runs in f64 and the 2D clip handles the huge coordinates of
/// points just in front of the eye.
const NEAR: f64 = 1e-6;

/// Draws the world-space segment `a`–`b` one pixel wide. The part behind the
/// camera is cut away before projecting, and the rest is clipped to the image.
pub fn draw_segment(
    img: &mut [Vec3],
    w: u32,
    h: u32,
    frame: &CameraFrame,
    a: Vec3,
    b: Vec3,
    color: Vec3,
) {
    let Some((p, q)) = frame.project_clip(a, b, NEAR) else {
        return;
    };
    let Some((p, q)) = clip_to_rect(p, q, w as f64, h as f64) else {
        return;
    };
    // DDA: consecutive samples are at most one pixel apart on each axis, so
    // the pixels form an 8-connected line.
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let steps = dx.abs().max(dy.abs()).ceil().max(1.0) as u64;
    for i in 0..=steps {
        let t = i as f64 / steps as f64;
        plot(img, w, h, p.0 + dx * t, p.1 + dy * t, color);
    }
}

/// Draws the 12 edges of `b`.
pub fn draw_box(img: &mut [Vec3], w: u32, h: u32, frame: &CameraFrame, b: &Aabb, color: Vec3) {
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
                draw_segment(img, w, h, frame, corner(i), corner(i | bit), color);
            }
        }
    }
}

/// Draws a vertical colour bar for a `0..=max` heat map at the right edge,
/// labelled with 0 at the bottom and `max` at the top.
pub fn legend(img: &mut [Vec3], w: u32, h: u32, max: u32) {
    let scale = (h / 160).max(1);
    let bar_w = (w / 40).max(3);
    let margin = (w / 80).max(2);
    if w < 16 || h < 16 {
        return;
    }
    let (top, bottom) = (h / 8, h - h / 8);
    let x0 = w - margin - bar_w;
    fill(
        img,
        w,
        h,
        x0 - 1,
        top - 1,
        bar_w + 2,
        bottom - top + 2,
        Vec3::ZERO,
    );
    let span = (bottom - top - 1).max(1);
    for y in top..bottom {
        // The top row is `max`, the bottom row 0.
        let t = (bottom - 1 - y) as f64 / span as f64;
        let c = heat_color((t * max as f64).round() as u32, max);
        fill(img, w, h, x0, y, bar_w, 1, c);
    }
    let label = |img: &mut [Vec3], text: &str, y: u32| {
        let tw = text_width(text, scale);
        let x = (x0 + bar_w).saturating_sub(tw);
        text_at(img, w, h, x, y, scale, text);
    };
    label(img, &max.to_string(), top.saturating_sub(7 * scale + 1));
    label(img, "0", bottom + 2 * scale);
}

fn plot(img: &mut [Vec3], w: u32, h: u32, x: f64, y: f64, color: Vec3) {
    let (x, y) = (x.floor(), y.floor());
    if x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64 {
        img[y as usize * w as usize + x as usize] = color;
    }
}

#[allow(clippy::too_many_arguments)]
fn fill(img: &mut [Vec3], w: u32, h: u32, x: u32, y: u32, fw: u32, fh: u32, color: Vec3) {
    for yy in y..(y + fh).min(h) {
        for xx in x..(x + fw).min(w) {
            img[(yy * w + xx) as usize] = color;
        }
    }
}

/// Clips segment `p`–`q` to `[0, w] x [0, h]` (Liang–Barsky).
fn clip_to_rect(p: (f64, f64), q: (f64, f64), w: f64, h: f64) -> Option<((f64, f64), (f64, f64))> {
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

/// 3x5 digit glyphs, one row per byte, bit 2 the left column.
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

fn text_width(text: &str, scale: u32) -> u32 {
    (text.len() as u32 * 4 + 1) * scale
}

/// White digits on a black box; other characters are left blank.
fn text_at(img: &mut [Vec3], w: u32, h: u32, x: u32, y: u32, s: u32, text: &str) {
    fill(img, w, h, x, y, text_width(text, s), 7 * s, Vec3::ZERO);
    for (i, ch) in text.chars().enumerate() {
        let Some(g) = ch.to_digit(10).map(|d| DIGITS[d as usize]) else {
            continue;
        };
        for (row, bits) in g.iter().enumerate() {
            for col in 0..3 {
                if bits & (4 >> col) != 0 {
                    let px = x + (1 + i as u32 * 4 + col) * s;
                    let py = y + (1 + row as u32) * s;
                    fill(img, w, h, px, py, s, s, Vec3::ONE);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    const W: u32 = 64;
    const H: u32 = 48;

    /// Camera at the origin looking down -z.
    fn frame() -> CameraFrame {
        Camera {
            eye: Vec3::ZERO,
            target: Vec3::NEG_Z,
            up: Vec3::Y,
            vfov: 60.0,
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
        let mut img = vec![Vec3::ZERO; (W * H) as usize];
        let f = frame();
        draw_segment(
            &mut img,
            W,
            H,
            &f,
            Vec3::new(-1.0, 0.2, 2.0),
            Vec3::new(1.0, -0.3, 5.0),
            Vec3::ONE,
        );
        // Lying in the eye's own plane, it is not in front either.
        draw_segment(
            &mut img,
            W,
            H,
            &f,
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::ONE,
        );
        assert!(drawn(&img).is_empty());
    }

    #[test]
    fn segment_crossing_the_eye_plane_stays_on_its_side() {
        // Left of the camera, from in front to behind: projecting the far
        // end naively would mirror it to the right half.
        let mut img = vec![Vec3::ZERO; (W * H) as usize];
        draw_segment(
            &mut img,
            W,
            H,
            &frame(),
            Vec3::new(-0.5, 0.1, -4.0),
            Vec3::new(-0.5, 0.1, 3.0),
            Vec3::ONE,
        );
        let px = drawn(&img);
        assert!(!px.is_empty());
        assert!(px.iter().all(|&(x, _)| x < W / 2), "{px:?}");
    }

    #[test]
    fn segment_across_the_image_is_a_connected_line() {
        let mut img = vec![Vec3::ZERO; (W * H) as usize];
        // From far left to far right, rising: both ends off-screen.
        draw_segment(
            &mut img,
            W,
            H,
            &frame(),
            Vec3::new(-10.0, -1.0, -5.0),
            Vec3::new(10.0, 1.5, -5.0),
            Vec3::X,
        );
        let px = drawn(&img);
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
        assert!(img.iter().all(|&c| c == Vec3::ZERO || c == Vec3::X));
    }

    #[test]
    fn box_outline_projects_its_corners() {
        let f = frame();
        let b = Aabb {
            min: Vec3::new(-1.0, -0.5, -6.0),
            max: Vec3::new(1.0, 0.5, -4.0),
        };
        let mut img = vec![Vec3::ZERO; (W * H) as usize];
        draw_box(&mut img, W, H, &f, &b, Vec3::ONE);
        let px = drawn(&img);
        // The front face's corners are the extremes of the outline.
        let (x0, y0) = f.project(Vec3::new(-1.0, 0.5, -4.0)).unwrap();
        let (x1, y1) = f.project(Vec3::new(1.0, -0.5, -4.0)).unwrap();
        let xs = (px.iter().map(|p| p.0).min(), px.iter().map(|p| p.0).max());
        let ys = (px.iter().map(|p| p.1).min(), px.iter().map(|p| p.1).max());
        assert_eq!(xs, (Some(x0 as u32), Some(x1 as u32)));
        assert_eq!(ys, (Some(y0 as u32), Some(y1 as u32)));
        // The inside of the back face is not filled.
        let c = f.project(Vec3::new(0.0, 0.0, -6.0)).unwrap();
        assert_eq!(img[c.1 as usize * W as usize + c.0 as usize], Vec3::ZERO);
    }

    #[test]
    fn legend_runs_from_dark_at_the_bottom_to_bright_at_the_top() {
        let (w, h) = (200u32, 160u32);
        let mut img = vec![Vec3::splat(0.5); (w * h) as usize];
        legend(&mut img, w, h, 42);
        let col = w - (w / 80).max(2) - 1;
        let at = |y: u32| img[(y * w + col) as usize];
        assert_eq!(at(h / 8), heat_color(42, 42));
        assert_eq!(at(h - h / 8 - 1), heat_color(0, 42));
        // The left half of the image is untouched.
        assert!(img.chunks(w as usize).all(|row| row[..(w / 2) as usize]
            .iter()
            .all(|&c| c == Vec3::splat(0.5))));
    }
}
