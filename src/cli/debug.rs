//! `rayterm render --debug VIEW`: a BVH debug view written as a PNG.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;

use super::render::Prepared;
use crate::render::debug_view::{self, DebugView};
use crate::render::{output, post};

pub fn run(p: &Prepared, view: DebugView, out: &Path) -> Result<ExitCode> {
    let start = Instant::now();
    let d = debug_view::draw(&p.tracer(), view)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    output::save_png_atomic(&post::to_rgb8(&d.image, p.width, p.height), out)?;
    println!(
        "{} {view} at {}x{}: {} triangles, {} BVH nodes, depth {} ({}); {} ({ms:.1} ms) -> {}",
        p.scene.name,
        p.width,
        p.height,
        p.bvh.stats.triangles,
        p.bvh.stats.nodes,
        p.bvh.stats.depth,
        p.bvh.stats.builder,
        d.summary,
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}
