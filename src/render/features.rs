//! User-facing feature toggles, with the names the CLI (`--no NAME`) and the
//! TUI use.

use serde::Serialize;

use crate::choice::Choice;

/// A feature; [`Choice::choice`] says what each is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Feature {
    Shadows,
    Reflections,
    SmoothNormals,
    Textures,
    Bilinear,
    SoftShadows,
    Supersampling,
    Glossy,
    Environment,
    Bloom,
    Bvh,
    NormalMaps,
    Emission,
    Indirect,
    Alpha,
    Regularize,
}

impl Choice for Feature {
    const ALL: &'static [Self] = &Feature::ALL;

    fn choice(self) -> (&'static str, &'static str) {
        let help = match self {
            Feature::Shadows => "Shadow rays toward every light",
            Feature::Reflections => "Mirror reflection for materials with ks > 0",
            Feature::SmoothNormals => "Barycentric interpolation of vertex normals",
            Feature::Textures => "Texture lookups for map_Kd",
            Feature::Bilinear => "Bilinear texture filtering (nearest otherwise)",
            Feature::SoftShadows => {
                "Sampling over the area of segment and parallelogram lights (their centre otherwise)"
            }
            Feature::Supersampling => "Jittered sub-pixel positions",
            Feature::Glossy => {
                "Reflections sampled from the Phong lobe for materials with Ns below the glossy threshold"
            }
            Feature::Environment => {
                "The cube map or environment light for rays that leave the scene"
            }
            Feature::Bloom => "Glow around bright pixels",
            Feature::Bvh => "The BVH (brute force over every triangle otherwise)",
            Feature::NormalMaps => "Normal maps of metallic-roughness materials",
            Feature::Emission => "Light emitted by materials",
            Feature::Indirect => {
                "Light arriving after bounces off other surfaces (path tracing; direct light only when off)"
            }
            Feature::Alpha => {
                "Cut-outs and see-through surfaces of glTF alpha (MASK, BLEND), for every ray"
            }
            Feature::Regularize => {
                "Smooth reflections made rougher after a diffuse bounce (path tracing): caustics blur instead of sparkling"
            }
        };
        (self.name(), help)
    }
}

impl Feature {
    pub(crate) const ALL: [Feature; 16] = [
        Feature::Shadows,
        Feature::Reflections,
        Feature::SmoothNormals,
        Feature::Textures,
        Feature::Bilinear,
        Feature::SoftShadows,
        Feature::Supersampling,
        Feature::Glossy,
        Feature::Environment,
        Feature::Bloom,
        Feature::Bvh,
        Feature::NormalMaps,
        Feature::Emission,
        Feature::Indirect,
        Feature::Alpha,
        Feature::Regularize,
    ];

    pub(crate) fn name(self) -> &'static str {
        match self {
            Feature::Shadows => "shadows",
            Feature::Reflections => "reflections",
            Feature::SmoothNormals => "smooth-normals",
            Feature::Textures => "textures",
            Feature::Bilinear => "bilinear",
            Feature::SoftShadows => "soft-shadows",
            Feature::Supersampling => "supersampling",
            Feature::Glossy => "glossy",
            Feature::Environment => "environment",
            Feature::Bloom => "bloom",
            Feature::Bvh => "bvh",
            Feature::NormalMaps => "normal-maps",
            Feature::Emission => "emission",
            Feature::Indirect => "indirect",
            Feature::Alpha => "alpha",
            Feature::Regularize => "regularize",
        }
    }

    fn bit(self) -> u16 {
        1 << self as u16
    }
}

/// A set of enabled features.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features(u16);

impl Default for Features {
    fn default() -> Self {
        Self::all()
    }
}

impl Features {
    pub fn all() -> Self {
        Features(Feature::ALL.iter().fold(0, |a, f| a | f.bit()))
    }

    pub fn without(mut self, off: &[Feature]) -> Self {
        for f in off {
            self.set(*f, false);
        }
        self
    }

    pub(crate) fn on(self, f: Feature) -> bool {
        self.0 & f.bit() != 0
    }

    pub(crate) fn set(&mut self, f: Feature, on: bool) {
        if on {
            self.0 |= f.bit();
        } else {
            self.0 &= !f.bit();
        }
    }

    pub(crate) fn toggle(&mut self, f: Feature) {
        self.0 ^= f.bit();
    }
}
