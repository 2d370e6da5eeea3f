//! The scene plan: from the scene, the feature toggles and the policy, a
//! decision for every stage and the reason for it. Computed once per
//! (scene, features) by [`Plan::new`]; `--explain`, the TUI's Features panel,
//! the worker, exports and the inspector all read the same plan.

use serde::Serialize;

use super::integrator::MAX_PATHS;
use super::{Feature, Features};
use crate::scene::{Environment, Integrator, Projection, Scene};

/// Whether stages the scene cannot use are left out (`--no-plan` runs them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PlanPolicy {
    /// Leave out what cannot change the image.
    #[default]
    Prune,
    /// Run every enabled stage, for measuring what the plan saves.
    Everything,
}

/// Why a scene cannot use a feature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reason {
    NoLights,
    NoReflective,
    NoGlossy,
    NoTextures,
    NoVertexNormals,
    PointLightsOnly,
    NoEnvironment,
    NoNormalMaps,
    NoEmission,
    NoAlpha,
    Whitted,
}

impl Reason {
    pub(crate) fn long(self) -> &'static str {
        match self {
            Reason::NoLights => "no lights in scene",
            Reason::NoReflective => "no material with ks > 0",
            Reason::NoGlossy => "no glossy material (ks > 0 and Ns < 1000)",
            Reason::NoTextures => "no textures in scene",
            Reason::NoVertexNormals => "no vertex normals in scene",
            Reason::PointLightsOnly => "point lights only",
            Reason::NoEnvironment => "no environment map in scene",
            Reason::NoNormalMaps => "no normal maps in scene",
            Reason::NoEmission => "no emissive material in scene",
            Reason::NoAlpha => "no alpha-tested material in scene",
            Reason::Whitted => "the Whitted integrator runs",
        }
    }

    /// At most 13 characters, for narrow panels.
    pub(crate) fn short(self) -> &'static str {
        match self {
            Reason::NoLights => "no lights",
            Reason::NoReflective => "no ks > 0",
            Reason::NoGlossy => "no glossy",
            Reason::NoTextures => "no textures",
            Reason::NoVertexNormals => "no normals",
            Reason::PointLightsOnly => "point lights",
            Reason::NoEnvironment => "no env. map",
            Reason::NoNormalMaps => "no normal map",
            Reason::NoEmission => "no emission",
            Reason::NoAlpha => "no alpha",
            Reason::Whitted => "whitted",
        }
    }
}

/// What the plan decided for one feature's stage.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decision {
    On,
    /// Switched off by the user.
    Off,
    /// Enabled, but the scene has nothing it could change.
    NotNeeded(Reason),
    /// Enabled, but the feature it refines is not running.
    Needs(Feature),
}

impl Decision {
    pub fn runs(self) -> bool {
        self == Decision::On
    }

    /// `on`, `off`, `not needed: ...`, `off: needs ...`.
    pub(crate) fn reason(self) -> String {
        match self {
            Decision::On => "on".into(),
            Decision::Off => "off".into(),
            Decision::NotNeeded(why) => format!("not needed: {}", why.long()),
            Decision::Needs(f) => format!("off: needs {}", f.name()),
        }
    }
}

/// What the scene needs of one feature: `None` when it can use it, or the
/// reason it cannot.
pub(crate) fn not_needed(scene: &Scene, f: Feature) -> Option<Reason> {
    let any_reflective = scene.materials.iter().any(|m| m.reflective());
    let any_area = scene.lights.iter().any(|l| l.is_area());
    match f {
        Feature::Shadows
            if scene.lights.is_empty() && !matches!(scene.environment, Environment::Light(_)) =>
        {
            Some(Reason::NoLights)
        }
        Feature::Reflections if !any_reflective => Some(Reason::NoReflective),
        Feature::Glossy if !scene.materials.iter().any(|m| m.glossy()) => Some(Reason::NoGlossy),
        Feature::Textures | Feature::Bilinear if !scene.has_textures() => Some(Reason::NoTextures),
        Feature::SmoothNormals if !scene.has_vertex_normals() => Some(Reason::NoVertexNormals),
        Feature::SoftShadows if !any_area => Some(Reason::PointLightsOnly),
        Feature::Environment if matches!(scene.environment, Environment::Color(_)) => {
            Some(Reason::NoEnvironment)
        }
        Feature::NormalMaps
            if !scene
                .materials
                .iter()
                .any(|m| m.pbr.as_ref().is_some_and(|p| p.normal.is_some())) =>
        {
            Some(Reason::NoNormalMaps)
        }
        Feature::Emission if !scene.materials.iter().any(|m| m.emissive()) => {
            Some(Reason::NoEmission)
        }
        Feature::Indirect if integrator(scene).0 == Integrator::Whitted => Some(Reason::Whitted),
        Feature::Alpha if !scene.materials.iter().any(|m| m.alpha.is_some()) => {
            Some(Reason::NoAlpha)
        }
        Feature::Regularize if integrator(scene).0 == Integrator::Whitted => Some(Reason::Whitted),
        Feature::Regularize if !any_reflective => Some(Reason::NoReflective),
        _ => None,
    }
}

/// Why `f`'s stage runs when the plan keeps it: what in a scene needs it.
fn needed_for(f: Feature) -> &'static str {
    match f {
        Feature::Shadows => "the lights are tested for occluders",
        Feature::Reflections => "some material reflects (ks > 0 or metallic)",
        Feature::Glossy => "some material has a glossy (rough) reflection",
        Feature::Textures => "some material has a texture",
        Feature::Bilinear => "textures are read between their texels",
        Feature::SmoothNormals => "the meshes have vertex normals",
        Feature::SoftShadows => "area lights are sampled over their surface",
        Feature::Supersampling => "samples jittered across each pixel smooth its edges",
        Feature::Environment => "the environment is looked up for missed rays",
        Feature::Bloom => "light above 1 glows (the scene's bloom settings)",
        Feature::Bvh => "rays walk the tree instead of testing every triangle",
        Feature::NormalMaps => "some material has a normal map",
        Feature::Emission => "some material emits light",
        Feature::Indirect => "paths bounce",
        Feature::Alpha => "some material is cut out or blended by alpha",
        Feature::Regularize => {
            "paths that bounced off a diffuse surface see smooth reflections rougher"
        }
    }
}

/// The stage each feature controls, as `--explain` names it.
fn stage_name(f: Feature) -> &'static str {
    match f {
        Feature::Shadows => "shadow rays",
        Feature::Reflections => "reflection rays",
        Feature::Glossy => "glossy sampling",
        Feature::Textures => "UV interpolation and texture lookups",
        Feature::Bilinear => "bilinear filtering",
        Feature::SmoothNormals => "normal interpolation",
        Feature::SoftShadows => "area light sampling",
        Feature::Supersampling => "jittered supersampling",
        Feature::Environment => "environment lookups",
        Feature::Bloom => "bloom",
        Feature::Bvh => "BVH traversal",
        Feature::NormalMaps => "normal maps",
        Feature::Emission => "emission",
        Feature::Indirect => "path tracing (indirect light)",
        Feature::Alpha => "alpha tests (cut-outs, blending)",
        Feature::Regularize => "path regularization",
    }
}

/// Stages in the order `--explain` lists them; a refinement comes after the
/// feature it needs.
const ORDER: [Feature; 16] = [
    Feature::Indirect,
    Feature::Regularize,
    Feature::Shadows,
    Feature::Reflections,
    Feature::Glossy,
    Feature::Textures,
    Feature::Bilinear,
    Feature::NormalMaps,
    Feature::Emission,
    Feature::Alpha,
    Feature::SmoothNormals,
    Feature::SoftShadows,
    Feature::Supersampling,
    Feature::Environment,
    Feature::Bloom,
    Feature::Bvh,
];

/// The integrator `scene` is rendered with, and why.
pub(crate) fn integrator(scene: &Scene) -> (Integrator, &'static str) {
    match scene.settings.integrator {
        Some(Integrator::Path) => (Integrator::Path, "asked for"),
        Some(Integrator::Whitted) => (Integrator::Whitted, "the Whitted integrator was asked for"),
        None if scene.materials.iter().any(|m| m.pbr.is_some()) => (
            Integrator::Path,
            "metallic-roughness materials (--integrator whitted for direct light only)",
        ),
        None => (
            Integrator::Whitted,
            "Phong materials only, made for Whitted's model (--integrator path traces paths)",
        ),
    }
}

/// The feature a refinement needs to be running.
fn refines(f: Feature) -> Option<Feature> {
    match f {
        Feature::Glossy => Some(Feature::Reflections),
        Feature::Bilinear | Feature::NormalMaps => Some(Feature::Textures),
        Feature::Regularize => Some(Feature::Indirect),
        _ => None,
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub(crate) features: Features,
    pub(crate) policy: PlanPolicy,
    decisions: [Decision; Feature::ALL.len()],
    /// Stages that run only because the policy runs every enabled one.
    unplanned: [bool; Feature::ALL.len()],
    // What the hot loop reads: one flag per stage, copied from `decisions`.
    pub shadows: bool,
    pub reflections: bool,
    /// The specular term of the lights (some material has `ks > 0`).
    pub specular: bool,
    pub glossy: bool,
    pub textures: bool,
    pub bilinear: bool,
    pub smooth_normals: bool,
    pub area_sampling: bool,
    pub supersampling: bool,
    pub environment: bool,
    pub(crate) bloom: bool,
    pub bvh: bool,
    pub(crate) normal_maps: bool,
    pub(crate) emission: bool,
    /// Rays pass the parts of alpha-tested surfaces that are not there.
    pub(crate) alpha: bool,
    /// A path's smooth lobes are made rougher after a diffuse bounce ([`Bsdf::regularized`](super::bsdf::Bsdf::regularized)).
    pub(crate) regularize: bool,
    /// Camera rays, which all start at the eye, are traced in packets
    /// ([`Bvh::intersect_packet`](crate::bvh::Bvh::intersect_packet)):
    /// the same hits, found together, whenever the BVH is used, for a
    /// pixel that a pass gives at least
    /// [`PACKET_SAMPLES`](super::progressive::PACKET_SAMPLES) samples.
    /// Not for an orthographic camera, whose rays start apart (a packet
    /// would walk them one by one).
    pub packets: bool,
    /// Nothing is sampled (no sample draws a random number): one pass
    /// gives the exact image.
    pub deterministic: bool,
    /// The integrator chosen, and why ([`integrator`]).
    pub(crate) integrator: Integrator,
    integrator_why: &'static str,
    /// Paths are traced: the path integrator with indirect light on.
    pub path: bool,
    /// The most bounces after the camera ray.
    pub(crate) max_depth: u32,
}

/// Whether the scene's camera is orthographic.
fn orthographic(scene: &Scene) -> bool {
    matches!(scene.camera.projection, Projection::Orthographic { .. })
}

impl Plan {
    /// The plan for `scene` with `features` enabled.
    pub fn new(scene: &Scene, features: Features, policy: PlanPolicy) -> Self {
        let prune = policy == PlanPolicy::Prune;
        let (integrator, integrator_why) = integrator(scene);
        let mut decisions = [Decision::Off; Feature::ALL.len()];
        for f in ORDER {
            decisions[f as usize] = if !features.on(f) {
                Decision::Off
            } else if f == Feature::Indirect && integrator == Integrator::Whitted {
                // Not a stage the plan prunes: the integrator is a choice.
                Decision::NotNeeded(Reason::Whitted)
            } else if let Some(g) = refines(f).filter(|g| !decisions[*g as usize].runs()) {
                Decision::Needs(g)
            } else if let Some(why) = not_needed(scene, f).filter(|_| prune) {
                Decision::NotNeeded(why)
            } else {
                Decision::On
            };
        }
        let on = |f: Feature| decisions[f as usize].runs();
        let unplanned = Feature::ALL.map(|f| on(f) && not_needed(scene, f).is_some());
        let any_area = scene.lights.iter().any(|l| l.is_area());
        // Surfaces that reflect and let light through split a ray tree in
        // two at each bounce; past `MAX_PATHS` a split picks one branch at
        // random.
        let forks = on(Feature::Reflections)
            && scene.settings.max_depth > MAX_PATHS.ilog2()
            && scene
                .materials
                .iter()
                .any(|m| m.reflective() && m.dissolve < 1.0);
        // An environment light is sampled at every hit.
        let env_light =
            on(Feature::Environment) && matches!(scene.environment, Environment::Light(_));
        let path = on(Feature::Indirect);
        let deterministic = !(path
            || on(Feature::Supersampling)
            || on(Feature::Glossy)
            || env_light
            || (on(Feature::SoftShadows) && any_area)
            || forks);
        Plan {
            features,
            policy,
            decisions,
            unplanned,
            shadows: on(Feature::Shadows),
            reflections: on(Feature::Reflections),
            specular: !prune || scene.materials.iter().any(|m| m.reflective()),
            glossy: on(Feature::Glossy),
            textures: on(Feature::Textures),
            bilinear: on(Feature::Bilinear),
            smooth_normals: on(Feature::SmoothNormals),
            area_sampling: on(Feature::SoftShadows),
            supersampling: on(Feature::Supersampling),
            environment: on(Feature::Environment),
            bloom: on(Feature::Bloom),
            bvh: on(Feature::Bvh),
            normal_maps: on(Feature::NormalMaps),
            emission: on(Feature::Emission),
            alpha: on(Feature::Alpha),
            regularize: on(Feature::Regularize),
            packets: on(Feature::Bvh) && !orthographic(scene),
            deterministic,
            integrator,
            integrator_why,
            path,
            max_depth: scene.settings.max_depth,
        }
    }

    /// The plan with another maximum depth (the TUI's `<` and `>`).
    pub(crate) fn with_max_depth(mut self, depth: u32) -> Self {
        self.max_depth = depth.min(crate::scene::MAX_DEPTH);
        self
    }

    /// The decision for `f`'s stage.
    pub fn decision(&self, f: Feature) -> Decision {
        self.decisions[f as usize]
    }

    /// Whether each stage runs, the specular term and the progressive
    /// passes included: what the image depends on.
    fn runs(&self) -> ([bool; Feature::ALL.len() + 2], u32) {
        let mut r = [false; Feature::ALL.len() + 2];
        for f in Feature::ALL {
            r[f as usize] = self.decision(f).runs();
        }
        r[Feature::ALL.len()] = self.specular;
        r[Feature::ALL.len() + 1] = self.deterministic;
        (r, self.max_depth)
    }

    /// Whether the same stages run under both plans (features that are not
    /// needed may differ).
    pub(crate) fn same_stages(&self, other: &Plan) -> bool {
        self.runs() == other.runs()
    }

    /// Whether a film rendered under `other` holds the same samples as one
    /// rendered under this plan: bloom is applied after the film and brute
    /// force finds the same hits as the BVH, so only they may differ.
    pub(crate) fn same_film(&self, other: &Plan) -> bool {
        let shaping = |p: &Plan| {
            let (mut r, depth) = p.runs();
            r[Feature::Bloom as usize] = false;
            r[Feature::Bvh as usize] = false;
            (r, depth)
        };
        shaping(self) == shaping(other)
    }

    /// Every row of `--explain`: the stage, whether it runs, and why.
    pub fn rows(&self) -> Vec<(&'static str, bool, String)> {
        let mut rows: Vec<(&'static str, bool, String)> = ORDER
            .iter()
            .map(|&f| {
                let d = self.decision(f);
                let why = match (f, d) {
                    (Feature::Indirect, Decision::On | Decision::NotNeeded(_)) => {
                        format!(
                            "{}: {}",
                            if d.runs() { "on" } else { "not needed" },
                            self.integrator_why
                        )
                    }
                    (Feature::Indirect, Decision::Off) => "off: direct light only".into(),
                    (_, Decision::On) if self.unplanned[f as usize] => {
                        "on: --no-plan runs every enabled stage".into()
                    }
                    (_, Decision::On) => format!("on: {}", needed_for(f)),
                    (_, Decision::Off) => "off: turned off (--no or its key)".into(),
                    _ => d.reason(),
                };
                (stage_name(f), d.runs(), why)
            })
            .collect();
        rows.push((
            "camera rays in packets",
            self.packets,
            if self.packets {
                format!(
                    "on: a pixel's samples in one pass, {} or more, walk together",
                    super::progressive::PACKET_SAMPLES
                )
            } else if self.bvh {
                "not needed: the orthographic camera's rays start apart".into()
            } else {
                format!("off: needs {}", Feature::Bvh.name())
            },
        ));
        rows.push((
            "specular term",
            self.specular,
            if self.specular {
                "on: some material has a highlight (ks > 0)".into()
            } else {
                "not needed: no material with ks > 0".into()
            },
        ));
        rows.push((
            "progressive passes",
            !self.deterministic,
            if self.deterministic {
                "not needed: nothing is sampled, one pass is exact".into()
            } else {
                "on: the image is sampled; each pass adds samples and lowers its error".into()
            },
        ));
        rows
    }

    /// The plan as a table for `--explain`.
    pub(crate) fn explain(&self) -> String {
        let rows = self.rows();
        let w = rows.iter().map(|r| r.0.len()).max().unwrap_or(0);
        let mut s = format!("  {:w$}  {:3}  {}\n", "stage", "run", "why");
        for (stage, on, reason) in rows {
            s += &format!(
                "  {stage:w$}  {:3}  {reason}\n",
                if on { "on" } else { "off" }
            );
        }
        s
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene;

    #[test]
    fn refinements_need_what_they_refine() {
        let s = scene::load::open("cube-textured", &Default::default())
            .unwrap()
            .scene;
        let p = Plan::new(
            &s,
            Features::all().without(&[Feature::Textures]),
            PlanPolicy::Prune,
        );
        assert_eq!(
            p.decision(Feature::Bilinear),
            Decision::Needs(Feature::Textures)
        );
        assert!(!p.bilinear && !p.textures);
        assert_eq!(p.decision(Feature::Textures), Decision::Off);
    }

    #[test]
    fn everything_runs_what_pruning_leaves_out() {
        let s = scene::load::open("cornell", &Default::default())
            .unwrap()
            .scene;
        let pruned = Plan::new(&s, Features::all(), PlanPolicy::Prune);
        let all = Plan::new(&s, Features::all(), PlanPolicy::Everything);
        assert_eq!(
            pruned.decision(Feature::Textures),
            Decision::NotNeeded(Reason::NoTextures)
        );
        assert!(all.textures && all.glossy && all.environment && all.specular);
        assert!(!pruned.same_film(&all));
    }

    #[test]
    fn bloom_and_bvh_keep_the_film() {
        let s = scene::load::open("cornell", &Default::default())
            .unwrap()
            .scene;
        let p = Plan::new(&s, Features::all(), PlanPolicy::Prune);
        let q = Plan::new(
            &s,
            Features::all().without(&[Feature::Bloom, Feature::Bvh]),
            PlanPolicy::Prune,
        );
        let r = Plan::new(
            &s,
            Features::all().without(&[Feature::Shadows]),
            PlanPolicy::Prune,
        );
        assert!(p.same_film(&q) && !p.same_film(&r));
    }

    #[test]
    fn explain_has_a_header_and_a_row_per_stage() {
        let s = scene::load::open("cornell", &Default::default())
            .unwrap()
            .scene;
        let text = Plan::new(&s, Features::all(), PlanPolicy::Prune).explain();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines[0].contains("stage") && lines[0].contains("why"));
        assert_eq!(lines.len(), 1 + Feature::ALL.len() + 3);
    }
}
