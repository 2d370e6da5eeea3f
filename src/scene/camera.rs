//! Pinhole and orthographic cameras, with the ray generation of the shared
//! ray workload (camera math in f64, rays cast to f32) so renders and
//! benchmarks agree.

use glam::{DVec3, Vec3};

use crate::geometry::{Aabb, Ray};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub projection: Projection,
}

/// How a camera's rays leave it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// From the eye, through a view of this vertical field of view, degrees.
    Perspective { vfov: f32 },
    /// Parallel, along the line of sight, from the plane through the eye
    /// square to it: a view this many scene units high, half above the eye
    /// and half below (glTF's `ymag`). Nothing behind that plane is seen.
    Orthographic { half_height: f32 },
}

impl Projection {
    /// The perspective view of vertical field of view `vfov` degrees.
    pub fn perspective(vfov: f32) -> Self {
        Projection::Perspective { vfov }
    }

    /// Scaled with the scene by `s`: an orthographic view's extent is a
    /// length, a field of view an angle.
    pub(crate) fn scaled(self, s: f32) -> Self {
        match self {
            Projection::Orthographic { half_height } => Projection::Orthographic {
                half_height: half_height * s,
            },
            p => p,
        }
    }
}

impl Camera {
    /// The workload's auto camera: looks at the box centre from `r * (1.2, 0.8, 2)`.
    pub(crate) fn auto(b: &Aabb) -> Self {
        let c = b.center();
        let r = (b.max - b.min).length() * 0.5;
        Camera {
            eye: c + r * Vec3::new(1.2, 0.8, 2.0),
            target: c,
            up: Vec3::Y,
            projection: Projection::perspective(45.0),
        }
    }

    /// Frame `k` (from 0) of a turntable of `n`: the eye turned `k / n` of
    /// a circle around the target, about the up axis (anticlockwise seen
    /// from above), in f64; frame 0 is this camera.
    pub fn turntable(&self, k: u32, n: u32) -> Camera {
        if k.is_multiple_of(n.max(1)) {
            return *self;
        }
        let angle = std::f64::consts::TAU * (k % n) as f64 / n as f64;
        let turn = glam::DQuat::from_axis_angle(self.up.as_dvec3().normalize(), angle);
        let (eye, target) = (self.eye.as_dvec3(), self.target.as_dvec3());
        Camera {
            eye: (target + turn * (eye - target)).as_vec3(),
            ..*self
        }
    }

    /// The workload's auto light position for a mesh with bounds `b`.
    pub(crate) fn auto_light(b: &Aabb) -> Vec3 {
        let c = b.center();
        let r = (b.max - b.min).length() * 0.5;
        c + r * Vec3::new(-1.5, 3.0, 2.0)
    }

    pub fn frame(&self, width: u32, height: u32) -> CameraFrame {
        CameraFrame::new(
            self.eye.as_dvec3(),
            self.target.as_dvec3(),
            self.up.as_dvec3(),
            self.projection,
            width,
            height,
        )
    }

    /// Rotates the eye about the target (yaw about `up`, pitch about the right axis).
    pub(crate) fn orbit(&mut self, yaw: f32, pitch: f32) {
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
    pub(crate) fn pan(&mut self, right: f32, up: f32, forward: f32) {
        let fwd = (self.target - self.eye).normalize();
        let r = fwd.cross(self.up).normalize();
        let u = r.cross(fwd);
        let d = r * right + u * up + fwd * forward;
        self.eye += d;
        self.target += d;
    }
}

/// Whether this CPU has AVX.
fn has_avx() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// Precomputed camera basis for one image size.
#[derive(Clone, Copy, Debug)]
pub struct CameraFrame {
    eye: DVec3,
    fwd: DVec3,
    right: DVec3,
    upv: DVec3,
    /// Orthographic: offsets are distances along `right` and `upv` on the
    /// plane through the eye, every ray along `fwd`; else the rays leave
    /// the eye through `fwd + sx * right + sy * upv`.
    ortho: bool,
    /// Half the view's height: `tan(vfov / 2)` at distance 1, or the
    /// orthographic half height.
    h: f64,
    aspect: f64,
    width: f64,
    height: f64,
    size: (u32, u32),
    /// Whether rays are made four at a time with AVX: only where the CPU
    /// has it, and not when the walks were held to the portable kernels
    /// ([`CameraFrame::lanes`]), so that a narrower level runs what a
    /// machine without AVX runs.
    avx: bool,
}

impl CameraFrame {
    /// The basis from an f64 eye, target and up: the ray workload derives
    /// them in f64 from the mesh bounds, and rounding them to f32 first
    /// would change the rays.
    pub(crate) fn new(
        eye: DVec3,
        target: DVec3,
        up: DVec3,
        projection: Projection,
        width: u32,
        height: u32,
    ) -> Self {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(up).normalize();
        let upv = right.cross(fwd);
        let (ortho, h) = match projection {
            Projection::Perspective { vfov } => (false, (vfov as f64 * 0.5).to_radians().tan()),
            Projection::Orthographic { half_height } => (true, half_height as f64),
        };
        CameraFrame {
            eye,
            fwd,
            right,
            upv,
            ortho,
            h,
            aspect: width as f64 / height as f64,
            width: width as f64,
            height: height as f64,
            size: (width, height),
            avx: has_avx(),
        }
    }

    /// This frame, making rays with AVX only if `avx` too (the BVH's
    /// kernels are AVX or wider).
    pub(crate) fn lanes(mut self, avx: bool) -> Self {
        self.avx &= avx;
        self
    }

    /// The frame for pixels shown `pixel_aspect` times as wide as they are
    /// tall (a terminal cell's sub-pixels): the view keeps its proportions
    /// on screen, its height seeing the same field.
    pub(crate) fn stretched(mut self, pixel_aspect: f64) -> Self {
        self.aspect *= pixel_aspect;
        self
    }

    /// The image size in pixels this frame was made for.
    pub(crate) fn size(&self) -> (u32, u32) {
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
    pub(crate) fn sx(&self, x: f64) -> f64 {
        (2.0 * x / self.width - 1.0) * self.h * self.aspect
    }

    /// The offset along `up` of image row `y`.
    #[inline]
    pub(crate) fn sy(&self, y: f64) -> f64 {
        (1.0 - 2.0 * y / self.height) * self.h
    }

    /// The ray at offsets `sx`, `sy` ([`CameraFrame::sx`], [`CameraFrame::sy`]):
    /// rays of a tile of pixels share theirs per column and per row.
    #[inline]
    pub(crate) fn ray_through(&self, sx: f64, sy: f64) -> Ray {
        match self.ortho {
            true => Ray::new(
                (self.eye + sx * self.right + sy * self.upv).as_vec3(),
                self.fwd.as_vec3(),
            ),
            false => Ray::new(self.eye.as_vec3(), self.dir(sx, sy).as_vec3()),
        }
    }

    /// The unit direction at offsets `sx`, `sy`, in f64.
    #[inline]
    fn dir(&self, sx: f64, sy: f64) -> DVec3 {
        (self.fwd + sx * self.right + sy * self.upv).normalize()
    }

    /// The rays at image positions `(x[i], y[i])` ([`CameraFrame::ray`])
    /// appended to `out`.
    pub(crate) fn rays(&self, x: &[f64], y: &[f64], out: &mut Vec<Ray>) {
        self.batch::<true>(x, y, out)
    }

    /// The rays at offsets `(sx[i], sy[i])` ([`CameraFrame::ray_through`])
    /// appended to `out`.
    pub(crate) fn rays_through(&self, sx: &[f64], sy: &[f64], out: &mut Vec<Ray>) {
        self.batch::<false>(sx, sy, out)
    }

    /// Four rays at a time in f64 lanes where the CPU has AVX (a ray's
    /// divisions and square root wait on one another): the same operations
    /// in the same order, each correctly rounded, so the same rays to the
    /// bit as one at a time. `POS`: `a` and `b` are image positions, else
    /// offsets. Orthographic rays, with no square root and one direction,
    /// are made one at a time.
    #[inline]
    fn batch<const POS: bool>(&self, a: &[f64], b: &[f64], out: &mut Vec<Ray>) {
        assert_eq!(a.len(), b.len());
        out.reserve(a.len());
        let mut done = 0;
        #[cfg(target_arch = "x86_64")]
        if !self.ortho && self.avx {
            done = a.len() / 4 * 4;
            // SAFETY: `avx` is set only where the CPU has AVX.
            unsafe { self.batch_avx::<POS>(&a[..done], &b[..done], out) };
        }
        for (&a, &b) in a[done..].iter().zip(&b[done..]) {
            out.push(match POS {
                true => self.ray(a, b),
                false => self.ray_through(a, b),
            });
        }
    }

    /// [`CameraFrame::batch`] on four rays at a time; `a.len()` is a
    /// multiple of four.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn batch_avx<const POS: bool>(&self, a: &[f64], b: &[f64], out: &mut Vec<Ray>) {
        use std::arch::x86_64::*;
        let eye = self.eye.as_vec3();
        for (a, b) in a.chunks_exact(4).zip(b.chunks_exact(4)) {
            let f32s = |v: __m256d| {
                let mut o = [0.0f32; 4];
                _mm_storeu_ps(o.as_mut_ptr(), _mm256_cvtpd_ps(v));
                o
            };
            let [x, y, z] = self.dirs_avx::<POS>(a, b).map(f32s);
            for i in 0..4 {
                out.push(Ray::new(eye, Vec3::new(x[i], y[i], z[i])));
            }
        }
    }

    /// The f64 directions ([`CameraFrame::dir`]) of four rays, by axis.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    unsafe fn dirs_avx<const POS: bool>(
        &self,
        a: &[f64],
        b: &[f64],
    ) -> [std::arch::x86_64::__m256d; 3] {
        use std::arch::x86_64::*;
        let set = |v: f64| _mm256_set1_pd(v);
        let (add, sub, mul, div) = (_mm256_add_pd, _mm256_sub_pd, _mm256_mul_pd, _mm256_div_pd);
        let (a, b) = (
            _mm256_loadu_pd(a[..4].as_ptr()),
            _mm256_loadu_pd(b[..4].as_ptr()),
        );
        let (sx, sy) = if POS {
            // `sx` and `sy` as written there, left to right.
            let two = set(2.0);
            let sx = mul(
                mul(
                    sub(div(mul(two, a), set(self.width)), set(1.0)),
                    set(self.h),
                ),
                set(self.aspect),
            );
            let sy = mul(
                sub(set(1.0), div(mul(two, b), set(self.height))),
                set(self.h),
            );
            (sx, sy)
        } else {
            (a, b)
        };
        // `fwd + sx * right + sy * upv`, then glam's `normalize`: the dot
        // product left to right, `1 / sqrt`, three products.
        let axis = |f: f64, r: f64, u: f64| add(add(set(f), mul(sx, set(r))), mul(sy, set(u)));
        let d = [
            axis(self.fwd.x, self.right.x, self.upv.x),
            axis(self.fwd.y, self.right.y, self.upv.y),
            axis(self.fwd.z, self.right.z, self.upv.z),
        ];
        let len = _mm256_sqrt_pd(add(add(mul(d[0], d[0]), mul(d[1], d[1])), mul(d[2], d[2])));
        let recip = div(set(1.0), len);
        d.map(|v| mul(v, recip))
    }

    /// Image position of a world point, or `None` when it is behind the
    /// camera (the eye, or an orthographic camera's plane).
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
    pub(crate) fn project_clip(
        &self,
        a: Vec3,
        b: Vec3,
        near: f64,
    ) -> Option<((f64, f64), (f64, f64))> {
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
        // Orthographic offsets are lengths on the view plane.
        let z = if self.ortho { 1.0 } else { d.dot(self.fwd) };
        let sx = d.dot(self.right) / z;
        let sy = d.dot(self.upv) / z;
        let x = (sx / (self.h * self.aspect) + 1.0) * 0.5 * self.width;
        let y = (1.0 - sy / self.h) * 0.5 * self.height;
        (x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An orthographic view: rays along the line of sight from the plane
    /// through the eye, spread over the view's height and the image's
    /// aspect; a point projects to the same place at any depth in front.
    #[test]
    fn orthographic_rays_are_parallel_and_spread_over_the_view() {
        let ortho = Projection::Orthographic { half_height: 2.0 };
        let (eye, target) = (DVec3::new(1.0, 2.0, 10.0), DVec3::new(1.0, 2.0, 0.0));
        let f = CameraFrame::new(eye, target, DVec3::Y, ortho, 64, 32);
        for (x, y, o) in [
            (0.0, 0.0, Vec3::new(-3.0, 4.0, 10.0)),
            (32.0, 16.0, Vec3::new(1.0, 2.0, 10.0)),
            (64.0, 32.0, Vec3::new(5.0, 0.0, 10.0)),
        ] {
            let r = f.ray(x, y);
            assert_eq!((r.origin, r.dir), (o, Vec3::NEG_Z), "({x}, {y})");
        }
        for z in [9.0, 0.0, -1e6] {
            assert_eq!(f.project(Vec3::new(-3.0, 4.0, z)), Some((0.0, 0.0)));
        }
        assert_eq!(f.project(Vec3::new(0.0, 0.0, 11.0)), None);
        let ((ax, _), (bx, _)) = f
            .project_clip(Vec3::new(1.0, 2.0, 20.0), Vec3::new(3.0, 2.0, 0.0), 1.0)
            .unwrap();
        // Cut at the plane 1 ahead of the eye: x = 1 + 2 * 11 / 20.
        assert!(
            (ax - 32.0 - 1.1 * 8.0).abs() < 1e-9 && (bx - 48.0).abs() < 1e-9,
            "{ax} {bx}"
        );
    }

    /// Batches of every length up to 13 (the four-lane part and the rest),
    /// over cameras and positions from a hash, give the rays made one at a
    /// time, bit for bit.
    #[test]
    fn batched_rays_are_the_rays_one_at_a_time() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let bits = |r: &Ray| [r.origin.to_array(), r.dir.to_array()].map(|v| v.map(f32::to_bits));
        for _ in 0..200 {
            let mut v = || DVec3::new(next(), next(), next()) * 200.0 - 100.0;
            let (eye, target) = (v(), v());
            let (w, h) = (1 + (next() * 3000.0) as u32, 1 + (next() * 3000.0) as u32);
            let projection = match next() < 0.25 {
                true => Projection::Orthographic {
                    half_height: (next() * 100.0) as f32,
                },
                false => Projection::perspective((1.0 + next() * 170.0) as f32),
            };
            let f = CameraFrame::new(eye, target, DVec3::Y, projection, w, h);
            let n = (next() * 14.0) as usize;
            let x: Vec<f64> = (0..n).map(|_| next() * w as f64).collect();
            let y: Vec<f64> = (0..n).map(|_| next() * h as f64).collect();
            let (mut at, mut through) = (Vec::new(), Vec::new());
            f.rays(&x, &y, &mut at);
            let sx: Vec<f64> = x.iter().map(|&x| f.sx(x)).collect();
            let sy: Vec<f64> = y.iter().map(|&y| f.sy(y)).collect();
            f.rays_through(&sx, &sy, &mut through);
            assert_eq!((at.len(), through.len()), (n, n));
            #[cfg(target_arch = "x86_64")]
            if !f.ortho && std::arch::is_x86_feature_detected!("avx") {
                // The f64 directions too: a difference there seldom
                // survives the rounding to f32.
                for i in (0..n / 4 * 4).step_by(4) {
                    let mut d = [[0.0; 4]; 3];
                    for (pos, (a, b)) in [(true, (&x, &y)), (false, (&sx, &sy))] {
                        // SAFETY: the CPU has AVX.
                        unsafe {
                            let v = match pos {
                                true => f.dirs_avx::<true>(&a[i..], &b[i..]),
                                false => f.dirs_avx::<false>(&a[i..], &b[i..]),
                            };
                            for (d, v) in d.iter_mut().zip(v) {
                                std::arch::x86_64::_mm256_storeu_pd(d.as_mut_ptr(), v);
                            }
                        }
                        for l in 0..4 {
                            let one = f.dir(sx[i + l], sy[i + l]).to_array().map(f64::to_bits);
                            assert_eq!([d[0][l], d[1][l], d[2][l]].map(f64::to_bits), one);
                        }
                    }
                }
            }
            for i in 0..n {
                let one = f.ray(x[i], y[i]);
                assert_eq!(bits(&at[i]), bits(&one), "{f:?} at ({}, {})", x[i], y[i]);
                assert_eq!(
                    bits(&through[i]),
                    bits(&one),
                    "{f:?} at ({}, {})",
                    x[i],
                    y[i]
                );
            }
        }
    }

    /// A turntable keeps the eye's distance and height, turns it evenly
    /// (half way round is opposite), and starts at the camera itself.
    #[test]
    fn a_turntable_circles_the_target_at_one_height() {
        let c = Camera {
            eye: Vec3::new(3.0, 2.0, 4.0),
            target: Vec3::new(1.0, 0.5, 0.0),
            up: Vec3::Y,
            projection: Projection::perspective(40.0),
        };
        assert_eq!(c.turntable(0, 12), c);
        assert_eq!(c.turntable(12, 12), c);
        let off = c.eye - c.target;
        for k in 1..12 {
            let t = c.turntable(k, 12);
            let o = t.eye - t.target;
            assert_eq!(
                (t.target, t.up, t.projection),
                (c.target, c.up, c.projection)
            );
            assert!((o.length() - off.length()).abs() < 1e-5 && (o.y - off.y).abs() < 1e-5);
            let turned = (k as f32 / 12.0) * std::f32::consts::TAU;
            let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize();
            assert!((flat(o).dot(flat(off)) - turned.cos()).abs() < 1e-5, "{k}");
        }
        let half = c.turntable(6, 12).eye - c.target;
        assert!((half.x + off.x).abs() < 1e-5 && (half.z + off.z).abs() < 1e-5);
        // Anticlockwise seen from above: a quarter turn takes +z to +x.
        let q = c.turntable(3, 12).eye - c.target;
        assert!(
            (q.x - off.z).abs() < 1e-5 && (q.z + off.x).abs() < 1e-5,
            "{q}"
        );
    }
}
