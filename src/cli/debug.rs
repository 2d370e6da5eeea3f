//! `rayterm render --debug VIEW`: a BVH debug view written as a PNG.

use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;

use crate::render::debug_view::{self, DebugView};
use crate::render::{output, post, Session};

pub fn run(s: &Session, view: DebugView, out: &Path) -> Result<ExitCode> {
    let start = Instant::now();
    let d = debug_view::draw(&s.tracer(), view)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    output::save_png_atomic(&post::to_rgb8(&d.image, s.width, s.height), out)?;
    let st = &s.bvh.stats;
    println!(
        "{} {view} at {}x{}: {} triangles, {} BVH nodes, depth {} ({}); {} ({ms:.1} ms) -> {}",
        s.scene.name,
        s.width,
        s.height,
        st.triangles,
        st.nodes,
        st.depth,
        st.builder,
        d.summary,
        out.display()
    );
    Ok(ExitCode::SUCCESS)
}
