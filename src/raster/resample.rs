//! A reference image taken onto a view of another size, so a progressive
//! render at terminal resolution can be compared with a reference rendered
//! at any size from the same camera.
//!
//! Both images see the same vertical field of view; a different aspect ratio
//! only widens or narrows the horizontal one. Each view pixel covering part
//! of the reference gets the area-weighted mean of the reference pixels
//! under it: the box-filtered pixel integral the film estimates, exactly so
//! when the reference's size is a whole multiple of the view's.

use glam::Vec3;

/// The reference on the view's pixel grid.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Resampled {
    /// `(view pixel index, reference value)` for each view pixel wholly
    /// inside the reference's field of view.
    pub(crate) pixels: Vec<(u32, Vec3)>,
    /// The share of the view's pixels in `pixels`.
    pub(crate) coverage: f64,
    /// Every compared view pixel is a whole block of reference pixels.
    pub(crate) exact: bool,
}

/// Overlaps of the view interval `[a, b)` (in reference pixels) with each
/// reference pixel: `(index, weight)`.
fn weights(a: f64, b: f64) -> Vec<(usize, f64)> {
    let first = a.floor() as usize;
    let last = (b.ceil() as usize).max(first + 1);
    (first..last)
        .map(|k| (k, b.min(k as f64 + 1.0) - a.max(k as f64)))
        .filter(|&(_, w)| w > 1e-9)
        .collect()
}

/// Tolerance for a view pixel edge to count as on the reference's border.
const EDGE: f64 = 1e-6;

/// Takes `reference` (`rw` x `rh`, row-major from the top) onto a `vw` x
/// `vh` view of the same camera.
/// Its pixels are `pixel_aspect` times as wide as they are tall (1 but in
/// the TUI's block symbols).
pub(crate) fn resample(
    rw: u32,
    rh: u32,
    reference: &[Vec3],
    vw: u32,
    vh: u32,
    pixel_aspect: f64,
) -> Resampled {
    let none = Resampled {
        pixels: Vec::new(),
        coverage: 0.0,
        exact: false,
    };
    if rw == 0 || rh == 0 || vw == 0 || vh == 0 || reference.len() != (rw * rh) as usize {
        return none;
    }
    let (ar, av) = (rw as f64 / rh as f64, vw as f64 / vh as f64 * pixel_aspect);
    // View column `i` spans screen x in [(2i/vw - 1) av, ...]; in reference
    // pixels that is (sx / ar + 1) rw / 2.
    let to_ref_x = |i: f64| ((2.0 * i / vw as f64 - 1.0) * av / ar + 1.0) * 0.5 * rw as f64;
    let to_ref_y = |j: f64| j * rh as f64 / vh as f64;
    let columns: Vec<Option<Vec<(usize, f64)>>> = (0..vw)
        .map(|i| {
            let (a, b) = (to_ref_x(i as f64), to_ref_x(i as f64 + 1.0));
            (a >= -EDGE && b <= rw as f64 + EDGE).then(|| weights(a.max(0.0), b.min(rw as f64)))
        })
        .collect();
    let rows: Vec<Vec<(usize, f64)>> = (0..vh)
        .map(|j| weights(to_ref_y(j as f64), to_ref_y(j as f64 + 1.0).min(rh as f64)))
        .collect();
    let whole = |w: &[(usize, f64)]| w.iter().all(|&(_, x)| (x - 1.0).abs() < 1e-9);
    let mut exact = rows.iter().all(|r| whole(r));
    let mut pixels = Vec::new();
    for (j, row) in rows.iter().enumerate() {
        for (i, col) in columns.iter().enumerate() {
            let Some(col) = col else { continue };
            exact &= whole(col);
            let (mut sum, mut total) = (glam::DVec3::ZERO, 0.0);
            for &(l, wy) in row {
                for &(k, wx) in col {
                    let w = wx * wy;
                    sum += reference[l * rw as usize + k].as_dvec3() * w;
                    total += w;
                }
            }
            pixels.push(((j * vw as usize + i) as u32, (sum / total).as_vec3()));
        }
    }
    Resampled {
        coverage: pixels.len() as f64 / (vw as f64 * vh as f64),
        exact: exact && !pixels.is_empty(),
        pixels,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(w: u32, h: u32) -> Vec<Vec3> {
        (0..w * h)
            .map(|i| Vec3::new((i % w) as f32, (i / w) as f32, 1.0))
            .collect()
    }

    #[test]
    fn the_same_size_is_the_identity() {
        let img = ramp(7, 5);
        let r = resample(7, 5, &img, 7, 5, 1.0);
        assert!(r.exact && r.coverage == 1.0);
        let back: Vec<Vec3> = r.pixels.iter().map(|p| p.1).collect();
        assert_eq!(back, img);
    }

    #[test]
    fn a_whole_multiple_averages_blocks_exactly() {
        let img = ramp(8, 6);
        let r = resample(8, 6, &img, 4, 3, 1.0);
        assert!(r.exact && r.coverage == 1.0);
        // View pixel (1, 2) is reference pixels x 2..4, y 4..6.
        let (i, v) = r.pixels[2 * 4 + 1];
        assert_eq!(i, 9);
        assert_eq!(v, Vec3::new(2.5, 4.5, 1.0));
    }

    #[test]
    fn a_fractional_size_weights_by_area() {
        // Three reference columns onto two view columns: 1.5 each (rows
        // alike, so only the columns' weights show).
        let row = [Vec3::ONE, Vec3::splat(2.0), Vec3::splat(4.0)];
        let img: Vec<Vec3> = (0..3).flat_map(|_| row).collect();
        let r = resample(3, 3, &img, 2, 2, 1.0);
        assert_eq!(r.coverage, 1.0);
        assert!(!r.exact);
        assert!((r.pixels[0].1.x - (1.0 + 0.5 * 2.0) / 1.5).abs() < 1e-6);
        assert!((r.pixels[1].1.x - (0.5 * 2.0 + 4.0) / 1.5).abs() < 1e-6);
    }

    #[test]
    fn a_wider_view_compares_only_the_columns_the_reference_sees() {
        // The view (aspect 2) is twice as wide as the reference (aspect 1):
        // its middle half sees the reference, one reference pixel per view
        // pixel.
        let img = ramp(4, 4);
        let r = resample(4, 4, &img, 8, 4, 1.0);
        assert!(r.exact);
        assert_eq!(r.coverage, 0.5);
        let cols: Vec<u32> = r.pixels.iter().filter(|p| p.0 < 8).map(|p| p.0).collect();
        assert_eq!(cols, vec![2, 3, 4, 5]);
        assert_eq!(r.pixels[0].1, img[0]);
        // A narrower view sits inside the reference's middle columns.
        let r = resample(8, 4, &ramp(8, 4), 4, 4, 1.0);
        assert!(r.exact && r.coverage == 1.0);
        assert_eq!(r.pixels[0].1.x, 2.0);
        // Pixels twice as wide as tall: 4x4 of them see all of it.
        let r = resample(8, 4, &ramp(8, 4), 4, 4, 2.0);
        assert!(r.exact && r.coverage == 1.0);
        assert_eq!(r.pixels[0].1.x, 0.5);
    }

    #[test]
    fn a_reference_of_the_wrong_length_covers_nothing() {
        assert_eq!(resample(4, 4, &ramp(3, 3), 4, 4, 1.0).coverage, 0.0);
    }
}
