//! The environment light: radiance from every direction, seen by rays that
//! leave the scene and sampled as a light. A constant colour, or an
//! equirectangular (latitude-longitude) map: Radiance `.hdr` and OpenEXR
//! `.exr` read as linear, PNG, JPEG and WebP sRGB-decoded (by
//! `scene::load::envmap`); times a `strength`, turned `rotation` degrees
//! about +Y.
//!
//! The map's convention, in rayterm's Y-up world: the top row looks up
//! (+Y), the bottom row down; the centre column looks along +X, the column
//! a quarter of the width to its left along -Z, a quarter to its right
//! along +Z: `u = 1/2 + atan2(z, x) / 2π`, `v = acos(y) / π` from the top.
//! This is Blender's mapping for its Environment Texture once its Z-up
//! world is made Y-up the way its glTF exporter does (and `scene::load::up`
//! turns Z-up files), and the mapping of three.js and the glTF Sample
//! Viewer: a map lights a glTF scene here as it does there. Seen from
//! inside, the image reads left to right, unmirrored. A positive rotation
//! turns the map counter-clockwise seen from above: at 90 degrees, what
//! the centre column showed along +X is seen along -Z.
//!
//! Sampling is pbrt-v4's `PiecewiseConstant2D`: a row by its share of the
//! weight, then a cell of the row by its share of the row's. A cell's
//! weight is the mean luminance of the bilinear lookup over it (so it is
//! positive wherever the lookup is) times the sine of its row's polar
//! angle (the solid angle the row covers); a density `pdf_uv` over the
//! map is `pdf_uv / (2π² sin θ)` per steradian. A constant colour is
//! sampled uniformly over the sphere. No random numbers are drawn here:
//! the same `u` gives the same sample. A light that gives none (a black
//! map or colour, strength 0) has density 0 everywhere, and its samples
//! zero radiance with density 0, which callers skip.

use std::f32::consts::{PI, TAU};

use glam::{DVec3, Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::texture::{Texture, Wrap};

/// Rec. 709 luminance: how much a texel weighs in sampling.
const LUMA: DVec3 = crate::color::LUMA_F64;

/// Bytes a map's sampling distribution takes per texel: a running sum
/// in f64, so that a cell a million times dimmer than the brightest keeps
/// its share.
pub(crate) const DISTRIBUTION_BYTES: u64 = 8;

/// The largest f32 below 1, where sample coordinates are clamped.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The density of uniform directions, per steradian.
const UNIFORM_PDF: f32 = 1.0 / (4.0 * PI);

/// What the inspector names a lookup in a map, where a cube map's names
/// its face.
pub(crate) const LATLONG: &str = "latlong";

/// Radiance arriving from every direction (see the module's documentation).
#[derive(Clone, Debug)]
pub struct EnvLight {
    radiance: Radiance,
    strength: f32,
    /// Degrees about +Y.
    rotation: f32,
    /// The turn from the map's frame to the world's, and back.
    to_world: Mat3,
    to_map: Mat3,
    /// Whether it gives no light, and so is sampled with density 0.
    dark: bool,
}

#[derive(Clone, Debug)]
enum Radiance {
    Constant(Vec3),
    Map { texture: Texture, cells: Cells },
}

/// A direction drawn from an [`EnvLight`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnvSample {
    /// Unit length: the way a ray leaves the scene to meet the light.
    pub(crate) dir: Vec3,
    /// [`EnvLight::eval`] of `dir`.
    pub radiance: Vec3,
    /// Per steradian, as [`EnvLight::pdf`] gives it; 0 for a light that
    /// gives none, or a direction exactly at a pole of the map.
    pub pdf: f32,
}

impl EnvLight {
    /// The same radiance from every direction.
    pub fn constant(color: Vec3) -> Self {
        Self::new(Radiance::Constant(color))
    }

    /// An equirectangular map of linear texels, row 0 at the top.
    pub(crate) fn from_map(mut texture: Texture) -> Self {
        // Round the sphere in u; at the poles, the edge row itself.
        texture.wrap = [Wrap::Repeat, Wrap::Clamp];
        texture.tint = Vec3::ONE;
        let cells = Cells::new(&texture);
        Self::new(Radiance::Map { texture, cells })
    }

    fn new(radiance: Radiance) -> Self {
        let mut light = Self {
            radiance,
            strength: 1.0,
            rotation: 0.0,
            to_world: Mat3::IDENTITY,
            to_map: Mat3::IDENTITY,
            dark: false,
        };
        light.dark = light.gives_none();
        light
    }

    fn gives_none(&self) -> bool {
        self.strength == 0.0
            || match &self.radiance {
                Radiance::Constant(c) => *c == Vec3::ZERO,
                Radiance::Map { cells, .. } => cells.total == 0.0,
            }
    }

    /// The light with every radiance multiplied by `strength` (finite, 0 or
    /// more).
    pub(crate) fn scaled(mut self, strength: f32) -> Self {
        self.strength = strength;
        self.dark = self.gives_none();
        self
    }

    /// The light turned `degrees` about +Y (finite).
    pub(crate) fn rotated(mut self, degrees: f32) -> Self {
        self.rotation = degrees;
        self.to_world = Mat3::from_rotation_y(degrees.to_radians());
        self.to_map = self.to_world.transpose();
        self
    }

    /// Radiance arriving along a ray that leaves the scene in direction
    /// `dir` (of any length but 0): the map looked up bilinearly, wrapping
    /// round in u, clamped at the poles.
    pub fn eval(&self, dir: Vec3) -> Vec3 {
        match &self.radiance {
            Radiance::Constant(c) => *c * self.strength,
            Radiance::Map { texture, .. } => match self.local(dir) {
                Some(d) => {
                    let uv = uv_of(d);
                    let (w, h) = (texture.width as f32, texture.height as f32);
                    texture.bilinear_px(uv.x * w, uv.y * h) * self.strength
                }
                None => Vec3::ZERO,
            },
        }
    }

    /// A direction drawn with the density [`EnvLight::pdf`] gives, from
    /// `u` in [0, 1)² (clamped into it).
    pub fn sample(&self, u: Vec2) -> EnvSample {
        let u = Vec2::new(unit(u.x), unit(u.y));
        let cells = match &self.radiance {
            Radiance::Map { cells, .. } if !self.dark => cells,
            _ => {
                let dir = uniform_sphere(u);
                let pdf = if self.dark { 0.0 } else { UNIFORM_PDF };
                return EnvSample {
                    dir,
                    radiance: self.eval(dir),
                    pdf,
                };
            }
        };
        let (uv, pdf_uv) = cells.sample(u);
        let (sin_theta, cos_theta) = (uv.y * PI).sin_cos();
        // Past π by rounding is the pole itself.
        let sin_theta = sin_theta.max(0.0);
        let (sin_phi, cos_phi) = ((uv.x - 0.5) * TAU).sin_cos();
        let local = Vec3::new(sin_theta * cos_phi, cos_theta, sin_theta * sin_phi);
        let dir = (self.to_world * local).normalize_or(Vec3::Y);
        EnvSample {
            dir,
            radiance: self.eval(dir),
            pdf: solid_angle(pdf_uv, sin_theta),
        }
    }

    /// The density per steradian with which [`EnvLight::sample`] draws
    /// `dir`.
    pub fn pdf(&self, dir: Vec3) -> f32 {
        if self.dark {
            return 0.0;
        }
        match &self.radiance {
            Radiance::Constant(_) => UNIFORM_PDF,
            Radiance::Map { cells, .. } => match self.local(dir) {
                Some(d) => solid_angle(cells.pdf(uv_of(d)), d.x.hypot(d.z)),
                None => 0.0,
            },
        }
    }

    /// Where in the map `dir` looks (u from the left, v from the top),
    /// where there is a map.
    pub(crate) fn map_uv(&self, dir: Vec3) -> Option<Vec2> {
        match &self.radiance {
            Radiance::Map { .. } => self.local(dir).map(uv_of),
            Radiance::Constant(_) => None,
        }
    }

    /// `dir` of unit length in the map's frame; `None` for no direction.
    fn local(&self, dir: Vec3) -> Option<Vec3> {
        let d = self.to_map * dir;
        let len = d.length();
        (len > 0.0 && len.is_finite()).then(|| d / len)
    }

    pub(crate) fn map(&self) -> Option<&Texture> {
        match &self.radiance {
            Radiance::Map { texture, .. } => Some(texture),
            Radiance::Constant(_) => None,
        }
    }

    /// The colour of a constant light, before its strength.
    pub(crate) fn color(&self) -> Option<Vec3> {
        match &self.radiance {
            Radiance::Constant(c) => Some(*c),
            Radiance::Map { .. } => None,
        }
    }

    pub(crate) fn strength(&self) -> f32 {
        self.strength
    }

    /// Degrees about +Y.
    pub(crate) fn rotation(&self) -> f32 {
        self.rotation
    }

    /// The largest channel of any radiance it gives (a bilinear lookup
    /// never exceeds the texels it blends).
    pub(crate) fn brightest(&self) -> f32 {
        let most = match &self.radiance {
            Radiance::Constant(c) => c.max_element(),
            Radiance::Map { texture, .. } => texture
                .texels
                .iter()
                .fold(0.0f32, |m, t| m.max(t.max_element())),
        };
        most * self.strength
    }
}

/// Where a map's samples fall: one cell per texel, a density constant
/// over each (pbrt-v4's `PiecewiseConstant2D`).
#[derive(Clone, Debug)]
struct Cells {
    width: usize,
    height: usize,
    /// Each row's running sum of its cells' weights, from 0 to 1
    /// (`width + 1` values; in equal steps for a row of no weight, which
    /// is never chosen).
    columns: Vec<f64>,
    /// The running sum of the rows' weights, from 0 to 1.
    rows: Vec<f64>,
    /// The sum of every weight: 0 for a map that gives no light.
    total: f64,
}

impl Cells {
    fn new(t: &Texture) -> Self {
        let (w, h) = (t.width as usize, t.height as usize);
        let mut columns = vec![0.0; h * (w + 1)];
        let sums: Vec<f64> = columns
            .par_chunks_mut(w + 1)
            .enumerate()
            .map(|(y, cdf)| {
                // The mean of the bilinear lookup over a texel's cell
                // weighs the texel 3/4 and each neighbour 1/8 along each
                // axis (neighbours as the lookup finds them: round in x,
                // the edge row itself past the poles).
                let across = |yy: i64| -> Vec<f64> {
                    let lum: Vec<f64> = (0..w as i64)
                        .map(|x| t.texel(x, yy).as_dvec3().dot(LUMA))
                        .collect();
                    (0..w)
                        .map(|x| (lum[(x + w - 1) % w] + lum[(x + 1) % w]) / 8.0 + lum[x] * 0.75)
                        .collect()
                };
                let y = y as i64;
                let [above, row, below] = [y - 1, y, y + 1].map(across);
                let sin = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
                let weights = (0..w).map(|x| ((above[x] + below[x]) / 8.0 + row[x] * 0.75) * sin);
                running(cdf, weights)
            })
            .collect();
        let mut rows = vec![0.0; h + 1];
        let total = running(&mut rows, sums.into_iter());
        Self {
            width: w,
            height: h,
            columns,
            rows,
            total,
        }
    }

    fn row(&self, y: usize) -> &[f64] {
        &self.columns[y * (self.width + 1)..][..self.width + 1]
    }

    /// A point of the map (u from the left, v from the top) for `u` in
    /// [0, 1)², and the density there.
    fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (y, dy, py) = pick(&self.rows, u.y);
        let (x, dx, px) = pick(self.row(y), u.x);
        let uv = Vec2::new(
            ((x as f64 + dx) / self.width as f64) as f32,
            ((y as f64 + dy) / self.height as f64) as f32,
        );
        (uv, (px * py) as f32)
    }

    /// The density at a point of the map.
    fn pdf(&self, uv: Vec2) -> f32 {
        // `as` takes NaN and negatives to 0.
        let x = ((uv.x * self.width as f32) as usize).min(self.width - 1);
        let y = ((uv.y * self.height as f32) as usize).min(self.height - 1);
        let row = self.row(y);
        let px = (row[x + 1] - row[x]) * self.width as f64;
        let py = (self.rows[y + 1] - self.rows[y]) * self.height as f64;
        (px * py) as f32
    }
}

/// Fills `cdf`, one longer than `weights`, with their running sum scaled
/// to end at exactly 1 (in equal steps where they sum to 0); returns the
/// sum.
fn running(cdf: &mut [f64], weights: impl Iterator<Item = f64>) -> f64 {
    let mut sum = 0.0;
    cdf[0] = 0.0;
    for (i, w) in weights.enumerate() {
        sum += w;
        cdf[i + 1] = sum;
    }
    let n = (cdf.len() - 1) as f64;
    for (i, c) in cdf.iter_mut().enumerate() {
        *c = if sum > 0.0 { *c / sum } else { i as f64 / n };
    }
    sum
}

/// The cell of `cdf` that `u` falls in, how far along it (0..1), and the
/// cell's density (its share times the number of cells). Cells of no
/// weight are passed over: the last cell starting at or below `u` is the
/// one whose end lies above it.
fn pick(cdf: &[f64], u: f32) -> (usize, f64, f64) {
    let n = cdf.len() - 1;
    let u = u as f64;
    let i = (cdf.partition_point(|&c| c <= u).max(1) - 1).min(n - 1);
    let span = cdf[i + 1] - cdf[i];
    let along = match span > 0.0 {
        true => ((u - cdf[i]) / span).clamp(0.0, 1.0),
        false => 0.0,
    };
    (i, along, span * n as f64)
}

/// A density over the map's (u, v) as one per steradian: the map's unit
/// square covers the sphere, `dω = 2π² sin θ du dv`. 0 at the poles.
fn solid_angle(pdf_uv: f32, sin_theta: f32) -> f32 {
    let p = pdf_uv / (2.0 * PI * PI * sin_theta);
    if sin_theta > 0.0 && p.is_finite() {
        p
    } else {
        0.0
    }
}

/// Where unit `d` (in the map's frame) looks in the map: u from the left,
/// v from the top.
fn uv_of(d: Vec3) -> Vec2 {
    Vec2::new(0.5 + d.z.atan2(d.x) / TAU, d.y.clamp(-1.0, 1.0).acos() / PI)
}

/// Uniform over the sphere.
fn uniform_sphere(u: Vec2) -> Vec3 {
    let y = 1.0 - 2.0 * u.y;
    let r = (1.0 - y * y).max(0.0).sqrt();
    let (s, c) = (TAU * u.x).sin_cos();
    Vec3::new(r * c, y, r * s)
}

/// `x` in [0, 1) (NaN to 0).
fn unit(x: f32) -> f32 {
    match x.is_nan() {
        true => 0.0,
        false => x.clamp(0.0, ONE_MINUS_EPSILON),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use crate::geometry::sampling::Rng;

    /// A `w` x `h` map of `f(x, y)`.
    fn map(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> EnvLight {
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect();
        EnvLight::from_map(Texture {
            name: "m".into(),
            width: w,
            height: h,
            texels: Arc::new(texels),
            wrap: [Wrap::Repeat; 2],
            tint: Vec3::ONE,
            uv: Default::default(),
        })
    }

    /// Colours over four orders of magnitude, and a band of black rows
    /// (cells of no weight between cells of some).
    fn lumpy() -> EnvLight {
        map(48, 24, |x, y| {
            if (9..13).contains(&y) {
                return Vec3::ZERO;
            }
            let mut r = Rng::for_sample(x as u64, y as u64, 5);
            let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            c * 10f32.powf(4.0 * r.next_f32() - 2.0)
        })
    }

    /// 1 everywhere but one texel, a million times brighter.
    fn hot() -> EnvLight {
        map(32, 16, |x, y| match (x, y) {
            (21, 5) => Vec3::splat(1e6),
            _ => Vec3::ONE,
        })
    }

    /// Black but the top row.
    fn zenith() -> EnvLight {
        map(16, 8, |_, y| Vec3::splat((y == 0) as u32 as f32))
    }

    /// The direction at polar angle `theta` from +Y and azimuth `phi` from
    /// +X toward +Z.
    fn polar(theta: f64, phi: f64) -> Vec3 {
        let (t, p) = (theta as f32, phi as f32);
        Vec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin())
    }

    /// ∫ pdf dω by the midpoint rule in (θ, φ), `k` steps a texel of a `w`
    /// x `h` map (a cell's edges on steps' edges).
    fn pdf_integral(l: &EnvLight, w: u32, h: u32, k: u32) -> f64 {
        let (nt, np) = (h * k, w * k);
        let dt = std::f64::consts::PI / nt as f64;
        let dp = std::f64::consts::TAU / np as f64;
        let mut sum = 0.0;
        for i in 0..nt {
            let t = (i as f64 + 0.5) * dt;
            for j in 0..np {
                let p = -std::f64::consts::PI + (j as f64 + 0.5) * dp;
                sum += l.pdf(polar(t, p)) as f64 * t.sin() * dt * dp;
            }
        }
        sum
    }

    #[test]
    fn the_pdf_integrates_to_one() {
        for (name, l, w, h) in [("lumpy", lumpy(), 48, 24), ("hot", hot(), 32, 16)] {
            let i = pdf_integral(&l, w, h, 12);
            assert!((i - 1.0).abs() < 1e-3, "{name}: {i}");
        }
        let c = EnvLight::constant(Vec3::new(0.2, 0.3, 0.5)).scaled(2.0);
        for d in [Vec3::X, Vec3::NEG_Y, Vec3::new(1.0, 2.0, -3.0)] {
            assert_eq!(c.pdf(d), 1.0 / (4.0 * PI));
        }
        assert!((pdf_integral(&c, 8, 4, 8) - 1.0).abs() < 1e-3);
    }

    /// Q(a, x), the regularised upper incomplete gamma function: the
    /// chi-square distribution's tail is `Q(dof / 2, x / 2)`.
    fn gamma_q(a: f64, x: f64) -> f64 {
        let front = (a * x.ln() - x - ln_gamma(a)).exp();
        if x < a + 1.0 {
            // The series for P = 1 - Q.
            let (mut term, mut sum, mut n) = (1.0 / a, 1.0 / a, a);
            while term > sum * 1e-16 {
                n += 1.0;
                term *= x / n;
                sum += term;
            }
            1.0 - sum * front
        } else {
            // The continued fraction for Q (modified Lentz).
            let tiny = 1e-300;
            let (mut b, mut c) = (x + 1.0 - a, 1.0 / tiny);
            let mut d = 1.0 / b;
            let mut q = d;
            for i in 1..10_000 {
                let an = -(i as f64) * (i as f64 - a);
                b += 2.0;
                d = an * d + b;
                d = if d.abs() < tiny { tiny } else { d };
                c = b + an / c;
                c = if c.abs() < tiny { tiny } else { c };
                d = 1.0 / d;
                q *= d * c;
                if (d * c - 1.0).abs() < 1e-16 {
                    break;
                }
            }
            q * front
        }
    }

    /// ln Γ(x) for x > 0 (Lanczos, g = 7).
    fn ln_gamma(x: f64) -> f64 {
        const C: [f64; 9] = [
            0.999_999_999_999_809_9,
            676.520_368_121_885_1,
            -1_259.139_216_722_402_8,
            771.323_428_777_653_1,
            -176.615_029_162_140_6,
            12.507_343_278_686_905,
            -0.138_571_095_265_720_12,
            9.984_369_578_019_572e-6,
            1.505_632_735_149_311_6e-7,
        ];
        let x = x - 1.0;
        let t = x + 7.5;
        let s = C[0]
            + (C[1..].iter().enumerate())
                .map(|(i, c)| c / (x + i as f64 + 1.0))
                .sum::<f64>();
        0.5 * std::f64::consts::TAU.ln() + (x + 0.5) * t.ln() - t + s.ln()
    }

    /// Points splitting `[a, b]` at every `a0 + k step` inside it.
    fn split(a: f64, b: f64, a0: f64, step: f64) -> Vec<f64> {
        let mut at = vec![a];
        let mut k = ((a - a0) / step).floor() + 1.0;
        while a0 + k * step < b {
            at.push(a0 + k * step);
            k += 1.0;
        }
        at.push(b);
        at
    }

    /// The p-value of Pearson's chi-square test of `samples` directions
    /// from `drawn` against the pdf of `l` (a `w` x `h` map turned
    /// `degrees`), in 32 x 64 bins of (cos θ, φ), those expecting fewer
    /// than 5 pooled, as pbrt and Mitsuba test their samplers. A bin's
    /// expected count is the pdf integrated over it piece by piece, each
    /// piece within one cell of the map, where `pdf sin θ` is constant:
    /// the midpoint is exact.
    fn chi_square_p(
        drawn: &EnvLight,
        l: &EnvLight,
        (w, h, degrees): (u32, u32, f64),
        samples: u32,
    ) -> f64 {
        const NC: usize = 32;
        const NP: usize = 64;
        let pi = std::f64::consts::PI;
        let bin = |d: Vec3| {
            let c = (((d.y + 1.0) / 2.0 * NC as f32) as usize).min(NC - 1);
            let p = (((d.z.atan2(d.x) + PI) / TAU * NP as f32) as usize).min(NP - 1);
            c * NP + p
        };
        let mut observed = vec![0.0f64; NC * NP];
        let mut rng = Rng::for_sample(1, 2, 12);
        for _ in 0..samples {
            observed[bin(drawn.sample(rng.next_vec2()).dir)] += 1.0;
        }
        // Turned by `degrees`, a cell's edges in φ move the other way.
        let phi0 = -pi - degrees.to_radians();
        let expected: Vec<f64> = (0..NC * NP)
            .map(|b| {
                let (ci, pj) = ((b / NP) as f64, (b % NP) as f64);
                let (c0, c1) = (
                    -1.0 + 2.0 * ci / NC as f64,
                    -1.0 + 2.0 * (ci + 1.0) / NC as f64,
                );
                let thetas = split(c1.acos(), c0.acos(), 0.0, pi / h as f64);
                let step = std::f64::consts::TAU / NP as f64;
                let phis = split(
                    -pi + pj * step,
                    -pi + (pj + 1.0) * step,
                    phi0,
                    2.0 * pi / w as f64,
                );
                let mut sum = 0.0;
                for t in thetas.windows(2) {
                    for p in phis.windows(2) {
                        let (tm, pm) = ((t[0] + t[1]) / 2.0, (p[0] + p[1]) / 2.0);
                        let area = (t[1] - t[0]) * (p[1] - p[0]);
                        sum += l.pdf(polar(tm, pm)) as f64 * tm.sin() * area;
                    }
                }
                sum * samples as f64
            })
            .collect();
        let (mut chi2, mut bins, mut pool) = (0.0, 0, (0.0, 0.0));
        for (o, e) in observed.iter().zip(&expected) {
            assert!(*e > 0.0 || *o == 0.0, "{o} samples where the pdf is 0");
            if *e < 5.0 {
                pool = (pool.0 + o, pool.1 + e);
            } else {
                chi2 += (o - e) * (o - e) / e;
                bins += 1;
            }
        }
        if pool.1 > 0.0 {
            chi2 += (pool.0 - pool.1) * (pool.0 - pool.1) / pool.1;
            bins += 1;
        }
        gamma_q((bins - 1) as f64 / 2.0, chi2 / 2.0)
    }

    #[test]
    fn samples_follow_the_pdf_by_chi_square() {
        // The tail itself: Q(2, x) = e^-x (1 + x), by both branches.
        for x in [1.0, 10.0f64] {
            assert!((gamma_q(2.0, x) - (-x).exp() * (1.0 + x)).abs() < 1e-12);
        }
        let cases = [
            ("lumpy", lumpy(), (48, 24, 0.0)),
            ("hot", hot(), (32, 16, 0.0)),
            ("turned", lumpy().rotated(37.0), (48, 24, 37.0)),
            ("zenith", zenith(), (16, 8, 0.0)),
            ("constant", EnvLight::constant(Vec3::ONE), (1, 1, 0.0)),
        ];
        for (name, l, grid) in cases {
            let p = chi_square_p(&l, &l, grid, 400_000);
            assert!(p > 1e-3, "{name}: p = {p}");
        }
    }

    /// Samples whose rows are chosen without sin θ are caught.
    #[test]
    fn the_chi_square_test_catches_a_wrong_sampler() {
        let mut wrong = lumpy();
        if let Radiance::Map { cells, .. } = &mut wrong.radiance {
            let h = cells.height;
            let sums: Vec<f64> = (0..h)
                .map(|y| {
                    let s = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
                    (cells.rows[y + 1] - cells.rows[y]) / s
                })
                .collect();
            running(&mut cells.rows, sums.into_iter());
        }
        let p = chi_square_p(&wrong, &lumpy(), (48, 24, 0.0), 400_000);
        assert!(p < 1e-6, "p = {p}");
    }

    #[test]
    fn a_sample_is_finite_and_its_radiance_is_eval_even_at_the_edges() {
        let edges = [0.0, 1e-7, 0.5, ONE_MINUS_EPSILON, 1.0, -0.5, 2.0, f32::NAN];
        let lights = [
            ("lumpy", lumpy()),
            ("hot", hot().rotated(200.0).scaled(3.0)),
            ("zenith", zenith()),
            (
                "bottom",
                map(8, 4, |_, y| Vec3::splat((y == 3) as u32 as f32)),
            ),
            ("black", map(8, 4, |_, _| Vec3::ZERO)),
            ("dimmed", hot().scaled(0.0)),
            ("constant", EnvLight::constant(Vec3::splat(0.5))),
        ];
        for (name, l) in &lights {
            for &a in &edges {
                for &b in &edges {
                    let s = l.sample(Vec2::new(a, b));
                    assert!(
                        s.dir.is_finite() && (s.dir.length() - 1.0).abs() < 1e-5,
                        "{name} {a} {b}: {s:?}"
                    );
                    assert!(s.radiance.is_finite() && s.pdf.is_finite() && s.pdf >= 0.0);
                    assert_eq!(s.radiance, l.eval(s.dir), "{name} {a} {b}");
                }
            }
            // Away from the edges, the pdf of the direction is the sample's.
            let mut rng = Rng::for_sample(9, 9, 9);
            let agree = (0..10_000)
                .filter(|_| {
                    let s = l.sample(rng.next_vec2());
                    assert_eq!(s.radiance, l.eval(s.dir), "{name}");
                    (l.pdf(s.dir) - s.pdf).abs() <= 1e-3 * s.pdf
                })
                .count();
            assert!(agree >= 9_990, "{name}: {agree}");
        }
        // A light that gives none is never sampled.
        for (_, l) in &lights[4..6] {
            let s = l.sample(Vec2::new(0.3, 0.6));
            assert_eq!((s.radiance, s.pdf), (Vec3::ZERO, 0.0));
            assert_eq!(l.pdf(Vec3::X), 0.0);
        }
        assert_eq!(lights[6].1.sample(Vec2::splat(0.2)).pdf, UNIFORM_PDF);
        assert_eq!(lights[6].1.eval(Vec3::NEG_Y), Vec3::splat(0.5));
    }

    /// Wherever the bilinear lookup gives light, sampling can find it.
    #[test]
    fn the_pdf_is_positive_wherever_there_is_light() {
        let l = map(16, 8, |x, y| Vec3::splat(((x, y) == (7, 3)) as u32 as f32));
        let mut lit = 0;
        for i in 0..400 {
            for j in 0..800 {
                let d = polar(
                    (i as f64 + 0.5) / 400.0 * std::f64::consts::PI,
                    j as f64 / 800.0 * std::f64::consts::TAU,
                );
                if l.eval(d) != Vec3::ZERO {
                    lit += 1;
                    assert!(l.pdf(d) > 0.0, "{d}");
                }
            }
        }
        assert!(lit > 1000, "{lit}");
    }

    /// A map black but for a block of 5x5 texels centred on `(u, v)`.
    fn spot(u: f32, v: f32) -> EnvLight {
        let (cx, cy) = ((u * 64.0) as i32, (v * 32.0) as i32);
        map(64, 32, |x, y| {
            let dx = (x as i32 - cx).rem_euclid(64);
            let near = dx.min(64 - dx) <= 2 && (y as i32 - cy).abs() <= 2;
            Vec3::splat(near as u32 as f32)
        })
    }

    #[test]
    fn the_centre_column_looks_along_x_and_u_turns_toward_z() {
        let around = [Vec3::X, Vec3::NEG_Z, Vec3::Z, Vec3::NEG_X];
        for (u, seen) in [
            (0.5, Vec3::X),
            (0.25, Vec3::NEG_Z),
            (0.75, Vec3::Z),
            (0.0, Vec3::NEG_X),
        ] {
            let l = spot(u, 0.5);
            for d in around {
                assert_eq!(
                    l.eval(d) == Vec3::ONE,
                    d == seen,
                    "spot at u {u}, looking along {d}"
                );
            }
            let du = (l.map_uv(seen).unwrap().x - u).rem_euclid(1.0);
            assert!(du.min(1.0 - du) < 1e-6, "{u}: {du}");
        }
        // The top row looks up, the bottom row down.
        assert_eq!(spot(0.5, 0.0).eval(Vec3::Y), Vec3::ONE);
        assert_eq!(spot(0.5, 0.0).eval(Vec3::NEG_Y), Vec3::ZERO);
        assert_eq!(spot(0.5, 1.0).eval(Vec3::NEG_Y), Vec3::ONE);
    }

    #[test]
    fn rotation_turns_the_map_about_y() {
        let l = spot(0.5, 0.5).rotated(90.0);
        assert_eq!(l.eval(Vec3::NEG_Z), Vec3::ONE);
        assert_eq!(l.eval(Vec3::X), Vec3::ZERO);
        assert_eq!(l.rotation(), 90.0);
        // Its samples go where it now is.
        let mut rng = Rng::for_sample(4, 4, 4);
        let mean = (0..1000).fold(Vec3::ZERO, |m, _| m + l.sample(rng.next_vec2()).dir) / 1000.0;
        assert!(mean.dot(Vec3::NEG_Z) > 0.9, "{mean}");
    }
}
