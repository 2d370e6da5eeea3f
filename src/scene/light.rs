//! Point, segment and parallelogram lights, whose colour a Phong surface
//! multiplies as it is (area lights carry one per end or corner,
//! interpolated over the light); and glTF's punctual lights in their
//! physical units.

use glam::{Vec2, Vec3};

#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        color: Vec3,
    },
    Segment {
        a: Vec3,
        b: Vec3,
        color_a: Vec3,
        color_b: Vec3,
    },
    /// Corner `p`, edges `e1`, `e2`; colours at `p`, `p+e1`, `p+e1+e2`, `p+e2`.
    Parallelogram {
        corner: Vec3,
        edge1: Vec3,
        edge2: Vec3,
        colors: [Vec3; 4],
    },
    /// A point or spot light of `intensity` candela per channel, falling
    /// off with the square of the distance and, with a `range`, to zero
    /// at it (`KHR_lights_punctual`'s recommended window).
    Photometric {
        position: Vec3,
        intensity: Vec3,
        range: Option<f32>,
        cone: Option<Cone>,
    },
    /// Parallel light travelling along `direction` (unit), of
    /// `illuminance` lux per channel on a surface facing it.
    Directional {
        direction: Vec3,
        illuminance: Vec3,
    },
}

/// A spot light's cone: full intensity inside `cos_inner`, none outside
/// `cos_outer`, the square of a linear ramp of the cosine between them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Where the spot points (unit).
    pub axis: Vec3,
    pub cos_inner: f32,
    pub cos_outer: f32,
}

impl Cone {
    /// The share of the intensity sent along `dir` (unit, from the light).
    pub(crate) fn falloff(&self, dir: Vec3) -> f32 {
        let scale = 1.0 / (self.cos_inner - self.cos_outer).max(1e-3);
        let t = ((dir.dot(self.axis) - self.cos_outer) * scale).clamp(0.0, 1.0);
        t * t
    }
}

/// Light arriving at a shading point from one point of a light (or from
/// a direction).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Arriving {
    /// The light's point, or, for a directional light, where the unit
    /// vector toward it points from the origin.
    pub(crate) from: From,
    /// Phong units (the colour a white Phong surface facing it shows) or,
    /// where `physical`, the illuminance in lux of a surface facing it.
    pub(crate) value: Vec3,
    pub(crate) physical: bool,
}

/// Where light comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum From {
    Point(Vec3),
    /// The unit direction toward a light at infinity.
    Direction(Vec3),
}

impl Light {
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Point { .. } => "point",
            Light::Segment { .. } => "segment",
            Light::Parallelogram { .. } => "parallelogram",
            Light::Photometric { cone: None, .. } => "point (cd)",
            Light::Photometric { .. } => "spot (cd)",
            Light::Directional { .. } => "directional (lux)",
        }
    }

    pub(crate) fn is_area(&self) -> bool {
        matches!(self, Light::Segment { .. } | Light::Parallelogram { .. })
    }

    /// The light reaching `p` from parameter `s` of the light (see
    /// [`Light::point_at`]); a photometric light's falls off with
    /// distance, range and cone.
    #[inline(always)]
    pub(crate) fn arriving(&self, p: Vec3, s: Vec2) -> Arriving {
        match self {
            Light::Photometric {
                position,
                intensity,
                range,
                cone,
            } => photometric(*position, *intensity, *range, cone.as_ref(), p),
            Light::Directional {
                direction,
                illuminance,
            } => Arriving {
                from: From::Direction(-*direction),
                value: *illuminance,
                physical: true,
            },
            _ => {
                let (lp, lc) = self.point_at(s);
                Arriving {
                    from: From::Point(lp),
                    value: lc,
                    physical: false,
                }
            }
        }
    }

    /// Position and colour at parameter `s` in `[0,1]^2` (segments use `s.x`).
    /// Always inlined: returned through memory, a point light's position
    /// was stored in an 8-byte and a 4-byte move and read back across both,
    /// a load the store buffer cannot forward.
    #[inline(always)]
    pub(crate) fn point_at(&self, s: Vec2) -> (Vec3, Vec3) {
        match self {
            Light::Point { position, color } => (*position, *color),
            Light::Photometric {
                position,
                intensity,
                ..
            } => (*position, *intensity),
            // Where the light comes from, a unit away from the origin.
            Light::Directional {
                direction,
                illuminance,
            } => (-*direction, *illuminance),
            Light::Segment {
                a,
                b,
                color_a,
                color_b,
            } => (a.lerp(*b, s.x), color_a.lerp(*color_b, s.x)),
            Light::Parallelogram {
                corner,
                edge1,
                edge2,
                colors,
            } => {
                let p = *corner + *edge1 * s.x + *edge2 * s.y;
                let bottom = colors[0].lerp(colors[1], s.x);
                let top = colors[3].lerp(colors[2], s.x);
                (p, bottom.lerp(top, s.y))
            }
        }
    }

    pub(crate) fn transform(&mut self, scale: f32, offset: Vec3) {
        let f = |p: &mut Vec3| *p = *p * scale + offset;
        match self {
            Light::Point { position, .. } => f(position),
            // The picture stays the same: the falloff over the scaled
            // distances is made up by the intensity; a range is a length.
            Light::Photometric {
                position,
                intensity,
                range,
                ..
            } => {
                f(position);
                *intensity *= scale * scale;
                if let Some(r) = range {
                    *r *= scale;
                }
            }
            Light::Directional { .. } => {}
            Light::Segment { a, b, .. } => {
                f(a);
                f(b);
            }
            Light::Parallelogram {
                corner,
                edge1,
                edge2,
                ..
            } => {
                f(corner);
                *edge1 *= scale;
                *edge2 *= scale;
            }
        }
    }
}

/// The light a photometric light sends to `p`. Never inlined: inlined,
/// its divisions and square root were computed for every light, Phong
/// lights too, whichever arm was taken (a fifth of a Phong render's time).
#[inline(never)]
fn photometric(
    position: Vec3,
    intensity: Vec3,
    range: Option<f32>,
    cone: Option<&Cone>,
    p: Vec3,
) -> Arriving {
    let d = position - p;
    let d2 = d.length_squared();
    let mut f = 1.0 / d2;
    if let Some(r) = range {
        let q = d2 / (r * r);
        f *= (1.0 - q * q).clamp(0.0, 1.0);
    }
    if let Some(c) = cone {
        f *= c.falloff(-d / d2.sqrt());
    }
    Arriving {
        from: From::Point(position),
        value: if f.is_finite() {
            intensity * f
        } else {
            Vec3::ZERO
        },
        physical: true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parallelogram_colours_interpolate_bilinearly() {
        let l = Light::Parallelogram {
            corner: Vec3::ZERO,
            edge1: Vec3::X,
            edge2: Vec3::Z,
            colors: [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
        };
        assert_eq!(l.point_at(Vec2::ZERO).1, Vec3::X);
        assert_eq!(l.point_at(Vec2::new(1.0, 0.0)).1, Vec3::Y);
        assert_eq!(l.point_at(Vec2::ONE).1, Vec3::Z);
        assert_eq!(l.point_at(Vec2::new(0.0, 1.0)).1, Vec3::ONE);
        let (p, c) = l.point_at(Vec2::splat(0.5));
        assert_eq!(p, Vec3::new(0.5, 0.0, 0.5));
        assert!((c - (Vec3::X + Vec3::Y + Vec3::Z + Vec3::ONE) / 4.0).length() < 1e-6);
    }
}
