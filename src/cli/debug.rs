//! `rayterm render --debug VIEW`: a BVH debug view written as a PNG.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::Result;

use crate::raster::{png, Output};
use crate::render::debug_view::{self, DebugView};
use crate::render::{post, Session};

pub fn run(s: &Session, view: DebugView, out: &Output) -> Result<ExitCode> {
    let start = Instant::now();
    let d = debug_view::draw(&s.tracer(), view)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    out.write(&png::encode(&post::to_rgb8(&d.image, s.width, s.height))?)?;
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
        out.path.display()
    );
    Ok(ExitCode::SUCCESS)
}
