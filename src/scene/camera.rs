//! Pinhole camera, with the ray generation of the shared ray workload
//! (camera math in f64, rays cast to f32) so renders and benchmarks agree.

use glam::{DVec3, Vec3};

use crate::geometry::{Aabb, Ray};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov: f32,
}

impl Camera {
    /// The workload's auto camera: looks at the box centre from `r * (1.2, 0.8, 2)`.
    pub fn auto(b: &Aabb) -> Self {
        let c = b.center();
        let r = (b.max - b.min).length() * 0.5;
        Camera {
            eye: c + r * Vec3::new(1.2, 0.8, 2.0),
            target: c,
            up: Vec3::Y,
            vfov: 45.0,
        }
    }

    /// The workload's auto light position for a mesh with bounds `b`.
    pub fn auto_light(b: &Aabb) -> Vec3 {
        let c = b.center();
        let r = (b.max - b.min).length() * 0.5;
        c + r * Vec3::new(-1.5, 3.0, 2.0)
    }

    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        CameraFrame::new(
            self.eye.as_dvec3(),
            self.target.as_dvec3(),
            self.up.as_dvec3(),
            self.vfov as f64,
            width,
            height,
        )
    }

    /// Rotates the eye about the target (yaw about `up`, pitch about the right axis).
    pub fn orbit(&mut self, yaw: f32, pitch: f32) {
        let off = self.eye - self.target;
        let r = off.length();
        let up = self.up.normalize();
        let q = glam::Quat::from_axis_angle(up, yaw);
        let mut o = q * off;
        let right = o.cross(up).normalize_or_zero();
        let p = glam::Quat::from_axis_angle(right, pitch);
        let o2 = p * o;
        // Stop short of the poles where the view would flip.
        if o2.normalize().dot(up).abs() < 0.995 {
            o = o2;
        }
        self.eye = self.target + o.normalize() * r;
    }

    /// Moves eye and target together in camera space (right, up, forward).
    pub fn pan(&mut self, right: f32, up: f32, forward: f32) {
        let fwd = (self.target - self.eye).normalize();
        let r = fwd.cross(self.up).normalize();
        let u = r.cross(fwd);
        let d = r * right + u * up + fwd * forward;
        self.eye += d;
        self.target += d;
    }
}

/// Precomputed camera basis for one image size.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    eye: DVec3,
    fwd: DVec3,
    right: DVec3,
    upv: DVec3,
    h: f64,
    aspect: f64,
    width: f64,
    height: f64,
    size: (u32, u32),
}

impl CameraFrame {
    /// The basis from an f64 eye, target and up: the ray workload derives
    /// them in f64 from the mesh bounds, and rounding them to f32 first
    /// would change the rays.
    pub fn new(eye: DVec3, target: DVec3, up: DVec3, vfov: f64, width: u32, height: u32) -> Self {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(up).normalize();
        let upv = right.cross(fwd);
        let h = (vfov * 0.5).to_radians().tan();
        CameraFrame {
            eye,
            fwd,
            right,
            upv,
            h,
            aspect: width as f64 / height as f64,
            width: width as f64,
            height: height as f64,
            size: (width, height),
        }
    }

    /// The image size in pixels this frame was made for.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// Ray through image position `(x, y)` in pixels, `y = 0` the top row;
    /// the pixel centre of `(i, j)` is `(i + 0.5, j + 0.5)`.
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        self.ray_through(self.sx(x), self.sy(y))
    }

    /// The offset along `right` of image column `x` (see [`CameraFrame::ray`]).
    #[inline]
    pub fn sx(&self, x: f64) -> f64 {
        (2.0 * x / self.width - 1.0) * self.h * self.aspect
    }

    /// The offset along `up` of image row `y`.
    #[inline]
    pub fn sy(&self, y: f64) -> f64 {
        (1.0 - 2.0 * y / self.height) * self.h
    }

    /// The ray at offsets `sx`, `sy` ([`CameraFrame::sx`], [`CameraFrame::sy`]):
    /// rays of a tile of pixels share theirs per column and per row.
    #[inline]
    pub fn ray_through(&self, sx: f64, sy: f64) -> Ray {
        let dir = (self.fwd + sx * self.right + sy * self.upv).normalize();
        Ray::new(self.eye.as_vec3(), dir.as_vec3())
    }

    /// Image position of a world point, or `None` when it is behind the camera.
    pub fn project(&self, p: Vec3) -> Option<(f64, f64)> {
        let d = p.as_dvec3() - self.eye;
        let z = d.dot(self.fwd);
        if z <= 1e-9 {
            return None;
        }
        Some(self.image_pos(d))
    }

    /// Image positions of the ends of segment `a`–`b` after cutting away the
    /// part behind the near plane (`depth < near`), or `None` when all of it is
    /// behind. Cutting in 3D first keeps points behind the eye from projecting
    /// through it to the wrong side of the image.
    pub fn project_clip(&self, a: Vec3, b: Vec3, near: f64) -> Option<((f64, f64), (f64, f64))> {
        let (a, b) = (a.as_dvec3() - self.eye, b.as_dvec3() - self.eye);
        let (za, zb) = (a.dot(self.fwd), b.dot(self.fwd));
        if za < near && zb < near || !(za.is_finite() && zb.is_finite()) {
            return None;
        }
        let cut = |p: DVec3, zp: f64, q: DVec3, zq: f64| {
            if zp >= near {
                p
            } else {
                p + (q - p) * ((near - zp) / (zq - zp))
            }
        };
        let (a2, b2) = (cut(a, za, b, zb), cut(b, zb, a, za));
        Some((self.image_pos(a2), self.image_pos(b2)))
    }

    /// Image position of a camera-relative point in front of the eye.
    fn image_pos(&self, d: DVec3) -> (f64, f64) {
        let z = d.dot(self.fwd);
        let sx = d.dot(self.right) / z;
        let sy = d.dot(self.upv) / z;
        let x = (sx / (self.h * self.aspect) + 1.0) * 0.5 * self.width;
        let y = (1.0 - sy / self.h) * 0.5 * self.height;
        (x, y)
    }
}
