//! The ray-tree inspector: a [`Recorder`](crate::render::Recorder) that turns
//! the integrator's hooks into a tree, and its text and JSON forms.

pub mod overlay;
pub mod text;
pub mod tree;

pub use text::{lines, to_text, LineKind, TreeLine};
pub use tree::{inspect_pixel, LightNode, PixelTree, RayNode, TreeRecorder};
