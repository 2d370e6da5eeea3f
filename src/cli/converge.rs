//! `rayterm converge`: error against run time, as a table, CSV and plot.

use std::process::ExitCode;

use anyhow::{bail, Result};

use super::args::{ConvergeArgs, MAX_SPP};
use super::open_scene;
use crate::raster::{png, ImageFormat, Output};
use crate::report::converge::{self, Config, ReferenceSource, RunLimit, Subject};

/// Small enough that a whole study takes seconds; `--size` changes it.
const DEFAULT_SIZE: (u32, u32) = (64, 64);

/// The longest budget: an hour a run (several seeds and strategies each).
const MAX_SECONDS: f64 = 3600.0;

/// The smallest relative error a conclusion is about.
const MIN_TARGET: f64 = 1e-6;

pub(crate) fn run(a: ConvergeArgs) -> Result<ExitCode> {
    // Outputs are checked before the study runs, which can take minutes.
    let inputs: Vec<std::path::PathBuf> = a.reference.iter().cloned().collect();
    let csv = a
        .csv
        .as_ref()
        .map(|p| Output::check(p, &inputs, &[ImageFormat::Csv]))
        .transpose()?;
    let plot = a
        .plot
        .as_ref()
        .map(|p| Output::check(p, &inputs, &[ImageFormat::Png]))
        .transpose()?;
    // Every option is checked before the scene loads.
    let mut budgets = if a.times.is_empty() {
        if a.spp.iter().any(|&n| n == 0 || n > MAX_SPP) {
            bail!("--spp budgets must be 1 to {MAX_SPP} samples per pixel");
        }
        a.spp.iter().map(|&n| RunLimit::Spp(n)).collect::<Vec<_>>()
    } else {
        if a.times
            .iter()
            .any(|t| !(t.is_finite() && *t > 0.0 && *t <= MAX_SECONDS))
        {
            bail!("--times must be positive numbers of seconds, each at most {MAX_SECONDS}");
        }
        a.times.iter().map(|&t| RunLimit::Seconds(t)).collect()
    };
    let key = |b: &RunLimit| match b {
        RunLimit::Spp(n) => *n as f64,
        RunLimit::Seconds(t) => *t,
    };
    budgets.sort_by(|x, y| key(x).total_cmp(&key(y)));
    budgets.dedup();
    // Below 1e-6 the answer would be beyond any render (and f32 films).
    if !(a.target >= MIN_TARGET && a.target < 1.0) {
        bail!("--target must be a fraction from {MIN_TARGET:e} to below 1 (0.01 for 1 %)");
    }
    let mut opts = a.scene.clone();
    opts.size = opts.size.or(Some(DEFAULT_SIZE));
    let p = open_scene(&opts)?;
    let reference = match a.reference {
        Some(f) => ReferenceSource::File(f),
        None => ReferenceSource::Render {
            spp: a.reference_spp,
            cache: a.cache_dir.or_else(converge::default_cache_dir),
        },
    };
    let cfg = Config {
        width: p.width,
        height: p.height,
        budgets,
        seeds: a.seeds,
        seed: p.seed,
        compare: !a.no_compare,
        adaptive: a.adaptive,
        reference,
        target: a.target,
    };
    let subject = Subject {
        scene: &p.scene,
        bvh: &p.bvh,
        plan: &p.plan,
    };
    // Ctrl-C, SIGTERM or SIGHUP cut the runs short; what they measured is
    // then not the study asked for, so nothing is printed or written.
    crate::interrupt::flag();
    let bar = super::progress::ReportBar::new();
    let study = subject.study(&cfg, &bar, crate::interrupt::Cancel::Signal);
    if crate::interrupt::requested() {
        crate::noteln!("interrupted: nothing written");
        return Ok(ExitCode::from(crate::interrupt::exit_code()));
    }
    let study = study?;
    match [&csv, &plot]
        .iter()
        .any(|o| o.as_ref().is_some_and(Output::is_stdout))
    {
        true => crate::console::note(format_args!("{}", study.text())),
        false => crate::out!("{}", study.text())?,
    }
    if let Some(out) = csv {
        out.write(study.csv().as_bytes())?;
        crate::noteln!("wrote {}", crate::words::path(&out.path));
    }
    if let Some(out) = plot {
        out.write(&png::encode(&converge::plot(&study))?)?;
        crate::noteln!("wrote {}", crate::words::path(&out.path));
    }
    Ok(ExitCode::SUCCESS)
}
