//! `rayterm render`: progressive passes to a PNG, with a progress bar,
//! Ctrl-C handling and an atomic write.

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressStyle};

use super::args::RenderArgs;
use super::open_scene;
use crate::render::{output, post, Ended, Progressive, Stop};
use crate::report::converge::save_reference;

pub fn run(a: RenderArgs) -> Result<ExitCode> {
    let s = open_scene(&a.scene)?;
    if a.explain {
        eprintln!("plan for {}:\n{}", s.scene.name, s.plan.explain());
    }
    if let Some(view) = a.debug {
        if is_hdr(&a.output) {
            bail!("--debug views are PNG images; name the output .png");
        }
        return super::debug::run(&s, view, &a.output);
    }
    let stop = match (a.spp, a.time, a.target_error) {
        (_, Some(t), _) if !(t > 0.0 && t.is_finite()) => {
            bail!("--time must be a positive number of seconds")
        }
        (_, _, Some(e)) if !(e > 0.0 && e.is_finite()) => bail!("--target-error must be positive"),
        (Some(0), _, _) => bail!("--spp must be at least 1"),
        (spp, None, None) => Stop::spp(spp.unwrap_or(s.scene.settings.spp)),
        (_, seconds, error) => Stop {
            spp: None,
            seconds,
            error,
        },
    };
    if s.plan.deterministic && stop != Stop::spp(1) {
        eprintln!(
            "note: nothing in this scene is sampled, so one pass is exact; extra passes skipped"
        );
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        // Failing to install the handler only loses the clean Ctrl-C message.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let tracer = s.tracer();
    let bar = match stop.spp {
        Some(n) if !s.plan.deterministic => ProgressBar::new(n as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed} (eta {eta})")
                .unwrap(),
        ),
        _ => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {pos} spp  {elapsed}  {msg}").unwrap(),
        ),
    };
    let mut p = Progressive::new(s.width, s.height);
    let cancel = || interrupted.load(Ordering::Relaxed);
    let outcome = p.run(&tracer, &stop, &cancel, |film, _| {
        bar.set_position(film.spp as u64);
        bar.set_message(format!("error {:.3}%", film.relative_error() * 100.0));
    });
    if outcome.ended == Ended::Cancelled {
        bar.abandon();
        eprintln!("interrupted: nothing written");
        return Ok(ExitCode::from(130));
    }
    bar.finish_and_clear();
    let film = &p.film;
    if is_hdr(&a.output) {
        // The film's mean as it is: what `converge` and the TUI's
        // `--reference` compare against.
        save_reference(&a.output, s.width, s.height, &film.image())?;
    } else {
        let shown = post::display(
            film.image(),
            s.width,
            s.height,
            &s.plan,
            &s.scene.settings.bloom,
        );
        output::save_png_atomic(&post::to_rgb8(&shown.image, s.width, s.height), &a.output)?;
    }
    let err = if s.plan.deterministic {
        "exact".to_string()
    } else {
        format!("{:.3}%", film.relative_error() * 100.0)
    };
    let render_ms = outcome.seconds * 1e3;
    println!(
        "{}: {} triangles, build {:.1} ms ({}), render {}, {} spp, {:.2} Mrays/s, error {}{} -> {}",
        s.scene.name,
        s.scene.geometry.triangle_count(),
        s.bvh.stats.build_ms,
        s.bvh.stats.builder,
        duration(render_ms),
        film.spp,
        outcome.rays as f64 / render_ms.max(1e-9) / 1e3,
        err,
        if film.bad_count > 0 {
            format!(", {} NaN/Inf samples dropped", film.bad_count)
        } else {
            String::new()
        },
        a.output.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// `812.3 ms` below ten seconds, `24.9 s` from there.
fn duration(ms: f64) -> String {
    if ms < 1e4 {
        format!("{ms:.1} ms")
    } else {
        format!("{:.1} s", ms / 1e3)
    }
}

/// A `.hdr` output gets the linear film instead of a PNG.
fn is_hdr(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hdr"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_in_the_unit_that_fits() {
        assert_eq!(duration(812.34), "812.3 ms");
        assert_eq!(duration(24_927.9), "24.9 s");
        assert!(is_hdr(std::path::Path::new("ref.HDR")) && !is_hdr(std::path::Path::new("a.png")));
    }
}
