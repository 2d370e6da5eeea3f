//! Point, segment and parallelogram lights. Area lights carry a colour per
//! end or corner, interpolated over the light.

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
}

impl Light {
    pub fn kind(&self) -> &'static str {
        match self {
            Light::Point { .. } => "point",
            Light::Segment { .. } => "segment",
            Light::Parallelogram { .. } => "parallelogram",
        }
    }

    pub fn is_area(&self) -> bool {
        !matches!(self, Light::Point { .. })
    }

    /// Position and colour at parameter `s` in [0,1]^2 (segments use `s.x`).
    /// Always inlined: returned through memory, a point light's position
    /// was stored in an 8-byte and a 4-byte move and read back across both,
    /// a load the store buffer cannot forward.
    #[inline(always)]
    pub fn point_at(&self, s: Vec2) -> (Vec3, Vec3) {
        match self {
            Light::Point { position, color } => (*position, *color),
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

    pub fn transform(&mut self, scale: f32, offset: Vec3) {
        let f = |p: &mut Vec3| *p = *p * scale + offset;
        match self {
            Light::Point { position, .. } => f(position),
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
