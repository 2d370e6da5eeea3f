//! `rayterm inspect`: the ray tree of one pixel, as text or JSON.

use std::io::Write;
use std::process::ExitCode;

use anyhow::{bail, Result};

use super::args::InspectArgs;
use super::open_scene;
use super::progress::ProgressMode;
use crate::color::LUMA;
use crate::inspect::{inspect_pixel, to_text};
use crate::render::{post, Film, Worst};

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
    // Looking for the worst pixel takes a render worth a progress report.
    let progress = match a.worst {
        Some(_) => ProgressMode::Auto,
        None => ProgressMode::None,
    };
    let film = match a.worst.is_some() || s.plan.bloom {
        true => match super::progress::film(&s, &tracer, spp, progress) {
            Some(f) => Some(f),
            None => return Ok(ExitCode::from(crate::interrupt::exit_code())),
        },
        false => None,
    };
    let (x, y, k) = match (a.pixel, a.worst, &film) {
        (Some((x, y)), _, _) => (x, y, a.sample),
        (None, Some(w), Some(film)) => match film.worst(w) {
            Some(found) => {
                crate::noteln!("{}", why_worst(film, w, found));
                found
            }
            None if s.plan.deterministic && w == Worst::Variance => {
                crate::outln!(
                    "no pixel varies: nothing in this scene is sampled, the image is exact"
                )?;
                return Ok(ExitCode::SUCCESS);
            }
            None => {
                crate::outln!(
                    "no pixel {} in {} sample{} per pixel",
                    match w {
                        Worst::Nan => "had a NaN or infinite sample",
                        Worst::Variance => "varies between samples",
                        Worst::Brightest => "exists",
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

/// Which pixel `--worst` picked, and by what measure, in `film`.
fn why_worst(film: &Film, w: Worst, (x, y, k): (u32, u32, u32)) -> String {
    let p = &film.pixels()[(y * film.width + x) as usize];
    let of = format!("of {} samples per pixel", film.spp);
    match w {
        Worst::Nan => format!(
            "worst pixel: ({x}, {y}), whose sample {k} was NaN or infinite ({} such samples {of})",
            film.bad_count
        ),
        Worst::Variance => format!(
            "worst pixel: ({x}, {y}), the highest variance of luminance between its samples ({} {of}; mean {})",
            crate::words::significant(p.variance()),
            crate::words::significant(p.mean.dot(LUMA.as_dvec3())),
        ),
        Worst::Brightest => format!(
            "worst pixel: ({x}, {y}), the brightest (mean luminance {} {of})",
            crate::words::significant(p.mean.dot(LUMA.as_dvec3())),
        ),
    }
}
