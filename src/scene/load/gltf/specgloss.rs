//! `KHR_materials_pbrSpecularGlossiness`, converted to metallic-roughness
//! as the Khronos group's converter does it (the glTF-Sample-Viewer's and
//! Babylon.js's `convertSpecularGlossinessToMetallicRoughness`, which
//! glTF-Transform's `metalRough` also follows): roughness is 1 -
//! glossiness; metalness solves the quadratic that makes a dielectric
//! (F0 0.04) mixed with a metal reflect the specular colour's perceived
//! brightness; the base colour blends the diffuse colour (less the light
//! the specular took) with the specular colour by metalness squared.

use glam::Vec3;

/// A dielectric's reflectance at normal incidence, as the converter has it.
const DIELECTRIC: f32 = 0.04;

/// Perceived brightness, as the converter weighs colours.
fn brightness(c: Vec3) -> f32 {
    (0.299 * c.x * c.x + 0.587 * c.y * c.y + 0.114 * c.z * c.z).sqrt()
}

/// The metalness whose mix of a dielectric and a metal gives `specular`
/// brightness beside `diffuse`.
fn metallic(diffuse: f32, specular: f32, one_minus_specular: f32) -> f32 {
    if specular < DIELECTRIC {
        return 0.0;
    }
    let a = DIELECTRIC;
    let b = diffuse * one_minus_specular / (1.0 - DIELECTRIC) + specular - 2.0 * DIELECTRIC;
    let c = DIELECTRIC - specular;
    let d = (b * b - 4.0 * a * c).max(0.0);
    ((-b + d.sqrt()) / (2.0 * a)).clamp(0.0, 1.0)
}

/// Metallic-roughness (base colour, metallic, roughness) of a diffuse
/// colour, a specular colour and a glossiness, all linear.
pub(super) fn convert(diffuse: Vec3, specular: Vec3, glossiness: f32) -> (Vec3, f32, f32) {
    let one_minus = 1.0 - specular.max_element();
    let m = metallic(brightness(diffuse), brightness(specular), one_minus);
    let from_diffuse = diffuse * (one_minus / (1.0 - DIELECTRIC) / (1.0 - m).max(1e-4));
    let from_specular = (specular - Vec3::splat(DIELECTRIC * (1.0 - m))) / m.max(1e-4);
    let base = from_diffuse
        .lerp(from_specular, m * m)
        .clamp(Vec3::ZERO, Vec3::ONE);
    (base, m, (1.0 - glossiness).clamp(0.0, 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectrics_keep_their_colour_and_metals_take_the_specular() {
        // A plastic: specular 0.04 grey is no metal; its diffuse colour is
        // the base colour, glossiness 0.3 a roughness of 0.7.
        let (base, m, r) = convert(Vec3::new(0.5, 0.2, 0.1), Vec3::splat(0.04), 0.3);
        assert_eq!(m, 0.0);
        assert!((r - 0.7).abs() < 1e-6);
        assert!(
            (base - Vec3::new(0.5, 0.2, 0.1)).abs().max_element() < 1e-6,
            "{base}"
        );
        // Gold as specular-glossiness writes it: no diffuse, the specular
        // its colour. Fully metallic, its base colour the specular's.
        let gold = Vec3::new(1.0, 0.766, 0.336);
        let (base, m, r) = convert(Vec3::ZERO, gold, 1.0);
        assert!(m > 0.99, "{m}");
        assert!((base - gold).abs().max_element() < 0.02, "{base}");
        assert_eq!(r, 0.0);
        // Below the dielectric's reflectance: no metal either.
        assert_eq!(convert(Vec3::ONE, Vec3::splat(0.01), 1.0).1, 0.0);
    }
}
