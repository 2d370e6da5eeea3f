//! Numbers as messages show them: plain near 1, in exponent form far
//! from it.

/// A number as messages show it: plain near 1, in exponent form when very
/// large or small (`1e45`, not forty-five digits).
pub(crate) fn show(x: f64) -> String {
    let plain = x == 0.0 || (1e-4..1e15).contains(&x.abs());
    let f = x as f32;
    if x == 0.0 || (f32::MIN_POSITIVE as f64..=f32::MAX as f64).contains(&x.abs()) {
        // The shortest form that reads back as the same f32.
        return if plain {
            format!("{f}")
        } else {
            format!("{f:e}")
        };
    }
    let s = format!("{x:.6e}");
    match s.split_once('e') {
        Some((m, e)) if m.contains('.') => {
            format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => s,
    }
}

/// A point as messages show it.
pub(crate) fn show3(p: glam::DVec3) -> String {
    format!("({}, {}, {})", show(p.x), show(p.y), show(p.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_show_briefly() {
        assert_eq!(show(0.5), "0.5");
        assert_eq!(show(-3.0), "-3");
        assert_eq!(show(1e45), "1e45");
        assert_eq!(show(1e-45), "1e-45");
        assert_eq!(show(1.0 / 1e-45), "1e45");
        assert_eq!(show(0.1 + 0.2), "0.3");
        assert_eq!(show(1e-300), "1e-300");
        assert_eq!(show3(glam::DVec3::new(1.0, 0.0, 2e20)), "(1, 0, 2e20)");
    }
}
