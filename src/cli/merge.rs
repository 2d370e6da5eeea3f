//! `rayterm merge`: the partial films of a split render into the image one
//! render of all their samples makes, post-processed as `render` does.

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};

use super::args::MergeArgs;
use super::render::{image_bytes, summary};
use crate::interrupt;
use crate::raster::{Format, Output};
use crate::render::partial::{self, ranges_text};
use crate::words;

pub fn run(a: MergeArgs) -> Result<ExitCode> {
    let out = Output::check(&a.output, &a.parts, Format::RENDERS)?;
    let interrupted = interrupt::flag();
    let cancel = || interrupted.load(std::sync::atomic::Ordering::Relaxed);
    let start = Instant::now();
    let plan = partial::plan(&a.parts)?;
    let count = plan.parts.len();
    if !plan.missing.is_empty() {
        let what = format!(
            "samples {} of 0..{} are missing",
            ranges_text(&plan.missing),
            plan.total
        );
        if !a.allow_missing {
            bail!("{what}: render those parts, or merge what there is with --allow-missing");
        }
        let held: u32 = plan.parts.iter().map(|(_, h)| h.range.len() as u32).sum();
        crate::noteln!(
            "warning: {what}: the image has {held} of {} spp",
            plan.total
        );
    }
    let merged = partial::merge(&plan, &cancel);
    if cancel() {
        crate::noteln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let merged = merged?;
    let (meta, (width, height)) = (&merged.meta, merged.size);
    let bytes = image_bytes(out.format, merged.image, width, height, meta.bloom.as_ref())?;
    let written = match cancel() {
        true => Err(interrupt::Interrupted.into()),
        false => out.write_result(&bytes),
    };
    match written {
        Err(e) if e.is::<interrupt::Interrupted>() => {
            crate::noteln!("interrupted: nothing written");
            return Ok(ExitCode::from(interrupt::exit_code()));
        }
        written => written?,
    }
    let head = format!(
        "{}: {}, merged {} in {}, render {} in all",
        meta.scene,
        words::count(meta.triangles, "triangle", "triangles"),
        words::count(count as u64, "part", "parts"),
        words::ms(start.elapsed().as_secs_f64() * 1e3),
        words::ms(meta.seconds * 1e3)
    );
    let mut line = summary(
        &head,
        &merged.report,
        false,
        meta.rays,
        meta.seconds * 1e3,
        meta.exact,
        "",
        &a.output,
    );
    if !plan.missing.is_empty() {
        line = line.replacen(" spp,", " spp (samples missing),", 1);
    }
    match out.is_stdout() {
        true => crate::noteln!("{line}"),
        false => crate::outln!("{line}")?,
    }
    Ok(ExitCode::SUCCESS)
}
