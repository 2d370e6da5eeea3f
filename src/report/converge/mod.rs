//! Error against run time: renders a scene at a series of budgets, each an
//! independent run with several seeds, measures the true error against a
//! reference image and the film's own estimate of it, and compares sampling
//! strategies at equal time.
//!
//! Errors are taken on Rec. 709 luminance, the quantity whose variance the
//! film tracks, so that the estimate and the truth measure the same thing:
//! `relMSE = mean over pixels of (x - ref)^2 / (ref^2 + 0.01)`, and the
//! "relative error" is its square root.

mod plot;
mod reference;
mod report;

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use glam::Vec3;

pub(crate) use crate::color::luminance;
pub use crate::raster::metrics::{rel_mse, rmse};
pub use plot::draw as plot;
pub use reference::save_reference;
pub(crate) use reference::{default_cache_dir, format_floor};

use crate::bvh::Bvh;
use crate::interrupt::{Cancel, Interrupted};
use crate::render::{Ended, Film, Job, Plan, Stop, Tracer};
use crate::report::stats::{fit_log_log, log_lerp, median};
use crate::report::Progress;
use crate::scene::{Integrator, Scene, Settings};
use reference::{load_cached, reference_key, save_cached};

/// A rendered reference has this many times the samples of the largest budget...
const REFERENCE_FACTOR: u32 = 64;
/// ...but at most this many samples per pixel unless asked for more.
const REFERENCE_MAX_SPP: u32 = 1024;
/// Reference seeds lie this far from the study's, so they never coincide.
const REFERENCE_SEED_OFFSET: u64 = 1 << 32;
/// Light samples per hit compared for scenes with area lights.
const LIGHT_SAMPLES: [u32; 4] = [1, 4, 16, 64];
/// Glossy directions per hit compared for scenes with glossy materials.
const GLOSSY_SAMPLES: [u32; 3] = [1, 4, 16];
/// Compared strategies double their spp until they reach the scene's
/// largest time, or this many spp.
const MAX_COMPARE_SPP: u32 = 4096;
/// The flattest slope of log(error) against log(spp) extrapolated from.
const MIN_FALL: f64 = -0.1;

/// Error against samples or time once strata are used up: Monte Carlo's.
const ASYMPTOTIC_SLOPE: f64 = -0.5;
/// A run that overshoots a time by at most this factor still counts as at it.
const TIME_SLACK: f64 = 1.25;

/// How one run is limited.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunLimit {
    Spp(u32),
    Seconds(f64),
}

impl std::fmt::Display for RunLimit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunLimit::Spp(n) => write!(f, "{n} spp"),
            RunLimit::Seconds(s) => write!(f, "{s} s"),
        }
    }
}

/// The sampling settings a strategy varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Strategy {
    pub(crate) light_samples: u32,
    pub(crate) glossy_samples: u32,
    pub(crate) stratify: bool,
    /// Passes after the minimum go to the pixels with the highest error.
    pub(crate) adaptive: bool,
    /// How light is followed: a strategy of another integrator converges
    /// to its own image, so against the reference its error levels off.
    pub(crate) integrator: Integrator,
}

/// Which sampled effects the plan runs, so labels name only those.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Uses {
    pub(crate) area_lights: bool,
    pub(crate) glossy: bool,
    pub(crate) supersampling: bool,
    /// The plan's integrator: labels name another.
    pub(crate) integrator: Integrator,
}

impl Uses {
    pub(crate) fn of(scene: &Scene, plan: &Plan) -> Self {
        Self {
            area_lights: plan.area_sampling && scene.lights.iter().any(|l| l.is_area()),
            glossy: plan.glossy,
            supersampling: plan.supersampling,
            integrator: plan.integrator,
        }
    }
}

impl Strategy {
    /// The strategy of settings `s` rendered under `plan`.
    pub(crate) fn of(s: &Settings, plan: &Plan) -> Self {
        Self {
            light_samples: s.light_samples,
            glossy_samples: s.glossy_samples,
            stratify: s.stratify,
            adaptive: false,
            integrator: plan.integrator,
        }
    }

    pub(crate) fn apply(&self, s: &mut Settings) {
        s.light_samples = self.light_samples;
        s.glossy_samples = self.glossy_samples;
        s.stratify = self.stratify;
        s.integrator = Some(self.integrator);
    }

    /// E.g. `L16 jittered`: light samples per hit (`L`), glossy directions
    /// per hit (`G`), and whether pixel and light samples are stratified,
    /// where the scene uses them.
    pub(crate) fn label(&self, uses: Uses) -> String {
        let mut parts = Vec::new();
        if self.integrator != uses.integrator {
            parts.push(self.integrator.to_string());
        }
        if uses.area_lights {
            parts.push(format!("L{}", self.light_samples));
        }
        if uses.glossy {
            parts.push(format!("G{}", self.glossy_samples));
        }
        if uses.area_lights || uses.supersampling {
            parts.push(
                if self.stratify {
                    "jittered"
                } else {
                    "independent"
                }
                .to_string(),
            );
        }
        if parts.is_empty() {
            return "nothing sampled".into();
        }
        if self.adaptive {
            parts.push("adaptive".into());
        }
        parts.join(" ")
    }

    /// The command-line options that select this strategy.
    pub(crate) fn options(&self, uses: Uses) -> String {
        let mut o = Vec::new();
        if self.integrator != uses.integrator {
            o.push(format!("--integrator {}", self.integrator));
        }
        if uses.area_lights {
            o.push(format!("--light-samples {}", self.light_samples));
        }
        if uses.glossy {
            o.push(format!("--glossy-samples {}", self.glossy_samples));
        }
        if !self.stratify {
            o.push("--independent".to_string());
        }
        if self.adaptive {
            o.push("adaptive: render --time or --target-error".to_string());
        }
        o.join(" ")
    }

    /// The strategies worth comparing with `base` on a scene that uses `uses`:
    /// the other integrator, light samples per hit, glossy samples per hit,
    /// independent sampling, adaptive sampling.
    pub(crate) fn alternatives(base: Strategy, uses: Uses) -> Vec<Strategy> {
        let mut out = vec![Strategy {
            integrator: match base.integrator {
                Integrator::Path => Integrator::Whitted,
                Integrator::Whitted => Integrator::Path,
            },
            ..base
        }];
        if uses.area_lights {
            out.extend(LIGHT_SAMPLES.iter().map(|&l| Strategy {
                light_samples: l,
                ..base
            }));
        }
        if uses.glossy {
            out.extend(GLOSSY_SAMPLES.iter().map(|&g| Strategy {
                glossy_samples: g,
                ..base
            }));
        }
        if uses.area_lights || uses.supersampling {
            out.push(Strategy {
                stratify: !base.stratify,
                ..base
            });
        }
        if uses.area_lights || uses.glossy || uses.supersampling {
            out.push(Strategy {
                adaptive: !base.adaptive,
                ..base
            });
        }
        let mut seen = vec![base];
        out.retain(|s| {
            let new = !seen.contains(s);
            seen.push(*s);
            new
        });
        out
    }
}

/// One budget of one strategy, averaged over seeds.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub budget: RunLimit,
    /// Mean samples per pixel reached.
    pub spp: f64,
    /// Median wall time of a run (robust to a run slowed by other work).
    pub(crate) seconds: f64,
    /// Mean rays traced by a run.
    pub(crate) rays: f64,
    /// Root of the mean squared error over seeds.
    pub rmse: f64,
    pub rel_mse: f64,
    /// The films' own relMSE estimate; `None` with one sample per pixel.
    pub est_rel_mse: Option<f64>,
}

impl Point {
    /// Relative error: the square root of relMSE.
    pub fn rel_err(&self) -> f64 {
        self.rel_mse.sqrt()
    }

    pub(crate) fn est_err(&self) -> Option<f64> {
        self.est_rel_mse.map(f64::sqrt)
    }

    /// Estimated over true relative error.
    pub fn ratio(&self) -> Option<f64> {
        let e = self.est_err()?;
        (self.rel_mse > 0.0).then(|| e / self.rel_err())
    }

    pub(crate) fn mrays_per_s(&self) -> f64 {
        if self.seconds > 0.0 {
            self.rays / self.seconds / 1e6
        } else {
            0.0
        }
    }
}

/// Where a series reaches a target error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Reach {
    pub(crate) spp: f64,
    pub(crate) seconds: f64,
    /// Inside the measured range (interpolated) rather than extrapolated.
    pub(crate) measured: bool,
}

/// One strategy's points, in budget order.
#[derive(Clone, Debug)]
pub struct Series {
    pub(crate) strategy: Strategy,
    pub label: String,
    pub points: Vec<Point>,
}

impl Series {
    fn pairs(&self, x: impl Fn(&Point) -> f64) -> Vec<(f64, f64)> {
        self.points.iter().map(|p| (x(p), p.rel_err())).collect()
    }

    /// Slope of log(relative error) against log(time); none where a run
    /// took less than [`MIN_TIMED`], whose time is mostly the timer's and
    /// the scheduler's.
    pub(crate) fn slope_time(&self) -> Option<f64> {
        if self.points.iter().any(|p| p.seconds < MIN_TIMED) {
            return None;
        }
        fit_log_log(&self.pairs(|p| p.seconds)).map(|f| f.0)
    }

    /// Slope of log(relative error) against log(spp).
    pub fn slope_spp(&self) -> Option<f64> {
        fit_log_log(&self.pairs(|p| p.spp)).map(|f| f.0)
    }

    /// Relative error at `seconds`, interpolated in log-log between the
    /// measured points around it; `None` outside the measured times (beyond
    /// the slack a timed run may overshoot by).
    pub(crate) fn error_at(&self, seconds: f64) -> Option<f64> {
        let mut pts = self.pairs(|p| p.seconds);
        pts.retain(|(t, e)| *t > 0.0 && *e > 0.0);
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (first, last) = (*pts.first()?, *pts.last()?);
        if seconds <= first.0 {
            return (seconds * TIME_SLACK >= first.0).then_some(first.1);
        }
        if seconds >= last.0 {
            return (seconds <= last.0 * TIME_SLACK).then_some(last.1);
        }
        let i = pts.iter().position(|p| p.0 >= seconds)?;
        Some(log_lerp(seconds, pts[i - 1], pts[i]))
    }

    /// Where the relative error falls to `target`: interpolated where the
    /// measured points cross it, else extrapolated from the last point along
    /// the slope of the last three, or -0.5 where that is steeper.
    pub(crate) fn reach(&self, target: f64) -> Option<Reach> {
        let pts = &self.points;
        if let Some(p) = pts.first().filter(|p| p.rel_err() <= target) {
            return Some(Reach {
                spp: p.spp,
                seconds: p.seconds,
                measured: true,
            });
        }
        for w in pts.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            if b.rel_err() > target {
                continue;
            }
            if b.rel_err() == 0.0 {
                return Some(Reach {
                    spp: b.spp,
                    seconds: b.seconds,
                    measured: true,
                });
            }
            // Invert the log-log line through the two points.
            let at = |x0: f64, x1: f64| log_lerp(target, (a.rel_err(), x0), (b.rel_err(), x1));
            return Some(Reach {
                spp: at(a.spp, b.spp),
                seconds: at(a.seconds, b.seconds),
                measured: true,
            });
        }
        let last = pts.last()?;
        let tail = Series {
            points: pts[pts.len().saturating_sub(3)..].to_vec(),
            ..self.clone()
        };
        // Never faster than -0.5: beyond a block of strata, samples are
        // independent, so a steeper tail is a transient. An error that
        // hardly falls (a bias, or a reference of something else) gives no
        // answer rather than an absurd one.
        let s_spp = tail.slope_spp()?.max(ASYMPTOTIC_SLOPE);
        if s_spp > MIN_FALL {
            return None;
        }
        let spp = last.spp * (target / last.rel_err()).powf(1.0 / s_spp);
        // Time follows the samples at the last point's rate: a fit of the
        // error against noisy timings would be steered by the noise.
        let seconds = last.seconds * spp / last.spp;
        (spp.is_finite() && seconds.is_finite()).then_some(Reach {
            spp,
            seconds,
            measured: false,
        })
    }
}

/// Where the reference comes from.
#[derive(Clone, Debug)]
pub enum ReferenceSource {
    /// A linear image (.exr or .hdr) of the study's size.
    File(PathBuf),
    /// An image known some other way (computed exactly, say).
    Image(Vec<Vec3>),
    /// Rendered with the scene's settings at `spp` (default: 64x the largest
    /// spp budget, at most 1024) and cached in `cache` when given.
    Render {
        spp: Option<u32>,
        cache: Option<PathBuf>,
    },
}

#[derive(Clone, Debug)]
pub struct Config {
    pub width: u32,
    pub height: u32,
    /// All in spp or all in seconds.
    pub budgets: Vec<RunLimit>,
    pub seeds: u32,
    /// Seed of the first run; run `i` uses `seed + i`.
    pub seed: u64,
    /// Compare the strategies of [`Strategy::alternatives`] too.
    pub compare: bool,
    /// Measure the scene's settings with adaptive sampling.
    pub adaptive: bool,
    pub reference: ReferenceSource,
    /// The relative error the conclusion is about.
    pub target: f64,
}

#[derive(Clone, Debug)]
pub struct ReferenceInfo {
    /// Where it came from, in words.
    pub source: String,
    pub(crate) spp: Option<u32>,
    /// Seconds spent rendering it in this run (0 when loaded).
    pub(crate) seconds: f64,
}

#[derive(Clone, Debug)]
pub struct Study {
    pub(crate) scene: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) seeds: u32,
    pub(crate) uses: Uses,
    /// Nothing is sampled: one pass was rendered and is the answer.
    pub exact: bool,
    pub reference: ReferenceInfo,
    /// The scene's own settings first, then the compared strategies.
    pub series: Vec<Series>,
    /// Passes rendered for the study, the reference's not counted.
    pub passes: u64,
    pub(crate) target: f64,
    /// Caveats found while measuring.
    pub notes: Vec<String>,
}

struct Run {
    film: Film,
    seconds: f64,
    rays: u64,
    /// The first pass took longer than the time budget.
    overran: bool,
}

/// Renders one independent run: passes of one sample (adaptive: of a block
/// to the noisiest pixels after the minimum) until the budget is met; an
/// adaptive spp budget is the mean over pixels, with no cap on any one.
fn run_once(
    tracer: &Tracer,
    budget: RunLimit,
    adaptive: bool,
    passes: &mut u64,
    cancel: Cancel,
) -> Run {
    let stop = match budget {
        RunLimit::Spp(_) if adaptive && !tracer.plan.deterministic => Stop::default(),
        RunLimit::Spp(n) => Stop::spp(n),
        RunLimit::Seconds(t) => Stop::seconds(t),
    };
    let mut p = Job::of(tracer, stop).adaptive(adaptive).start();
    let mut overran = false;
    match budget {
        RunLimit::Spp(n) if adaptive && !tracer.plan.deterministic => {
            while p.film().spp_range().1 < n as f64 {
                *passes += 1;
                let pass = p.pass(tracer, cancel);
                if pass.is_none_or(|s| s.pixels == 0) {
                    break;
                }
            }
        }
        _ => {
            let mut first = None;
            *passes += p
                .run(tracer, cancel, |_, pass| {
                    first.get_or_insert(pass.ms / 1e3);
                })
                .passes as u64;
            // A render always completes its first pass: one that overran a
            // time budget says the budget is too short.
            overran = matches!((budget, first), (RunLimit::Seconds(t), Some(f)) if f > t);
        }
    }
    Run {
        seconds: p.seconds(),
        rays: p.rays(),
        film: p.into_film(),
        overran,
    }
}

/// The study's subject: a scene ready to trace.
pub struct Subject<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a Bvh,
    pub plan: &'a Plan,
}

impl Subject<'_> {
    #[allow(clippy::too_many_arguments)]
    fn measure(
        &self,
        strategy: Strategy,
        budget: RunLimit,
        cfg: &Config,
        reference: &[Vec3],
        passes: &mut u64,
        progress: &dyn Progress,
        cancel: Cancel,
    ) -> Option<Point> {
        progress.doing(&format!(
            "{}: {budget}",
            strategy.label(Uses::of(self.scene, self.plan))
        ));
        let mut scene = self.scene.clone();
        strategy.apply(&mut scene.settings);
        // The plan of the strategy's integrator, at the study's depth.
        let plan = Plan::new(&scene, self.plan.features, self.plan.policy)
            .with_max_depth(self.plan.max_depth);
        let n = cfg.seeds as f64;
        let (mut spp, mut rays, mut mse, mut rel) = (0.0, 0.0, 0.0, 0.0);
        let mut times = Vec::new();
        let mut est = Some(0.0);
        for i in 0..cfg.seeds {
            let seed = cfg.seed.wrapping_add(i as u64);
            let frame = scene.camera.frame(cfg.width, cfg.height);
            let tracer = Tracer::new(&scene, self.bvh, &plan, frame, seed);
            let r = run_once(&tracer, budget, strategy.adaptive, passes, cancel);
            // A time budget shorter than one sample per pixel measures
            // nothing: an unsampled pixel is not an error of the method.
            if r.overran || r.film.spp_range().0 == 0 {
                return None;
            }
            let img = r.film.image();
            spp += r.film.spp_range().1 / n;
            times.push(r.seconds);
            rays += r.rays as f64 / n;
            mse += rmse(&img, reference).powi(2) / n;
            rel += rel_mse(&img, reference) / n;
            est = est.zip(r.film.estimated_rel_mse()).map(|(a, b)| a + b / n);
        }
        Some(Point {
            budget,
            spp,
            seconds: median(&mut times),
            rays,
            rmse: mse.sqrt(),
            rel_mse: rel,
            est_rel_mse: est,
        })
    }

    fn reference(
        &self,
        cfg: &Config,
        notes: &mut Vec<String>,
        progress: &dyn Progress,
        cancel: Cancel,
    ) -> Result<(Vec<Vec3>, ReferenceInfo)> {
        let (w, h) = (cfg.width, cfg.height);
        match &cfg.reference {
            ReferenceSource::Image(img) => {
                if img.len() != (w * h) as usize {
                    bail!("reference has {} pixels, the study {w}x{h}", img.len());
                }
                let info = ReferenceInfo {
                    source: "given image".into(),
                    spp: None,
                    seconds: 0.0,
                };
                Ok((img.clone(), info))
            }
            ReferenceSource::File(path) => {
                let loaded = crate::raster::read_linear(path)
                    .with_context(|| format!("cannot load the reference {}", path.display()))?;
                let (rw, rh, img) = (loaded.width, loaded.height, loaded.pixels);
                crate::raster::reference::check_finite(path, rw, &img)?;
                if (rw, rh) != (w, h) {
                    bail!(
                        "reference {} is {rw}x{rh} but the study renders {w}x{h}: pass --size {rw}x{rh}",
                        path.display()
                    );
                }
                let floor = format_floor(loaded.format, &img);
                if floor > 0.0 {
                    notes.push(format!(
                        "the reference {} is Radiance .hdr (8-bit mantissas): its rounding alone \
                         is a relative error of {:.3} %, so errors below about that cannot be \
                         measured against it (an .exr reference stores f32 exactly)",
                        path.display(),
                        100.0 * floor
                    ));
                }
                let info = ReferenceInfo {
                    source: path.display().to_string(),
                    spp: None,
                    seconds: 0.0,
                };
                Ok((img, info))
            }
            ReferenceSource::Render { spp, cache } => {
                let largest = cfg.budgets.iter().fold(0, |m, b| match b {
                    RunLimit::Spp(n) => m.max(*n),
                    RunLimit::Seconds(_) => m,
                });
                let spp = spp.unwrap_or(if largest > 0 {
                    (largest.saturating_mul(REFERENCE_FACTOR)).min(REFERENCE_MAX_SPP)
                } else {
                    REFERENCE_MAX_SPP
                });
                let seed = cfg.seed.wrapping_add(REFERENCE_SEED_OFFSET);
                let key = reference_key(self.scene, self.plan, w, h, spp, seed);
                let slug: String = self
                    .scene
                    .name
                    .chars()
                    .map(|c| {
                        if c.is_ascii_alphanumeric() || c == '-' {
                            c
                        } else {
                            '_'
                        }
                    })
                    .take(40)
                    .collect();
                let file = cache
                    .as_ref()
                    .map(|d| d.join(format!("{slug}-{w}x{h}-{spp}spp-{key:016x}.exr")));
                if let Some(f) = file.as_ref().filter(|f| f.exists()) {
                    match load_cached(f, key, w, h) {
                        Ok(img) => {
                            let info = ReferenceInfo {
                                source: format!("cached {}", f.display()),
                                spp: Some(spp),
                                seconds: 0.0,
                            };
                            return Ok((img, info));
                        }
                        Err(e) => notes.push(format!(
                            "cached reference {} not used: {e:#}; rendered anew",
                            f.display()
                        )),
                    }
                }
                let frame = self.scene.camera.frame(w, h);
                let tracer = Tracer::new(self.scene, self.bvh, self.plan, frame, seed);
                // Several samples per pass keep the pass overhead small.
                let mut p = Job::of(&tracer, Stop::spp(spp)).passes_of(8).start();
                let o = p.run(&tracer, cancel, |film, _| {
                    progress.doing(&format!("reference: {}/{spp} spp", film.spp))
                });
                // A cut reference must not be cached as a whole one.
                if o.ended == Ended::Cancelled {
                    bail!(Interrupted);
                }
                let seconds = o.seconds;
                let img = p.film().image();
                let cached = |f: &std::path::Path| -> Result<()> {
                    if let Some(dir) = f.parent() {
                        if dir.exists() && !dir.is_dir() {
                            bail!("{} is not a directory", dir.display());
                        }
                        std::fs::create_dir_all(dir)
                            .with_context(|| format!("cannot create {}", dir.display()))?;
                    }
                    save_cached(f, key, w, h, &img)
                };
                let source = match &file {
                    Some(f) => match cached(f) {
                        Ok(()) => format!("rendered, cached as {}", f.display()),
                        Err(e) => {
                            notes.push(format!("reference not cached: {e:#}"));
                            "rendered".into()
                        }
                    },
                    None => "rendered (not cached)".into(),
                };
                Ok((
                    img,
                    ReferenceInfo {
                        source,
                        spp: Some(spp),
                        seconds,
                    },
                ))
            }
        }
    }

    /// Runs the study described by `cfg`, until `cancel` says stop.
    pub fn study(&self, cfg: &Config, progress: &dyn Progress, cancel: Cancel) -> Result<Study> {
        if cfg.budgets.is_empty() {
            bail!("no budgets to measure");
        }
        if cfg.seeds == 0 {
            bail!("at least one seed is needed");
        }
        let uses = Uses::of(self.scene, self.plan);
        let base = Strategy {
            adaptive: cfg.adaptive,
            ..Strategy::of(&self.scene.settings, self.plan)
        };
        let mut notes = Vec::new();
        progress.begin(None);
        let mut passes = 0;
        let mut study = Study {
            scene: self.scene.name.clone(),
            width: cfg.width,
            height: cfg.height,
            seeds: cfg.seeds,
            uses,
            exact: self.plan.deterministic,
            reference: ReferenceInfo {
                source: String::new(),
                spp: None,
                seconds: 0.0,
            },
            series: Vec::new(),
            passes: 0,
            target: cfg.target,
            notes: Vec::new(),
        };
        if self.plan.deterministic {
            // One pass is the answer: it is its own reference unless one is given.
            let frame = self.scene.camera.frame(cfg.width, cfg.height);
            let tracer = Tracer::new(self.scene, self.bvh, self.plan, frame, cfg.seed);
            let r = run_once(&tracer, RunLimit::Spp(1), false, &mut passes, cancel);
            let img = r.film.image();
            let (reference, info) = match cfg.reference {
                ReferenceSource::Render { .. } => (
                    img.clone(),
                    ReferenceInfo {
                        source: "the one pass (nothing is sampled)".into(),
                        spp: Some(1),
                        seconds: 0.0,
                    },
                ),
                _ => self.reference(cfg, &mut notes, progress, cancel)?,
            };
            study.reference = info;
            study.series.push(Series {
                strategy: base,
                label: base.label(uses),
                points: vec![Point {
                    budget: RunLimit::Spp(1),
                    spp: 1.0,
                    seconds: r.seconds,
                    rays: r.rays as f64,
                    rmse: rmse(&img, &reference),
                    rel_mse: rel_mse(&img, &reference),
                    est_rel_mse: Some(0.0),
                }],
            });
            progress.end();
            study.passes = passes;
            study.notes = notes;
            return Ok(study);
        }
        let (reference, info) = self.reference(cfg, &mut notes, progress, cancel)?;
        study.reference = info;
        let mut main = Series {
            strategy: base,
            label: base.label(uses),
            points: Vec::new(),
        };
        // One run untimed first: the first budget's time would otherwise
        // include the caches and threads warming up.
        if let Some(&first) = cfg.budgets.first() {
            self.measure(base, first, cfg, &reference, &mut 0, progress, cancel);
        }
        for &b in &cfg.budgets {
            match self.measure(base, b, cfg, &reference, &mut passes, progress, cancel) {
                Some(p) => main.points.push(p),
                None => notes.push(format!(
                    "{b} is too short for one sample per pixel here; not measured"
                )),
            }
        }
        if main.points.is_empty() {
            bail!(
                "every budget is too short for one sample per pixel at {}x{}; give longer --times",
                cfg.width,
                cfg.height
            );
        }
        let t_max = main.points.iter().map(|p| p.seconds).fold(0.0, f64::max);
        let max_spp = main.points.iter().map(|p| p.spp).fold(0.0, f64::max);
        if let Some(r) = study.reference.spp {
            if matches!(cfg.reference, ReferenceSource::Render { .. })
                && (r as f64) < REFERENCE_FACTOR as f64 * max_spp
            {
                notes.push(format!(
                    "the reference has {r} samples per pixel against {max_spp:.0} in the largest budget ({}x that advised): its own noise adds about {:.1} % to the relMSE measured there (--reference-spp to raise it)",
                    REFERENCE_FACTOR,
                    100.0 * max_spp / r as f64
                ));
            }
        }
        study.series.push(main);
        if cfg.compare {
            for s in Strategy::alternatives(base, uses) {
                let mut series = Series {
                    strategy: s,
                    label: s.label(uses),
                    points: Vec::new(),
                };
                if matches!(cfg.budgets[0], RunLimit::Seconds(_)) {
                    series.points.extend(cfg.budgets.iter().filter_map(|&b| {
                        self.measure(s, b, cfg, &reference, &mut passes, progress, cancel)
                    }));
                } else {
                    // Double the spp until the run takes as long as the scene's largest budget.
                    let mut n = 1;
                    while let Some(p) = self.measure(
                        s,
                        RunLimit::Spp(n),
                        cfg,
                        &reference,
                        &mut passes,
                        progress,
                        cancel,
                    ) {
                        let done = p.seconds >= t_max || n >= MAX_COMPARE_SPP;
                        series.points.push(p);
                        if done {
                            break;
                        }
                        n *= 2;
                    }
                }
                study.series.push(series);
            }
        }
        progress.end();
        study.passes = passes;
        study.notes = notes;
        Ok(study)
    }
}

/// The shortest run whose time a slope is fitted to, in seconds.
pub(crate) const MIN_TIMED: f64 = 0.01;

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs too short to time give no slope against time, only against spp.
    #[test]
    fn no_slope_against_times_too_short_to_measure() {
        let point = |spp: f64, seconds: f64| Point {
            budget: RunLimit::Spp(spp as u32),
            spp,
            seconds,
            rays: 0.0,
            rmse: 0.0,
            rel_mse: 1.0 / spp,
            est_rel_mse: None,
        };
        let series = |scale: f64| Series {
            strategy: Strategy {
                light_samples: 1,
                glossy_samples: 1,
                stratify: true,
                adaptive: false,
                integrator: Integrator::Whitted,
            },
            label: String::new(),
            points: vec![point(1.0, 0.02 * scale), point(4.0, 0.08 * scale)],
        };
        assert!((series(1.0).slope_time().unwrap() + 0.5).abs() < 1e-9);
        assert!(series(0.01).slope_time().is_none());
        assert!((series(0.01).slope_spp().unwrap() + 0.5).abs() < 1e-9);
    }

    fn series(errs: &[(f64, f64, f64)]) -> Series {
        Series {
            strategy: Strategy {
                light_samples: 1,
                glossy_samples: 1,
                stratify: true,
                adaptive: false,
                integrator: Integrator::Whitted,
            },
            label: "x".into(),
            points: errs
                .iter()
                .map(|&(spp, seconds, e)| Point {
                    budget: RunLimit::Spp(spp as u32),
                    spp,
                    seconds,
                    rays: 0.0,
                    rmse: e,
                    rel_mse: e * e,
                    est_rel_mse: None,
                })
                .collect(),
        }
    }

    #[test]
    fn reach_interpolates_inside_and_extrapolates_outside() {
        // err = 0.1 / sqrt(spp), time = spp / 100.
        let s = series(&[(1.0, 0.01, 0.1), (4.0, 0.04, 0.05), (16.0, 0.16, 0.025)]);
        let r = s.reach(0.05 / 2f64.sqrt()).unwrap();
        assert!(r.measured && (r.spp - 8.0).abs() < 1e-9 && (r.seconds - 0.08).abs() < 1e-9);
        let r = s.reach(0.01).unwrap();
        assert!(!r.measured && (r.spp - 100.0).abs() < 1e-6 && (r.seconds - 1.0).abs() < 1e-6);
        assert_eq!(
            s.error_at(0.02).map(|e| (e * 1e6).round()),
            Some((0.1 / 2f64.sqrt() * 1e6).round())
        );
        assert_eq!(s.error_at(0.001), None);
        assert_eq!(s.error_at(1.0), None);
    }

    #[test]
    fn reach_follows_samples_not_noisy_times_and_refuses_flat_errors() {
        // err = 0.1 / sqrt(spp), but the timings are noise: the last run
        // happened to be quicker than the one before.
        let s = series(&[(1.0, 0.01, 0.1), (4.0, 0.09, 0.05), (16.0, 0.08, 0.025)]);
        let r = s.reach(0.01).unwrap();
        assert!(!r.measured && (r.spp - 100.0).abs() < 1e-6);
        assert!((r.seconds - 0.08 * 100.0 / 16.0).abs() < 1e-9, "{r:?}");
        // An error that does not fall (a reference of another scene): no
        // answer, rather than an infinite or absurd sample count.
        let flat = series(&[(1.0, 0.01, 2.79), (4.0, 0.04, 2.78), (16.0, 0.16, 2.774)]);
        assert_eq!(flat.reach(0.01), None);
    }

    #[test]
    fn far_extrapolations_give_a_bound_not_a_figure() {
        let study = |target: f64| Study {
            scene: "x".into(),
            width: 8,
            height: 8,
            seeds: 1,
            uses: Uses {
                area_lights: true,
                glossy: false,
                supersampling: false,
                integrator: Integrator::Whitted,
            },
            exact: false,
            reference: ReferenceInfo {
                source: "rendered".into(),
                spp: Some(1024),
                seconds: 0.0,
            },
            series: vec![series(&[
                (1.0, 0.01, 0.1),
                (4.0, 0.04, 0.05),
                (16.0, 0.16, 0.025),
            ])],
            passes: 3,
            target,
            notes: Vec::new(),
        };
        // 100 spp is within reach of the data; 1.6e11 is not.
        let near = study(0.01).conclusion();
        assert!(
            near.contains("you need about 10") && near.contains("(extrapolated)"),
            "{near}"
        );
        let far = study(1e-6).conclusion();
        assert!(far.contains("more than 16000 spp"), "{far}");
        assert!(!far.contains("about"), "{far}");
    }

    #[test]
    fn alternatives_cover_light_glossy_stratification_and_adaptive_once() {
        let base = Strategy {
            light_samples: 16,
            glossy_samples: 1,
            stratify: true,
            adaptive: false,
            integrator: Integrator::Whitted,
        };
        let uses = Uses {
            area_lights: true,
            glossy: true,
            supersampling: true,
            integrator: Integrator::Whitted,
        };
        let alts = Strategy::alternatives(base, uses);
        let labels: Vec<String> = alts.iter().map(|s| s.label(uses)).collect();
        assert_eq!(
            labels,
            [
                "path L16 G1 jittered",
                "L1 G1 jittered",
                "L4 G1 jittered",
                "L64 G1 jittered",
                "L16 G4 jittered",
                "L16 G16 jittered",
                "L16 G1 independent",
                "L16 G1 jittered adaptive"
            ]
        );
        let none = Uses {
            area_lights: false,
            glossy: false,
            supersampling: false,
            integrator: Integrator::Whitted,
        };
        // Nothing sampled: only the other integrator.
        let alts = Strategy::alternatives(base, none);
        assert_eq!(alts.len(), 1);
        assert_eq!(alts[0].label(none), "path");
        assert_eq!(alts[0].options(none), "--integrator path");
    }
}
