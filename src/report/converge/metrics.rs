//! Error measures on luminance, and straight lines in log-log space.

use glam::Vec3;

use crate::render::film::{LUMA, REL_EPS};

/// Luminance of a linear colour.
#[inline]
pub fn luminance(c: Vec3) -> f64 {
    c.as_dvec3().dot(LUMA.as_dvec3())
}

fn mean_over<F: Fn(f64, f64) -> f64>(img: &[Vec3], reference: &[Vec3], f: F) -> f64 {
    assert_eq!(
        img.len(),
        reference.len(),
        "image and reference differ in size"
    );
    if img.is_empty() {
        return 0.0;
    }
    let sum: f64 = img
        .iter()
        .zip(reference)
        .map(|(&x, &r)| f(luminance(x), luminance(r)))
        .sum();
    sum / img.len() as f64
}

/// Root mean squared error of the luminance. Panics when the sizes differ.
pub fn rmse(img: &[Vec3], reference: &[Vec3]) -> f64 {
    mean_over(img, reference, |x, r| (x - r) * (x - r)).sqrt()
}

/// Mean of `(x - ref)^2 / (ref^2 + 0.01)` over pixels, on luminance.
/// Panics when the sizes differ.
pub fn rel_mse(img: &[Vec3], reference: &[Vec3]) -> f64 {
    mean_over(img, reference, |x, r| (x - r) * (x - r) / (r * r + REL_EPS))
}

/// [`rel_mse`] over some pixels only: `(index into img, reference value)`
/// pairs, as [`super::Resampled`] gives them; 0 when there are none.
pub fn rel_mse_on(img: &[Vec3], pairs: &[(u32, Vec3)]) -> f64 {
    if pairs.is_empty() {
        return 0.0;
    }
    let sum: f64 = pairs
        .iter()
        .map(|&(i, r)| {
            let (x, r) = (luminance(img[i as usize]), luminance(r));
            (x - r) * (x - r) / (r * r + REL_EPS)
        })
        .sum();
    sum / pairs.len() as f64
}

/// Least-squares slope and intercept of `ln y` against `ln x` over the
/// positive pairs; `None` with fewer than two distinct `x`.
pub fn fit_log_log(xy: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = xy
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if pts.len() < 2 || sxx < 1e-12 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// `y` at `x` on the straight line through two points in log-log space.
pub(super) fn log_lerp(x: f64, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> f64 {
    if (x1 / x0).ln().abs() < 1e-12 {
        return y0;
    }
    let t = (x / x0).ln() / (x1 / x0).ln();
    (y0.ln() + t * (y1 / y0).ln()).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_log_fit_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0, 16.0]
            .iter()
            .map(|&x| (x, 3.0 * f64::powf(x, -0.5)))
            .collect();
        let (s, c) = fit_log_log(&pts).unwrap();
        assert!((s + 0.5).abs() < 1e-12 && (c - 3f64.ln()).abs() < 1e-12);
        assert_eq!(fit_log_log(&pts[..1]), None);
    }

    #[test]
    fn metrics_on_luminance() {
        let r = vec![Vec3::splat(0.5), Vec3::ZERO];
        let x = vec![Vec3::splat(0.6), Vec3::splat(0.1)];
        assert!((rmse(&x, &r) - 0.1).abs() < 1e-6);
        let expected = (0.01 / 0.26 + 0.01 / 0.01) / 2.0;
        assert!((rel_mse(&x, &r) - expected).abs() < 1e-6);
        assert_eq!(rmse(&r, &r), 0.0);
    }
}
