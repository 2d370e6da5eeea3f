//! The integration tests that can share a process, as one test binary: one
//! module per subject, run on parallel threads like the tests of any one
//! file. One binary builds and links against the library once where a
//! binary per file did so 26 times (CONTRIBUTING.md has the figures).
//!
//! A new test file goes here, as a module below. Only a test that cannot
//! share a process gets a binary of its own in `tests/`: one that drives a
//! real or pseudo-terminal, changes process-wide state (environment
//! variables, the current directory, signal handlers) or must be alone.
//! Tests here run at the same time: each writes under a temporary folder
//! named for it and the process, and signals only processes it started.

// Helpers shared by the modules below.
mod campaign;
mod common;
mod exact;
mod files;

mod adaptive;
mod aov;
mod bench_rays;
mod bvh;
mod converge;
mod debug_overlays;
mod envlight;
mod farm;
mod formats;
mod fuzz_loaders;
mod gltf_accessors;
mod gltf_scene;
mod hostile_input;
mod inspect;
mod loaders;
mod outputs;
mod path;
mod plan;
mod properties;
mod render;
mod sampling;
mod scale;
mod shading;
mod split;
mod stability;
mod tolerant_loaders;
mod turntable;
