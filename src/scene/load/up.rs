//! Which way is up in a mesh file. rayterm's world is Y-up, as OBJ, PLY
//! and glTF files mostly are; STL files come from 3D printing and CAD,
//! which are Z-up, and would lie on their side. A file's up axis is turned
//! to +Y as it is placed, before anything else.

use std::fmt;
use std::str::FromStr;

use glam::{DAffine3, DMat3, DVec3};

/// A mesh file's up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Up {
    X,
    Y,
    Z,
    NegX,
    NegY,
    NegZ,
}

/// The axes `--up` and a `[[mesh]]`'s `up` take, as messages list them.
pub(crate) const UP_AXES: &str = "x, y, z, -x, -y or -z";

impl FromStr for Up {
    type Err = String;

    fn from_str(s: &str) -> Result<Up, String> {
        let t = s.trim().to_ascii_lowercase();
        Ok(match t.strip_prefix('+').unwrap_or(&t) {
            "x" => Up::X,
            "y" => Up::Y,
            "z" => Up::Z,
            "-x" => Up::NegX,
            "-y" => Up::NegY,
            "-z" => Up::NegZ,
            _ => {
                return Err(format!(
                    "{} is not an axis: up is one of {UP_AXES}",
                    crate::words::quoted(s)
                ))
            }
        })
    }
}

impl fmt::Display for Up {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Up::X => "x",
            Up::Y => "y",
            Up::Z => "z",
            Up::NegX => "-x",
            Up::NegY => "-y",
            Up::NegZ => "-z",
        })
    }
}

impl Up {
    /// The rotation that turns this axis to +Y: a quarter turn about X (for
    /// ±Z: Z-up `(x, y, z)` becomes `(x, z, -y)`, as Blender converts) or
    /// about Z (for ±X), a half turn about X for -Y; exact, as each entry
    /// is 0 or ±1.
    pub(crate) fn to_y(self) -> DAffine3 {
        let cols = |x: [f64; 3], y: [f64; 3], z: [f64; 3]| {
            DAffine3::from_mat3(DMat3::from_cols(
                DVec3::from(x),
                DVec3::from(y),
                DVec3::from(z),
            ))
        };
        match self {
            Up::Y => DAffine3::IDENTITY,
            Up::Z => cols([1., 0., 0.], [0., 0., -1.], [0., 1., 0.]),
            Up::NegZ => cols([1., 0., 0.], [0., 0., 1.], [0., -1., 0.]),
            Up::X => cols([0., 1., 0.], [-1., 0., 0.], [0., 0., 1.]),
            Up::NegX => cols([0., -1., 0.], [1., 0., 0.], [0., 0., 1.]),
            Up::NegY => cols([1., 0., 0.], [0., -1., 0.], [0., 0., -1.]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_axis_turns_to_y_by_a_rotation() {
        let axes = [
            (Up::X, DVec3::X),
            (Up::Y, DVec3::Y),
            (Up::Z, DVec3::Z),
            (Up::NegX, -DVec3::X),
            (Up::NegY, -DVec3::Y),
            (Up::NegZ, -DVec3::Z),
        ];
        for (up, axis) in axes {
            let r = up.to_y();
            assert_eq!(r.transform_vector3(axis), DVec3::Y, "{up}");
            // A rotation: no mirror, no scale.
            assert_eq!(r.matrix3.determinant(), 1.0, "{up}");
            assert_eq!(r.matrix3 * r.matrix3.transpose(), DMat3::IDENTITY, "{up}");
            assert_eq!(up.to_string().parse::<Up>(), Ok(up));
        }
        // A Z-up file's front view looks along +Y, rayterm's along -Z: the
        // front stays the front.
        assert_eq!(Up::Z.to_y().transform_vector3(DVec3::Y), -DVec3::Z);
        assert_eq!("+Z".parse::<Up>(), Ok(Up::Z));
        assert!("up"
            .parse::<Up>()
            .unwrap_err()
            .contains("x, y, z, -x, -y or -z"));
    }
}
