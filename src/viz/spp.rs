//! Samples per pixel, in place of the picture: where adaptive sampling
//! spent them.

use glam::Vec3;

use super::draw::Legend;
use super::heat::scale_color;
use crate::render::Film;

/// Each pixel's samples, on a log scale from the fewest (dark blue) to the
/// most (yellow), and the legend with the fewest, mean and most.
pub(crate) fn spp_view(film: &Film) -> (Vec<Vec3>, Legend) {
    let (min, mean, max) = film.spp_range();
    let span = (max.max(1) as f64 / min.max(1) as f64).log2();
    let image = (0..film.pixels_len())
        .map(|i| {
            let n = film.pixel_spp(i).max(1) as f64;
            scale_color(if span > 0.0 {
                (n / min.max(1) as f64).log2() / span
            } else {
                0.0
            })
        })
        .collect();
    let legend = if min == max {
        vec![(None, format!("samples per pixel: every pixel {min}"))]
    } else {
        vec![
            (
                Some(scale_color(0.0)),
                format!("samples per pixel: dark blue {min}"),
            ),
            (Some(scale_color(1.0)), format!("yellow {max} (log scale)")),
            (None, format!("mean {mean:.1}")),
        ]
    };
    (image, legend)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viz::draw::legend_line;

    /// The map colours by the film's own counts: the fewest and most
    /// samples at the ends of the scale.
    #[test]
    fn the_map_shows_counts() {
        let mut f = Film::new_adaptive(3, 1);
        for k in 0..16 {
            f.add(0, 0, k, None, Vec3::ONE);
        }
        for k in 0..64 {
            f.add(1, 0, k, None, Vec3::ONE);
        }
        f.add(2, 0, 0, None, Vec3::ONE);
        let (img, legend) = spp_view(&f);
        assert_eq!(img[1], scale_color(1.0));
        assert_eq!(img[2], scale_color(0.0));
        assert!(img[0] != img[1] && img[0] != img[2]);
        let text = legend_line(&legend);
        assert!(
            text.contains("dark blue 1") && text.contains("yellow 64"),
            "{text}"
        );
    }
}
