//! The one way a scene is opened for rendering: a [`SceneRequest`] (what the
//! user asked for, free of any command-line parser) becomes a [`Session`]
//! (the scene, its BVH, the plan, the camera and the image size). The CLI,
//! the TUI, the reports, the benchmarks and the tests all open scenes here.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{bail, Result};

use super::plan::{Plan, PlanPolicy};
use super::{Features, Film, Tracer};
use crate::bvh::{self, Bvh};
use crate::scene::load::{self, source::InputFile, Opened};
use crate::scene::{self, Builder, Camera, Scene};

/// What to open and how to render it.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRequest {
    /// A built-in name, a `.toml` scene file or a mesh file.
    pub spec: String,
    /// Image size (default: the scene's).
    pub size: Option<(u32, u32)>,
    /// BVH builder (default: the scene's).
    pub builder: Option<Builder>,
    pub features: Features,
    pub policy: PlanPolicy,
    pub seed: u64,
    /// Samples per area light per shading point (default: the scene's).
    pub light_samples: Option<u32>,
    /// Glossy directions per glossy hit (default: the scene's).
    pub glossy_samples: Option<u32>,
    /// The integrator (default: the scene's, else the plan's choice).
    pub integrator: Option<crate::scene::Integrator>,
    /// The most bounces a ray tree or path takes (default: the scene's).
    pub max_depth: Option<u32>,
    /// Independent instead of jittered sub-pixel and light samples.
    pub independent: bool,
    /// Which of a glTF file's cameras to look through (name or number).
    pub camera: Option<String>,
    /// Whether glTF files may name files outside their folder.
    pub allow_outside: bool,
    /// A mesh file's up axis, where not its format's.
    pub up: Option<crate::scene::load::up::Up>,
    /// An environment light in place of the scene's environment.
    pub env: Option<crate::scene::load::EnvRequest>,
    /// The SIMD kernels the BVH walks with, at most (default: the widest
    /// this CPU has); every level finds the same hits.
    pub simd: Option<crate::bvh::Simd>,
    /// Whether opening refuses an image size whose film of statistics
    /// would not fit in memory; off for a caller that checks the film it
    /// makes, which may keep far less ([`Job::bytes_per_pixel`]).
    ///
    /// [`Job::bytes_per_pixel`]: super::Job::bytes_per_pixel
    pub check_film: bool,
}

impl SceneRequest {
    /// Everything at its default: every feature, the plan, seed 1.
    pub fn new(spec: &str) -> Self {
        Self {
            spec: spec.to_string(),
            size: None,
            builder: None,
            features: Features::all(),
            policy: PlanPolicy::Prune,
            seed: 1,
            light_samples: None,
            glossy_samples: None,
            integrator: None,
            max_depth: None,
            independent: false,
            camera: None,
            allow_outside: false,
            up: None,
            env: None,
            simd: None,
            check_film: true,
        }
    }
}

/// A scene ready to render: shared, so the TUI's worker, exports and
/// background jobs hold the same scene and BVH.
#[derive(Clone)]
pub struct Session {
    pub scene: Arc<Scene>,
    pub bvh: Arc<Bvh>,
    pub plan: Plan,
    /// The scene's camera (the TUI moves its own copy).
    pub camera: Camera,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) seed: u64,
    /// The files the scene was read from, which no output may replace.
    pub(crate) inputs: Vec<InputFile>,
}

impl Session {
    /// Loads the scene `req` names and prepares it; the load warnings are
    /// returned for the caller to show.
    pub fn open(req: &SceneRequest) -> Result<(Session, Vec<String>)> {
        if let Some(s) = req.simd {
            s.on_this_cpu()?;
        }
        let (scene, inputs) = Self::load(req)?;
        let (w, h) = req
            .size
            .unwrap_or((scene.settings.width, scene.settings.height));
        if req.check_film {
            check_film(w, h, Film::BYTES_PER_PIXEL)?;
        }
        let (mut session, warnings) = Self::with_scene(scene, req);
        session.inputs = inputs;
        Ok((session, warnings))
    }

    /// The scene `req` names, loaded as [`Session::open`] loads it, and the
    /// files it was read from, with no BVH built: what `rayterm inputs`
    /// lists. Its warnings are the scene's.
    pub(crate) fn load(req: &SceneRequest) -> Result<(Scene, Vec<InputFile>)> {
        let how = load::Opening {
            camera: req.camera.clone(),
            allow_outside: req.allow_outside,
            up: req.up,
            env: req.env.clone(),
            source: None,
        };
        let Opened { scene, inputs } = load::open(&req.spec, &how)?;
        if let Err(e) = scene::check_reach(&scene) {
            // The load's warnings (a rescale, say) may be why, and would
            // otherwise never be shown.
            let mut msg = format!("{}: {e:#}", req.spec);
            for w in &scene.warnings {
                msg += &format!("\n  note: {w}");
            }
            bail!(msg);
        }
        Ok((scene, inputs))
    }

    /// The paths of the files the scene was read from.
    pub(crate) fn input_paths(&self) -> Vec<PathBuf> {
        self.inputs.iter().map(|i| i.path.clone()).collect()
    }

    /// Prepares a scene already in memory (built in code, or loaded another
    /// way) with the request's settings; `req.spec` is not read.
    pub fn with_scene(mut scene: Scene, req: &SceneRequest) -> (Session, Vec<String>) {
        let warnings = std::mem::take(&mut scene.warnings);
        let st = &mut scene.settings;
        st.builder = req.builder.unwrap_or(st.builder);
        st.light_samples = req.light_samples.unwrap_or(st.light_samples);
        st.glossy_samples = req.glossy_samples.unwrap_or(st.glossy_samples);
        st.integrator = req.integrator.or(st.integrator);
        st.max_depth = req.max_depth.unwrap_or(st.max_depth);
        st.stratify &= !req.independent;
        let (width, height) = req.size.unwrap_or((st.width, st.height));
        let plan = Plan::new(&scene, req.features, req.policy);
        let mut bvh = bvh::build(&scene.geometry, scene.settings.builder);
        if let Some(s) = req.simd {
            bvh.cap_simd(s);
        }
        let session = Session {
            camera: scene.camera,
            scene: Arc::new(scene),
            bvh: Arc::new(bvh),
            plan,
            width,
            height,
            seed: req.seed,
            inputs: Vec::new(),
        };
        (session, warnings)
    }

    /// The plan for other features, under this session's policy.
    pub(crate) fn plan_for(&self, features: Features) -> Plan {
        Plan::new(&self.scene, features, self.plan.policy)
    }

    /// A tracer for the session's camera, size and plan.
    /// Renders from `camera` from now on, the scene's own camera too, so
    /// that partial films of another view (a turntable's other frame) have
    /// another content hash and never merge with these.
    pub(crate) fn set_camera(&mut self, camera: Camera) {
        Arc::make_mut(&mut self.scene).camera = camera;
        self.camera = camera;
    }

    pub fn tracer(&self) -> Tracer<'_> {
        self.tracer_for(&self.plan, &self.camera, (self.width, self.height))
    }

    /// A tracer for another view of the same scene.
    pub fn tracer_for<'a>(
        &'a self,
        plan: &'a Plan,
        camera: &Camera,
        (width, height): (u32, u32),
    ) -> Tracer<'a> {
        Tracer::new(
            &self.scene,
            &self.bvh,
            plan,
            camera.frame(width, height),
            self.seed,
        )
    }
}

/// Refuses a `w` x `h` film of `bytes_per_pixel` that would not fit in
/// memory.
pub(crate) fn check_film(w: u32, h: u32, bytes_per_pixel: u64) -> Result<()> {
    crate::memory::check(
        &format!("a {w}x{h} film"),
        w as u64 * h as u64 * bytes_per_pixel,
        None,
    )
}
