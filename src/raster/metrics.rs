//! Error measures on luminance: RMSE and relMSE of an image against a
//! reference, the measure the film's own error estimate follows.

use glam::Vec3;

use crate::color::luminance;

/// Offset in relative errors (`x^2 + REL_EPS` below the squared error) so
/// that black pixels do not dominate them.
pub const REL_EPS: f64 = 0.01;

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
/// pairs, as [`Resampled`](crate::raster::resample::Resampled) gives them; 0 when there are none.
pub(crate) fn rel_mse_on(img: &[Vec3], pairs: &[(u32, Vec3)]) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

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
