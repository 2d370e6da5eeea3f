//! The render worker: owns the film on its own thread (rayon inside). Each
//! view change restarts accumulation; the first frame of a view is a coarse
//! pass (when full passes are slow) so something appears at once, then every
//! full-resolution pass adds samples to every pixel and sends a snapshot;
//! passes grow with the view's age. A newer view cancels the pass in flight
//! between rows, so camera motion never waits for a pass, and any other
//! command ends a long pass, keeping its rows. BVH overlays are computed
//! here too, once per view, so drawing never traverses the BVH.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;

use crate::bvh::{self, Bvh};
use crate::inspect::inspect_pixel;
use crate::interrupt::{Cancel, Running};
use crate::raster::metrics::rel_mse_on;
use crate::raster::resample::resample;
use crate::render::progressive::MAX_PASS_SPP;
use crate::render::recorder::WorkCounter;
use crate::render::{post, Job, PassStats, Plan, Progressive, Stop, Tracer, WorstPixels};
use crate::scene::camera::CameraFrame;
use crate::scene::{Builder, Camera, Scene};
use crate::viz::draw::{legend_line, Layer};
use crate::viz::{self, pixel, DrawnFrom};

/// A full pass of one sample per pixel slower than this is preceded by a
/// quarter-resolution pass when the view changes.
const COARSE_ABOVE_MS: f64 = 20.0;
/// Passes grow ([`Job::growing`]) while one would take at most
/// this long at the last full pass's pace: long enough to trace a pixel's
/// samples in packets where the scene is quick, short enough to show the
/// picture improve several times a second.
const PASS_MS: f64 = 125.0;
/// An older view's passes may take up to this share of its age, up to
/// [`MAX_PASS_MS`]: each then adds about half again to the samples, so the
/// noise visibly falls at every pass, while a pixel's samples, traced
/// together, share what the caches hold and fill packets (passes of one
/// sample per pixel of a dense mesh at 1024x768 trace at about 0.7x the
/// rate of the same samples in one pass; BENCHMARKS.md).
const AGE_SHARE: f64 = 0.5;
/// The longest a pass of an old view may take.
const MAX_PASS_MS: f64 = 2000.0;
/// Coarse passes render every `COARSE`-th pixel in each direction.
const COARSE: u32 = 4;
/// A view stops accumulating here: the image no longer visibly changes
/// (`scene::MAX_SPP` is the most any render takes).
pub(crate) const VIEW_SPP: u32 = 1024;
/// A pixel counts as converged in the Render panel below this estimated
/// relative error (the default target of `rayterm converge`).
pub(crate) const CONVERGED_BELOW: f64 = 0.01;

/// How long a pass of a view `age_s` seconds old may take.
fn pass_budget(age_s: f64) -> f64 {
    (age_s * 1e3 * AGE_SHARE).clamp(PASS_MS, MAX_PASS_MS)
}

/// What to render: a camera, the plan of what runs, and the size.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct RenderView {
    pub(crate) camera: Camera,
    pub(crate) plan: Plan,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// A pixel's width over its height on screen.
    pub(crate) pixel_aspect: f64,
}

impl RenderView {
    pub(crate) fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The camera's frame for `w x h` pixels of this view's shape.
    pub(crate) fn frame(&self, (w, h): (u32, u32)) -> CameraFrame {
        self.camera.frame(w, h).stretched(self.pixel_aspect)
    }
}

pub(crate) enum Cmd {
    /// Render this view; `u64` is its generation.
    View(u64, Box<RenderView>),
    /// Rebuild the BVH with this builder, then render the current view as
    /// generation `u64`.
    Builder(u64, Builder),
    /// Keep this view of the whole image: a BVH view drawn over every
    /// view, a film view drawn into every pass (`Snapshot::film_view`);
    /// none: neither.
    ImageView(Option<viz::View>),
    /// Keep the selected pixel's overlay drawn (none: no overlay).
    Pixel(Option<PixelRequest>),
    Quit,
}

pub(crate) enum Msg {
    Frame(Box<Snapshot>),
    /// The BVH was rebuilt.
    Bvh(Arc<Bvh>),
    Overlay(Box<OverlayFrame>),
    Pixel(Box<PixelFrame>),
}

/// The selected pixel's overlay: which pixel and sample, which view, the
/// ray of the one-ray views (none: the view's default) and the samples the
/// zoom shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PixelRequest {
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) sample: u32,
    pub(crate) view: viz::View,
    pub(crate) ray: Option<usize>,
    pub(crate) spp: u32,
}

/// A pixel overlay drawn for one view of the scene.
pub(crate) struct PixelFrame {
    pub(crate) generation: u64,
    pub(crate) request: PixelRequest,
    /// The layer and its legend in one line, or why it cannot be drawn.
    pub(crate) layer: Result<(Layer, String), String>,
}

/// A BVH view drawn for one view of the scene.
pub(crate) struct OverlayFrame {
    pub(crate) generation: u64,
    /// The layer, or why it cannot be drawn.
    pub(crate) layer: Result<(Layer, String), String>,
}

/// A reference image (`--reference`) and the view it shows.
pub(crate) struct Reference {
    /// The file's name, for the panel.
    pub(crate) name: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Linear colours, row-major from the top.
    pub(crate) image: Vec<Vec3>,
    /// The camera and plan it was rendered with; other views are not
    /// compared.
    pub(crate) camera: Camera,
    pub(crate) plan: Plan,
}

/// Whether the true error against the reference is measured, and if not why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Truth {
    /// No reference was given.
    NoReference,
    /// Measured over `coverage` of the view's pixels; `exact` when each is
    /// a whole block of reference pixels (otherwise resampling adds error).
    Compared { coverage: f64, exact: bool },
    /// The camera is not the one the reference shows.
    CameraMoved,
    /// Features that change the image differ from the reference's.
    FeaturesChanged,
    /// The view and the reference share no pixel.
    NoOverlap,
}

/// The pass in flight, for a progress readout while a pass is slow.
#[derive(Debug, Default)]
pub(crate) struct PassProgress {
    pub(crate) generation: AtomicU64,
    /// Rows finished and rows in all.
    pub(crate) rows_done: Arc<AtomicU32>,
    pub(crate) rows: AtomicU32,
    /// When the pass began; `None` between passes.
    pub(crate) started: Mutex<Option<Running>>,
}

impl PassProgress {
    /// (generation, rows done, rows, seconds running) of the pass in flight.
    pub(crate) fn current(&self) -> Option<(u64, u32, u32, f64)> {
        let started = (*self.started.lock().ok()?)?;
        Some((
            self.generation.load(Ordering::Relaxed),
            self.rows_done.load(Ordering::Relaxed),
            self.rows.load(Ordering::Relaxed),
            started.elapsed().as_secs_f64(),
        ))
    }

    fn begin(&self, generation: u64, rows: u32) {
        self.generation.store(generation, Ordering::Relaxed);
        self.rows_done.store(0, Ordering::Relaxed);
        self.rows.store(rows, Ordering::Relaxed);
        if let Ok(mut s) = self.started.lock() {
            *s = Some(Running::now());
        }
    }

    fn end(&self) {
        if let Ok(mut s) = self.started.lock() {
            *s = None;
        }
    }
}

/// Mean BVH work per ray (camera and shadow rays) of a full pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PerRay {
    pub(crate) nodes: f64,
    pub(crate) triangle_tests: f64,
}

impl PerRay {
    fn of(pass: &PassStats, work: &WorkCounter) -> PerRay {
        let n = pass.rays.max(1) as f64;
        PerRay {
            nodes: work.work.nodes_visited as f64 / n,
            triangle_tests: work.work.triangle_tests as f64 / n,
        }
    }
}

/// One finished pass, ready to show.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub(crate) generation: u64,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Linear colours as displayed (after bloom), row-major.
    pub(crate) image: Vec<Vec3>,
    /// The mean before bloom, when bloom ran.
    pub(crate) pre_bloom: Option<Vec<Vec3>>,
    /// With a film view on: the pass as `viz::film_view` draws it (bloom,
    /// samples or error per pixel), and its legend in one line.
    pub(crate) film_view: Option<(viz::View, Vec<Vec3>, String)>,
    /// A quarter-resolution preview, not yet a sample of the film.
    pub(crate) coarse: bool,
    pub(crate) spp: u32,
    /// Mean samples per pixel (adaptive films differ per pixel).
    pub(crate) spp_mean: f64,
    /// Fraction of pixels predicted below [`CONVERGED_BELOW`] (adaptive).
    pub(crate) converged: Option<f64>,
    pub(crate) pass_ms: f64,
    pub(crate) mrays: f64,
    /// The film's estimated relative error ([`Film::relative_error`](crate::render::Film::relative_error)),
    /// unknown below two samples.
    pub(crate) error: Option<f64>,
    /// Nothing is sampled and one pass is done: the image is exact.
    pub(crate) exact: bool,
    /// No more passes will come for this view.
    pub done: bool,
    /// Seconds from the view's start to the end of its last pass.
    pub(crate) elapsed: f64,
    /// (seconds, error) after each pass with an error estimate.
    pub(crate) history: Vec<(f64, f64)>,
    /// The true error (root relMSE against the reference) when measured.
    pub(crate) true_error: Option<f64>,
    pub(crate) truth: Truth,
    /// (seconds, true error) after each pass.
    pub(crate) true_history: Vec<(f64, f64)>,
    pub(crate) per_ray: Option<PerRay>,
    pub(crate) worst: WorstPixels,
    pub(crate) bad_samples: u64,
}

/// What the last full pass took.
#[derive(Clone, Copy, Debug)]
struct LastPass {
    ms: f64,
    /// Its time over the samples per pixel it added.
    ms_per_spp: f64,
    /// Whether it used the BVH.
    bvh: bool,
}

/// The worker's state; [`Worker::step`] runs one pass. The thread in
/// [`spawn`] and the benchmark drive the same code.
pub(crate) struct Worker {
    scene: Arc<Scene>,
    bvh: Arc<Bvh>,
    seed: u64,
    generation: u64,
    view: Option<RenderView>,
    film: Progressive,
    coarse_pending: bool,
    started: Running,
    /// Seconds from `started` to the end of the last pass: what snapshots
    /// report, so that a view resent after its last pass stops the clock.
    ran: f64,
    history: Vec<(f64, f64)>,
    per_ray: Option<PerRay>,
    /// The last full pass, to decide whether coarse passes pay off and how
    /// long passes may grow.
    last_full: Option<LastPass>,
    /// The pass in flight, shared with the app.
    pub(crate) progress: Arc<PassProgress>,
    reference: Option<Arc<Reference>>,
    truth: Truth,
    /// The reference on the view's pixels while `truth` is `Compared`.
    reference_pixels: Vec<(u32, Vec3)>,
    true_history: Vec<(f64, f64)>,
    /// Mrays/s of the last full pass.
    last_mrays: f64,
    /// The film is unchanged but the view's generation is new: show it again.
    resend: bool,
    /// The BVH view to draw, and the generation it was last drawn for.
    overlay: Option<viz::View>,
    overlay_drawn: Option<(u64, viz::View)>,
    /// The pixel overlay to draw, and the generation it was last drawn for.
    pixel: Option<PixelRequest>,
    pixel_drawn: Option<(u64, PixelRequest)>,
    film_view: Option<viz::View>,
}

impl Worker {
    pub(crate) fn new(
        scene: Arc<Scene>,
        bvh: Arc<Bvh>,
        seed: u64,
        reference: Option<Arc<Reference>>,
    ) -> Self {
        Self {
            scene,
            bvh,
            seed,
            generation: 0,
            view: None,
            film: Progressive::default(),
            coarse_pending: false,
            started: Running::now(),
            ran: 0.0,
            history: Vec::new(),
            per_ray: None,
            last_full: None,
            progress: Arc::default(),
            reference,
            truth: Truth::NoReference,
            reference_pixels: Vec::new(),
            true_history: Vec::new(),
            last_mrays: 0.0,
            resend: false,
            overlay: None,
            overlay_drawn: None,
            pixel: None,
            pixel_drawn: None,
            film_view: None,
        }
    }

    /// Applies a command; returns a message for the app when there is one.
    /// `Quit` is handled by the thread loop.
    pub(crate) fn apply(&mut self, cmd: Cmd) -> Option<Msg> {
        match cmd {
            Cmd::View(generation, view) => {
                let view = *view;
                self.generation = generation;
                // A plan that keeps the film (bloom, the BVH toggle) keeps its
                // samples: the film is only shown again. (A pass cancelled
                // halfway leaves some rows a sample short; each pixel's mean
                // and error are its own, so the film is still sound.)
                let same_film = self.film.film().spp > 0
                    && self.view.as_ref().is_some_and(|old| {
                        (old.camera, old.size(), old.pixel_aspect)
                            == (view.camera, view.size(), view.pixel_aspect)
                            && old.plan.same_film(&view.plan)
                    });
                self.view = Some(view);
                if same_film {
                    self.resend = true;
                } else {
                    self.restart();
                }
                None
            }
            Cmd::Builder(generation, builder) => {
                self.bvh = Arc::new(bvh::build(&self.scene.geometry, builder));
                self.generation = generation;
                self.last_full = None;
                self.restart();
                Some(Msg::Bvh(self.bvh.clone()))
            }
            Cmd::ImageView(v) => {
                self.overlay = v.filter(|v| v.source() == DrawnFrom::Bvh);
                self.overlay_drawn = None;
                self.film_view = v.filter(|v| v.source() == DrawnFrom::Film);
                // The film is the same: shown again, with or without it.
                self.resend = self.film.film().spp > 0;
                None
            }
            Cmd::Pixel(p) => {
                self.pixel = p;
                self.pixel_drawn = None;
                None
            }
            Cmd::Quit => None,
        }
    }

    fn restart(&mut self) {
        let (w, h) = self.view.as_ref().map_or((0, 0), RenderView::size);
        // Adaptive after the first quarter block (docs/adaptive.md).
        self.film = match &self.view {
            Some(v) => Job::new(w, h, &v.plan, Self::stop())
                .adaptive(true)
                .growing()
                .rows_done(self.progress.rows_done.clone())
                .start(),
            None => Progressive::default(),
        };
        // A pass is slow when the last one was, or when it is the first
        // without the BVH (brute force is orders of magnitude slower).
        let bvh = self.view.as_ref().is_some_and(|v| v.plan.bvh);
        self.coarse_pending = self
            .last_full
            .is_none_or(|l| l.ms_per_spp > COARSE_ABOVE_MS || l.bvh != bvh);
        self.started = Running::now();
        self.ran = 0.0;
        self.history.clear();
        self.per_ray = None;
        self.true_history.clear();
        self.compare_with_reference();
    }

    /// Decides whether the view can be compared with the reference, and
    /// takes the reference onto the view's pixels when it can.
    fn compare_with_reference(&mut self) {
        self.reference_pixels.clear();
        self.truth = match (&self.reference, &self.view) {
            (None, _) | (_, None) => Truth::NoReference,
            (Some(r), Some(v)) if v.camera != r.camera => Truth::CameraMoved,
            (Some(r), Some(v)) if !v.plan.same_film(&r.plan) => Truth::FeaturesChanged,
            (Some(r), Some(v)) => {
                let m = resample(
                    r.width,
                    r.height,
                    &r.image,
                    v.width,
                    v.height,
                    v.pixel_aspect,
                );
                if m.pixels.is_empty() {
                    Truth::NoOverlap
                } else {
                    self.reference_pixels = m.pixels;
                    Truth::Compared {
                        coverage: m.coverage,
                        exact: m.exact,
                    }
                }
            }
        };
    }

    fn stop() -> Stop {
        Stop::spp(VIEW_SPP)
    }

    /// Whether the overlay asked for is not yet drawn for this view.
    fn overlay_due(&self) -> Option<viz::View> {
        let o = self.overlay?;
        (self.overlay_drawn != Some((self.generation, o))).then_some(o)
    }

    /// Whether the pixel overlay asked for is not yet drawn for this view.
    fn pixel_due(&self) -> Option<PixelRequest> {
        let p = self.pixel?;
        (self.pixel_drawn != Some((self.generation, p))).then_some(p)
    }

    /// Whether more work would change what is shown.
    pub(crate) fn idle(&self) -> bool {
        let due = self.overlay_due().is_some() || self.pixel_due().is_some();
        if self.resend || due && self.view.is_some() {
            return false;
        }
        match &self.view {
            None => true,
            Some(v) if v.width == 0 || v.height == 0 => true,
            Some(v) => self.film.finished(&v.plan, 0.0).is_some(),
        }
    }

    /// A tracer for the current view.
    fn tracer<'a>(&'a self, view: &'a RenderView, (w, h): (u32, u32)) -> Tracer<'a> {
        Tracer::new(
            &self.scene,
            &self.bvh,
            &view.plan,
            view.frame((w, h)),
            self.seed,
        )
    }

    /// The film's samples from each pixel's `from`th on, traced again in
    /// one pass as a one-shot render of the same counts would
    /// ([`Progressive::retrace`]); `None` before a view.
    pub(crate) fn retrace(&self, from: u32) -> Option<crate::render::PassStats> {
        let view = self.view.as_ref()?;
        let f = self.film.film();
        Some(
            self.film
                .retrace(&self.tracer(view, (f.width, f.height)), from),
        )
    }

    /// Does the next piece of work: shows a kept film again, draws the
    /// overlay, or runs a pass; `None` when idle or cancelled. `waiting`
    /// says a command waits: a pass then ends after [`PASS_MS`].
    pub(crate) fn step(&mut self, cancel: Cancel, waiting: Cancel) -> Option<Msg> {
        if self.idle() {
            return None;
        }
        let view = self.view.clone()?;
        if std::mem::take(&mut self.resend) {
            // A kept film whose passes ran without the BVH has no figures
            // for the panel: one throwaway sample per pixel measures them.
            if view.plan.bvh && self.per_ray.is_none() {
                let t = self.tracer(&view, view.size());
                let mut probe = Job::of(&t, Stop::spp(1)).start();
                let (pass, work) = probe.pass_with::<WorkCounter>(&t, cancel)?;
                self.per_ray = Some(PerRay::of(&pass, &work));
            }
            let mean = self.film.film().image();
            let truth = self.true_error(&mean);
            return Some(Msg::Frame(Box::new(self.snapshot(&view, mean, truth))));
        }
        if std::mem::take(&mut self.coarse_pending) {
            return self.coarse(&view, cancel).map(|s| Msg::Frame(Box::new(s)));
        }
        if let Some(o) = self.overlay_due() {
            self.overlay_drawn = Some((self.generation, o));
            let layer =
                viz::layer(&self.tracer(&view, view.size()), o).map_err(|e| format!("{e:#}"));
            return Some(Msg::Overlay(Box::new(OverlayFrame {
                generation: self.generation,
                layer,
            })));
        }
        if let Some(p) = self.pixel_due() {
            self.pixel_drawn = Some((self.generation, p));
            let mut t = self.tracer(&view, view.size());
            // One sample's tree can take seconds: a quit or a new view stops
            // it, and a tree cut short is never shown.
            t.cancel = cancel;
            let layer = if p.x < view.width && p.y < view.height {
                let tree = inspect_pixel(&t, p.x, p.y, p.sample);
                if cancel.is_set() {
                    return None;
                }
                pixel::draw(&t, &tree, p.view, p.ray, p.spp)
                    .map(|o| (o.layer, legend_line(&o.legend)))
                    .map_err(|e| format!("{e:#}"))
            } else {
                Err("the selected pixel is outside the view".into())
            };
            return Some(Msg::Pixel(Box::new(PixelFrame {
                generation: self.generation,
                request: p,
                layer,
            })));
        }
        self.full_pass(&view, cancel, waiting)
            .map(|s| Msg::Frame(Box::new(s)))
    }

    /// One sample more for every pixel of the view.
    fn full_pass(
        &mut self,
        view: &RenderView,
        cancel: Cancel,
        waiting: Cancel,
    ) -> Option<Snapshot> {
        let t = Tracer::new(
            &self.scene,
            &self.bvh,
            &view.plan,
            view.frame(view.size()),
            self.seed,
        );
        let budget = pass_budget(self.started.elapsed().as_secs_f64());
        self.film.cap_passes(self.pass_cap(view.plan.bvh, budget));
        let before = self.film.film().spp_range().1;
        // A long pass gives way to a command that waits (a pixel's tree, an
        // overlay): the rows it traced stay in the film.
        let start = Instant::now();
        let stop =
            || cancel.is_set() || waiting.is_set() && start.elapsed().as_secs_f64() * 1e3 > PASS_MS;
        let cancel = Cancel::When(&stop);
        self.progress.begin(self.generation, view.height);
        // The first pass of a view counts BVH work for the panel; later ones
        // take the fast path.
        let pass = if self.film.film().spp == 0 && view.plan.bvh {
            let pass = self.film.pass_with::<WorkCounter>(&t, cancel);
            self.progress.end();
            let (pass, work) = pass?;
            self.per_ray = Some(PerRay::of(&pass, &work));
            pass
        } else {
            let pass = self.film.pass(&t, cancel);
            self.progress.end();
            pass?
        };
        self.last_full = Some(LastPass {
            ms: pass.ms,
            ms_per_spp: pass.ms / (self.film.film().spp_range().1 - before).max(1.0),
            bvh: view.plan.bvh,
        });
        self.last_mrays = pass.mrays_per_s();
        let elapsed = self.started.elapsed().as_secs_f64();
        self.ran = elapsed;
        if let Some(error) = self.film.film().relative_error().filter(|&e| e > 0.0) {
            self.history.push((elapsed, error));
        }
        let mean = self.film.film().image();
        let truth = self.true_error(&mean);
        if let Some(e) = truth {
            self.true_history.push((elapsed, e));
        }
        Some(self.snapshot(view, mean, truth))
    }

    /// The most samples per pixel the next pass may give: the most that
    /// fit in `budget_ms` at the last full pass's pace (with the BVH as
    /// the view has it), in powers of two.
    fn pass_cap(&self, bvh: bool, budget_ms: f64) -> u32 {
        let Some(last) = self.last_full.filter(|l| l.bvh == bvh) else {
            return 1;
        };
        let mut n = 1;
        while n < MAX_PASS_SPP && 2.0 * n as f64 * last.ms_per_spp <= budget_ms {
            n *= 2;
        }
        n
    }

    /// Root relMSE of `mean` against the reference, where it is compared.
    fn true_error(&self, mean: &[Vec3]) -> Option<f64> {
        matches!(self.truth, Truth::Compared { .. })
            .then(|| rel_mse_on(mean, &self.reference_pixels).sqrt())
    }

    /// The film as it stands, for the app; `mean` is its image and
    /// `true_error` that image's error against the reference.
    fn snapshot(&self, view: &RenderView, mean: Vec<Vec3>, true_error: Option<f64>) -> Snapshot {
        let film = self.film.film();
        // Only views of the film are kept in `film_view`: none fails.
        let film_view = self.film_view.and_then(|v| {
            let (image, legend) = viz::film_view(
                v,
                film,
                &mean,
                view.size(),
                &self.scene.settings.bloom,
                (view.plan.bloom, "this"),
            )
            .ok()?;
            Some((v, image, legend_line(&legend)))
        });
        let shown = post::display(
            mean,
            view.width,
            view.height,
            &view.plan,
            &self.scene.settings.bloom,
        );
        Snapshot {
            generation: self.generation,
            width: view.width,
            height: view.height,
            image: shown.image,
            pre_bloom: shown.before_bloom,
            film_view,
            coarse: false,
            spp: film.spp,
            spp_mean: film.spp_range().1,
            converged: film.converged(CONVERGED_BELOW),
            pass_ms: self.last_full.map_or(0.0, |l| l.ms),
            mrays: self.last_mrays,
            error: film.relative_error(),
            exact: view.plan.deterministic,
            done: self.idle(),
            elapsed: self.ran,
            history: self.history.clone(),
            true_error,
            truth: self.truth,
            true_history: self.true_history.clone(),
            per_ray: self.per_ray,
            worst: film.worst_pixels(),
            bad_samples: film.bad_count,
        }
    }

    /// One sample of every `COARSE`-th pixel, upscaled to the view.
    fn coarse(&self, view: &RenderView, cancel: Cancel) -> Option<Snapshot> {
        let (cw, ch) = (view.width.div_ceil(COARSE), view.height.div_ceil(COARSE));
        let t = self.tracer(view, (cw, ch));
        let mut small = Job::of(&t, Stop::spp(1))
            .rows_done(self.progress.rows_done.clone())
            .start();
        self.progress.begin(self.generation, ch);
        let pass = small.pass(&t, cancel);
        self.progress.end();
        let pass = pass?;
        let small = small.film().image();
        let mut image = Vec::with_capacity((view.width * view.height) as usize);
        for y in 0..view.height {
            for x in 0..view.width {
                image.push(small[((y / COARSE) * cw + x / COARSE) as usize]);
            }
        }
        let shown = post::display(
            image,
            view.width,
            view.height,
            &view.plan,
            &self.scene.settings.bloom,
        );
        Some(Snapshot {
            generation: self.generation,
            width: view.width,
            height: view.height,
            image: shown.image,
            pre_bloom: shown.before_bloom,
            film_view: None,
            coarse: true,
            spp: 0,
            spp_mean: 0.0,
            converged: None,
            pass_ms: pass.ms,
            mrays: pass.mrays_per_s(),
            error: None,
            exact: false,
            done: false,
            elapsed: self.started.elapsed().as_secs_f64(),
            history: Vec::new(),
            true_error: None,
            truth: self.truth,
            true_history: Vec::new(),
            per_ray: None,
            worst: WorstPixels::default(),
            bad_samples: 0,
        })
    }
}

/// The app's end of the worker.
pub(crate) struct Handle {
    tx: Sender<Cmd>,
    pub(crate) rx: Receiver<Msg>,
    pub(crate) progress: Arc<PassProgress>,
    /// Generation of the newest command; passes of older ones stop.
    latest: Arc<AtomicU64>,
    /// Commands sent: more than the worker has taken means one waits.
    sent: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

/// Starts the worker thread.
pub(crate) fn spawn(worker: Worker) -> Result<Handle> {
    let (tx, cmd_rx) = mpsc::channel();
    let (msg_tx, rx) = mpsc::channel();
    let latest = Arc::new(AtomicU64::new(0));
    let sent = Arc::new(AtomicU64::new(0));
    let counters = (latest.clone(), sent.clone());
    let progress = worker.progress.clone();
    let thread = std::thread::Builder::new()
        .name("rayterm-render".into())
        .spawn(move || run(worker, cmd_rx, msg_tx, counters))
        .context("cannot start the render thread")?;
    Ok(Handle {
        tx,
        rx,
        progress,
        latest,
        sent,
        thread: Some(thread),
    })
}

impl Handle {
    /// Sends a command; a view or builder change cancels the pass in flight.
    pub(crate) fn send(&self, cmd: Cmd) {
        if let Cmd::View(g, _) | Cmd::Builder(g, _) = cmd {
            self.latest.store(g, Ordering::SeqCst);
        }
        self.sent.fetch_add(1, Ordering::SeqCst);
        // A worker that has gone away reports itself through `rx`.
        let _ = self.tx.send(cmd);
    }
}

impl Drop for Handle {
    fn drop(&mut self) {
        self.latest.store(u64::MAX, Ordering::SeqCst);
        let _ = self.tx.send(Cmd::Quit);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The worker thread: `latest` is the newest generation sent, `sent` the
/// commands sent so far.
fn run(
    mut w: Worker,
    rx: Receiver<Cmd>,
    tx: Sender<Msg>,
    (latest, sent): (Arc<AtomicU64>, Arc<AtomicU64>),
) {
    let mut taken = 0u64;
    loop {
        // Block while idle; otherwise take whatever commands are waiting.
        let mut next = if w.idle() {
            match rx.recv() {
                Ok(c) => Some(c),
                Err(_) => return,
            }
        } else {
            None
        };
        loop {
            let cmd = match next.take() {
                Some(c) => c,
                None => match rx.try_recv() {
                    Ok(c) => c,
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => return,
                },
            };
            taken += 1;
            if matches!(cmd, Cmd::Quit) {
                return;
            }
            if let Some(m) = w.apply(cmd) {
                if tx.send(m).is_err() {
                    return;
                }
            }
        }
        let generation = w.generation;
        let cancel = || latest.load(Ordering::Relaxed) != generation;
        let waiting = || sent.load(Ordering::Relaxed) != taken;
        if let Some(m) = w.step(Cancel::When(&cancel), Cancel::When(&waiting)) {
            if tx.send(m).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Feature, Features, Progressive, SceneRequest, Session};

    fn session(spec: &str) -> Session {
        Session::open(&SceneRequest::new(spec)).unwrap().0
    }

    fn view(s: &Session, features: Features) -> RenderView {
        RenderView {
            camera: s.camera,
            plan: s.plan_for(features),
            width: 16,
            height: 12,
            pixel_aspect: 1.0,
        }
    }

    fn worker(features: Features) -> Worker {
        let s = session("cornell");
        let mut w = Worker::new(s.scene.clone(), s.bvh.clone(), 1, None);
        w.apply(Cmd::View(1, Box::new(view(&s, features))));
        w
    }

    /// The next frame the worker sends; `None` once it is idle.
    fn next_frame(w: &mut Worker) -> Option<Box<Snapshot>> {
        loop {
            match w.step(Cancel::Never, Cancel::Never)? {
                Msg::Frame(s) => return Some(s),
                _ => continue,
            }
        }
    }

    /// The next full (not coarse) frame.
    fn full(w: &mut Worker) -> Box<Snapshot> {
        std::iter::from_fn(|| next_frame(w))
            .find(|s| !s.coarse)
            .expect("a full pass")
    }

    #[test]
    fn a_coarse_preview_comes_first_then_passes_that_double_the_film() {
        let mut w = worker(Features::all());
        let s = next_frame(&mut w).unwrap();
        assert!(s.coarse && s.spp == 0);
        assert_eq!(s.image.len(), 16 * 12);
        // Each 4x4 block of the preview is one coarse pixel.
        assert_eq!(s.image[0], s.image[3 * 16 + 3]);
        // One sample, then as many as the film has (the first quarter
        // block, then adaptive passes raising the mean likewise), each pass
        // at a pace that lets the next grow, however busy the machine.
        let fast = |w: &mut Worker| {
            w.last_full = Some(LastPass {
                ms: 1.0,
                ms_per_spp: 1.0,
                bvh: true,
            })
        };
        for spp in [1, 2, 4] {
            let s = next_frame(&mut w).unwrap();
            assert!(!s.coarse);
            assert_eq!((s.spp, s.generation), (spp, 1));
            fast(&mut w);
        }
        let s = next_frame(&mut w).unwrap();
        assert!(s.per_ray.is_some());
        assert!((7.9..8.5).contains(&s.spp_mean), "{}", s.spp_mean);
    }

    /// Passes grow while one would fit in the budget at the last pass's
    /// pace, in powers of two, and a view of another BVH setting starts
    /// again from one sample.
    #[test]
    fn passes_grow_as_far_as_the_pace_allows() {
        let mut w = worker(Features::all());
        let at = |w: &mut Worker, ms_per_spp: f64, budget: f64| {
            w.last_full = Some(LastPass {
                ms: 0.0,
                ms_per_spp,
                bvh: true,
            });
            (w.pass_cap(true, budget), w.pass_cap(false, budget))
        };
        assert_eq!(at(&mut w, 100.0, PASS_MS), (1, 1));
        assert_eq!(at(&mut w, PASS_MS / 3.0, PASS_MS), (2, 1));
        assert_eq!(at(&mut w, PASS_MS / 8.0, PASS_MS), (8, 1));
        assert_eq!(at(&mut w, 10.0, PASS_MS), (8, 1));
        assert_eq!(at(&mut w, 0.01, PASS_MS), (MAX_PASS_SPP, 1));
        // An older view's budget lets slow passes grow too.
        assert_eq!(at(&mut w, 400.0, pass_budget(1.5)), (1, 1));
        assert_eq!(at(&mut w, 400.0, pass_budget(2.0)), (2, 1));
        assert_eq!(at(&mut w, 400.0, pass_budget(4.0)), (4, 1));
        w.last_full = None;
        assert_eq!(w.pass_cap(true, MAX_PASS_MS), 1);
    }

    /// A pass may take half its view's age, from `PASS_MS` for a new view
    /// to `MAX_PASS_MS`.
    #[test]
    fn the_pass_budget_grows_with_the_views_age() {
        assert_eq!(pass_budget(0.0), PASS_MS);
        assert_eq!(pass_budget(0.2), PASS_MS);
        assert_eq!(pass_budget(1.0), 500.0);
        assert_eq!(pass_budget(4.0), MAX_PASS_MS);
        assert_eq!(pass_budget(1e6), MAX_PASS_MS);
    }

    /// A command that waits ends a pass once it has run `PASS_MS`, and the
    /// rows it traced stay in the film; before that the pass runs on.
    #[test]
    fn a_waiting_command_ends_a_long_pass_and_keeps_its_rows() {
        let s = session("cornell");
        let mut w = Worker::new(s.scene.clone(), s.bvh.clone(), 1, None);
        let mut v = view(&s, Features::all());
        (v.width, v.height) = (64, 48);
        w.apply(Cmd::View(1, Box::new(v)));
        // The coarse pass, then a first full pass with no command waiting.
        while w.film.film().spp == 0 {
            w.step(Cancel::Never, Cancel::Never);
        }
        let before = w.film.film().image();
        // A command waits from the start: a pass that has not yet run
        // `PASS_MS` goes on, so only a slow pass stops.
        let rows = w.progress.rows_done.clone();
        let waiting = || {
            // From the 8th row on, a check takes longer than `PASS_MS`, so
            // the pass is old when it is answered.
            if rows.load(Ordering::Relaxed) >= 8 {
                std::thread::sleep(std::time::Duration::from_millis(PASS_MS as u64 + 10));
            }
            true
        };
        assert!(w.step(Cancel::Never, Cancel::When(&waiting)).is_none());
        let after = w.film.film().image();
        let changed = |y: usize| (0..64).any(|x| before[y * 64 + x] != after[y * 64 + x]);
        assert!(changed(0), "the rows traced before the stop are kept");
        assert!(!changed(47), "the pass stopped before the last row");
        assert!(w.progress.current().is_none(), "no pass is in flight");
    }

    #[test]
    fn the_true_error_is_measured_only_for_the_references_view() {
        let s = session("cornell-area");
        let features = Features::all();
        // The reference: twice the view's size, many samples.
        let t = s.tracer_for(&s.plan, &s.camera, (32, 24));
        let film = Progressive::render(&t, 256);
        let reference = Arc::new(Reference {
            name: "ref.exr".into(),
            width: 32,
            height: 24,
            image: film.image(),
            camera: s.camera,
            plan: s.plan.clone(),
        });
        let mut w = Worker::new(s.scene.clone(), s.bvh.clone(), 1, Some(reference));
        let v = view(&s, features);
        w.apply(Cmd::View(1, Box::new(v.clone())));
        // Full passes up to 16 spp, where the film's noise is still well
        // above the reference's (passes grow: one, one, two, four...).
        let mut frames: Vec<Box<Snapshot>> = Vec::new();
        while frames.last().is_none_or(|f| f.spp < 16) {
            frames.push(full(&mut w));
        }
        let (first, last) = (&frames[0], frames.last().unwrap());
        assert_eq!(
            last.truth,
            Truth::Compared {
                coverage: 1.0,
                exact: true
            }
        );
        let (e1, en) = (first.true_error.unwrap(), last.true_error.unwrap());
        assert!(
            en < 0.5 * e1,
            "true error {e1} after 1 spp, {en} after {}",
            last.spp
        );
        let est = last.error.expect("an estimate at the end");
        assert!(
            (0.5..2.0).contains(&(est / en)),
            "estimate {est} against true {en}"
        );
        assert_eq!(last.true_history.len(), frames.len());
        // Bloom does not change the film; shadows and the camera do.
        let with = |off: Feature| RenderView {
            plan: s.plan_for(features.without(&[off])),
            ..v.clone()
        };
        let mut moved = v.clone();
        moved.camera.orbit(0.1, 0.0);
        for (v, truth) in [
            (with(Feature::Bloom), None),
            (with(Feature::Shadows), Some(Truth::FeaturesChanged)),
            (moved, Some(Truth::CameraMoved)),
        ] {
            w.apply(Cmd::View(2, Box::new(v)));
            let s = full(&mut w);
            match truth {
                None => assert!(s.true_error.is_some()),
                Some(t) => assert_eq!((s.truth, s.true_error), (t, None)),
            }
        }
    }

    #[test]
    fn bloom_and_bvh_toggles_keep_the_samples() {
        let s = session("cornell");
        let mut w = worker(Features::all());
        // Passes of one sample each, before adaptive ones begin; the second
        // at a pace that lets the next grow, however busy the machine.
        full(&mut w);
        w.last_full = Some(LastPass {
            ms: 1.0,
            ms_per_spp: 1.0,
            bvh: true,
        });
        full(&mut w);
        let plain = view(&s, Features::all().without(&[Feature::Bloom, Feature::Bvh]));
        w.apply(Cmd::View(2, Box::new(plain.clone())));
        let f = next_frame(&mut w).unwrap();
        assert_eq!((f.generation, f.spp, f.pre_bloom.is_none()), (2, 2, true));
        // The film goes on, passes growing from where they were.
        assert_eq!(full(&mut w).spp, 4);
        let shadowless = RenderView {
            plan: s.plan_for(Features::all().without(&[
                Feature::Bloom,
                Feature::Bvh,
                Feature::Shadows,
            ])),
            ..plain
        };
        w.apply(Cmd::View(3, Box::new(shadowless)));
        assert_eq!(full(&mut w).spp, 1);
    }

    #[test]
    fn overlays_are_drawn_once_per_view() {
        let mut w = worker(Features::all());
        w.apply(Cmd::ImageView(Some(viz::View::Leaves)));
        let mut overlays = 0;
        for _ in 0..6 {
            if let Some(Msg::Overlay(o)) = w.step(Cancel::Never, Cancel::Never) {
                let (layer, summary) = o.layer.unwrap();
                assert_eq!((o.generation, layer.width, layer.height), (1, 16, 12));
                assert!(!layer.is_blank() && summary.contains("leaf boxes"));
                overlays += 1;
            }
        }
        assert_eq!(overlays, 1);
    }

    #[test]
    fn cancelled_passes_send_nothing() {
        let mut w = worker(Features::all());
        assert!(w.step(Cancel::When(&|| true), Cancel::Never).is_none());
    }

    #[test]
    fn deterministic_views_stop_after_one_pass() {
        let mut w = worker(Features::all().without(&[Feature::Supersampling]));
        let mut last = None;
        while let Some(s) = next_frame(&mut w) {
            last = Some(s);
        }
        let s = last.unwrap();
        assert!(s.exact && s.done && s.spp == 1);
        assert!(w.idle());
    }
}
