//! `rayterm inspect`: the ray tree of one pixel, as text or JSON.

use std::process::ExitCode;

use std::io::Write;

use anyhow::{bail, Result};

use super::args::{InspectArgs, Worst};
use super::render::prepare;
use crate::inspect::{inspect_pixel, to_text};
use crate::render::{film::LUMA, pass, post, Film};

pub fn run(a: InspectArgs) -> Result<ExitCode> {
    let p = prepare(&a.scene)?;
    let tracer = p.tracer();
    let (x, y, k) = match (a.pixel, a.worst) {
        (Some((x, y)), _) => {
            if x >= p.width || y >= p.height {
                bail!(
                    "pixel ({x}, {y}) is outside the {}x{} image",
                    p.width,
                    p.height
                );
            }
            (x, y, a.sample)
        }
        (None, Some(w)) => {
            let mut film = Film::new(p.width, p.height);
            let spp = if p.plan.deterministic {
                1
            } else {
                a.spp.max(2)
            };
            pass::render_pass(&tracer, &mut film, spp, &|| false);
            match find_worst(&film, w) {
                Some(found) => found,
                None => {
                    println!("no pixel had a NaN or infinite sample in {spp} samples per pixel");
                    return Ok(ExitCode::SUCCESS);
                }
            }
        }
        (None, None) => bail!("give --pixel X,Y or --worst nan|variance|brightest"),
    };
    let mut tree = inspect_pixel(&tracer, x, y, k);
    if p.plan.bloom {
        let mut film = Film::new(p.width, p.height);
        pass::render_pass(&tracer, &mut film, 1, &|| false);
        let mut img = film.image();
        let before = img[(y * p.width + x) as usize];
        post::bloom(
            &mut img,
            p.width as usize,
            p.height as usize,
            &p.scene.settings.bloom,
        );
        tree.pixel_before_bloom = Some(before);
        tree.pixel_after_bloom = Some(img[(y * p.width + x) as usize]);
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

/// Pixel and sample index of the worst pixel by the given measure.
pub fn find_worst(film: &Film, w: Worst) -> Option<(u32, u32, u32)> {
    let at = |i: usize| (i as u32 % film.width, i as u32 / film.width);
    match w {
        Worst::Nan => film.bad.first().map(|b| (b.x, b.y, b.sample)),
        Worst::Variance => film
            .pixels
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.variance().total_cmp(&b.1.variance()))
            .map(|(i, _)| {
                let (x, y) = at(i);
                (x, y, 0)
            }),
        Worst::Brightest => film
            .pixels
            .iter()
            .enumerate()
            .max_by(|a, b| {
                a.1.mean
                    .dot(LUMA.as_dvec3())
                    .total_cmp(&b.1.mean.dot(LUMA.as_dvec3()))
            })
            .map(|(i, _)| {
                let (x, y) = at(i);
                (x, y, 0)
            }),
    }
}
