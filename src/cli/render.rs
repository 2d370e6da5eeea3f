//! `rayterm render`: progressive passes to an image file, with a progress
//! bar and an estimate of the time left, stopped cleanly by Ctrl-C, SIGTERM
//! or SIGHUP. The output is checked before anything renders.

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{bail, Result};
use glam::Vec3;

use super::args::{RenderArgs, MAX_SPP};
use super::open_request;
use super::progress::{Begin, Reporter};
use crate::interrupt::{self, Cancel};
use crate::raster::claim::Claim;
use crate::raster::{png, ImageFormat, Output};
use crate::render::aov;
use crate::render::partial::{self, Meta, Part};
use crate::render::session::check_film;
use crate::render::{post, Ended, Film, Job, Needs, Report, SceneRequest, Session, Stop};
use crate::scene::BloomSettings;
use crate::words;

pub(crate) fn run(a: RenderArgs) -> Result<ExitCode> {
    if let Some(frames) = a.turntable {
        return super::turntable::run(&a, frames);
    }
    let stop = stop(&a)?;
    let scene_file = scene_file(&a);
    let split = a.samples.is_some() || a.part.is_some();
    let formats = if split {
        &[ImageFormat::Exr][..]
    } else {
        ImageFormat::RENDERS
    };
    if split {
        partial_name(&a.output, "a part")?;
    }
    let out = Output::check(&a.output, &scene_file, formats)?;
    if a.debug.is_some() && out.format != ImageFormat::Png {
        bail!("--debug views are PNG images; name the output .png");
    }
    if !a.aov.is_empty() && out.format != ImageFormat::Exr {
        bail!(
            "--aov writes channels beside the picture in an OpenEXR file; name the output .exr, not {}",
            words::path(&a.output)
        );
    }
    // The checkpoint is claimed for the whole render, before it is read
    // or asked about: a second render of it is refused at once, where it
    // would write over the first's every few seconds.
    let mut _claim = None;
    let checkpoint = match &a.checkpoint {
        Some(c) => {
            if same_path(c, &a.output) {
                bail!(
                    "{} is the output; name the checkpoint another file",
                    words::path(c)
                );
            }
            partial_name(c, "a checkpoint")?;
            let out = Output::check(c, &scene_file, &[ImageFormat::Exr])?;
            if !out.in_place() {
                _claim = Some(Claim::take(c)?);
            }
            // A checkpoint left by an interrupted render is work to keep.
            if c.is_file() && !a.resume.as_deref().is_some_and(|r| same_path(r, c)) {
                bail!(
                    "{} already exists: continue the render it holds with --resume {}, or remove it",
                    words::path(c),
                    words::path(c)
                );
            }
            Some(out)
        }
        None => None,
    };
    // The film is checked against memory once it is known how much it
    // keeps.
    let mut s = open_request(&SceneRequest {
        check_film: false,
        ..a.scene.request()
    })?;
    if let Some((k, n)) = a.frame {
        s.set_camera(s.camera.turntable(k - 1, n));
    }
    let inputs = s.input_paths();
    out.check_not_input(&inputs)?;
    // The film resumed from is work to keep, not to write over.
    if let Some(r) = &a.resume {
        out.check_not_input(std::slice::from_ref(r))?;
    }
    if let Some(c) = &checkpoint {
        c.check_not_input(&inputs)?;
    }
    if a.explain {
        explain(&s);
    }
    if let Some(spec) = a.debug {
        check_film(s.width, s.height, Film::BYTES_PER_PIXEL)?;
        return super::debug::run(&s, spec, a.spp, &out, a.progress);
    }
    // A note only where the user asked for more than the one exact pass.
    if s.plan.deterministic && stop.is_some_and(|st| st != Stop::spp(1)) && !split {
        crate::noteln!(
            "note: nothing in this scene is sampled, so one pass is exact; extra passes skipped"
        );
    }
    let range = sample_range(&a, &s)?;
    let stop = match &range {
        Some((r, _)) => Stop::spp(r.end - r.start),
        None => stop.unwrap_or(Stop::spp(s.scene.settings.spp)),
    };
    let total = match &range {
        Some((_, total)) => *total,
        None => stop
            .spp
            .filter(|_| stop.seconds.is_none() && stop.error.is_none()),
    };
    // What a partial film says of its render, made only where one is read
    // or written: its content hash is a pass over all the scene's data.
    let mut meta = (split || checkpoint.is_some() || a.resume.is_some()).then(|| Meta {
        part: a.part,
        command: shared_options(),
        ..Meta::of(&s, total)
    });
    // A render that writes an image reads nothing else from its film; a
    // part of a split render writes the film's statistics, a checkpointed
    // one those of whole passes.
    let needs = match (checkpoint.is_some(), split) {
        (true, _) => Needs::WholePasses,
        (false, true) => Needs::Statistics,
        (false, false) => Needs::Image,
    };
    let part = match (&a.resume, &meta) {
        (Some(path), Some(meta)) => Some(resumed(
            path,
            &s,
            meta,
            range.as_ref().map(|r| &r.0),
            &stop,
        )?),
        _ => None,
    };
    let (rays_before, seconds_before) = part
        .as_ref()
        .map_or((0, 0.0), |p| (p.meta.rays, p.meta.seconds));
    // --time is the whole render's: a resumed one has spent some of it.
    let stop = Stop {
        seconds: stop.seconds.map(|t| (t - seconds_before).max(0.0)),
        ..stop
    };
    // The readout follows the rows of a pass as they finish.
    let rows = Arc::new(AtomicU32::new(0));
    let job = Job::new(s.width, s.height, &s.plan, stop)
        .samples_from(range.as_ref().map_or(0, |r| r.0.start))
        .needs(needs)
        // Adaptive where a time or an error ends the render, except into
        // partial films, which are uniform.
        .adaptive(
            !a.uniform
                && (stop.seconds.is_some() || stop.error.is_some())
                && checkpoint.is_none()
                && a.resume.is_none(),
        )
        .passes_for_stop()
        .rows_done(rows.clone());
    let job = match part {
        Some(part) => job.resume(part.film, rays_before, seconds_before),
        None => job,
    };
    let fixed = stop.seconds.is_none() && stop.error.is_none();
    // A resumed film was checked as it was read; a new one is checked
    // before it is allocated (under an address space limit even untouched
    // memory counts), dry run or not, and again with the AOVs' planes.
    if a.resume.is_none() {
        check_film(s.width, s.height, job.bytes_per_pixel())?;
    }
    if a.dry_run {
        return dry_run(&s, &job, checkpoint.is_some(), split);
    }
    if a.resume.is_none() && !a.aov.is_empty() {
        check_film(
            s.width,
            s.height,
            job.bytes_per_pixel() + aov::BYTES_PER_PIXEL,
        )?;
    }
    let mut p = job.start();
    interrupt::flag();
    let cancel = Cancel::Signal;
    let asked = interrupt::checkpoint_flag();
    let tracer = s.tracer();
    let held = p.film().start..p.film().start + p.film().spp;
    let report = Reporter::new(a.progress, &stop, s.plan.deterministic, p.film().spp);
    report.begin(&Begin {
        scene: &s.scene.name,
        size: (s.width, s.height),
        samples: range.as_ref().map(|r| r.0.clone()),
        total,
        resumed: a
            .resume
            .as_deref()
            .map(|path| (path, held.clone(), seconds_before)),
        frames: None,
    });
    let start = Instant::now();
    let every = a.checkpoint_every.unwrap_or(CHECKPOINT_SECONDS);
    // The first checkpoint follows the first pass: a render killed before
    // the interval loses no more than that pass.
    let mut last_checkpoint = None::<Instant>;
    let mut work = (rays_before, seconds_before);
    let mut failed = None;
    // Samples per pixel done, as f64 bits: an adaptive film's mean.
    let done_spp = AtomicU64::new((p.film().spp as f64).to_bits());
    let pass_spp = p.samples_per_pass();
    let finished = AtomicBool::new(false);
    let ticker = || {
        while !finished.load(Ordering::Relaxed) {
            let rows = rows.load(Ordering::Relaxed) as f64;
            let done = f64::from_bits(done_spp.load(Ordering::Relaxed));
            // Within a pass only where its samples are known; the last
            // pass may be shorter than the others.
            let within = match report.length().filter(|_| fixed) {
                Some(len) => (pass_spp as f64).min(len as f64 - done) * rows / s.height as f64,
                None => 0.0,
            };
            report.at(done + within.max(0.0));
            std::thread::park_timeout(std::time::Duration::from_millis(100));
        }
    };
    let mut warned_usr1 = false;
    let outcome = std::thread::scope(|scope| {
        let tick = (!report.quiet()).then(|| scope.spawn(ticker));
        let outcome = p.run(&tracer, cancel, |film, pass| {
            // Rows count the next pass's from here.
            rows.store(0, Ordering::Relaxed);
            let spp = film.spp_range().1;
            done_spp.store(spp.to_bits(), Ordering::Relaxed);
            if stop.spp.is_none() || stop.error.is_some() {
                let (text, left) = progress(film, &stop, start.elapsed().as_secs_f64());
                report.estimate(text, left);
            }
            report.at(spp);
            work.0 += pass.rays;
            work.1 += pass.ms / 1e3;
            let now = asked.swap(false, Ordering::Relaxed);
            match (&checkpoint, &mut meta) {
                (Some(c), Some(meta)) => {
                    let due = last_checkpoint.is_none_or(|t| t.elapsed().as_secs_f64() >= every);
                    if (due || now) && failed.is_none() {
                        (meta.rays, meta.seconds) = work;
                        failed = write_part(c, film, meta).err();
                        let range = film.start..film.start + film.spp;
                        report.checkpoint(&c.path, range, now || last_checkpoint.is_none());
                        last_checkpoint = Some(Instant::now());
                    }
                }
                _ if now && !warned_usr1 => {
                    warned_usr1 = true;
                    crate::noteln!("SIGUSR1: this render has no --checkpoint to write");
                }
                _ => {}
            }
        });
        finished.store(true, Ordering::Relaxed);
        if let Some(t) = tick {
            t.thread().unpark();
            let _ = t.join();
        }
        outcome
    });
    if let Some(e) = failed {
        report.abandon();
        return Err(e);
    }
    if let Some(meta) = &mut meta {
        (meta.rays, meta.seconds) = (p.rays(), p.seconds());
        // A render its --time ended has spent it all, though its passes'
        // own times leave out the checkpoints written between them: a
        // resume of it adds nothing.
        if let (Ended::Time, Some(t)) = (outcome.ended, a.time) {
            meta.seconds = meta.seconds.max(t);
        }
    }
    let checkpoint = checkpoint.as_ref().zip(meta.as_ref());
    if outcome.ended == Ended::Cancelled {
        report.abandon();
        return stopped(checkpoint, p.film(), true);
    }
    report.finish(p.film().spp_range().1);
    if let Some((c, meta)) = checkpoint {
        write_part(c, p.film(), meta)?;
    }
    let film = p.film();
    let bytes = match &meta {
        Some(meta) if split => partial::encode(film, meta)?,
        _ => {
            // Bloom and encoding take seconds on a large image: made on
            // their own thread, so that a signal meanwhile ends the render
            // at once, with nothing written.
            let (format, image, (w, h)) = (out.format, film.image(), (s.width, s.height));
            let bloom = s.plan.bloom.then_some(s.scene.settings.bloom);
            let aovs = match a.aov.is_empty() {
                true => Vec::new(),
                false => match aov::render(&tracer, &a.aov, cancel) {
                    Some(planes) => planes,
                    None => return stopped(checkpoint, film, false),
                },
            };
            let work = std::thread::spawn(move || match aovs.is_empty() {
                true => image_bytes(format, image, w, h, bloom.as_ref()),
                false => crate::raster::openexr::encode_with(w, h, &image, aovs),
            });
            while !work.is_finished() && !cancel.is_set() {
                std::thread::park_timeout(std::time::Duration::from_millis(20));
            }
            if !work.is_finished() {
                return stopped(checkpoint, film, false);
            }
            work.join()
                .map_err(|_| anyhow::anyhow!("making the image failed"))??
        }
    };
    if cancel.is_set() {
        return stopped(checkpoint, film, false);
    }
    match out.write_result(&bytes, cancel) {
        Err(e) if e.is::<interrupt::Interrupted>() => return stopped(checkpoint, film, false),
        written => written?,
    }
    let render_ms = outcome.seconds * 1e3;
    // A --time or --target-error render that the --max-spp cap ended says so.
    let cap = film.spp_range().2;
    let capped = match (outcome.ended, stop.error, stop.seconds) {
        (Ended::Spp, Some(e), _) if a.spp.is_none() => format!(
            " (stopped at the --max-spp cap of {cap} before reaching {}%)",
            percent(e)
        ),
        (Ended::Spp, None, Some(t)) if a.spp.is_none() => {
            format!(
                " (stopped at the --max-spp cap of {cap} before the --time of {} s)",
                crate::scene::show::show(t)
            )
        }
        _ => String::new(),
    };
    let head = format!(
        "{}: {}, build {} ({}), render {}",
        s.scene.name,
        words::count(
            s.scene.geometry.triangle_count() as u64,
            "triangle",
            "triangles"
        ),
        words::ms(s.bvh.stats.build_ms),
        s.bvh.stats.builder,
        words::ms(render_ms),
    );
    // A resumed render's rate is that of all its passes, the resumed
    // film's and this run's (which may have had nothing left to do).
    let (head, rays, ms) = match a.resume {
        Some(_) => (
            format!("{head} ({} in all)", words::ms(p.seconds() * 1e3)),
            p.rays(),
            p.seconds() * 1e3,
        ),
        None => (head, outcome.rays, render_ms),
    };
    let line = summary(
        &head,
        &film.report(),
        split,
        rays,
        ms,
        s.plan.deterministic,
        &capped,
        &a.output,
    );
    match out.is_stdout() {
        true => crate::noteln!("{line}"),
        false => crate::outln!("{line}")?,
    }
    if a.compare_one_shot {
        check_film(s.width, s.height, Film::SUMMARY_BYTES_PER_PIXEL)?;
        let again = p.retrace(&tracer, 0);
        let passes = rays as f64 / (ms.max(1e-6) / 1e3);
        let once = again.rays as f64 / (again.ms.max(1e-6) / 1e3);
        let line = format!(
            "the same samples in one pass: {} in {}; the passes' {} are {:.2}x that",
            words::rays_per_s(once),
            words::ms(again.ms),
            words::rays_per_s(passes),
            passes / once.max(1e-12)
        );
        match out.is_stdout() {
            true => crate::noteln!("{line}"),
            false => crate::outln!("{line}")?,
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The scene file itself, as an input no output may replace: checked
/// now, the files it names once they are read.
pub(super) fn scene_file(a: &RenderArgs) -> Vec<PathBuf> {
    Path::new(&a.scene.scene)
        .is_file()
        .then(|| PathBuf::from(&a.scene.scene))
        .into_iter()
        .collect()
}

/// `--explain`: the plan and what the materials and lights are.
pub(super) fn explain(s: &Session) {
    crate::noteln!(
        "plan for {}:\n{}{}\n",
        s.scene.name,
        s.plan.explain(),
        crate::scene::summary::explain(&s.scene, s.plan.path)
    );
}

/// The options of this `render` that every part of a split render shares,
/// as given: all but where it writes, what it resumes, which part it is
/// and how it reports, which each job has of its own.
fn shared_options() -> Vec<String> {
    const OWN_VALUE: [&str; 9] = [
        "-o",
        "--output",
        "--checkpoint",
        "--resume",
        "--part",
        "--samples",
        "--progress",
        "--checkpoint-every",
        "--threads",
    ];
    const OWN: [&str; 2] = ["--explain", "--dry-run"];
    let args: Vec<String> = std::env::args_os()
        .skip(2)
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    let mut kept = Vec::new();
    let mut words = args.into_iter();
    while let Some(w) = words.next() {
        let name = w.split_once('=').map_or(w.as_str(), |(n, _)| n);
        if OWN_VALUE.contains(&name) {
            if !w.contains('=') {
                words.next();
            }
        } else if !(OWN.contains(&name) || w.starts_with("-o") && w.len() > 2) {
            kept.push(w);
        }
    }
    kept
}

/// `render --dry-run`: what the render will take, from the scene as
/// loaded and built and the film as it will be, and nothing rendered.
fn dry_run(s: &Session, job: &Job, checkpoint: bool, split: bool) -> Result<ExitCode> {
    use crate::memory::{bytes, mesh_bytes};
    let g = &s.scene.geometry;
    let (tris, verts) = (g.triangle_count() as u64, g.positions.len() as u64);
    let pixels = s.width as u64 * s.height as u64;
    let mesh = mesh_bytes(verts, tris);
    let mut textures: Vec<&crate::scene::texture::Texture> = s.scene.textures.iter().collect();
    match &s.scene.environment {
        crate::scene::Environment::CubeMap(c) => textures.extend(c.faces.iter()),
        crate::scene::Environment::Light(l) => textures.extend(l.map()),
        crate::scene::Environment::Color(_) => {}
    }
    let texels: u64 = textures.iter().map(|t| t.texels.len() as u64 * 12).sum();
    let per_pixel = job.bytes_per_pixel();
    let film = per_pixel * pixels;
    // A checkpointing pass keeps each row's statistics as they were
    // before it, to undo a pass cut short; a partial film is encoded
    // whole in memory before it is written.
    let stats = std::mem::size_of::<crate::render::film::PixelStats>() as u64;
    let undo = if job.whole_passes() {
        stats * pixels
    } else {
        0
    };
    let encoded = if checkpoint || split {
        PARTIAL_BYTES * pixels
    } else {
        0
    };
    let peak = PROGRAM_BYTES + mesh + texels + film + undo.max(encoded);
    let rows = [
        ("triangles", format!("{tris} ({verts} vertices)")),
        (
            "scene + BVH",
            format!(
                "{} while built (the BVH {})",
                bytes(mesh),
                bytes(s.bvh.bytes())
            ),
        ),
        ("textures", bytes(texels)),
        (
            "film",
            format!("{} ({per_pixel} bytes a pixel)", bytes(film)),
        ),
        (
            "checkpoints",
            match (checkpoint, split) {
                (false, false) => "none".to_string(),
                _ => format!(
                    "at most {} a file ({PARTIAL_BYTES} bytes a pixel), made in memory",
                    bytes(encoded)
                ),
            },
        ),
        (
            "peak memory",
            format!(
                "about {} ({peak} bytes; {} available)",
                bytes(peak),
                bytes(crate::memory::available())
            ),
        ),
    ];
    crate::outln!(
        "{} at {}x{}: a dry run, nothing rendered",
        s.scene.name,
        s.width,
        s.height
    )?;
    for (what, value) in rows {
        crate::outln!("  {what:<12} {value}")?;
    }
    Ok(ExitCode::SUCCESS)
}

/// The most bytes a pixel of a partial film takes (the mean and every
/// word of its statistics).
const PARTIAL_BYTES: u64 = 152;

/// What the program takes before any scene: its code, its threads'
/// stacks, the allocator's arenas (measured: 9 MB for `render cornell` at
/// 8x8).
const PROGRAM_BYTES: u64 = 12 << 20;

/// Refuses a partial film (`what`) named for another image format; other
/// faults of the path are `Output::check`'s to name.
fn partial_name(path: &Path, what: &str) -> Result<()> {
    match ImageFormat::of(path) {
        Some(f) if f != ImageFormat::Exr => bail!(
            "{}: {what} is a partial film: name it .exr",
            words::path(path)
        ),
        _ => Ok(()),
    }
}

/// The most samples per pixel --time and --target-error add unless told.
const DEFAULT_MAX_SPP: u32 = 4096;

/// Seconds between checkpoints unless --checkpoint-every says.
const CHECKPOINT_SECONDS: f64 = 5.0;

/// Ends a render a signal stopped: the film goes to the checkpoint, if
/// there is one and the film holds a sample (`write`: not written yet);
/// nothing else is written.
fn stopped(checkpoint: Option<(&Output, &Meta)>, f: &Film, write: bool) -> Result<ExitCode> {
    match checkpoint {
        Some((c, meta)) if f.spp > 0 => {
            if write {
                write_part(c, f, meta)?;
            }
            crate::noteln!(
                "interrupted: {} holds samples {}..{}; continue with --resume {}",
                words::path(&c.path),
                f.start,
                f.start + f.spp,
                words::path(&c.path)
            );
        }
        _ => crate::noteln!("interrupted: nothing written"),
    }
    Ok(ExitCode::from(interrupt::exit_code()))
}

/// The image file `render` and `merge` write from a film: the linear mean
/// as it is for .exr and .hdr (what `converge` and the TUI's `--reference`
/// compare against), the post-processed picture for .png.
pub(crate) fn image_bytes(
    format: ImageFormat,
    image: Vec<Vec3>,
    width: u32,
    height: u32,
    bloom: Option<&BloomSettings>,
) -> Result<Vec<u8>> {
    match format {
        ImageFormat::Hdr
        | ImageFormat::Exr
        | ImageFormat::Csv
        | ImageFormat::Gif
        | ImageFormat::Apng => format.encode_linear(width, height, &image),
        ImageFormat::Png => {
            let mut image = image;
            if let Some(b) = bloom {
                post::bloom(&mut image, width as usize, height as usize, b);
            }
            png::encode(&post::to_rgb8(&image, width, height))
        }
    }
}

/// The line a render or merge ends with: `head`, the samples, speed and
/// error, and the output.
#[allow(clippy::too_many_arguments)]
pub(crate) fn summary(
    head: &str,
    film: &Report,
    split: bool,
    rays: u64,
    render_ms: f64,
    exact: bool,
    capped: &str,
    output: &std::path::Path,
) -> String {
    let err = if exact {
        "error exact".to_string()
    } else {
        error_text(film.relative_error, film.spp.0)
    };
    let samples = if split {
        let r = &film.samples;
        format!("{} spp (samples {}..{})", r.len(), r.start, r.end)
    } else {
        spp_text(film)
    };
    format!(
        "{head}, {samples}, {}, {err}{capped}{} -> {}",
        // Parts that record no time (edited by hand) have no rate.
        match render_ms > 0.0 {
            true => words::rays_per_s(rays as f64 / (render_ms / 1e3)),
            false => "no time recorded".to_string(),
        },
        if film.bad_count > 0 {
            format!(", {} NaN/Inf samples dropped", film.bad_count)
        } else {
            String::new()
        },
        words::path(output)
    )
}

/// Whether two paths name the same file, existing or not.
fn same_path(a: &std::path::Path, b: &std::path::Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y,
        _ => std::path::absolute(a).ok() == std::path::absolute(b).ok(),
    }
}

/// Writes `film` as a partial film to `out`, atomically.
fn write_part(out: &Output, film: &Film, meta: &Meta) -> Result<()> {
    out.write(&partial::encode(film, meta)?)
}

/// The sample range a split render renders, and the total it is part of.
fn sample_range(a: &RenderArgs, s: &Session) -> Result<Option<(Range<u32>, Option<u32>)>> {
    let total = a.spp.unwrap_or(s.scene.settings.spp).min(MAX_SPP);
    let range = match (&a.samples, a.part) {
        (Some(r), _) => (r.clone(), None),
        (None, Some((k, n))) => {
            let at = |i: u32| (i as u64 * total as u64 / n as u64) as u32;
            let r = at(k - 1)..at(k);
            if r.is_empty() {
                bail!(
                    "part {k}/{n} of {total} samples has none: split {total} samples into at most {total} parts"
                );
            }
            (r, Some(total))
        }
        (None, None) => return Ok(None),
    };
    if s.plan.deterministic && range.0 != (0..1) {
        bail!(
            "nothing in this scene is sampled, so one sample is the exact image: render samples 0..1 (or part 1/1) only"
        );
    }
    Ok(Some(range))
}

/// The checkpoint of this render to continue.
fn resumed(
    path: &std::path::Path,
    s: &Session,
    meta: &Meta,
    range: Option<&Range<u32>>,
    stop: &Stop,
) -> Result<Part> {
    let part = Part::read(path)?;
    part.header()
        .check_same(meta, (s.width, s.height), &words::path(path), "this render")?;
    let want = range.map_or(0, |r| r.start);
    let held = part.range();
    if held.start != want {
        bail!(
            "{} holds samples {}..{}; this render starts at sample {want}",
            words::path(path),
            held.start,
            held.end
        );
    }
    if let Some(n) = stop.spp.filter(|&n| part.film.spp > n) {
        bail!(
            "{} already holds {} samples per pixel, more than the {n} this render takes \
             (--spp, or the scene's)",
            words::path(path),
            part.film.spp
        );
    }
    Ok(part)
}

/// The stop the options ask for; `None` means the scene's spp.
pub(super) fn stop(a: &RenderArgs) -> Result<Option<Stop>> {
    if let Some(t) = a.time {
        if !(t > 0.0 && t.is_finite()) {
            bail!("--time must be a positive number of seconds");
        }
    }
    if let Some(e) = a.target_error {
        if !(e > 0.0 && e.is_finite()) {
            bail!("--target-error must be a positive fraction (0.01 for 1 %)");
        }
    }
    Ok(match (a.spp, a.time, a.target_error) {
        (Some(n), _, _) => Some(Stop::spp(n)),
        (None, None, None) => None,
        (None, seconds, error) => Some(Stop {
            spp: Some(a.max_spp.unwrap_or(DEFAULT_MAX_SPP)),
            seconds,
            error,
        }),
    })
}

/// A target error as a percentage, as short as it reads: `1`, `0.25`,
/// `1.00e-298`.
fn percent(e: f64) -> String {
    let p = e * 100.0;
    let fixed = format!("{p:.6}");
    let fixed = fixed.trim_end_matches('0').trim_end_matches('.');
    if fixed == "0" || fixed == "-0" {
        format!("{p:.2e}")
    } else {
        fixed.to_string()
    }
}

/// `64 spp`, or `16 / 75.4 / 880 spp (min / mean / max, adaptive)` where
/// pixels differ.
fn spp_text(film: &Report) -> String {
    match film.spp {
        (min, mean, max) if film.adaptive && min < max => {
            format!("{min} / {mean:.1} / {max} spp (min / mean / max, adaptive)")
        }
        (n, ..) => format!("{n} spp"),
    }
}

/// The estimated error, or why it is not known after `spp` samples in
/// the sparest pixel.
fn error_text(relative_error: Option<f64>, spp: u32) -> String {
    match relative_error {
        Some(e) => format!("error {:.3}%", e * 100.0),
        None => words::error_unknown(spp).into(),
    }
}

/// The error and the time left for a render that stops on time or error,
/// in words and in seconds: the error of a sampled image falls as
/// 1/sqrt(spp), which says how many samples the target needs.
fn progress(film: &Film, stop: &Stop, elapsed: f64) -> (String, Option<f64>) {
    // An adaptive film's mean spp: what its time is spent on.
    let spp = film.spp_range().1;
    let per_spp = elapsed / spp.max(1.0);
    let cap = stop.spp.unwrap_or(u32::MAX) as f64;
    let mut left = stop
        .seconds
        .map_or(f64::INFINITY, |t| (t - elapsed).max(0.0));
    let mut text = error_text(film.relative_error(), film.spp_range().0);
    let err = film.relative_error().filter(|&e| e > 0.0);
    if let (Some(target), Some(err)) = (stop.error, err) {
        let need = (spp * (err / target).powi(2)).min(cap);
        left = left.min((need - spp).max(0.0) * per_spp);
        text += &format!(" (target {}%, about {need:.0} spp)", percent(target));
    }
    left = left.min((cap - spp).max(0.0) * per_spp);
    if left.is_finite() {
        text += &format!(", eta {}", words::ms(left * 1e3));
    }
    (text, left.is_finite().then_some(left))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn targets_read_short() {
        assert_eq!(percent(0.01), "1");
        assert_eq!(percent(0.0025), "0.25");
        assert_eq!(percent(1e-300), "1.00e-298");
    }

    #[test]
    fn durations_read_in_the_unit_that_fits() {
        assert_eq!(words::ms(812.34), "812 ms");
        assert_eq!(words::ms(3731.8), "3.73 s");
        assert_eq!(words::ms(24_927.9), "24.9 s");
        assert_eq!(words::ms(125_400.0), "2 min 05 s");
    }

    #[test]
    fn progress_estimates_the_time_to_the_target() {
        let mut f = Film::new(1, 1);
        for k in 0..4 {
            let c = glam::Vec3::splat(if k % 2 == 0 { 0.4 } else { 0.6 });
            f.add(0, 0, k, None, c);
        }
        f.spp = 4;
        let stop = Stop {
            spp: Some(4096),
            seconds: None,
            error: Some(f.relative_error().unwrap() / 2.0),
        };
        // Half the error needs four times the samples: 12 more, at 0.25 s each.
        let (text, left) = progress(&f, &stop, 1.0);
        assert!(
            text.contains("about 16 spp") && text.ends_with("eta 3.00 s"),
            "{text}"
        );
        assert_eq!(left, Some(3.0));
        let timed = Stop {
            seconds: Some(5.0),
            ..Stop::default()
        };
        assert!(progress(&f, &timed, 1.0).0.ends_with("eta 4.00 s"));
    }
}
