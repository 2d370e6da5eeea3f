//! `rayterm render --debug VIEW`: a debug view written as a PNG: the BVH
//! views, bloom's parts, or one pixel's overlays over the rendered image.

use std::fmt;
use std::process::ExitCode;
use std::str::FromStr;
use std::time::Instant;

use anyhow::{bail, Result};
use glam::Vec3;

use crate::inspect::inspect_pixel;
use crate::inspect::overlay::{self as pixel, tree_rays, PixelView};
use crate::raster::canvas::Canvas;
use crate::raster::{png, Output};
use crate::render::debug_view::{self, DebugView};
use crate::render::overlay::{draw_legend, Legend};
use crate::render::{post, Progressive, Session};

/// What `--debug` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DebugSpec {
    Bvh(DebugView),
    /// `bloom`
    Bloom,
    /// `ray:X,Y[:VIEW[:N]]` and `samples:X,Y`.
    Pixel {
        x: u32,
        y: u32,
        view: PixelView,
        ray: Option<usize>,
    },
}

const SPECS: &str = "bvh-level:K, bvh-leaves, bvh-heat[:tests], bloom, \
                     ray:X,Y[:VIEW[:N]] or samples:X,Y";

impl FromStr for DebugSpec {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "bloom" {
            return Ok(DebugSpec::Bloom);
        }
        let example = if s.starts_with("samples") {
            "samples:400,300"
        } else {
            "ray:400,300"
        };
        let pixel = |p: &str| {
            let (x, y) = p
                .split_once(',')
                .ok_or_else(|| format!("'{s}': the pixel must be X,Y, as in {example}"))?;
            let coord = |c: &str, what: &str| {
                c.trim().parse::<u32>().map_err(|_| {
                    format!("'{s}': {what} must be a whole number from 0, as in {example}")
                })
            };
            Ok::<_, String>((coord(x, "x")?, coord(y, "y")?))
        };
        if let Some(rest) = s.strip_prefix("samples:") {
            let (x, y) = pixel(rest)?;
            return Ok(DebugSpec::Pixel {
                x,
                y,
                view: PixelView::Samples,
                ray: None,
            });
        }
        if let Some(rest) = s.strip_prefix("ray:") {
            let mut parts = rest.splitn(3, ':');
            let (x, y) = pixel(parts.next().unwrap_or(""))?;
            let view = match parts.next() {
                None => PixelView::Rays,
                Some(v) => v.parse().map_err(|e| format!("'{s}': {e}"))?,
            };
            let ray = match parts.next() {
                None => None,
                Some(_) if !view.one_ray() => {
                    return Err(format!(
                        "'{s}': the {view} overlay draws the whole tree; a ray number is for \
                         traversal, normals, texture and environment"
                    ))
                }
                Some(n) => Some(n.trim().parse::<usize>().map_err(|_| {
                    format!(
                        "'{s}': the ray number must be a whole number from 0 (0 is the camera ray)"
                    )
                })?),
            };
            return Ok(DebugSpec::Pixel { x, y, view, ray });
        }
        if s.starts_with("bvh") {
            return s.parse().map(DebugSpec::Bvh);
        }
        Err(format!("unknown debug view '{s}': expected {SPECS}"))
    }
}

impl fmt::Display for DebugSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DebugSpec::Bvh(v) => v.fmt(f),
            DebugSpec::Bloom => f.write_str("bloom"),
            DebugSpec::Pixel {
                x,
                y,
                view: PixelView::Samples,
                ..
            } => write!(f, "samples:{x},{y}"),
            DebugSpec::Pixel { x, y, view, ray } => {
                write!(f, "ray:{x},{y}:{view}")?;
                match ray {
                    Some(n) => write!(f, ":{n}"),
                    None => Ok(()),
                }
            }
        }
    }
}

/// Draws `spec` and writes it to `out`; `spp` is the samples of the image
/// under the bloom and pixel views (default: the scene's).
pub fn run(s: &Session, spec: DebugSpec, spp: Option<u32>, out: &Output) -> Result<ExitCode> {
    let start = Instant::now();
    let t = s.tracer();
    let (w, h) = (s.width, s.height);
    let spp = match (spec, spp) {
        (DebugSpec::Bvh(_), Some(_)) => {
            bail!("--spp is for the bloom, ray and samples views; the BVH views draw over one sample per pixel")
        }
        (_, n) => n.unwrap_or(s.scene.settings.spp).max(1),
    };
    let mut rays: Vec<String> = Vec::new();
    let (image, legend): (Vec<Vec3>, Legend) = match spec {
        DebugSpec::Bvh(view) => return bvh(s, view, out),
        DebugSpec::Bloom => {
            let film = Progressive::render(&t, spp);
            let (image, mut legend) =
                debug_view::bloom_view(&film.image(), w, h, &s.scene.settings.bloom);
            if !s.plan.bloom {
                legend.push((None, "bloom is off in this render's plan".into()));
            }
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
            let film = Progressive::render(&t, spp);
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
        "{} {spec} at {w}x{h}: {} triangles, {} BVH nodes, depth {} ({}); {ms:.1} ms -> {}",
        s.scene.name,
        st.triangles,
        st.nodes,
        st.depth,
        st.builder,
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
fn bvh(s: &Session, view: DebugView, out: &Output) -> Result<ExitCode> {
    let start = Instant::now();
    let d = debug_view::draw(&s.tracer(), view)?;
    let ms = start.elapsed().as_secs_f64() * 1e3;
    out.write(&png::encode(&post::to_rgb8(&d.image, s.width, s.height))?)?;
    let st = &s.bvh.stats;
    crate::outln!(
        "{} {view} at {}x{}: {} triangles, {} BVH nodes, depth {} ({}); {} ({ms:.1} ms) -> {}",
        s.scene.name,
        s.width,
        s.height,
        st.triangles,
        st.nodes,
        st.depth,
        st.builder,
        d.summary,
        crate::words::path(&out.path)
    )?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_read_back_as_written() {
        for s in [
            "bvh-leaves",
            "bvh-level:2",
            "bloom",
            "ray:3,4:rays",
            "ray:3,4:traversal:2",
            "ray:0,7:environment",
            "samples:5,6",
        ] {
            let spec: DebugSpec = s.parse().unwrap();
            assert_eq!(spec.to_string(), s);
        }
        assert_eq!(
            "ray:3,4".parse(),
            Ok(DebugSpec::Pixel {
                x: 3,
                y: 4,
                view: PixelView::Rays,
                ray: None
            })
        );
        assert_eq!(
            "ray:1,2:color".parse::<DebugSpec>().unwrap().to_string(),
            "ray:1,2:colour"
        );
        assert_eq!(
            "ray:1,2:samples".parse::<DebugSpec>().unwrap().to_string(),
            "samples:1,2"
        );
        let e = "samples:1,x".parse::<DebugSpec>().unwrap_err();
        assert!(e.contains("as in samples:400,300"), "{e}");
    }
}
