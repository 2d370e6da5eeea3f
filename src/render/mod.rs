//! Rendering: the plan of what runs, the one shading code path (generic over
//! a [`Recorder`]), the progressive film, passes and post-processing.

pub mod debug_view;
pub mod features;
pub mod film;
pub mod integrator;
pub mod output;
pub mod overlay;
pub mod pass;
pub mod plan;
pub mod post;
pub mod recorder;

pub use features::{Feature, Features};
pub use film::Film;
pub use integrator::Tracer;
pub use plan::Plan;
pub use recorder::{RayCounter, Recorder};
