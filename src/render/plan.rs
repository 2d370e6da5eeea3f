//! The scene plan: from the scene and the feature toggles, which stages run
//! and why. Stages a scene cannot use are left out of the hot loop.

use serde::Serialize;

use super::{Feature, Features};
use crate::scene::{Environment, Scene};

/// One line of `--explain`: a stage, whether it runs, and why.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Stage {
    pub stage: &'static str,
    pub on: bool,
    pub reason: String,
}

#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    pub features: Features,
    pub shadows: bool,
    pub reflections: bool,
    pub specular: bool,
    pub glossy: bool,
    pub textures: bool,
    pub bilinear: bool,
    pub smooth_normals: bool,
    pub area_sampling: bool,
    pub supersampling: bool,
    pub environment: bool,
    pub bloom: bool,
    pub bvh: bool,
    /// Nothing is sampled: one pass gives the exact image.
    pub deterministic: bool,
    pub stages: Vec<Stage>,
}

impl serde::Serialize for Features {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(
            Feature::ALL
                .iter()
                .filter(|f| self.on(**f))
                .map(|f| f.name()),
        )
    }
}

/// What the scene needs of one feature: `None` when it can use it, or the
/// reason it cannot.
pub fn not_needed(scene: &Scene, f: Feature) -> Option<&'static str> {
    let any_reflective = scene.materials.iter().any(|m| m.reflective());
    let any_area = scene.lights.iter().any(|l| l.is_area());
    match f {
        Feature::Shadows if scene.lights.is_empty() => Some("no lights in scene"),
        Feature::Reflections if !any_reflective => Some("no material with ks > 0"),
        Feature::Glossy if !scene.materials.iter().any(|m| m.glossy()) => {
            Some("no glossy material (ks > 0 and Ns < 1000)")
        }
        Feature::Textures | Feature::Bilinear if !scene.has_textures() => {
            Some("no textures in scene")
        }
        Feature::SmoothNormals if !scene.has_vertex_normals() => Some("no vertex normals in scene"),
        Feature::SoftShadows if !any_area => Some("point lights only"),
        Feature::Environment if !matches!(scene.environment, Environment::CubeMap(_)) => {
            Some("no environment map in scene")
        }
        _ => None,
    }
}

impl Plan {
    /// The plan for `scene` with `features` enabled.
    pub fn new(scene: &Scene, features: Features) -> Self {
        Self::make(scene, features, true)
    }

    /// Every enabled stage runs whether the scene needs it or not (`--no-plan`),
    /// for measuring what the plan saves.
    pub fn everything(scene: &Scene, features: Features) -> Self {
        Self::make(scene, features, false)
    }

    fn make(scene: &Scene, features: Features, prune: bool) -> Self {
        let mut stages = Vec::new();
        let mut stage = |name: &'static str, f: Feature, extra: Option<&'static str>| -> bool {
            let (on, reason) = if !features.on(f) {
                (false, "off".to_string())
            } else if let Some(why) = extra {
                (false, format!("off: needs {why}"))
            } else if let Some(why) = not_needed(scene, f).filter(|_| prune) {
                (false, format!("not needed: {why}"))
            } else {
                (true, "on".to_string())
            };
            stages.push(Stage {
                stage: name,
                on,
                reason,
            });
            on
        };
        let shadows = stage("shadow rays", Feature::Shadows, None);
        let reflections = stage("reflection rays", Feature::Reflections, None);
        let glossy = stage(
            "glossy sampling",
            Feature::Glossy,
            (!reflections).then_some("reflections"),
        );
        let textures = stage(
            "UV interpolation and texture lookups",
            Feature::Textures,
            None,
        );
        let bilinear = stage(
            "bilinear filtering",
            Feature::Bilinear,
            (!textures).then_some("textures"),
        );
        let smooth_normals = stage("normal interpolation", Feature::SmoothNormals, None);
        let area_sampling = stage("area light sampling", Feature::SoftShadows, None);
        let supersampling = stage("jittered supersampling", Feature::Supersampling, None);
        let environment = stage("environment lookups", Feature::Environment, None);
        let bloom = stage("bloom", Feature::Bloom, None);
        let bvh = stage("BVH traversal", Feature::Bvh, None);
        let any_ks = scene.materials.iter().any(|m| m.reflective());
        let specular = !prune || any_ks;
        stages.push(Stage {
            stage: "specular term",
            on: specular,
            reason: if specular {
                "on"
            } else {
                "not needed: no material with ks > 0"
            }
            .into(),
        });
        let any_area = scene.lights.iter().any(|l| l.is_area());
        let deterministic = !(supersampling || glossy || (area_sampling && any_area));
        stages.push(Stage {
            stage: "progressive passes",
            on: !deterministic,
            reason: if deterministic {
                "not needed: nothing is sampled, one pass is exact".into()
            } else {
                "on".into()
            },
        });
        Plan {
            features,
            shadows,
            reflections,
            specular,
            glossy,
            textures,
            bilinear,
            smooth_normals,
            area_sampling,
            supersampling,
            environment,
            bloom,
            bvh,
            deterministic,
            stages,
        }
    }

    /// The plan as a table for `--explain`.
    pub fn explain(&self) -> String {
        let w = self.stages.iter().map(|s| s.stage.len()).max().unwrap_or(0);
        self.stages
            .iter()
            .map(|s| {
                format!(
                    "  {:w$}  {:3}  {}\n",
                    s.stage,
                    if s.on { "on" } else { "off" },
                    s.reason
                )
            })
            .collect()
    }
}
