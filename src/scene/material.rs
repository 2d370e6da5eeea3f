//! Materials: Phong as read from MTL, and glTF's metallic-roughness model
//! beside it.

use glam::Vec3;

/// Shininess at and above which a reflective material is a perfect mirror;
/// below it, with glossy reflection on, reflections are sampled from the
/// Phong lobe of exponent `ns`.
pub(crate) const GLOSSY_MAX_NS: f32 = 1000.0;

/// Roughness below which a metallic-roughness material's specular lobe is
/// a mirror (GGX alpha under [`crate::render::brdf::MIRROR_ALPHA`]).
pub(crate) const MIRROR_ROUGHNESS: f32 = 0.0316;

#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// Diffuse colour; a metallic-roughness material's base colour.
    pub kd: Vec3,
    pub ks: Vec3,
    pub ns: f32,
    /// Opacity (MTL `d`): the rest of the light passes straight through.
    pub dissolve: f32,
    /// The texture of `kd` (of the base colour).
    pub texture: Option<u32>,
    /// Shaded by glTF's metallic-roughness BRDF rather than Phong, with
    /// lights in their physical units.
    pub pbr: Option<Pbr>,
    /// How much of the surface is there (glTF's `MASK` and `BLEND`): rays
    /// of every kind pass where it is not.
    pub alpha: Option<Alpha>,
    /// glTF's `KHR_materials_unlit`: the surface shows its base colour
    /// (texture and vertex colours included), lit by nothing.
    pub unlit: bool,
}

/// glTF alpha: the base colour factor's alpha times its texture's, at a
/// hit; `MASK` keeps the surface where that reaches `cutoff`, `BLEND`
/// keeps it with that probability (stochastic transparency).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alpha {
    /// `MASK`'s cutoff; `None` for `BLEND`.
    pub cutoff: Option<f32>,
    pub factor: f32,
    /// The base colour image's alpha channel, linear, in every component.
    pub texture: Option<u32>,
}

/// glTF 2.0's metallic-roughness parameters and textures (texture indices
/// into the scene's textures).
#[derive(Clone, Debug, PartialEq)]
pub struct Pbr {
    pub metallic: f32,
    pub roughness: f32,
    /// Linear texels: blue scales `metallic`, green `roughness`.
    pub metallic_roughness: Option<u32>,
    /// Textures of one value each (linear, red channel), as MTL's `map_Pr`
    /// and `map_Pm` hold them: they scale `roughness` and `metallic`.
    pub roughness_texture: Option<u32>,
    pub metallic_texture: Option<u32>,
    /// Tangent-space normals (linear texels) and their scale.
    pub normal: Option<(u32, f32)>,
    /// Emitted radiance, strength included, before its texture.
    pub emissive: Vec3,
    pub emissive_texture: Option<u32>,
    /// Ambient occlusion (linear, red channel) and its strength: it
    /// darkens ambient and environment light only, as the glTF
    /// specification intends (direct light finds its own shadows).
    pub occlusion: Option<(u32, f32)>,
    /// A dielectric's reflectance at normal incidence: 0.04, or what
    /// `KHR_materials_ior` makes it, `((ior - 1) / (ior + 1))²`.
    pub dielectric_f0: f32,
    /// `KHR_materials_specular`: the dielectric's Fresnel term is scaled
    /// by `specular` (times its texture's alpha) and its reflectance at
    /// normal incidence tinted by `specular_color` (times its texture,
    /// sRGB), at most 1. 1 and white leave the glTF core's BRDF.
    pub specular: f32,
    pub specular_texture: Option<u32>,
    pub specular_color: Vec3,
    pub specular_color_texture: Option<u32>,
}

impl Default for Pbr {
    /// The specification's defaults: a fully metallic, fully rough
    /// material.
    fn default() -> Self {
        Self {
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness: None,
            roughness_texture: None,
            metallic_texture: None,
            normal: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            occlusion: None,
            dielectric_f0: 0.04,
            specular: 1.0,
            specular_texture: None,
            specular_color: Vec3::ONE,
            specular_color_texture: None,
        }
    }
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
            pbr: None,
            alpha: None,
            unlit: false,
        }
    }
}

impl Material {
    /// Whether it reflects the scene in a mirror or glossy lobe: a Phong
    /// material with ks, every metallic-roughness one (even a dielectric
    /// reflects at grazing angles).
    pub(crate) fn reflective(&self) -> bool {
        self.pbr.is_some() || self.ks.max_element() > 0.0
    }

    /// Whether its reflection is sampled from a lobe rather than a mirror.
    pub(crate) fn glossy(&self) -> bool {
        match &self.pbr {
            Some(p) => {
                p.roughness >= MIRROR_ROUGHNESS
                    || p.metallic_roughness.is_some()
                    || p.roughness_texture.is_some()
            }
            None => self.reflective() && self.ns < GLOSSY_MAX_NS,
        }
    }

    /// Whether it emits light.
    pub fn emissive(&self) -> bool {
        self.pbr
            .as_ref()
            .is_some_and(|p| p.emissive.max_element() > 0.0)
    }
}
