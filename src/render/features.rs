//! User-facing feature toggles, with the names the CLI (`--no NAME`) and the
//! TUI use.

use serde::Serialize;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum Feature {
    /// Shadow rays toward every light.
    Shadows,
    /// Mirror reflection for materials with ks > 0.
    Reflections,
    /// Barycentric interpolation of vertex normals.
    SmoothNormals,
    /// Texture lookups for map_Kd.
    Textures,
    /// Bilinear texture filtering (nearest otherwise).
    Bilinear,
    /// Sampling over the area of segment and parallelogram lights (their centre otherwise).
    SoftShadows,
    /// Jittered sub-pixel positions.
    Supersampling,
    /// Reflections sampled from the Phong lobe for materials with Ns below the glossy threshold.
    Glossy,
    /// The cube map or environment light for rays that leave the scene.
    Environment,
    /// Glow around bright pixels.
    Bloom,
    /// The BVH (brute force over every triangle otherwise).
    Bvh,
    /// Normal maps of metallic-roughness materials.
    NormalMaps,
    /// Light emitted by materials.
    Emission,
    /// Light arriving after bounces off other surfaces (path tracing;
    /// direct light only when off).
    Indirect,
}

impl Feature {
    pub const ALL: [Feature; 14] = [
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
    ];

    pub fn name(self) -> &'static str {
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

    pub fn none() -> Self {
        Features(0)
    }

    pub fn without(mut self, off: &[Feature]) -> Self {
        for f in off {
            self.set(*f, false);
        }
        self
    }

    pub fn on(self, f: Feature) -> bool {
        self.0 & f.bit() != 0
    }

    pub fn set(&mut self, f: Feature, on: bool) {
        if on {
            self.0 |= f.bit();
        } else {
            self.0 &= !f.bit();
        }
    }

    pub fn toggle(&mut self, f: Feature) {
        self.0 ^= f.bit();
    }
}
