//! rayterm: a ray tracer that lives in the terminal.
//!
//! Data flows `scene::load::open` → `bvh::build` → `render::Plan` →
//! `render::Tracer::sample` (generic over a recorder) → `render::Film` →
//! `render::post`; the CLI, the TUI, the inspector and the reports consume it.

pub mod bvh;
pub mod choice;
pub mod cli;
pub mod color;
pub(crate) mod console;
pub mod geometry;
pub mod inspect;
pub mod interrupt;
pub mod memory;
pub mod raster;
pub mod render;
pub mod report;
pub mod scene;
pub mod tui;
pub mod viz;
pub mod words;

#[cfg(test)]
mod layers;
