//! The render worker: owns the film on its own thread (rayon inside). Each
//! view change restarts accumulation; the first frame of a view is a coarse
//! pass (when full passes are slow) so something appears at once, then every
//! full-resolution pass adds one sample per pixel and sends a snapshot. A
//! newer view cancels the pass in flight between rows, so camera motion never
//! waits for a pass.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::{Context, Result};
use glam::Vec3;

use crate::bvh::{self, Bvh};
use crate::cli::{find_worst, Worst};
use crate::render::recorder::WorkCounter;
use crate::render::{pass, post, Features, Film, Plan, Tracer};
use crate::report::converge::{rel_mse_on, resample};
use crate::scene::{Builder, Camera, Scene};

/// A full pass slower than this is preceded by a quarter-resolution pass
/// when the view changes.
const COARSE_ABOVE_MS: f64 = 20.0;
/// Coarse passes render every `COARSE`-th pixel in each direction.
const COARSE: u32 = 4;
/// Accumulation stops here; the image no longer visibly changes.
pub const MAX_SPP: u32 = 1024;

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub camera: Camera,
    pub features: Features,
    pub width: u32,
    pub height: u32,
}

pub enum Cmd {
    /// Render this view; `u64` is its generation.
    View(u64, View),
    /// Rebuild the BVH with this builder, then render the current view as
    /// generation `u64`.
    Builder(u64, Builder),
    Quit,
}

pub enum Msg {
    Frame(Box<Snapshot>),
    /// The BVH was rebuilt.
    Bvh(Arc<Bvh>),
}

/// A reference image (`--reference`) and the view it shows.
pub struct Reference {
    /// The file's name, for the panel.
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Linear colours, row-major from the top.
    pub image: Vec<Vec3>,
    /// The camera and features it was rendered with; other views are not
    /// compared.
    pub camera: Camera,
    pub features: Features,
}

/// Whether the true error against the reference is measured, and if not why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Truth {
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

/// Mean BVH work per ray (camera and shadow rays) of a full pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerRay {
    pub nodes: f64,
    pub triangle_tests: f64,
}

/// One finished pass, ready to show.
#[derive(Clone, Debug)]
pub struct Snapshot {
    pub generation: u64,
    pub width: u32,
    pub height: u32,
    /// Linear colours as displayed (after bloom), row-major.
    pub image: Vec<Vec3>,
    /// The mean before bloom, when bloom ran.
    pub pre_bloom: Option<Vec<Vec3>>,
    /// A quarter-resolution preview, not yet a sample of the film.
    pub coarse: bool,
    pub spp: u32,
    pub pass_ms: f64,
    pub mrays: f64,
    /// The film's estimated relative error ([`Film::relative_error`]),
    /// unknown below two samples.
    pub error: Option<f64>,
    /// Nothing is sampled and one pass is done: the image is exact.
    pub exact: bool,
    /// No more passes will come for this view.
    pub done: bool,
    /// Seconds since the view started.
    pub elapsed: f64,
    /// (seconds, error) after each pass with an error estimate.
    pub history: Vec<(f64, f64)>,
    /// The true error (root relMSE against the reference) when measured.
    pub true_error: Option<f64>,
    pub truth: Truth,
    /// (seconds, true error) after each pass.
    pub true_history: Vec<(f64, f64)>,
    pub per_ray: Option<PerRay>,
    /// Worst pixels by [`Worst::Nan`], [`Worst::Variance`], [`Worst::Brightest`].
    pub worst: [Option<(u32, u32, u32)>; 3],
    pub bad_samples: u64,
}

/// A tracer for `camera` instead of the scene's own.
pub fn tracer<'a>(
    scene: &'a Scene,
    bvh: &'a Bvh,
    plan: &'a Plan,
    camera: &Camera,
    (width, height): (u32, u32),
    seed: u64,
) -> Tracer<'a> {
    let mut t = Tracer::new(scene, bvh, plan, width, height, seed);
    t.frame = camera.frame(width, height);
    t
}

/// The worker's state; [`Worker::step`] runs one pass. The thread in
/// [`spawn`] and the benchmark drive the same code.
pub struct Worker {
    scene: Arc<Scene>,
    bvh: Arc<Bvh>,
    seed: u64,
    generation: u64,
    view: Option<View>,
    plan: Plan,
    film: Film,
    coarse_pending: bool,
    started: Instant,
    history: Vec<(f64, f64)>,
    per_ray: Option<PerRay>,
    /// Time of the last full pass, to decide whether coarse passes pay off.
    last_full_ms: Option<f64>,
    reference: Option<Arc<Reference>>,
    truth: Truth,
    /// The reference on the view's pixels while `truth` is `Compared`.
    reference_pixels: Vec<(u32, Vec3)>,
    true_history: Vec<(f64, f64)>,
    /// Mrays/s of the last full pass.
    last_mrays: f64,
    /// The film is unchanged but the view's generation is new: show it again.
    resend: bool,
}

impl Worker {
    pub fn new(
        scene: Arc<Scene>,
        bvh: Arc<Bvh>,
        seed: u64,
        reference: Option<Arc<Reference>>,
    ) -> Self {
        let plan = Plan::new(&scene, Features::all());
        Self {
            scene,
            bvh,
            seed,
            generation: 0,
            view: None,
            plan,
            film: Film::new(0, 0),
            coarse_pending: false,
            started: Instant::now(),
            history: Vec::new(),
            per_ray: None,
            last_full_ms: None,
            reference,
            truth: Truth::NoReference,
            reference_pixels: Vec::new(),
            true_history: Vec::new(),
            last_mrays: 0.0,
            resend: false,
        }
    }

    /// Applies a command; returns a message for the app when there is one.
    /// `Quit` is handled by the thread loop.
    pub fn apply(&mut self, cmd: Cmd) -> Option<Msg> {
        match cmd {
            Cmd::View(generation, view) => {
                self.generation = generation;
                // Bloom and the BVH toggle leave the film as it is: keep its
                // samples and only show it again. (A pass cancelled halfway
                // leaves some rows a sample short; each pixel's mean and
                // error are its own, so the film is still sound.)
                let same_film = self.film.spp > 0
                    && self.view.is_some_and(|old| {
                        (old.camera, old.width, old.height)
                            == (view.camera, view.width, view.height)
                            && old.features.shaping_film() == view.features.shaping_film()
                    });
                if self.view != Some(view) {
                    self.plan = Plan::new(&self.scene, view.features);
                    self.view = Some(view);
                }
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
                self.last_full_ms = None;
                self.restart();
                Some(Msg::Bvh(self.bvh.clone()))
            }
            Cmd::Quit => None,
        }
    }

    fn restart(&mut self) {
        let (w, h) = self.view.map_or((0, 0), |v| (v.width, v.height));
        self.film = Film::new(w, h);
        self.coarse_pending = self.last_full_ms.is_none_or(|ms| ms > COARSE_ABOVE_MS);
        self.started = Instant::now();
        self.history.clear();
        self.per_ray = None;
        self.true_history.clear();
        self.compare_with_reference();
    }

    /// Decides whether the view can be compared with the reference, and
    /// takes the reference onto the view's pixels when it can.
    fn compare_with_reference(&mut self) {
        self.reference_pixels.clear();
        self.truth = match (&self.reference, self.view) {
            (None, _) | (_, None) => Truth::NoReference,
            (Some(r), Some(v)) if v.camera != r.camera => Truth::CameraMoved,
            (Some(r), Some(v)) if v.features.shaping_film() != r.features.shaping_film() => {
                Truth::FeaturesChanged
            }
            (Some(r), Some(v)) => {
                let m = resample(r.width, r.height, &r.image, v.width, v.height);
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

    /// Whether more passes would change the image.
    pub fn idle(&self) -> bool {
        if self.resend {
            return false;
        }
        match self.view {
            None => true,
            Some(v) if v.width == 0 || v.height == 0 => true,
            Some(_) => self.film.spp >= MAX_SPP || (self.plan.deterministic && self.film.spp >= 1),
        }
    }

    /// Runs the next pass; `None` when idle or cancelled.
    pub fn step(&mut self, cancel: &(dyn Fn() -> bool + Sync)) -> Option<Snapshot> {
        if self.idle() {
            return None;
        }
        let view = self.view?;
        if std::mem::take(&mut self.resend) {
            let mean = self.film.image();
            let truth = self.true_error(&mean);
            return Some(self.snapshot(&view, mean, truth));
        }
        if std::mem::take(&mut self.coarse_pending) {
            return self.coarse(&view, cancel);
        }
        let t = tracer(
            &self.scene,
            &self.bvh,
            &self.plan,
            &view.camera,
            (view.width, view.height),
            self.seed,
        );
        let start = Instant::now();
        // The first pass of a view counts BVH work for the panel; later ones
        // take the fast path.
        let rays = if self.film.spp == 0 && self.plan.bvh {
            let (rays, work) = pass::render_pass_with::<WorkCounter>(&t, &mut self.film, 1, cancel);
            let n = rays.max(1) as f64;
            self.per_ray = Some(PerRay {
                nodes: work.work.nodes_visited as f64 / n,
                triangle_tests: work.work.triangle_tests as f64 / n,
            });
            rays
        } else {
            pass::render_pass(&t, &mut self.film, 1, cancel)
        };
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if cancel() {
            return None;
        }
        self.last_full_ms = Some(ms);
        self.last_mrays = rays as f64 / (ms.max(1e-6) * 1e3);
        let elapsed = self.started.elapsed().as_secs_f64();
        if let Some(error) = self.film.relative_error().filter(|&e| e > 0.0) {
            self.history.push((elapsed, error));
        }
        let mean = self.film.image();
        let truth = self.true_error(&mean);
        if let Some(e) = truth {
            self.true_history.push((elapsed, e));
        }
        Some(self.snapshot(&view, mean, truth))
    }

    /// Root relMSE of `mean` against the reference, where it is compared.
    fn true_error(&self, mean: &[Vec3]) -> Option<f64> {
        matches!(self.truth, Truth::Compared { .. })
            .then(|| rel_mse_on(mean, &self.reference_pixels).sqrt())
    }

    /// The film as it stands, for the app; `mean` is its image and
    /// `true_error` that image's error against the reference.
    fn snapshot(&self, view: &View, mean: Vec<Vec3>, true_error: Option<f64>) -> Snapshot {
        let (image, pre_bloom) = self.bloomed(mean, view.width, view.height);
        let worst =
            [Worst::Nan, Worst::Variance, Worst::Brightest].map(|w| find_worst(&self.film, w));
        Snapshot {
            generation: self.generation,
            width: view.width,
            height: view.height,
            image,
            pre_bloom,
            coarse: false,
            spp: self.film.spp,
            pass_ms: self.last_full_ms.unwrap_or(0.0),
            mrays: self.last_mrays,
            error: self.film.relative_error(),
            exact: self.plan.deterministic,
            done: self.idle(),
            elapsed: self.started.elapsed().as_secs_f64(),
            history: self.history.clone(),
            true_error,
            truth: self.truth,
            true_history: self.true_history.clone(),
            per_ray: self.per_ray,
            worst,
            bad_samples: self.film.bad_count,
        }
    }

    /// Bloom applied when the plan has it: (displayed, mean before bloom).
    fn bloomed(&self, mut img: Vec<Vec3>, w: u32, h: u32) -> (Vec<Vec3>, Option<Vec<Vec3>>) {
        if !self.plan.bloom {
            return (img, None);
        }
        let before = img.clone();
        post::bloom(&mut img, w as usize, h as usize, &self.scene.settings.bloom);
        (img, Some(before))
    }

    /// One sample of every `COARSE`-th pixel, upscaled to the view.
    fn coarse(&self, view: &View, cancel: &(dyn Fn() -> bool + Sync)) -> Option<Snapshot> {
        let (cw, ch) = (view.width.div_ceil(COARSE), view.height.div_ceil(COARSE));
        let t = tracer(
            &self.scene,
            &self.bvh,
            &self.plan,
            &view.camera,
            (cw, ch),
            self.seed,
        );
        let mut film = Film::new(cw, ch);
        let start = Instant::now();
        let rays = pass::render_pass(&t, &mut film, 1, cancel);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        if cancel() {
            return None;
        }
        let small = film.image();
        let mut image = Vec::with_capacity((view.width * view.height) as usize);
        for y in 0..view.height {
            for x in 0..view.width {
                image.push(small[((y / COARSE) * cw + x / COARSE) as usize]);
            }
        }
        let (image, pre_bloom) = self.bloomed(image, view.width, view.height);
        Some(Snapshot {
            generation: self.generation,
            width: view.width,
            height: view.height,
            image,
            pre_bloom,
            coarse: true,
            spp: 0,
            pass_ms: ms,
            mrays: rays as f64 / (ms.max(1e-6) * 1e3),
            error: None,
            exact: false,
            done: false,
            elapsed: self.started.elapsed().as_secs_f64(),
            history: Vec::new(),
            true_error: None,
            truth: self.truth,
            true_history: Vec::new(),
            per_ray: None,
            worst: [None; 3],
            bad_samples: 0,
        })
    }
}

/// The app's end of the worker.
pub struct Handle {
    tx: Sender<Cmd>,
    pub rx: Receiver<Msg>,
    /// Generation of the newest command; passes of older ones stop.
    latest: Arc<AtomicU64>,
    thread: Option<JoinHandle<()>>,
}

/// Starts the worker thread.
pub fn spawn(worker: Worker) -> Result<Handle> {
    let (tx, cmd_rx) = mpsc::channel();
    let (msg_tx, rx) = mpsc::channel();
    let latest = Arc::new(AtomicU64::new(0));
    let seen = latest.clone();
    let thread = std::thread::Builder::new()
        .name("rayterm-render".into())
        .spawn(move || run(worker, cmd_rx, msg_tx, seen))
        .context("cannot start the render thread")?;
    Ok(Handle {
        tx,
        rx,
        latest,
        thread: Some(thread),
    })
}

impl Handle {
    /// Sends a command; a view or builder change cancels the pass in flight.
    pub fn send(&self, cmd: Cmd) {
        if let Cmd::View(g, _) | Cmd::Builder(g, _) = cmd {
            self.latest.store(g, Ordering::SeqCst);
        }
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

fn run(mut w: Worker, rx: Receiver<Cmd>, tx: Sender<Msg>, latest: Arc<AtomicU64>) {
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
        if let Some(s) = w.step(&cancel) {
            if tx.send(Msg::Frame(Box::new(s))).is_err() {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Feature;

    fn worker(features: Features) -> Worker {
        let scene = Arc::new(crate::scene::load("cornell").unwrap());
        let bvh = Arc::new(bvh::build(&scene.geometry, Builder::Sah));
        let mut w = Worker::new(scene.clone(), bvh, 1, None);
        w.apply(Cmd::View(
            1,
            View {
                camera: scene.camera,
                features,
                width: 16,
                height: 12,
            },
        ));
        w
    }

    #[test]
    fn a_coarse_preview_comes_first_then_one_sample_per_pass() {
        let mut w = worker(Features::all());
        let s = w.step(&|| false).unwrap();
        assert!(s.coarse && s.spp == 0);
        assert_eq!(s.image.len(), 16 * 12);
        // Each 4x4 block of the preview is one coarse pixel.
        assert_eq!(s.image[0], s.image[3 * 16 + 3]);
        for spp in 1..=3 {
            let s = w.step(&|| false).unwrap();
            assert!(!s.coarse);
            assert_eq!((s.spp, s.generation), (spp, 1));
        }
        assert!(w.step(&|| false).unwrap().per_ray.is_some());
    }

    #[test]
    fn the_true_error_is_measured_only_for_the_references_view() {
        let scene = Arc::new(crate::scene::load("cornell-area").unwrap());
        let bvh = Arc::new(bvh::build(&scene.geometry, Builder::Sah));
        let features = Features::all();
        // The reference: twice the view's size, many samples.
        let plan = Plan::new(&scene, features);
        let t = Tracer::new(&scene, &bvh, &plan, 32, 24, 99);
        let mut film = Film::new(32, 24);
        pass::render_pass(&t, &mut film, 256, &|| false);
        let reference = Arc::new(Reference {
            name: "ref.hdr".into(),
            width: 32,
            height: 24,
            image: film.image(),
            camera: scene.camera,
            features,
        });
        let mut w = Worker::new(scene.clone(), bvh, 1, Some(reference));
        let view = View {
            camera: scene.camera,
            features,
            width: 16,
            height: 12,
        };
        w.apply(Cmd::View(1, view));
        let mut frames = Vec::new();
        while frames.len() < 17 {
            let s = w.step(&|| false).unwrap();
            if !s.coarse {
                frames.push(s);
            }
        }
        let (first, last) = (&frames[0], &frames[16]);
        assert_eq!(
            last.truth,
            Truth::Compared {
                coverage: 1.0,
                exact: true
            }
        );
        let (e1, e17) = (first.true_error.unwrap(), last.true_error.unwrap());
        assert!(
            e17 < 0.5 * e1,
            "true error {e1} after 1 spp, {e17} after 17"
        );
        let est = last.error.expect("an estimate at 17 spp");
        assert!(
            (0.5..2.0).contains(&(est / e17)),
            "estimate {est} against true {e17}"
        );
        assert_eq!(last.true_history.len(), 17);
        // Bloom does not change the film; shadows and the camera do.
        let mut bloomless = view;
        bloomless.features.set(Feature::Bloom, false);
        let mut shadowless = view;
        shadowless.features.set(Feature::Shadows, false);
        let mut moved = view;
        moved.camera.orbit(0.1, 0.0);
        for (v, truth) in [
            (bloomless, None),
            (shadowless, Some(Truth::FeaturesChanged)),
            (moved, Some(Truth::CameraMoved)),
        ] {
            w.apply(Cmd::View(2, v));
            let s = std::iter::from_fn(|| w.step(&|| false))
                .find(|s| !s.coarse)
                .unwrap();
            match truth {
                None => assert!(s.true_error.is_some()),
                Some(t) => assert_eq!((s.truth, s.true_error), (t, None)),
            }
        }
    }

    #[test]
    fn bloom_and_bvh_toggles_keep_the_samples() {
        let mut w = worker(Features::all());
        let view = w.view.unwrap();
        let full = |w: &mut Worker| {
            std::iter::from_fn(|| w.step(&|| false))
                .find(|s| !s.coarse)
                .unwrap()
        };
        for _ in 0..4 {
            full(&mut w);
        }
        let mut plain = view;
        plain.features.set(Feature::Bloom, false);
        plain.features.set(Feature::Bvh, false);
        w.apply(Cmd::View(2, plain));
        let s = w.step(&|| false).unwrap();
        assert_eq!((s.generation, s.spp, s.pre_bloom.is_none()), (2, 4, true));
        assert_eq!(full(&mut w).spp, 5);
        let mut shadowless = plain;
        shadowless.features.set(Feature::Shadows, false);
        w.apply(Cmd::View(3, shadowless));
        assert_eq!(full(&mut w).spp, 1);
    }

    #[test]
    fn cancelled_passes_send_nothing() {
        let mut w = worker(Features::all());
        assert!(w.step(&|| true).is_none());
    }

    #[test]
    fn deterministic_views_stop_after_one_pass() {
        let mut w = worker(Features::all().without(&[Feature::Supersampling]));
        let mut last = None;
        while let Some(s) = w.step(&|| false) {
            last = Some(s);
        }
        let s = last.unwrap();
        assert!(s.exact && s.done && s.spp == 1);
        assert!(w.idle());
    }
}
