//! The progressive film: per-pixel running mean and variance (Welford, f64),
//! from which each pixel knows its standard error. Non-finite samples are
//! never averaged in; they are counted and their first occurrences kept.

use glam::{DVec3, Vec3};

/// Rec. 709 luminance weights.
pub const LUMA: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// How many non-finite samples are listed individually.
const MAX_LISTED: usize = 1000;

#[derive(Clone, Copy, Debug, Default)]
pub struct PixelStats {
    pub mean: DVec3,
    /// Sum of squared deviations of the luminance (Welford's M2).
    pub m2: f64,
    pub n: u32,
}

impl PixelStats {
    #[inline]
    pub fn add(&mut self, c: Vec3) {
        let c = c.as_dvec3();
        self.n += 1;
        let n = self.n as f64;
        let lum_old = self.mean.dot(LUMA.as_dvec3());
        self.mean += (c - self.mean) / n;
        let lum = c.dot(LUMA.as_dvec3());
        self.m2 += (lum - lum_old) * (lum - self.mean.dot(LUMA.as_dvec3()));
    }

    /// Sample variance of the luminance.
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// Standard error of the mean luminance.
    pub fn std_error(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            (self.variance() / self.n as f64).sqrt()
        }
    }
}

/// A sample that was NaN or infinite.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct BadSample {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
}

#[derive(Clone, Debug)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<PixelStats>,
    /// Samples per pixel attempted so far (the next pass starts at this index).
    pub spp: u32,
    pub bad_count: u64,
    pub bad: Vec<BadSample>,
}

/// Offset in relative errors (`x^2 + REL_EPS` below the squared error) so
/// black pixels do not dominate them.
pub const REL_EPS: f64 = 0.01;

impl Film {
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            pixels: vec![PixelStats::default(); width as usize * height as usize],
            spp: 0,
            bad_count: 0,
            bad: Vec::new(),
        }
    }

    /// Adds one sample, or records it as bad when not finite.
    pub fn add(&mut self, x: u32, y: u32, sample: u32, c: Vec3) {
        if c.is_finite() {
            self.pixels[(y * self.width + x) as usize].add(c);
        } else {
            self.record_bad(BadSample { x, y, sample });
        }
    }

    pub fn record_bad(&mut self, b: BadSample) {
        self.bad_count += 1;
        if self.bad.len() < MAX_LISTED {
            self.bad.push(b);
        }
    }

    pub fn mean(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize].mean.as_vec3()
    }

    /// Linear mean image, row-major.
    pub fn image(&self) -> Vec<Vec3> {
        self.pixels.iter().map(|p| p.mean.as_vec3()).collect()
    }

    /// The film's estimate of its relMSE: the mean over pixels of the squared
    /// standard error of the mean luminance over `lum^2 + REL_EPS`. Pixels
    /// with fewer than two samples count as exact.
    pub fn estimated_rel_mse(&self) -> f64 {
        if self.pixels.is_empty() {
            return 0.0;
        }
        let sum: f64 = self
            .pixels
            .iter()
            .map(|p| {
                let lum = p.mean.dot(LUMA.as_dvec3());
                p.std_error().powi(2) / (lum * lum + REL_EPS)
            })
            .sum();
        sum / self.pixels.len() as f64
    }

    /// The relative error shown everywhere (TUI, `--target-error`,
    /// `converge`): the square root of [`Film::estimated_rel_mse`]; 0 for a
    /// deterministic image after one pass.
    pub fn relative_error(&self) -> f64 {
        self.estimated_rel_mse().sqrt()
    }
}

/// What makes a pixel the worst of a film.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Worst {
    /// The first pixel with a NaN or infinite sample.
    Nan,
    /// The pixel whose samples vary most.
    Variance,
    /// The brightest pixel.
    Brightest,
}

/// A pixel and the sample of it worth replaying.
pub type PixelSample = (u32, u32, u32);

/// The worst pixel of a film by each measure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WorstPixels {
    pub nan: Option<PixelSample>,
    pub variance: Option<PixelSample>,
    pub brightest: Option<PixelSample>,
}

impl WorstPixels {
    pub fn get(&self, w: Worst) -> Option<PixelSample> {
        match w {
            Worst::Nan => self.nan,
            Worst::Variance => self.variance,
            Worst::Brightest => self.brightest,
        }
    }
}

impl Film {
    /// The worst pixel by `w`, with the sample to replay: the first NaN/Inf
    /// sample; the pixel of highest variance (none while no pixel varies);
    /// the brightest pixel (none on an empty film).
    pub fn worst(&self, w: Worst) -> Option<PixelSample> {
        let at = |i: usize| (i as u32 % self.width, i as u32 / self.width, 0);
        let lum = |p: &PixelStats| p.mean.dot(LUMA.as_dvec3());
        let top = |key: &dyn Fn(&PixelStats) -> f64| {
            self.pixels
                .iter()
                .enumerate()
                .map(|(i, p)| (i, key(p)))
                .filter(|(_, v)| v.is_finite())
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        match w {
            Worst::Nan => self.bad.first().map(|b| (b.x, b.y, b.sample)),
            Worst::Variance => top(&PixelStats::variance)
                .filter(|(_, v)| *v > 0.0)
                .map(|(i, _)| at(i)),
            Worst::Brightest => top(&lum).map(|(i, _)| at(i)),
        }
    }

    pub fn worst_pixels(&self) -> WorstPixels {
        WorstPixels {
            nan: self.worst(Worst::Nan),
            variance: self.worst(Worst::Variance),
            brightest: self.worst(Worst::Brightest),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn welford_matches_two_pass() {
        let xs = [0.1f32, 0.5, 0.25, 0.9, 0.3];
        let mut p = PixelStats::default();
        for x in xs {
            p.add(Vec3::splat(x));
        }
        let m: f64 = xs.iter().map(|&x| x as f64).sum::<f64>() / 5.0;
        let v: f64 = xs.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / 4.0;
        assert!((p.mean.x - m).abs() < 1e-12);
        // Luminance of a grey is the grey (weights sum to 1 up to f32 rounding).
        assert!((p.variance() - v).abs() < 1e-6, "{} vs {v}", p.variance());
    }

    #[test]
    fn worst_pixels_by_each_measure() {
        let mut f = Film::new(3, 1);
        assert_eq!(f.worst(Worst::Variance), None);
        f.add(0, 0, 0, Vec3::ONE);
        f.add(1, 0, 0, Vec3::splat(0.2));
        f.add(1, 0, 1, Vec3::splat(0.4));
        f.add(2, 0, 0, Vec3::splat(0.5));
        f.add(2, 0, 1, Vec3::NAN);
        assert_eq!(
            f.worst_pixels(),
            WorstPixels {
                nan: Some((2, 0, 1)),
                variance: Some((1, 0, 0)),
                brightest: Some((0, 0, 0)),
            }
        );
    }

    #[test]
    fn bad_samples_are_not_averaged() {
        let mut f = Film::new(2, 1);
        f.add(0, 0, 0, Vec3::ONE);
        f.add(0, 0, 1, Vec3::NAN);
        f.add(1, 0, 0, Vec3::INFINITY);
        assert_eq!(f.mean(0, 0), Vec3::ONE);
        assert_eq!(f.bad_count, 2);
        assert_eq!(
            f.bad[1],
            BadSample {
                x: 1,
                y: 0,
                sample: 0
            }
        );
    }
}
