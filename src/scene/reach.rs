//! Whether a scene lies within the coordinates f32 shading can render.

use anyhow::{bail, Result};
use glam::Vec2;

use super::Scene;
use crate::geometry::MAX_COORDINATE;

/// An error naming what lies too far when a point of `scene` (a vertex,
/// the camera, a light) is beyond [`MAX_COORDINATE`] or not finite: f32
/// shading cannot render it, and would show a black image instead.
pub fn check_reach(scene: &Scene) -> Result<()> {
    let c = &scene.camera;
    let mut far: Vec<(String, f32)> = [("the camera", c.eye), ("the camera's target", c.target)]
        .into_iter()
        .map(|(what, p)| (what.to_string(), p.abs().max_element()))
        .collect();
    let b = scene.bounds();
    if !b.is_empty() {
        far.push((
            "the geometry".into(),
            b.min.abs().max(b.max.abs()).max_element(),
        ));
    }
    for (i, l) in scene.lights.iter().enumerate() {
        for s in [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE] {
            far.push((
                format!("light {}", i + 1),
                l.point_at(s).0.abs().max_element(),
            ));
        }
    }
    let beyond = |m: f32| m.partial_cmp(&MAX_COORDINATE).is_none_or(|o| o.is_gt());
    let Some((what, m)) = far.iter().find(|(_, m)| beyond(*m)) else {
        return Ok(());
    };
    let place = if m.is_finite() {
        format!("lies {m:e} from the origin")
    } else {
        "is beyond f32's range".into()
    };
    bail!(
        "{what} {place}: rayterm shades in f32, where the squared lengths of such \
         distances overflow; it renders coordinates up to {MAX_COORDINATE:e} (scale the \
         scene down)"
    )
}
