//! `rayterm merge`: the partial films of a split render into the image one
//! render of all their samples makes, post-processed as `render` does.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};

use super::args::MergeArgs;
use super::render::{image_bytes, summary};
use crate::interrupt;
use crate::raster::{Format, Output};
use crate::render::partial::{self, ranges_text, Part};

pub fn run(a: MergeArgs) -> Result<ExitCode> {
    let out = Output::check(&a.output, &a.parts, Format::RENDERS)?;
    let interrupted = interrupt::flag();
    let cancel = || interrupted.load(std::sync::atomic::Ordering::Relaxed);
    let start = Instant::now();
    let mut parts = Vec::with_capacity(a.parts.len());
    for path in &a.parts {
        if cancel() {
            break;
        }
        parts.push((path.clone(), Part::read(path)?));
    }
    let count = parts.len();
    let merged = partial::merge(parts, &cancel);
    if cancel() {
        eprintln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let merged = merged?;
    let (film, meta) = (&merged.part.film, &merged.part.meta);
    let total = meta.total.unwrap_or(film.spp);
    if !merged.missing.is_empty() {
        let what = format!(
            "samples {} of 0..{total} are missing",
            ranges_text(&merged.missing)
        );
        if !a.allow_missing {
            bail!("{what}: render those parts, or merge what there is with --allow-missing");
        }
        eprintln!("warning: {what}: the image has {} of {total} spp", film.spp);
    }
    let bytes = image_bytes(
        out.format,
        film,
        film.width,
        film.height,
        meta.bloom.as_ref(),
    )?;
    if cancel() {
        eprintln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    out.write(&bytes)?;
    let head = format!(
        "{}: {} triangles, merged {count} part{} in {:.1} ms, render {:.1} s in all",
        meta.scene,
        meta.triangles,
        if count == 1 { "" } else { "s" },
        start.elapsed().as_secs_f64() * 1e3,
        meta.seconds
    );
    let mut line = summary(
        &head,
        film,
        false,
        meta.rays,
        meta.seconds * 1e3,
        meta.exact,
        "",
        &a.output,
    );
    if !merged.missing.is_empty() {
        line = line.replacen(" spp,", " spp (samples missing),", 1);
    }
    println!("{line}");
    Ok(ExitCode::SUCCESS)
}
