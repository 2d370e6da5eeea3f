//! Phong materials as read from MTL.

use glam::Vec3;

/// Shininess at and above which a reflective material is a perfect mirror;
/// below it, with glossy reflection on, reflections are sampled from the
/// Phong lobe of exponent `ns`.
pub const GLOSSY_MAX_NS: f32 = 1000.0;

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kd: Vec3,
    pub ks: Vec3,
    pub ns: f32,
    /// Opacity (MTL `d`): the rest of the light passes straight through.
    pub dissolve: f32,
    pub texture: Option<u32>,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            kd: Vec3::splat(0.8),
            ks: Vec3::ZERO,
            ns: 10.0,
            dissolve: 1.0,
            texture: None,
        }
    }
}

impl Material {
    pub fn reflective(&self) -> bool {
        self.ks.max_element() > 0.0
    }

    pub fn glossy(&self) -> bool {
        self.reflective() && self.ns < GLOSSY_MAX_NS
    }
}
