//! `rayterm render`: progressive passes to a PNG, with a progress bar,
//! Ctrl-C handling and an atomic write.

use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Result};
use indicatif::{ProgressBar, ProgressStyle};

use super::args::{RenderArgs, SceneOpts};
use crate::bvh::{self, Bvh};
use crate::render::{output, pass, post, Features, Film, Plan, Tracer};
use crate::report::converge::save_reference;
use crate::scene::{self, Scene};

/// A scene loaded and ready to render with the options given.
pub struct Prepared {
    pub scene: Scene,
    pub bvh: Bvh,
    pub plan: Plan,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
}

impl Prepared {
    pub fn tracer(&self) -> Tracer<'_> {
        Tracer::new(
            &self.scene,
            &self.bvh,
            &self.plan,
            self.width,
            self.height,
            self.seed,
        )
    }
}

pub fn prepare(o: &SceneOpts) -> Result<Prepared> {
    let mut scene = scene::load(&o.scene)?;
    crate::report::stability::check_reach(&scene)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(b) = o.builder {
        scene.settings.builder = b;
    }
    let st = &mut scene.settings;
    st.light_samples = o.light_samples.unwrap_or(st.light_samples);
    st.glossy_samples = o.glossy_samples.unwrap_or(st.glossy_samples);
    st.stratify &= !o.independent;
    let (width, height) = o
        .size
        .unwrap_or((scene.settings.width, scene.settings.height));
    let features = Features::all().without(&o.off);
    let plan = if o.no_plan {
        Plan::everything(&scene, features)
    } else {
        Plan::new(&scene, features)
    };
    let bvh = bvh::build(&scene.geometry, scene.settings.builder);
    Ok(Prepared {
        scene,
        bvh,
        plan,
        width,
        height,
        seed: o.seed,
    })
}

/// When to stop adding passes.
enum Stop {
    Spp(u32),
    Time(f64),
    Error(f64),
}

pub fn run(a: RenderArgs) -> Result<ExitCode> {
    let p = prepare(&a.scene)?;
    if a.explain {
        eprintln!("plan for {}:\n{}", p.scene.name, p.plan.explain());
    }
    if let Some(view) = a.debug {
        if is_linear(&a.output) {
            bail!("--debug views are PNG images; name the output .png");
        }
        return super::debug::run(&p, view, &a.output);
    }
    let mut stop = match (a.spp, a.time, a.target_error) {
        (_, Some(t), _) if !(t > 0.0 && t.is_finite()) => {
            bail!("--time must be a positive number of seconds")
        }
        (_, _, Some(e)) if !(e > 0.0 && e.is_finite()) => bail!("--target-error must be positive"),
        (_, Some(t), _) => Stop::Time(t),
        (_, _, Some(e)) => Stop::Error(e),
        (Some(0), _, _) => bail!("--spp must be at least 1"),
        (Some(n), _, _) => Stop::Spp(n),
        (None, None, None) => Stop::Spp(p.scene.settings.spp),
    };
    if p.plan.deterministic {
        if !matches!(stop, Stop::Spp(1)) {
            eprintln!("note: nothing in this scene is sampled, so one pass is exact; extra passes skipped");
        }
        stop = Stop::Spp(1);
    }
    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        // Failing to install the handler only loses the clean Ctrl-C message.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    let tracer = p.tracer();
    let mut film = Film::new(p.width, p.height);
    let bar = match stop {
        Stop::Spp(n) => ProgressBar::new(n as u64).with_style(
            ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed} (eta {eta})")
                .unwrap(),
        ),
        _ => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {pos} spp  {elapsed}  {msg}").unwrap(),
        ),
    };
    let start = Instant::now();
    let mut rays = 0u64;
    let cancel = || interrupted.load(Ordering::Relaxed);
    loop {
        rays += pass::render_pass(&tracer, &mut film, 1, &cancel);
        if cancel() {
            bar.abandon();
            eprintln!("interrupted: nothing written");
            return Ok(ExitCode::from(130));
        }
        bar.inc(1);
        let err = film.relative_error();
        bar.set_message(error_text(err));
        let done = match stop {
            Stop::Spp(n) => film.spp >= n,
            Stop::Time(t) => start.elapsed().as_secs_f64() >= t,
            Stop::Error(e) => film.error_is_meaningful() && err.is_some_and(|err| err < e),
        };
        if done {
            break;
        }
    }
    let render_ms = start.elapsed().as_secs_f64() * 1e3;
    bar.finish_and_clear();
    let mut img = film.image();
    if is_linear(&a.output) {
        // The film's mean as it is: what `converge` and the TUI's
        // `--reference` compare against.
        save_reference(&a.output, p.width, p.height, &img)?;
    } else {
        if p.plan.bloom {
            post::bloom(
                &mut img,
                p.width as usize,
                p.height as usize,
                &p.scene.settings.bloom,
            );
        }
        output::save_png_atomic(&post::to_rgb8(&img, p.width, p.height), &a.output)?;
    }
    let err = if p.plan.deterministic {
        "error exact".to_string()
    } else {
        error_text(film.relative_error())
    };
    println!(
        "{}: {} triangles, build {:.1} ms ({}), render {}, {} spp, {:.2} Mrays/s, {}{} -> {}",
        p.scene.name,
        p.scene.geometry.triangle_count(),
        p.bvh.stats.build_ms,
        p.bvh.stats.builder,
        duration(render_ms),
        film.spp,
        rays as f64 / render_ms / 1e3,
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

/// The estimated error, or that it is unknown until two samples.
fn error_text(err: Option<f64>) -> String {
    match err {
        Some(e) => format!("error {:.3}%", e * 100.0),
        None => "error unknown until 2 spp".into(),
    }
}

/// `812.3 ms` below ten seconds, `24.9 s` from there.
fn duration(ms: f64) -> String {
    if ms < 1e4 {
        format!("{ms:.1} ms")
    } else {
        format!("{:.1} s", ms / 1e3)
    }
}

/// A `.exr` or `.hdr` output gets the linear film instead of a PNG.
fn is_linear(path: &std::path::Path) -> bool {
    crate::raster::Linear::of(path).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_read_in_the_unit_that_fits() {
        assert_eq!(duration(812.34), "812.3 ms");
        assert_eq!(duration(24_927.9), "24.9 s");
        assert!(
            is_linear(std::path::Path::new("ref.HDR")) && !is_linear(std::path::Path::new("a.png"))
        );
        assert!(is_linear(std::path::Path::new("ref.exr")));
    }
}
