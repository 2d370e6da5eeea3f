//! The selected pixel's ray tree drawn into the image: every ray as a
//! projected segment, shadow rays red when occluded and white when clear.

use glam::{DVec2, Vec3};

use crate::inspect::{PixelTree, RayNode};
use crate::render::recorder::RayKind;
use crate::scene::camera::CameraFrame;
use crate::scene::Camera;

const OCCLUDED: Vec3 = Vec3::new(1.0, 0.0, 0.0);
const CLEAR: Vec3 = Vec3::ONE;

fn kind_color(k: RayKind) -> Vec3 {
    match k {
        RayKind::Camera => Vec3::new(1.0, 1.0, 0.0),
        RayKind::Reflection => Vec3::new(0.0, 1.0, 1.0),
        RayKind::Glossy => Vec3::new(0.3, 0.5, 1.0),
        RayKind::Transmission => Vec3::new(0.0, 1.0, 0.0),
    }
}

/// Draws every ray of `tree`; rays that miss are drawn `reach` long.
pub fn draw(
    img: &mut [Vec3],
    w: u32,
    h: u32,
    camera: &Camera,
    frame: &CameraFrame,
    tree: &PixelTree,
    reach: f32,
) {
    let mut seg = |a: Vec3, b: Vec3, c: Vec3| segment(img, w, h, camera, frame, a, b, c);
    let mut stack: Vec<&RayNode> = vec![&tree.root];
    while let Some(n) = stack.pop() {
        let end = n
            .hit
            .as_ref()
            .map_or(n.origin + n.dir.normalize_or_zero() * reach, |h| h.point);
        seg(n.origin, end, kind_color(n.kind));
        for s in n.lights.iter().flat_map(|l| &l.samples) {
            if let Some(r) = &s.shadow_ray {
                let c = if s.occluder.is_some() {
                    OCCLUDED
                } else {
                    CLEAR
                };
                seg(r.origin, s.point, c);
            }
        }
        stack.extend(&n.children);
    }
}

/// Rasterizes the world-space segment `a`-`b`, clipped at a near plane in
/// front of the camera and at the image border.
#[allow(clippy::too_many_arguments)]
pub fn segment(
    img: &mut [Vec3],
    w: u32,
    h: u32,
    camera: &Camera,
    frame: &CameraFrame,
    a: Vec3,
    b: Vec3,
    color: Vec3,
) {
    let fwd = (camera.target - camera.eye).normalize_or_zero();
    let near = 1e-3 * (camera.target - camera.eye).length();
    let (za, zb) = ((a - camera.eye).dot(fwd), (b - camera.eye).dot(fwd));
    if za < near && zb < near || !(za.is_finite() && zb.is_finite()) {
        return;
    }
    let clip = |p: Vec3, zp: f32, q: Vec3, zq: f32| {
        if zp >= near {
            p
        } else {
            p + (q - p) * ((near - zp) / (zq - zp))
        }
    };
    let (a, b) = (clip(a, za, b, zb), clip(b, zb, a, za));
    let (Some(pa), Some(pb)) = (frame.project(a), frame.project(b)) else {
        return;
    };
    let Some((p, q)) = clip_rect(DVec2::from(pa), DVec2::from(pb), w as f64, h as f64) else {
        return;
    };
    let steps = (q - p).abs().max_element().ceil().max(1.0) as u32;
    for i in 0..=steps {
        let t = p + (q - p) * (i as f64 / steps as f64);
        let (x, y) = (t.x.floor() as i64, t.y.floor() as i64);
        if x >= 0 && y >= 0 && x < w as i64 && y < h as i64 {
            img[(y * w as i64 + x) as usize] = color;
        }
    }
}

/// Liang-Barsky clipping of segment `p`-`q` to `[0, w] x [0, h]`.
fn clip_rect(p: DVec2, q: DVec2, w: f64, h: f64) -> Option<(DVec2, DVec2)> {
    let d = q - p;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (den, num) in [(-d.x, p.x), (d.x, w - p.x), (-d.y, p.y), (d.y, h - p.y)] {
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
    (t0 <= t1).then(|| (p + d * t0, p + d * t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            vfov: 90.0,
        }
    }

    #[test]
    fn segments_are_drawn_between_projected_points() {
        let (w, h) = (20, 20);
        let cam = camera();
        let frame = cam.frame(w, h);
        let mut img = vec![Vec3::ZERO; (w * h) as usize];
        // A horizontal line through the target, from x = 5.2 to 14.8 on screen.
        let (a, b) = (Vec3::new(-2.4, 0.0, 0.0), Vec3::new(2.4, 0.0, 0.0));
        segment(&mut img, w, h, &cam, &frame, a, b, Vec3::ONE);
        let lit: Vec<(u32, u32)> = (0..w * h)
            .filter(|&i| img[i as usize] == Vec3::ONE)
            .map(|i| (i % w, i / w))
            .collect();
        assert!(lit.iter().all(|&(_, y)| y == 10), "{lit:?}");
        let xs: Vec<u32> = lit.iter().map(|p| p.0).collect();
        assert_eq!((xs.iter().min(), xs.iter().max()), (Some(&5), Some(&14)));
    }

    #[test]
    fn segments_behind_the_camera_are_clipped() {
        let (w, h) = (20, 20);
        let cam = camera();
        let frame = cam.frame(w, h);
        let mut img = vec![Vec3::ZERO; (w * h) as usize];
        // Entirely behind the eye: nothing.
        segment(
            &mut img,
            w,
            h,
            &cam,
            &frame,
            Vec3::new(0.0, 0.0, 6.0),
            Vec3::new(1.0, 0.0, 9.0),
            Vec3::ONE,
        );
        assert!(img.iter().all(|c| *c == Vec3::ZERO));
        // From behind the eye to the target: drawn, ending at the centre.
        segment(
            &mut img,
            w,
            h,
            &cam,
            &frame,
            Vec3::new(1.0, 0.0, 8.0),
            Vec3::ZERO,
            Vec3::ONE,
        );
        assert_eq!(img[(10 * w + 10) as usize], Vec3::ONE);
    }
}
