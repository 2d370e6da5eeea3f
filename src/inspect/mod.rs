//! The ray-tree inspector: a [`Recorder`](crate::render::Recorder) that turns
//! the integrator's hooks into a tree, and its text and JSON forms.

pub(crate) mod rays;
pub mod text;
pub mod tree;

pub use rays::{tree_rays, TreeRay};
pub use text::{lines, to_text, LineKind, TreeLine};
pub use tree::{inspect_pixel, LightNode, PixelTree, RayNode, TreeRecorder};
