//! Rendering: the session a scene is opened into, the plan of what runs,
//! the one shading code path (generic over a [`Recorder`]), the film, the
//! one progressive loop and the one post-processing step.

pub mod aov;
pub(crate) mod brdf;
pub(crate) mod bsdf;
pub mod content;
pub mod features;
pub mod film;
pub mod integrator;
pub mod job;
pub mod partial;
mod path;
pub mod plan;
pub mod post;
pub mod progressive;
pub mod recorder;
pub mod session;

pub use features::{Feature, Features};
pub use film::{Film, Report, Worst, WorstPixels};
pub use integrator::Tracer;
pub use job::{Job, Needs};
pub use plan::{Decision, Plan, PlanPolicy};
pub use progressive::{Ended, Outcome, PassStats, Progressive, Stop, MIN_SPP};
pub use recorder::{RayCounter, Recorder};
pub use session::{SceneRequest, Session};
