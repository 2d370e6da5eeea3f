//! Rendering: the session a scene is opened into, the plan of what runs,
//! the one shading code path (generic over a [`Recorder`]), the film, the
//! one progressive loop and the one post-processing step.

mod alpha;
pub(crate) mod aov;
pub(crate) mod brdf;
pub(crate) mod bsdf;
pub(crate) mod content;
pub(crate) mod features;
pub mod film;
pub mod integrator;
pub(crate) mod job;
pub mod partial;
mod path;
pub(crate) mod plan;
pub mod post;
pub(crate) mod progressive;
pub mod recorder;
pub(crate) mod session;

pub use features::{Feature, Features};
pub use film::Film;
pub(crate) use film::Report;
pub use film::{Worst, WorstPixels};
pub use integrator::Tracer;
pub use job::Job;
pub(crate) use job::Needs;
pub use plan::Decision;
pub use plan::{Plan, PlanPolicy};
pub(crate) use progressive::Ended;
pub use progressive::{Outcome, PassStats};
pub use progressive::{Progressive, Stop, MIN_SPP};
pub use recorder::RayCounter;
pub use recorder::Recorder;
pub use session::{SceneRequest, Session};
