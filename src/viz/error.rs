//! Estimated relative error per pixel, in place of the picture: where the
//! image is still noisy.

use glam::Vec3;

use super::draw::Legend;
use super::heat::scale_color;
use crate::render::Film;

/// The smallest and largest estimated relative errors the error map
/// tells apart (0.1 % and 10 %).
const ERROR_SCALE: (f64, f64) = (1e-3, 1e-1);

/// Each pixel's estimated relative error (its standard error over
/// `√(lum² + 0.01)`, as the film's estimate counts it) on a log scale from
/// 0.1 % or less (dark blue) to 10 % or more (yellow), grey where unknown
/// (below two samples); and the legend.
pub(crate) fn error_view(film: &Film) -> (Vec<Vec3>, Legend) {
    let (lo, hi) = ERROR_SCALE;
    let image: Vec<Vec3> = film
        .pixels()
        .iter()
        .map(|p| match p.relative_error() {
            Some(e) => scale_color((e.max(lo) / lo).log10() / (hi / lo).log10()),
            None => UNKNOWN,
        })
        .collect();
    let mut legend = vec![
        (
            Some(scale_color(0.0)),
            "estimated relative error per pixel: dark blue 0.1 % or less".into(),
        ),
        (Some(scale_color(0.5)), "teal 1 %".into()),
        (
            Some(scale_color(1.0)),
            "yellow 10 % or more (log scale)".into(),
        ),
    ];
    if film.pixels().iter().any(|p| p.n < 2) {
        legend.push((Some(UNKNOWN), "grey unknown (below 2 samples)".into()));
    }
    (image, legend)
}

/// Pixels of the error map whose error is unknown.
const UNKNOWN: Vec3 = Vec3::splat(0.2);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viz::draw::legend_line;

    /// The map colours by the film's own errors: none at the scale's dark
    /// end, 1 % at its middle, grey below two samples.
    #[test]
    fn the_map_shows_errors() {
        let mut f = Film::new_adaptive(3, 1);
        // Pixel 0: 16 equal samples (no error); 1: 64 alternating 0.9 and
        // 1.1 (error 0.1 / √64 over √1.01); 2: one sample.
        for k in 0..16 {
            f.add(0, 0, k, None, Vec3::ONE);
        }
        for k in 0..64 {
            let v = if k % 2 == 0 { 0.9 } else { 1.1 };
            f.add(1, 0, k, None, Vec3::splat(v));
        }
        f.add(2, 0, 0, None, Vec3::ONE);
        let (img, legend) = error_view(&f);
        assert_eq!(img[0], scale_color(0.0));
        assert_eq!(img[2], UNKNOWN);
        let e = f.pixels()[1].relative_error().unwrap();
        let want = 0.1 * (64.0f64 / 63.0).sqrt() / 8.0 / 1.01f64.sqrt();
        assert!((e - want).abs() < 1e-6, "{e} against {want}");
        let t = (e / 1e-3).log10() / 2.0;
        assert_eq!(img[1], scale_color(t));
        assert!(legend_line(&legend).contains("grey unknown"));
    }
}
