//! `rayterm inspect`: the ray tree of one pixel, as text or JSON.

use std::io::Write;
use std::process::ExitCode;

use anyhow::{bail, Result};

use super::args::InspectArgs;
use super::open_scene;
use crate::inspect::{inspect_pixel, to_text};
use crate::render::{post, Progressive};

pub(crate) fn run(a: InspectArgs) -> Result<ExitCode> {
    let s = open_scene(&a.scene)?;
    let tracer = s.tracer();
    if let Some((x, y)) = a.pixel {
        if x >= s.width || y >= s.height {
            bail!(
                "pixel ({x}, {y}) is outside the {}x{} image",
                s.width,
                s.height
            );
        }
    }
    // The image the pixel belongs to: rendered to pick the worst pixel, and
    // for the pixel's value before and after bloom.
    let spp = a.spp.unwrap_or(if a.worst.is_some() { 16 } else { 1 });
    let film = (a.worst.is_some() || s.plan.bloom).then(|| Progressive::render(&tracer, spp));
    let (x, y, k) = match (a.pixel, a.worst, &film) {
        (Some((x, y)), _, _) => (x, y, a.sample),
        (None, Some(w), Some(film)) => match film.worst(w) {
            Some(found) => found,
            None if s.plan.deterministic && w == crate::render::Worst::Variance => {
                crate::outln!(
                    "no pixel varies: nothing in this scene is sampled, the image is exact"
                )?;
                return Ok(ExitCode::SUCCESS);
            }
            None => {
                crate::outln!(
                    "no pixel {} in {} sample{} per pixel",
                    match w {
                        crate::render::Worst::Nan => "had a NaN or infinite sample",
                        crate::render::Worst::Variance => "varies between samples",
                        crate::render::Worst::Brightest => "exists",
                    },
                    film.spp,
                    if film.spp == 1 { "" } else { "s" }
                )?;
                return Ok(ExitCode::SUCCESS);
            }
        },
        _ => bail!("give --pixel X,Y or --worst nan|variance|brightest"),
    };
    let mut tree = inspect_pixel(&tracer, x, y, k);
    if let Some(film) = &film {
        let shown = post::display(
            film.image(),
            s.width,
            s.height,
            &s.plan,
            &s.scene.settings.bloom,
        );
        tree.set_pixel(&shown, film.spp);
    }
    let text = if a.json {
        serde_json::to_string_pretty(&tree)? + "\n"
    } else {
        to_text(&tree, a.expand)
    };
    // A closed pipe (`| head`) is an error to return, not a panic.
    std::io::stdout().lock().write_all(text.as_bytes())?;
    Ok(ExitCode::SUCCESS)
}
