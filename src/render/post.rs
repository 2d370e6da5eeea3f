//! Post-processing of the linear mean image: bloom and tone mapping. Every
//! image shown or saved goes through [`display`].

use glam::Vec3;

use super::Plan;
use crate::color::{encode_srgb, LUMA};
use crate::scene::BloomSettings;

/// A film's mean as it is shown: after bloom when the plan runs it.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Displayed {
    /// Linear colours after post-processing, row-major.
    pub(crate) image: Vec<Vec3>,
    /// The mean before bloom, when bloom ran.
    pub(crate) before_bloom: Option<Vec<Vec3>>,
}

/// The one post-processing step from a film's mean image to what is shown
/// (the TUI), saved (PNG) or inspected.
pub(crate) fn display(
    mean: Vec<Vec3>,
    width: u32,
    height: u32,
    plan: &Plan,
    s: &BloomSettings,
) -> Displayed {
    display_with(mean, width, height, plan.bloom.then_some(s))
}

/// [`display`] with bloom's settings when it runs (what a merge of partial
/// films knows instead of the plan).
fn display_with(
    mean: Vec<Vec3>,
    width: u32,
    height: u32,
    bloom_with: Option<&BloomSettings>,
) -> Displayed {
    let Some(s) = bloom_with else {
        return Displayed {
            image: mean,
            before_bloom: None,
        };
    };
    let mut image = mean.clone();
    bloom(&mut image, width as usize, height as usize, s);
    Displayed {
        image,
        before_bloom: Some(mean),
    }
}

/// Adds a glow around pixels brighter than the threshold: the bright part is
/// blurred with a separable Gaussian and added back with `strength`.
/// Returns whether anything was over the threshold (nothing changes otherwise).
pub(crate) fn bloom(img: &mut [Vec3], width: usize, height: usize, s: &BloomSettings) -> bool {
    let Some(g) = glow(img, width, height, s) else {
        return false;
    };
    for (c, g) in img.iter_mut().zip(g.glow) {
        *c += g;
    }
    true
}

/// What bloom does to an image: the pixels over the threshold (their
/// colour, zero elsewhere) and the glow it adds (strength applied).
pub(crate) struct Glow {
    pub(crate) bright: Vec<Vec3>,
    pub(crate) glow: Vec<Vec3>,
}

/// Bloom's parts for `img`, or `None` when nothing is over the threshold.
pub(crate) fn glow(img: &[Vec3], width: usize, height: usize, s: &BloomSettings) -> Option<Glow> {
    let bright: Vec<Vec3> = img
        .iter()
        .map(|c| {
            if c.dot(LUMA) > s.threshold {
                *c
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    if bright.iter().all(|c| *c == Vec3::ZERO) {
        return None;
    }
    let r = s.radius as i64;
    let kernel: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f32 / (2.0 * s.sigma * s.sigma)).exp())
        .collect();
    let norm: f32 = kernel.iter().sum();
    let kernel: Vec<f32> = kernel.iter().map(|k| k / norm).collect();
    let blur = |src: &[Vec3], dx: i64, dy: i64| -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; src.len()];
        for y in 0..height as i64 {
            for x in 0..width as i64 {
                let mut acc = Vec3::ZERO;
                for (k, w) in kernel.iter().enumerate() {
                    let o = k as i64 - r;
                    let sx = (x + o * dx).clamp(0, width as i64 - 1);
                    let sy = (y + o * dy).clamp(0, height as i64 - 1);
                    acc += src[(sy * width as i64 + sx) as usize] * *w;
                }
                out[(y * width as i64 + x) as usize] = acc;
            }
        }
        out
    };
    let glow = blur(&blur(&bright, 1, 0), 0, 1)
        .into_iter()
        .map(|g| g * s.strength)
        .collect();
    Some(Glow { bright, glow })
}

pub fn to_rgb8(img: &[Vec3], width: u32, height: u32) -> image::RgbImage {
    let mut out = image::RgbImage::new(width, height);
    for (p, c) in out.pixels_mut().zip(img) {
        *p = image::Rgb([encode_srgb(c.x), encode_srgb(c.y), encode_srgb(c.z)]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bloom_leaves_dim_images_unchanged() {
        let mut img: Vec<Vec3> = (0..64).map(|i| Vec3::splat(i as f32 / 100.0)).collect();
        let before = img.clone();
        assert!(!bloom(&mut img, 8, 8, &BloomSettings::default()));
        assert_eq!(img, before);
    }

    #[test]
    fn bloom_spreads_bright_pixels() {
        let mut img = vec![Vec3::ZERO; 81];
        img[40] = Vec3::splat(10.0);
        assert!(bloom(&mut img, 9, 9, &BloomSettings::default()));
        assert!(img[39].x > 0.0 && img[31].x > 0.0);
        assert!((img[39].x - img[41].x).abs() < 1e-6);
    }
}
