//! From the coordinates of the files to the ones the renderer uses.
//!
//! Files are read in f64 and placed (scaled, rotated, translated) in f64;
//! only then are positions rounded to the f32 the renderer stores. Before
//! rounding, a scene far from the origin for its size is moved next to it
//! (f32 positions out there are coarse: 1/16 apart at 1e6, 2 apart at 1e7),
//! and a scene too large or too small for f32 arithmetic is scaled by a
//! power of two. Both are exact or nearly so in f64, so the f32 scene keeps the
//! precision its file had; each says so in a warning.

use glam::{DVec3, Vec3};

use super::show::{show, show3};

/// A scene whose centre is farther from the origin than this many times its
/// size is moved next to the origin.
pub(crate) const FAR: f64 = 1024.0;

/// A scene larger than this across (2^40, about 1.1e12) is scaled down: the
/// triangle test multiplies three coordinates together, and beyond about
/// 7e12 that product overflows f32.
pub(crate) const HUGE: f64 = (1u64 << 40) as f64;

/// A scene smaller than this across (2^-40, about 9.1e-13) is scaled up:
/// products of three coordinates would fall below the smallest normal f32.
pub(crate) const TINY: f64 = 1.0 / HUGE;

/// The map from file coordinates to render coordinates:
/// `(p - shift) * scale`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rebase {
    pub(crate) shift: DVec3,
    /// A power of two.
    pub(crate) scale: f64,
}

impl Default for Rebase {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// The shift that moves a scene spanning `min..max` next to the origin when
/// it lies far from it for its size (see [`FAR`]): its centre, on the axes
/// where the centre is farther out than the size; `None` for a near scene.
pub(crate) fn far_shift(min: DVec3, max: DVec3) -> Option<DVec3> {
    let c = (min + max) * 0.5;
    let size = (max - min).max_element();
    if !c.is_finite() || !size.is_finite() || c.abs().max_element() <= FAR * size {
        return None;
    }
    Some(DVec3::select(
        c.abs().cmpgt(DVec3::splat(size)),
        c,
        DVec3::ZERO,
    ))
}

/// The warning for a scene moved by `shift`: where it was and how coarse
/// f32 positions are out there.
pub(crate) fn far_warning(shift: DVec3, min: DVec3, max: DVec3) -> String {
    let c = (min + max) * 0.5;
    let size = (max - min).max_element();
    let far = c.abs().max_element() as f32;
    let spacing = far.next_up() - far;
    format!(
        "the scene lies around {}, far from the origin for its size {}: \
         f32 positions there are {} apart; moved next to the origin for rendering \
         (coordinates shown are relative to that point)",
        show3(shift),
        show(size),
        show(spacing as f64)
    )
}

impl Rebase {
    pub const IDENTITY: Rebase = Rebase {
        shift: DVec3::ZERO,
        scale: 1.0,
    };

    /// The frame for a scene whose geometry spans `min..max`, and the
    /// warnings that say what it does; the identity for an empty or near,
    /// not huge scene.
    pub(crate) fn fit(min: DVec3, max: DVec3) -> (Rebase, Vec<String>) {
        let mut frame = Rebase::IDENTITY;
        let mut warnings = Vec::new();
        if !(min.is_finite() && max.is_finite()) || min.cmpgt(max).any() {
            return (frame, warnings);
        }
        if let Some(shift) = far_shift(min, max) {
            frame.shift = shift;
            warnings.push(far_warning(shift, min, max));
        }
        let size = (max - min).max_element();
        if size > HUGE || (size > 0.0 && size < TINY) {
            // To between 1 and 2 across: exact, a power of two.
            let k = size.log2().floor() as i32;
            frame.scale = 2f64.powi(-k);
            let why = if size > HUGE {
                format!("beyond {HUGE:.1e} the triangle test's f32 arithmetic overflows")
            } else {
                format!("below {TINY:.1e} the triangle test's f32 arithmetic underflows")
            };
            warnings.push(format!(
                "the scene is {} across: {why}; scaled by 2^{} for rendering \
                 (coordinates shown are scaled alike)",
                show(size),
                -k
            ));
        }
        (frame, warnings)
    }

    pub(crate) fn point(&self, p: DVec3) -> Vec3 {
        ((p - self.shift) * self.scale).as_vec3()
    }

    pub(crate) fn vector(&self, v: DVec3) -> Vec3 {
        (v * self.scale).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_scenes_stay_far_ones_move() {
        let (f, w) = Rebase::fit(DVec3::splat(-1.0), DVec3::splat(1.0));
        assert_eq!(f, Rebase::IDENTITY);
        assert!(w.is_empty());
        let off = DVec3::new(2e7, 0.5, -3e7);
        let (f, w) = Rebase::fit(off - 1.0, off + 1.0);
        assert_eq!(f.shift, DVec3::new(2e7, 0.0, -3e7));
        assert_eq!(f.scale, 1.0);
        assert_eq!(w.len(), 1);
        assert!(w[0].contains("far from the origin"), "{w:?}");
        // Exact in f64: a vertex 0.1 off the centre stays 0.1 off.
        assert_eq!(f.point(off + DVec3::X * 0.1).x, 0.1f64 as f32);
    }

    #[test]
    fn huge_scenes_are_scaled_by_a_power_of_two() {
        let (f, w) = Rebase::fit(DVec3::splat(-1e20), DVec3::splat(1e20));
        assert!(f.scale < 1.0 && f.scale.log2().fract() == 0.0);
        assert!((f.vector(DVec3::splat(2e20)).x as f64) < 2.0);
        assert!(w[0].contains("scaled by 2^-67"), "{w:?}");
        let (f, _) = Rebase::fit(DVec3::ZERO, DVec3::splat(1e12));
        assert_eq!(f.scale, 1.0);
        let (f, w) = Rebase::fit(DVec3::ZERO, DVec3::splat(1e-30));
        assert_eq!(f.scale, 2f64.powi(100));
        assert!(w[0].contains("underflows; scaled by 2^100"), "{w:?}");
        let (f, _) = Rebase::fit(DVec3::ZERO, DVec3::splat(1e-6));
        assert_eq!(f.scale, 1.0);
    }

    #[test]
    fn empty_and_non_finite_bounds_are_left_alone() {
        let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        assert_eq!(Rebase::fit(empty.0, empty.1).0, Rebase::IDENTITY);
        assert!(far_shift(DVec3::splat(f64::NAN), DVec3::ONE).is_none());
    }
}
