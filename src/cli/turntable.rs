//! `render --turntable N`: the camera orbits its target once in N frames,
//! each rendered as `render` renders one picture, then joined into a GIF
//! or APNG; and `rayterm animate`, which joins frames rendered apart
//! (`render --frame K/N`, one job of an array each).

use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};

use super::args::{AnimateArgs, RenderArgs};
use super::open_request;
use super::progress::{Begin, Reporter};
use super::render::{explain, scene_file, stop};
use crate::interrupt::{self, Cancel};
use crate::raster::animation::{self, Frames};
use crate::raster::{ImageFormat, Output};
use crate::render::session::check_film;
use crate::render::{post, Job, Needs, SceneRequest, Stop};
use crate::words;

/// Frames a second unless --fps says.
pub(crate) const DEFAULT_FPS: u32 = 15;

pub(crate) fn run(a: &RenderArgs, frames: u32) -> Result<ExitCode> {
    let stop = stop(a)?;
    let out = Output::check(&a.output, &scene_file(a), ImageFormat::ANIMATIONS)?;
    let s = open_request(&SceneRequest {
        check_film: false,
        ..a.scene.request()
    })?;
    out.check_not_input(&s.input_paths())?;
    if a.explain {
        explain(&s);
    }
    let stop = stop.unwrap_or(Stop::spp(s.scene.settings.spp));
    let (w, h) = (s.width, s.height);
    let adaptive = !a.uniform && (stop.seconds.is_some() || stop.error.is_some());
    let job = || {
        Job::new(w, h, &s.plan, stop)
            .needs(Needs::Image)
            .adaptive(adaptive)
            .passes_for_stop()
    };
    // One film at a time, and every frame's pixels until they are joined
    // (twice over while encoded).
    check_film(w, h, job().bytes_per_pixel())?;
    crate::memory::check(
        &format!("{frames} frames of {w}x{h}"),
        2 * frames as u64 * w as u64 * h as u64 * 3,
        None,
    )?;
    let fps = a.fps.unwrap_or(DEFAULT_FPS);
    interrupt::flag();
    let cancel = Cancel::Signal;
    // Progress counts the samples of every frame, in one run.
    let fixed = stop.seconds.is_none() && stop.error.is_none();
    let whole = Stop {
        spp: stop.spp.map(|n| n.saturating_mul(frames)),
        seconds: stop.seconds.map(|t| t * frames as f64),
        error: stop.error,
    };
    let report = Reporter::new(a.progress, &whole, s.plan.deterministic, 0);
    report.begin(&Begin {
        scene: &s.scene.name,
        size: (w, h),
        samples: None,
        total: whole.spp.filter(|_| fixed),
        resumed: None,
        frames: Some(frames),
    });
    let start = Instant::now();
    let bloom = s.plan.bloom.then_some(s.scene.settings.bloom);
    let (mut rgb, mut rays, mut done) = (Vec::new(), 0u64, 0.0);
    for k in 0..frames {
        report.estimate(format!("frame {} of {frames}", k + 1), None);
        let camera = s.camera.turntable(k, frames);
        let tracer = s.tracer_for(&s.plan, &camera, (w, h));
        let mut p = job().start();
        let outcome = p.run(&tracer, cancel, |film, _| {
            report.at(done + film.spp_range().1);
        });
        if cancel.is_set() {
            report.abandon();
            crate::noteln!("interrupted: nothing written");
            return Ok(ExitCode::from(interrupt::exit_code()));
        }
        rays += outcome.rays;
        done += p.film().spp_range().1;
        let mut image = p.film().image();
        if let Some(b) = &bloom {
            post::bloom(&mut image, w as usize, h as usize, b);
        }
        rgb.push(post::to_rgb8(&image, w, h).into_raw());
    }
    report.finish(done);
    let bytes = encode(out.format, w, h, fps, &rgb)?;
    if cancel.is_set() {
        crate::noteln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    match out.write_result(&bytes, cancel) {
        Err(e) if e.is::<interrupt::Interrupted>() => {
            crate::noteln!("interrupted: nothing written");
            return Ok(ExitCode::from(interrupt::exit_code()));
        }
        written => written?,
    }
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let line = format!(
        "{}: turntable of {frames} frames at {w}x{h}, {:.0} spp a frame on average, render {}, {} -> {} ({fps} frames a second)",
        s.scene.name,
        done / frames as f64,
        crate::words::ms(ms),
        words::rays_per_s(rays as f64 / (ms.max(1e-6) / 1e3)),
        words::path(&a.output),
    );
    match out.is_stdout() {
        true => crate::noteln!("{line}"),
        false => crate::outln!("{line}")?,
    }
    Ok(ExitCode::SUCCESS)
}

/// The frames as the animation `format` names (a `.png` is an APNG).
fn encode(format: ImageFormat, w: u32, h: u32, fps: u32, rgb: &[Vec<u8>]) -> Result<Vec<u8>> {
    let frames = Frames {
        width: w,
        height: h,
        fps,
        rgb,
    };
    match format {
        ImageFormat::Gif => animation::gif(&frames),
        _ => animation::apng(&frames),
    }
}

/// `rayterm animate`: PNG frames, in the order given, into one animation.
pub(crate) fn animate(a: AnimateArgs) -> Result<ExitCode> {
    let out = Output::check(&a.output, &a.frames, ImageFormat::ANIMATIONS)?;
    let mut rgb = Vec::with_capacity(a.frames.len());
    let mut size = None;
    for path in &a.frames {
        let (w, h, pixels) = crate::raster::png::read_rgb(path)?;
        match size {
            None => size = Some((w, h, path)),
            Some((w0, h0, first)) if (w0, h0) != (w, h) => bail!(
                "{} is {w}x{h}, but {} is {w0}x{h0}: an animation's frames are of one size",
                words::path(path),
                words::path(first)
            ),
            Some(_) => {}
        }
        rgb.push(pixels);
    }
    let Some((w, h, _)) = size else {
        bail!("no frames to animate");
    };
    let bytes = encode(out.format, w, h, a.fps, &rgb)?;
    out.write_result(&bytes, Cancel::Signal)?;
    crate::outln!(
        "{} frames of {w}x{h} -> {} ({} frames a second)",
        rgb.len(),
        words::path(&a.output),
        a.fps
    )?;
    Ok(ExitCode::SUCCESS)
}
