//! Colour, written once: the sRGB transfer function both ways and Rec. 709
//! luminance, for the loaders, the renderer, the views and the terminal.

use glam::{DVec3, Vec3};

/// Rec. 709 luminance weights.
pub const LUMA: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// The same weights as f64 literals, not [`LUMA`] widened (which differs
/// in the last bits): what an environment map's sampling weighs texels by.
pub(crate) const LUMA_F64: DVec3 = DVec3::new(0.2126, 0.7152, 0.0722);

/// Luminance of a linear colour, in f64 (of [`LUMA`]'s weights).
#[inline]
pub fn luminance(c: Vec3) -> f64 {
    c.as_dvec3().dot(LUMA.as_dvec3())
}

/// The sRGB transfer function, decoded to linear.
#[inline]
pub(crate) fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// A linear value to 8-bit sRGB, clamped (what is not finite is black).
#[inline]
pub(crate) fn encode_srgb(x: f32) -> u8 {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// A linear colour to 8-bit sRGB.
pub(crate) fn srgb(c: Vec3) -> [u8; 3] {
    [encode_srgb(c.x), encode_srgb(c.y), encode_srgb(c.z)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_endpoints() {
        assert_eq!(encode_srgb(0.0), 0);
        assert_eq!(encode_srgb(1.0), 255);
        assert_eq!(encode_srgb(2.0), 255);
        assert_eq!(encode_srgb(f32::NAN), 0);
        assert_eq!(encode_srgb(0.214_041_14), 128);
    }

    #[test]
    fn decoding_inverts_encoding_on_every_level() {
        for v in 0..=255u8 {
            assert_eq!(encode_srgb(srgb_to_linear(v as f32 / 255.0)), v);
        }
    }

    #[test]
    fn the_weights_sum_to_one() {
        assert!((LUMA.x + LUMA.y + LUMA.z - 1.0).abs() < 1e-6);
        assert_eq!(luminance(Vec3::ONE), LUMA.as_dvec3().element_sum());
    }
}
