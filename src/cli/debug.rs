//! `rayterm render --debug VIEW`: a debug view written as a PNG: the BVH
//! views, bloom's parts, or one pixel's overlays over the rendered image.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};
use glam::Vec3;

use super::progress::ProgressMode;
use crate::inspect::{inspect_pixel, tree_rays};
use crate::interrupt;
use crate::raster::canvas::Canvas;
use crate::raster::{png, Output};
use crate::render::{post, Session};
use crate::viz::draw::{draw_legend, Legend};
use crate::viz::{self, pixel, DebugSpec, DrawnFrom, View};

/// Draws `spec` and writes it to `out`; `spp` is the samples of the image
/// under the bloom and pixel views (default: the scene's).
pub(crate) fn run(
    s: &Session,
    spec: DebugSpec,
    spp: Option<u32>,
    out: &Output,
    progress: ProgressMode,
) -> Result<ExitCode> {
    let start = Instant::now();
    let t = s.tracer();
    let (w, h) = (s.width, s.height);
    let spp = match (spec, spp) {
        (DebugSpec::Image(v), Some(_)) if v.source() == DrawnFrom::Bvh => {
            bail!("--spp is for the bloom, ray and samples views; the BVH views draw over one sample per pixel")
        }
        (_, n) => n.unwrap_or(s.scene.settings.spp).max(1),
    };
    let mut rays: Vec<String> = Vec::new();
    let (image, legend): (Vec<Vec3>, Legend) = match spec {
        DebugSpec::Image(view) if view.source() == DrawnFrom::Bvh => return bvh(s, view, out),
        DebugSpec::Image(view) => {
            let Some(film) = super::progress::film(s, &t, spp, progress) else {
                return Ok(ExitCode::from(interrupt::exit_code()));
            };
            let (image, legend) = viz::film_view(
                view,
                &film,
                &film.image(),
                (w, h),
                &s.scene.settings.bloom,
                (s.plan.bloom, "this render's"),
            )?;
            let mut layer = Canvas::new(w, h, None);
            draw_legend(&mut layer, &legend, true);
            let mut image = image;
            layer.over(&mut image);
            (image, legend)
        }
        DebugSpec::Pixel { x, y, view, ray } => {
            if x >= w || y >= h {
                bail!(
                    "pixel ({x}, {y}) is outside the {w}x{h} image (0..{} by 0..{})",
                    w - 1,
                    h - 1
                );
            }
            let tree = inspect_pixel(&t, x, y, 0);
            let mut o = pixel::draw(&t, &tree, view, ray, spp)?;
            let Some(film) = super::progress::film(s, &t, spp, progress) else {
                return Ok(ExitCode::from(interrupt::exit_code()));
            };
            let mut image =
                post::display(film.image(), w, h, &s.plan, &s.scene.settings.bloom).image;
            draw_legend(&mut o.layer, &o.legend, o.legend_bottom);
            o.layer.over(&mut image);
            if view.one_ray() {
                rays.push(format!(
                    "rays of this sample (ray:{x},{y}:{view}:N picks one):"
                ));
                rays.extend(
                    tree_rays(&tree)
                        .iter()
                        .enumerate()
                        .map(|(i, r)| format!("  {i:>3}  {}", r.label())),
                );
            }
            (image, o.legend)
        }
    };
    let ms = start.elapsed().as_secs_f64() * 1e3;
    out.write(&png::encode(&post::to_rgb8(&image, w, h))?)?;
    let st = &s.bvh.stats;
    crate::outln!(
        "{} {spec} at {w}x{h}: {} triangles, {} BVH nodes, depth {} ({}); {} -> {}",
        s.scene.name,
        st.triangles,
        st.nodes,
        st.depth,
        st.builder,
        crate::words::ms(ms),
        crate::words::path(&out.path)
    )?;
    for (_, line) in &legend {
        crate::outln!("  {line}")?;
    }
    for r in rays {
        crate::outln!("{r}")?;
    }
    Ok(ExitCode::SUCCESS)
}

/// A BVH view, with its one-line summary.
fn bvh(s: &Session, view: View, out: &Output) -> Result<ExitCode> {
    let start = Instant::now();
    let d = viz::draw(&s.tracer(), view)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    out.write(&png::encode(&post::to_rgb8(&d.image, s.width, s.height))?)?;
    let st = &s.bvh.stats;
    crate::outln!(
        "{} {view} at {}x{}: {} triangles, {} BVH nodes, depth {} ({}); {} ({}) -> {}",
        s.scene.name,
        s.width,
        s.height,
        st.triangles,
        st.nodes,
        st.depth,
        st.builder,
        d.summary,
        crate::words::ms(ms),
        crate::words::path(&out.path)
    )?;
    Ok(ExitCode::SUCCESS)
}
