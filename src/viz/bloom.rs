//! What bloom does, in place of the picture: the pixels over its threshold
//! and the glow they spread, with the threshold and the kernel.

use glam::Vec3;

use super::draw::Legend;
use crate::color::LUMA;
use crate::render::post;
use crate::scene::BloomSettings;

/// Pixels over bloom's threshold in the bloom view.
pub const BRIGHT: Vec3 = Vec3::new(0.0, 1.0, 1.0);
/// The glow bloom spreads, at its brightest, in the bloom view.
pub const GLOW: Vec3 = Vec3::new(1.0, 0.45, 0.0);

/// What bloom does to `before` (an image before bloom): the pixels over the
/// threshold in cyan and the glow they spread in orange (brighter where it
/// adds more), over the image dimmed; and the legend with the threshold and
/// the kernel.
pub fn bloom_view(
    before: &[Vec3],
    width: u32,
    height: u32,
    s: &BloomSettings,
) -> (Vec<Vec3>, Legend) {
    let dim = |c: &Vec3| Vec3::splat(c.dot(LUMA).clamp(0.0, 1.0) * 0.25);
    let mut image: Vec<Vec3> = before.iter().map(dim).collect();
    let kernel = format!(
        "Gaussian sigma {} px, kernel {}x{} px, strength {}",
        s.sigma,
        2 * s.radius + 1,
        2 * s.radius + 1,
        s.strength
    );
    let Some(g) = post::glow(before, width as usize, height as usize, s) else {
        let legend = vec![
            (
                None,
                format!(
                    "no pixel is over the threshold (luminance > {})",
                    s.threshold
                ),
            ),
            (None, kernel),
        ];
        return (image, legend);
    };
    let most = g.glow.iter().map(|c| c.dot(LUMA)).fold(0.0f32, f32::max);
    for (px, glow) in image.iter_mut().zip(&g.glow) {
        let t = (glow.dot(LUMA) / most).clamp(0.0, 1.0);
        if t > 0.0 {
            *px = px.lerp(GLOW, t.sqrt());
        }
    }
    let mut bright = 0u32;
    for (px, b) in image.iter_mut().zip(&g.bright) {
        if *b != Vec3::ZERO {
            *px = BRIGHT;
            bright += 1;
        }
    }
    let legend = vec![
        (
            Some(BRIGHT),
            format!(
                "cyan: {} over the threshold (luminance > {})",
                crate::words::count(bright, "pixel", "pixels"),
                s.threshold
            ),
        ),
        (
            Some(GLOW),
            format!("orange: their glow, up to +{most:.3} luminance"),
        ),
        (None, kernel),
    ];
    (image, legend)
}
