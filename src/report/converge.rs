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

use std::fmt::Write as _;
use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use glam::Vec3;
use image::codecs::hdr::{HdrDecoder, HdrEncoder};
use image::Rgb;
use indicatif::{ProgressBar, ProgressStyle};

pub use plot::draw as plot;

use crate::bvh::Bvh;
use crate::render::film::LUMA;
use crate::render::{pass, Film, Plan, Tracer};
use crate::scene::{Environment, Scene, Settings};

/// Offset in relMSE so black pixels do not dominate it.
const REL_EPS: f64 = 0.01;
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
/// Error against samples or time once strata are used up: Monte Carlo's.
const ASYMPTOTIC_SLOPE: f64 = -0.5;
/// A run that overshoots a time by at most this factor still counts as at it.
const TIME_SLACK: f64 = 1.25;

/// Luminance of a linear colour.
#[inline]
pub fn luminance(c: Vec3) -> f64 {
    c.as_dvec3().dot(LUMA.as_dvec3())
}

fn mean_over<F: Fn(f64, f64) -> f64>(img: &[Vec3], reference: &[Vec3], f: F) -> f64 {
    assert_eq!(
        img.len(),
        reference.len(),
        "image and reference differ in size"
    );
    if img.is_empty() {
        return 0.0;
    }
    let sum: f64 = img
        .iter()
        .zip(reference)
        .map(|(&x, &r)| f(luminance(x), luminance(r)))
        .sum();
    sum / img.len() as f64
}

/// Root mean squared error of the luminance. Panics when the sizes differ.
pub fn rmse(img: &[Vec3], reference: &[Vec3]) -> f64 {
    mean_over(img, reference, |x, r| (x - r) * (x - r)).sqrt()
}

/// Mean of `(x - ref)^2 / (ref^2 + 0.01)` over pixels, on luminance.
/// Panics when the sizes differ.
pub fn rel_mse(img: &[Vec3], reference: &[Vec3]) -> f64 {
    mean_over(img, reference, |x, r| (x - r) * (x - r) / (r * r + REL_EPS))
}

/// The film's own estimate of its relMSE: the squared standard error of each
/// pixel's mean over its squared luminance. `None` before every pixel has
/// two samples, when there is no variance to go on.
pub fn estimated_rel_mse(film: &Film) -> Option<f64> {
    if film.pixels.is_empty() || film.pixels.iter().any(|p| p.n < 2) {
        return None;
    }
    let sum: f64 = film
        .pixels
        .iter()
        .map(|p| {
            let lum = p.mean.dot(LUMA.as_dvec3());
            p.variance() / p.n as f64 / (lum * lum + REL_EPS)
        })
        .sum();
    Some(sum / film.pixels.len() as f64)
}

/// Radiance's RGBE truncates the mantissa; adding half a step first makes
/// it round, so a stored reference is unbiased.
fn round_for_rgbe(c: Vec3) -> Rgb<f32> {
    let mx = c.max_element();
    if mx <= 0.0 || !mx.is_finite() {
        return Rgb([c.x.max(0.0), c.y.max(0.0), c.z.max(0.0)]);
    }
    let half = (mx.log2().floor() + 1.0).exp2() / 512.0;
    let r = |v: f32| if v > 0.0 { v + half } else { 0.0 };
    Rgb([r(c.x), r(c.y), r(c.z)])
}

fn encode_hdr(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
    let px: Vec<Rgb<f32>> = img.iter().map(|&c| round_for_rgbe(c)).collect();
    let mut bytes = Vec::new();
    HdrEncoder::new(&mut bytes)
        .encode(&px, width as usize, height as usize)
        .context("encoding Radiance HDR")?;
    Ok(bytes)
}

fn decode_hdr(bytes: &[u8]) -> Result<(u32, u32, Vec<Vec3>)> {
    let img = image::DynamicImage::from_decoder(HdrDecoder::new(Cursor::new(bytes))?)?;
    let rgb = match img {
        image::DynamicImage::ImageRgb32F(i) => i,
        other => other.to_rgb32f(),
    };
    let (w, h) = rgb.dimensions();
    let px = rgb.pixels().map(|p| Vec3::from_array(p.0)).collect();
    Ok((w, h, px))
}

/// Loads a linear reference image (Radiance .hdr), row-major from the top.
pub fn load_reference(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let bytes =
        std::fs::read(path).with_context(|| format!("cannot read reference {}", path.display()))?;
    decode_hdr(&bytes).with_context(|| {
        format!(
            "{} is not a Radiance .hdr image (a reference must be linear)",
            path.display()
        )
    })
}

/// Saves a linear image as Radiance .hdr, atomically (temporary file, rename).
pub fn save_reference(path: &Path, width: u32, height: u32, img: &[Vec3]) -> Result<()> {
    let bytes = encode_hdr(width, height, img)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let tmp = path.with_extension(format!("{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| {
        let _ = std::fs::remove_file(&tmp);
        format!("cannot rename to {}", path.display())
    })
}

/// What an image looks like after a trip through a .hdr file.
fn quantised(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<Vec3>> {
    Ok(decode_hdr(&encode_hdr(width, height, img)?)?.2)
}

/// `$XDG_CACHE_HOME/rayterm`, else `~/.cache/rayterm`.
pub fn default_cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("rayterm"))
}

/// FNV-1a, 64 bit: a hash that stays the same across builds, for cache names.
struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100_0000_01b3);
        }
    }

    fn vec3s(&mut self, v: &[Vec3]) {
        for c in v {
            for x in c.to_array() {
                self.bytes(&x.to_bits().to_le_bytes());
            }
        }
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

/// Everything that decides a reference's pixels.
fn reference_key(scene: &Scene, plan: &Plan, width: u32, height: u32, spp: u32, seed: u64) -> u64 {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let _ = write!(
        h,
        "rayterm reference 1 {} {width}x{height} {spp} {seed} {:?} {} {:?} {:?} {:?} {:?} {:?}",
        env!("CARGO_PKG_VERSION"),
        plan.features,
        plan.explain(),
        scene.settings,
        scene.lights,
        scene.materials,
        scene.camera,
        scene.meshes,
    );
    let g = &scene.geometry;
    h.vec3s(&g.positions);
    h.vec3s(&g.normals);
    for uv in &g.uvs {
        h.bytes(&uv.x.to_bits().to_le_bytes());
        h.bytes(&uv.y.to_bits().to_le_bytes());
    }
    for (i, (&m, &o)) in g.indices.iter().zip(g.tri_material.iter().zip(&g.tri_mesh)) {
        let _ = write!(h, "{i:?}{m},{o};");
    }
    let mut textures: Vec<_> = scene.textures.iter().collect();
    match &scene.environment {
        Environment::Color(c) => {
            let _ = write!(h, "env {c:?}");
        }
        Environment::CubeMap(cube) => textures.extend(cube.faces.iter()),
    }
    for t in textures {
        let _ = write!(h, "tex {}x{}", t.width, t.height);
        h.vec3s(&t.texels);
    }
    h.0
}

/// How one run is limited.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    Spp(u32),
    Seconds(f64),
}

impl std::fmt::Display for Budget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Budget::Spp(n) => write!(f, "{n} spp"),
            Budget::Seconds(s) => write!(f, "{s} s"),
        }
    }
}

/// The sampling settings a strategy varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Strategy {
    pub light_samples: u32,
    pub glossy_samples: u32,
    pub stratify: bool,
}

/// Which sampled effects the plan runs, so labels name only those.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Uses {
    pub area_lights: bool,
    pub glossy: bool,
    pub supersampling: bool,
}

impl Uses {
    pub fn of(scene: &Scene, plan: &Plan) -> Self {
        Self {
            area_lights: plan.area_sampling && scene.lights.iter().any(|l| l.is_area()),
            glossy: plan.glossy,
            supersampling: plan.supersampling,
        }
    }
}

impl Strategy {
    pub fn of(s: &Settings) -> Self {
        Self {
            light_samples: s.light_samples,
            glossy_samples: s.glossy_samples,
            stratify: s.stratify,
        }
    }

    pub fn apply(&self, s: &mut Settings) {
        s.light_samples = self.light_samples;
        s.glossy_samples = self.glossy_samples;
        s.stratify = self.stratify;
    }

    /// E.g. `L16 jittered`: light samples per hit (`L`), glossy directions
    /// per hit (`G`), and the kind of sampling, where the scene uses them.
    pub fn label(&self, uses: Uses) -> String {
        let mut parts = Vec::new();
        if uses.area_lights {
            parts.push(format!("L{}", self.light_samples));
        }
        if uses.glossy {
            parts.push(format!("G{}", self.glossy_samples));
        }
        parts.push(
            if self.stratify {
                "jittered"
            } else {
                "independent"
            }
            .to_string(),
        );
        parts.join(" ")
    }

    /// The command-line options that select this strategy.
    pub fn options(&self, uses: Uses) -> String {
        let mut o = Vec::new();
        if uses.area_lights {
            o.push(format!("--light-samples {}", self.light_samples));
        }
        if uses.glossy {
            o.push(format!("--glossy-samples {}", self.glossy_samples));
        }
        if !self.stratify {
            o.push("--independent".to_string());
        }
        o.join(" ")
    }

    /// The strategies worth comparing with `base` on a scene that uses `uses`:
    /// light samples per hit, glossy samples per hit, independent sampling.
    pub fn alternatives(base: Strategy, uses: Uses) -> Vec<Strategy> {
        let mut out = Vec::new();
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
    pub budget: Budget,
    /// Mean samples per pixel reached.
    pub spp: f64,
    /// Median wall time of a run (robust to a run slowed by other work).
    pub seconds: f64,
    /// Mean rays traced by a run.
    pub rays: f64,
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

    pub fn est_err(&self) -> Option<f64> {
        self.est_rel_mse.map(f64::sqrt)
    }

    /// Estimated over true relative error.
    pub fn ratio(&self) -> Option<f64> {
        let e = self.est_err()?;
        (self.rel_mse > 0.0).then(|| e / self.rel_err())
    }

    pub fn mrays_per_s(&self) -> f64 {
        if self.seconds > 0.0 {
            self.rays / self.seconds / 1e6
        } else {
            0.0
        }
    }
}

/// Where a series reaches a target error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    pub spp: f64,
    pub seconds: f64,
    /// Inside the measured range (interpolated) rather than extrapolated.
    pub measured: bool,
}

/// Least-squares slope and intercept of `ln y` against `ln x` over the
/// positive pairs; `None` with fewer than two distinct `x`.
pub fn fit_log_log(xy: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = xy
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if pts.len() < 2 || sxx < 1e-12 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// `y` at `x` on the straight line through two points in log-log space.
fn log_lerp(x: f64, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> f64 {
    if (x1 / x0).ln().abs() < 1e-12 {
        return y0;
    }
    let t = (x / x0).ln() / (x1 / x0).ln();
    (y0.ln() + t * (y1 / y0).ln()).exp()
}

/// One strategy's points, in budget order.
#[derive(Clone, Debug)]
pub struct Series {
    pub strategy: Strategy,
    pub label: String,
    pub points: Vec<Point>,
}

impl Series {
    fn pairs(&self, x: impl Fn(&Point) -> f64) -> Vec<(f64, f64)> {
        self.points.iter().map(|p| (x(p), p.rel_err())).collect()
    }

    /// Slope of log(relative error) against log(time).
    pub fn slope_time(&self) -> Option<f64> {
        fit_log_log(&self.pairs(|p| p.seconds)).map(|f| f.0)
    }

    /// Slope of log(relative error) against log(spp).
    pub fn slope_spp(&self) -> Option<f64> {
        fit_log_log(&self.pairs(|p| p.spp)).map(|f| f.0)
    }

    /// Relative error at `seconds`, interpolated in log-log between the
    /// measured points around it; `None` outside the measured times (beyond
    /// the slack a timed run may overshoot by).
    pub fn error_at(&self, seconds: f64) -> Option<f64> {
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
    pub fn reach(&self, target: f64) -> Option<Reach> {
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
        // independent, so a steeper tail is a transient.
        let s_spp = tail.slope_spp()?.max(ASYMPTOTIC_SLOPE);
        let s_time = tail.slope_time()?.max(ASYMPTOTIC_SLOPE);
        if s_spp >= 0.0 || s_time >= 0.0 {
            return None;
        }
        let k = target / last.rel_err();
        Some(Reach {
            spp: last.spp * k.powf(1.0 / s_spp),
            seconds: last.seconds * k.powf(1.0 / s_time),
            measured: false,
        })
    }
}

/// Where the reference comes from.
#[derive(Clone, Debug)]
pub enum ReferenceSource {
    /// A linear .hdr image of the study's size.
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
    pub budgets: Vec<Budget>,
    pub seeds: u32,
    /// Seed of the first run; run `i` uses `seed + i`.
    pub seed: u64,
    /// Compare the strategies of [`Strategy::alternatives`] too.
    pub compare: bool,
    pub reference: ReferenceSource,
    /// The relative error the conclusion is about.
    pub target: f64,
    /// Progress on stderr.
    pub verbose: bool,
}

#[derive(Clone, Debug)]
pub struct ReferenceInfo {
    /// Where it came from, in words.
    pub source: String,
    pub spp: Option<u32>,
    /// Seconds spent rendering it in this run (0 when loaded).
    pub seconds: f64,
}

#[derive(Clone, Debug)]
pub struct Study {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub seeds: u32,
    pub uses: Uses,
    /// Nothing is sampled: one pass was rendered and is the answer.
    pub exact: bool,
    pub reference: ReferenceInfo,
    /// The scene's own settings first, then the compared strategies.
    pub series: Vec<Series>,
    /// Passes rendered for the study, the reference's not counted.
    pub passes: u64,
    pub target: f64,
    /// Caveats found while measuring.
    pub notes: Vec<String>,
}

struct Run {
    film: Film,
    seconds: f64,
    rays: u64,
}

/// Renders one independent run: passes of one sample until the budget is met.
fn run_once(tracer: &Tracer, budget: Budget, passes: &mut u64) -> Run {
    let mut film = Film::new(tracer.width, tracer.height);
    let start = Instant::now();
    let mut rays = 0;
    loop {
        rays += pass::render_pass(tracer, &mut film, 1, &|| false);
        *passes += 1;
        let done = match budget {
            Budget::Spp(n) => film.spp >= n,
            Budget::Seconds(t) => start.elapsed().as_secs_f64() >= t,
        };
        if done {
            break;
        }
    }
    Run {
        film,
        seconds: start.elapsed().as_secs_f64(),
        rays,
    }
}

/// The study's subject: a scene ready to trace.
pub struct Subject<'a> {
    pub scene: &'a Scene,
    pub bvh: &'a Bvh,
    pub plan: &'a Plan,
}

impl Subject<'_> {
    fn measure(
        &self,
        strategy: Strategy,
        budget: Budget,
        cfg: &Config,
        reference: &[Vec3],
        passes: &mut u64,
        bar: &ProgressBar,
    ) -> Point {
        bar.set_message(format!(
            "{}: {budget}",
            strategy.label(Uses::of(self.scene, self.plan))
        ));
        let mut scene = self.scene.clone();
        strategy.apply(&mut scene.settings);
        let n = cfg.seeds as f64;
        let (mut spp, mut rays, mut mse, mut rel) = (0.0, 0.0, 0.0, 0.0);
        let mut times = Vec::new();
        let mut est = Some(0.0);
        for i in 0..cfg.seeds {
            let seed = cfg.seed.wrapping_add(i as u64);
            let tracer = Tracer::new(&scene, self.bvh, self.plan, cfg.width, cfg.height, seed);
            let r = run_once(&tracer, budget, passes);
            let img = r.film.image();
            spp += r.film.spp as f64 / n;
            times.push(r.seconds);
            rays += r.rays as f64 / n;
            mse += rmse(&img, reference).powi(2) / n;
            rel += rel_mse(&img, reference) / n;
            est = est.zip(estimated_rel_mse(&r.film)).map(|(a, b)| a + b / n);
        }
        times.sort_by(f64::total_cmp);
        Point {
            budget,
            spp,
            seconds: times[times.len() / 2],
            rays,
            rmse: mse.sqrt(),
            rel_mse: rel,
            est_rel_mse: est,
        }
    }

    fn reference(
        &self,
        cfg: &Config,
        notes: &mut Vec<String>,
        bar: &ProgressBar,
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
                let (rw, rh, img) = load_reference(path)?;
                if (rw, rh) != (w, h) {
                    bail!(
                        "reference {} is {rw}x{rh} but the study renders {w}x{h}: pass --size {rw}x{rh}",
                        path.display()
                    );
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
                    Budget::Spp(n) => m.max(*n),
                    Budget::Seconds(_) => m,
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
                    .map(|d| d.join(format!("{slug}-{w}x{h}-{spp}spp-{key:016x}.hdr")));
                if let Some(f) = file.as_ref().filter(|f| f.exists()) {
                    match load_reference(f) {
                        Ok((rw, rh, img)) if (rw, rh) == (w, h) => {
                            let info = ReferenceInfo {
                                source: format!("cached {}", f.display()),
                                spp: Some(spp),
                                seconds: 0.0,
                            };
                            return Ok((img, info));
                        }
                        _ => notes.push(format!(
                            "cached reference {} was unreadable; rendered anew",
                            f.display()
                        )),
                    }
                }
                let tracer = Tracer::new(self.scene, self.bvh, self.plan, w, h, seed);
                let mut film = Film::new(w, h);
                let start = Instant::now();
                // Several samples per pass keep the pass overhead small.
                while film.spp < spp {
                    bar.set_message(format!("reference: {}/{spp} spp", film.spp));
                    let n = (spp - film.spp).min(8);
                    pass::render_pass(&tracer, &mut film, n, &|| false);
                }
                let seconds = start.elapsed().as_secs_f64();
                let img = quantised(w, h, &film.image())?;
                let source = match &file {
                    Some(f) => match save_reference(f, w, h, &img) {
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

    /// Runs the study described by `cfg`.
    pub fn study(&self, cfg: &Config) -> Result<Study> {
        if cfg.budgets.is_empty() {
            bail!("no budgets to measure");
        }
        if cfg.seeds == 0 {
            bail!("at least one seed is needed");
        }
        let uses = Uses::of(self.scene, self.plan);
        let base = Strategy::of(&self.scene.settings);
        let mut notes = Vec::new();
        let bar = if cfg.verbose {
            let b = ProgressBar::new_spinner().with_style(
                ProgressStyle::with_template("{spinner} {elapsed} {msg}").expect("valid template"),
            );
            b.enable_steady_tick(std::time::Duration::from_millis(200));
            b
        } else {
            ProgressBar::hidden()
        };
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
            let tracer = Tracer::new(
                self.scene, self.bvh, self.plan, cfg.width, cfg.height, cfg.seed,
            );
            let r = run_once(&tracer, Budget::Spp(1), &mut passes);
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
                _ => self.reference(cfg, &mut notes, &bar)?,
            };
            study.reference = info;
            study.series.push(Series {
                strategy: base,
                label: base.label(uses),
                points: vec![Point {
                    budget: Budget::Spp(1),
                    spp: 1.0,
                    seconds: r.seconds,
                    rays: r.rays as f64,
                    rmse: rmse(&img, &reference),
                    rel_mse: rel_mse(&img, &reference),
                    est_rel_mse: Some(0.0),
                }],
            });
            bar.finish_and_clear();
            study.passes = passes;
            study.notes = notes;
            return Ok(study);
        }
        let (reference, info) = self.reference(cfg, &mut notes, &bar)?;
        study.reference = info;
        let mut main = Series {
            strategy: base,
            label: base.label(uses),
            points: Vec::new(),
        };
        for &b in &cfg.budgets {
            main.points
                .push(self.measure(base, b, cfg, &reference, &mut passes, &bar));
        }
        let t_max = main.points.iter().map(|p| p.seconds).fold(0.0, f64::max);
        let max_spp = main.points.iter().map(|p| p.spp).fold(0.0, f64::max);
        if let Some(r) = study.reference.spp {
            if matches!(cfg.reference, ReferenceSource::Render { .. })
                && (r as f64) < REFERENCE_FACTOR as f64 * max_spp
            {
                notes.push(format!(
                    "the reference has {:.0}x the samples of the largest budget ({}x advised): its own noise adds about {:.1} % to the relMSE measured there (--reference-spp to raise it)",
                    r as f64 / max_spp,
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
                if matches!(cfg.budgets[0], Budget::Seconds(_)) {
                    for &b in &cfg.budgets {
                        series
                            .points
                            .push(self.measure(s, b, cfg, &reference, &mut passes, &bar));
                    }
                } else {
                    // Double the spp until the run takes as long as the scene's largest budget.
                    let mut n = 1;
                    loop {
                        let p = self.measure(s, Budget::Spp(n), cfg, &reference, &mut passes, &bar);
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
        bar.finish_and_clear();
        study.passes = passes;
        study.notes = notes;
        Ok(study)
    }
}

fn pct(x: f64) -> String {
    format!("{:.3} %", 100.0 * x)
}

/// Number with three significant digits.
fn sig3(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// Up to three significant digits, without trailing zeros: `1`, `0.5`.
fn short(x: f64) -> String {
    let s = sig3(x);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

impl Study {
    /// Times the strategies are compared at: the scene's own budgets.
    pub fn comparison_times(&self) -> Vec<f64> {
        self.series
            .first()
            .map(|s| {
                s.points
                    .iter()
                    .map(|p| match p.budget {
                        Budget::Seconds(t) => t,
                        Budget::Spp(_) => p.seconds,
                    })
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The strategy that reaches the target first, and where.
    pub fn fastest_to_target(&self) -> Option<(&Series, Reach)> {
        self.series
            .iter()
            .filter_map(|s| s.reach(self.target).map(|r| (s, r)))
            .min_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds))
    }

    /// The conclusion, in a sentence or two.
    pub fn conclusion(&self) -> String {
        let size = format!("{}x{}", self.width, self.height);
        if self.exact {
            let e = self.series[0].points[0].rel_err();
            return if e == 0.0 {
                "Nothing in this scene is sampled: one pass is exact (error 0), so no more passes, budgets or reference renders are needed.".to_string()
            } else {
                format!(
                    "Nothing in this scene is sampled: one pass is final, yet it differs from the given reference by {} relative error.",
                    pct(e)
                )
            };
        }
        let t = format!("{} %", short(100.0 * self.target));
        let main = &self.series[0];
        let how = |r: &Reach| {
            format!(
                "about {:.0} spp, {:.2} s at {size} on this machine ({})",
                r.spp.ceil(),
                r.seconds,
                if r.measured {
                    "measured"
                } else {
                    "extrapolated"
                }
            )
        };
        let mut out = match main.reach(self.target) {
            Some(r) => format!(
                "To reach {t} error with the scene's settings ({}) you need {}.",
                main.label,
                how(&r)
            ),
            None => format!(
                "The scene's settings ({}) show no falling error, so no sample count for {t} can be given.",
                main.label
            ),
        };
        if self.series.len() > 1 {
            match self.fastest_to_target() {
                Some((s, _)) if std::ptr::eq(s, main) => {
                    out += " None of the other settings compared gets there sooner.";
                }
                Some((s, r)) => {
                    let _ = write!(
                        out,
                        " {} ({}) gets there first: {}.",
                        s.label,
                        s.strategy.options(self.uses),
                        how(&r)
                    );
                }
                None => {}
            }
        }
        out
    }

    /// The text report: per-budget table, slopes, the equal-time comparison
    /// and the conclusion.
    pub fn text(&self) -> String {
        let mut o = String::new();
        let _ = writeln!(
            o,
            "converge {} at {}x{}, {} seed{} per budget",
            self.scene,
            self.width,
            self.height,
            self.seeds,
            if self.seeds == 1 { "" } else { "s" }
        );
        let _ = writeln!(
            o,
            "reference: {}{}{}",
            self.reference.source,
            self.reference
                .spp
                .map(|s| format!(", {s} spp"))
                .unwrap_or_default(),
            if self.reference.seconds > 0.0 {
                format!(", {:.1} s", self.reference.seconds)
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            o,
            "errors on luminance: rel err = sqrt(relMSE), relMSE = mean (x - ref)^2 / (ref^2 + 0.01); est = the film's own estimate\n"
        );
        for (i, s) in self.series.iter().enumerate() {
            if i > 0 && self.series.len() > 1 && i == 1 {
                let _ = writeln!(o, "compared strategies:");
            }
            let _ = writeln!(
                o,
                "{}{}:",
                s.label,
                if i == 0 {
                    " (the scene's settings)"
                } else {
                    ""
                }
            );
            let _ = writeln!(
                o,
                "  {:>8} {:>8} {:>9} {:>8} {:>10} {:>10} {:>10} {:>10} {:>8}",
                "budget",
                "spp",
                "time s",
                "Mrays/s",
                "RMSE",
                "relMSE",
                "rel err",
                "est err",
                "est/true"
            );
            for p in &s.points {
                let _ = writeln!(
                    o,
                    "  {:>8} {:>8} {:>9.4} {:>8.2} {:>10.3e} {:>10.3e} {:>10} {:>10} {:>8}",
                    p.budget.to_string(),
                    sig3(p.spp),
                    p.seconds,
                    p.mrays_per_s(),
                    p.rmse,
                    p.rel_mse,
                    pct(p.rel_err()),
                    p.est_err().map(pct).unwrap_or_else(|| "-".into()),
                    p.ratio()
                        .map(|r| format!("{r:.2}"))
                        .unwrap_or_else(|| "-".into()),
                );
            }
            if !self.exact {
                let slope = |x: Option<f64>| x.map(|v| format!("{v:.2}")).unwrap_or("-".into());
                let _ = writeln!(
                    o,
                    "  slope of log(rel err): {} against log(time), {} against log(spp)\n",
                    slope(s.slope_time()),
                    slope(s.slope_spp())
                );
            }
        }
        if self.series.len() > 1 {
            let w = self
                .series
                .iter()
                .map(|s| s.label.len())
                .max()
                .unwrap_or(0)
                .max(10);
            let _ = write!(o, "rel err at equal time (* = lowest):\n  {:>9}", "time s");
            for s in &self.series {
                let _ = write!(o, " {:>w$}", s.label);
            }
            o.push('\n');
            for t in self.comparison_times() {
                let errs: Vec<Option<f64>> = self.series.iter().map(|s| s.error_at(t)).collect();
                let best = errs.iter().flatten().copied().fold(f64::INFINITY, f64::min);
                let _ = write!(o, "  {t:>9.4}");
                for e in &errs {
                    let cell = match e {
                        Some(e) => format!("{}{}", pct(*e), if *e == best { "*" } else { " " }),
                        None => "- ".into(),
                    };
                    let _ = write!(o, " {cell:>w$}");
                }
                o.push('\n');
            }
            let _ = writeln!(
                o,
                "  (interpolated in log-log between each strategy's measured points; - = outside them)\n"
            );
        }
        for n in &self.notes {
            let _ = writeln!(o, "note: {n}");
        }
        let _ = writeln!(o, "{}", self.conclusion());
        o
    }

    /// Every measured point as CSV, one row per strategy and budget.
    pub fn csv(&self) -> String {
        let mut o = String::from(
            "strategy,light_samples,glossy_samples,stratified,budget,seeds,spp,seconds,mrays_per_s,rmse,rel_mse,rel_err,est_rel_mse,est_over_true\n",
        );
        let opt = |x: Option<f64>| x.map(|v| format!("{v:e}")).unwrap_or_default();
        for s in &self.series {
            for p in &s.points {
                let _ = writeln!(
                    o,
                    "{},{},{},{},{},{},{},{},{},{:e},{:e},{:e},{},{}",
                    s.label,
                    s.strategy.light_samples,
                    s.strategy.glossy_samples,
                    s.strategy.stratify,
                    p.budget.to_string().replace(' ', ""),
                    self.seeds,
                    p.spp,
                    p.seconds,
                    p.mrays_per_s(),
                    p.rmse,
                    p.rel_mse,
                    p.rel_err(),
                    opt(p.est_rel_mse),
                    opt(p.ratio()),
                );
            }
        }
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_log_fit_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = [1.0, 2.0, 4.0, 8.0, 16.0]
            .iter()
            .map(|&x| (x, 3.0 * f64::powf(x, -0.5)))
            .collect();
        let (s, c) = fit_log_log(&pts).unwrap();
        assert!((s + 0.5).abs() < 1e-12 && (c - 3f64.ln()).abs() < 1e-12);
        assert_eq!(fit_log_log(&pts[..1]), None);
    }

    fn series(errs: &[(f64, f64, f64)]) -> Series {
        Series {
            strategy: Strategy {
                light_samples: 1,
                glossy_samples: 1,
                stratify: true,
            },
            label: "x".into(),
            points: errs
                .iter()
                .map(|&(spp, seconds, e)| Point {
                    budget: Budget::Spp(spp as u32),
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
    fn alternatives_cover_light_glossy_and_stratification_once() {
        let base = Strategy {
            light_samples: 16,
            glossy_samples: 1,
            stratify: true,
        };
        let uses = Uses {
            area_lights: true,
            glossy: true,
            supersampling: true,
        };
        let alts = Strategy::alternatives(base, uses);
        let labels: Vec<String> = alts.iter().map(|s| s.label(uses)).collect();
        assert_eq!(
            labels,
            [
                "L1 G1 jittered",
                "L4 G1 jittered",
                "L64 G1 jittered",
                "L16 G4 jittered",
                "L16 G16 jittered",
                "L16 G1 independent"
            ]
        );
        let none = Uses {
            area_lights: false,
            glossy: false,
            supersampling: false,
        };
        assert!(Strategy::alternatives(base, none).is_empty());
    }

    #[test]
    fn hdr_round_trip_rounds_to_within_half_a_step() {
        let img: Vec<Vec3> = (0..64)
            .map(|i| {
                Vec3::new(
                    0.013 * i as f32,
                    0.5 + 0.001 * i as f32,
                    3.7 / (i + 1) as f32,
                )
            })
            .collect();
        let back = quantised(8, 8, &img).unwrap();
        let mut bias = 0.0;
        for (a, b) in img.iter().zip(&back) {
            // One RGBE step is at most 1/128 of the largest component.
            let step = a.max_element() / 128.0;
            assert!((*a - *b).abs().max_element() <= step, "{a} -> {b}");
            bias += (luminance(*b) - luminance(*a)) / luminance(*a).max(1e-3);
        }
        assert!(
            (bias / 64.0).abs() < 1e-3,
            "mean relative bias {}",
            bias / 64.0
        );
    }

    #[test]
    fn metrics_on_luminance() {
        let r = vec![Vec3::splat(0.5), Vec3::ZERO];
        let x = vec![Vec3::splat(0.6), Vec3::splat(0.1)];
        assert!((rmse(&x, &r) - 0.1).abs() < 1e-6);
        let expected = (0.01 / 0.26 + 0.01 / 0.01) / 2.0;
        assert!((rel_mse(&x, &r) - expected).abs() < 1e-6);
        assert_eq!(rmse(&r, &r), 0.0);
    }
}
