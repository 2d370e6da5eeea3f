//! Area lights over a plane with no occluder, whose pixel values are known
//! by quadrature: the shading integral is computed here in f64 from the
//! light's definition, independently of the renderer's sampling code.

use glam::{DVec3, Vec3};
use rayterm::color::LUMA;
use rayterm::render::{Feature, Features};
use rayterm::scene::{Camera, Light, Projection, Scene};

use crate::common::{material, quad_y, scene, top_camera};

pub const KD: Vec3 = Vec3::new(0.7, 0.6, 0.5);

/// Everything on but supersampling (so a pixel's exact value is the one at
/// its centre) and bloom.
pub fn features() -> Features {
    Features::all().without(&[Feature::Supersampling, Feature::Bloom])
}

/// A parallelogram light with four corner colours above a diffuse plane.
pub fn parallelogram() -> Light {
    Light::Parallelogram {
        corner: Vec3::new(-0.6, 0.7, -0.5),
        edge1: Vec3::new(1.1, 0.15, 0.2),
        edge2: Vec3::new(0.1, 0.0, 0.9),
        colors: [
            Vec3::new(1.2, 0.5, 0.3),
            Vec3::new(1.1, 1.0, 0.6),
            Vec3::new(0.4, 0.6, 1.3),
            Vec3::new(0.9, 0.9, 1.1),
        ],
    }
}

/// A segment light with two end colours above a diffuse plane.
pub fn segment() -> Light {
    Light::Segment {
        a: Vec3::new(-0.7, 0.6, 0.3),
        b: Vec3::new(0.8, 0.9, -0.4),
        color_a: Vec3::new(1.3, 0.6, 0.2),
        color_b: Vec3::new(0.3, 0.7, 1.2),
    }
}

/// The plane y = 0 (kd only) under `light`, seen from straight above.
pub fn plane_under(light: Light) -> Scene {
    let (p, t) = quad_y(-10.0, -10.0, 10.0, 10.0, 0.0);
    let mut s = scene(
        &[(p, t, material(KD, Vec3::ZERO, 1.0))],
        vec![light],
        top_camera(3.0),
    );
    s.settings.ambient = Vec3::ZERO;
    s.settings.max_depth = 0;
    s
}

/// Composite Simpson weights for `n` (even) intervals on [0, 1].
fn simpson(n: usize) -> Vec<(f64, f64)> {
    (0..=n)
        .map(|i| {
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            (i as f64 / n as f64, w / (3.0 * n as f64))
        })
        .collect()
}

/// Diffuse light from one point of a light at `p` on the plane (normal +y).
fn diffuse(p: DVec3, lp: DVec3, c: DVec3) -> DVec3 {
    let l = (lp - p).normalize();
    KD.as_dvec3() * l.y.max(0.0) * c
}

/// The light's average diffuse contribution at `p`, by quadrature over its
/// parameter domain (the renderer averages samples uniform in it).
pub fn shade(light: &Light, p: DVec3) -> DVec3 {
    let q = simpson(64);
    match *light {
        Light::Segment {
            a,
            b,
            color_a,
            color_b,
        } => q
            .iter()
            .map(|&(s, w)| {
                let lp = a.as_dvec3() * (1.0 - s) + b.as_dvec3() * s;
                let c = color_a.as_dvec3() * (1.0 - s) + color_b.as_dvec3() * s;
                diffuse(p, lp, c) * w
            })
            .sum(),
        Light::Parallelogram {
            corner,
            edge1,
            edge2,
            colors,
        } => {
            let c = colors.map(|c| c.as_dvec3());
            let mut sum = DVec3::ZERO;
            for &(s, ws) in &q {
                for &(t, wt) in &q {
                    let lp = corner.as_dvec3() + edge1.as_dvec3() * s + edge2.as_dvec3() * t;
                    let bottom = c[0] * (1.0 - s) + c[1] * s;
                    let top = c[3] * (1.0 - s) + c[2] * s;
                    sum += diffuse(p, lp, bottom * (1.0 - t) + top * t) * (ws * wt);
                }
            }
            sum
        }
        Light::Point { position, color } => diffuse(p, position.as_dvec3(), color.as_dvec3()),
        Light::Photometric { .. } | Light::Directional { .. } => {
            unimplemented!("the exact images use Phong lights")
        }
    }
}

/// The exact image of [`plane_under`]: each pixel centre's ray meets the
/// plane at a point whose shading is integrated by quadrature.
pub fn exact_image(s: &Scene, w: u32, h: u32) -> Vec<Vec3> {
    let frame = s.camera.frame(w, h);
    let mut img = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let ray = frame.ray(x as f64 + 0.5, y as f64 + 0.5);
            let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
            let p = o + d * (-o.y / d.y);
            img.push(
                s.lights
                    .iter()
                    .map(|l| shade(l, p))
                    .sum::<DVec3>()
                    .as_vec3(),
            );
        }
    }
    img
}

pub fn lum(c: Vec3) -> f64 {
    c.as_dvec3().dot(LUMA.as_dvec3())
}

/// Gauss-Legendre nodes and weights for `n` points on [0, 1] (Newton's
/// method on the Legendre recurrence).
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let k = k as f64;
                    (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / dp;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            ((1.0 - x) / 2.0, w / 2.0)
        })
        .collect()
}

/// The exact image of [`plane_under`] with supersampling: each pixel is
/// the mean over its square of the shading where the camera ray meets the
/// plane (8x8 Gauss-Legendre points; the integrand is smooth).
pub fn exact_image_area(s: &Scene, w: u32, h: u32) -> Vec<Vec3> {
    let frame = s.camera.frame(w, h);
    let q = gauss_legendre(8);
    let mut img = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut sum = DVec3::ZERO;
            for &(u, wu) in &q {
                for &(v, wv) in &q {
                    let ray = frame.ray(x as f64 + u, y as f64 + v);
                    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
                    let p = o + d * (-o.y / d.y);
                    let c: DVec3 = s.lights.iter().map(|l| shade(l, p)).sum();
                    sum += c * (wu * wv);
                }
            }
            img.push(sum.as_vec3());
        }
    }
    img
}

/// A box on a plane under `light`, seen from above at an angle: edges and
/// soft shadows inside pixels, where jittered sub-pixel samples are far
/// from independent.
pub fn box_under(light: Light) -> Scene {
    let (pp, pt) = quad_y(-2.0, -2.0, 2.0, 2.0, 0.0);
    let corner = |i: u32| {
        Vec3::new(0.05, 0.25, -0.1)
            + 0.25
                * Vec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                )
    };
    let bt = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ];
    let floor = material(Vec3::splat(0.15), Vec3::ZERO, 1.0);
    let m = material(KD, Vec3::ZERO, 1.0);
    let mut s = scene(
        &[(pp, pt, floor), ((0..8).map(corner).collect(), bt, m)],
        vec![light],
        Camera {
            eye: Vec3::new(0.2, 1.6, 1.3),
            target: Vec3::new(0.0, 0.1, -0.1),
            up: Vec3::Y,
            projection: Projection::perspective(40.0),
        },
    );
    s.settings.ambient = Vec3::splat(0.02);
    s.settings.max_depth = 0;
    s.settings.light_samples = 16;
    s
}
