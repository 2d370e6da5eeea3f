//! The scene's emissive triangles as lights: chosen in proportion to their
//! power (area times the brightest channel of their material's emission),
//! then a point uniformly on the one chosen. The density of a point per
//! unit area is then its material's emission over the total, whatever
//! the triangle, which is what a path that hits an emitter by chance
//! needs to weigh itself against light sampling.

use glam::{Vec2, Vec3};

use super::Scene;

/// Emissive triangles and their cumulative power.
#[derive(Clone, Debug, Default)]
pub(crate) struct Emitters {
    prims: Vec<u32>,
    /// Cumulative power, ending at `total`.
    cdf: Vec<f64>,
    total: f64,
}

/// A point drawn on an emitter.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EmitterPoint {
    pub(crate) prim: u32,
    /// Barycentric `(u, v)` of the point, as a hit gives them.
    pub(crate) uv: Vec2,
    pub(crate) point: Vec3,
}

/// The weight an emissive material gives its triangles.
fn strength(scene: &Scene, material: u32) -> f64 {
    scene.materials[material as usize]
        .pbr
        .as_ref()
        .map_or(0.0, |p| p.emissive.max_element().max(0.0) as f64)
}

impl Emitters {
    /// The emissive triangles of `scene`.
    pub(crate) fn of(scene: &Scene) -> Self {
        let geo = &scene.geometry;
        let mut out = Emitters::default();
        if !scene.materials.iter().any(|m| m.emissive()) {
            return out;
        }
        for (prim, idx) in geo.indices.iter().enumerate() {
            let s = strength(scene, geo.tri_material[prim]);
            if s <= 0.0 {
                continue;
            }
            let [a, b, c] = idx.map(|i| geo.positions[i as usize].as_dvec3());
            let area = 0.5 * (b - a).cross(c - a).length();
            let power = area * s;
            if power > 0.0 && power.is_finite() {
                out.total += power;
                out.prims.push(prim as u32);
                out.cdf.push(out.total);
            }
        }
        out
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }

    /// A point on an emitter, from `pick` (which triangle) and `u` (where
    /// on it), with its density per unit area; `None` when nothing emits.
    pub(crate) fn sample(&self, scene: &Scene, pick: f32, u: Vec2) -> Option<(EmitterPoint, f32)> {
        let target = pick as f64 * self.total;
        let i = self
            .cdf
            .partition_point(|&c| c <= target)
            .min(self.prims.len().checked_sub(1)?);
        let prim = self.prims[i];
        // Uniform on the triangle (the square root warp).
        let su = u.x.sqrt();
        let (b1, b2) = (1.0 - su, u.y * su);
        let geo = &scene.geometry;
        let [a, b, c] = geo.indices[prim as usize].map(|i| geo.positions[i as usize]);
        let point = a * (1.0 - b1 - b2) + b * b1 + c * b2;
        let pdf = self.pdf_area(scene, prim);
        (pdf > 0.0).then_some((
            EmitterPoint {
                prim,
                uv: Vec2::new(b1, b2),
                point,
            },
            pdf,
        ))
    }

    /// The density per unit area with which [`Emitters::sample`] draws a
    /// point of triangle `prim`.
    pub(crate) fn pdf_area(&self, scene: &Scene, prim: u32) -> f32 {
        if self.total <= 0.0 {
            return 0.0;
        }
        let m = scene.geometry.tri_material[prim as usize];
        (strength(scene, m) / self.total) as f32
    }
}
