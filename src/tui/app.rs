//! The TUI's state and what every action does to it. Drawing reads this
//! state (see `widgets`); rendering happens in the worker.

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{bail, Result};
use ratatui::crossterm::event::{Event, MouseButton, MouseEventKind};
use ratatui::layout::Rect;

use super::color::ColorMode;
use super::export;
use super::keys::{self, Action, Key, Mode};
use super::worker::{self, Cmd, Msg, Reference, Snapshot, Truth, View, Worker};
use crate::bvh::Bvh;
use crate::cli::{Prepared, Worst};
use crate::inspect::{inspect_pixel, lines, PixelTree, TreeLine};
use crate::render::plan::not_needed;
use crate::render::{Feature, Features, Plan};
use crate::report::converge::load_reference;
use crate::report::stability;
use crate::scene::{Builder, Camera, Scene};

/// Camera orbit step per key press, in radians (5 degrees).
const ORBIT_STEP: f32 = 0.087_266_46;
/// Camera move step per key press, as a fraction of the initial eye-target distance.
const MOVE_STEP: f32 = 0.05;
/// Field-of-view step per key press, in degrees, and its limits.
const FOV_STEP: f32 = 5.0;
const FOV_RANGE: (f32, f32) = (5.0, 150.0);

/// BVH visualisation over the viewport.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Overlay {
    Off,
    /// Outlines of the boxes at level `App::level`.
    Level,
    /// Outlines of the leaf boxes.
    Leaves,
    /// Each pixel coloured by the nodes its camera ray visited.
    HeatNodes,
    /// Each pixel coloured by the triangle tests of its camera ray.
    HeatTests,
}

impl Overlay {
    fn next(self) -> Self {
        match self {
            Overlay::Off => Overlay::Level,
            Overlay::Level => Overlay::Leaves,
            Overlay::Leaves => Overlay::HeatNodes,
            Overlay::HeatNodes => Overlay::HeatTests,
            Overlay::HeatTests => Overlay::Off,
        }
    }
}

/// A feature's state as the Features panel shows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FeatureState {
    On,
    Off,
    /// On, but the scene has nothing it could change.
    NotNeeded(&'static str),
    /// On, but the feature it refines is off.
    Needs(Feature),
}

/// The selected pixel and the sample replayed for its ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Selected {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
}

/// A scrollable text window over the layout (the help, or a report table).
pub struct Popup {
    pub title: String,
    pub lines: Vec<String>,
    pub scroll: usize,
}

pub struct App {
    pub scene: Arc<Scene>,
    pub bvh: Arc<Bvh>,
    pub plan: Plan,
    pub seed: u64,
    home: Camera,
    pub camera: Camera,
    pub features: Features,
    pub builder: Builder,
    pub color: ColorMode,
    export_size: (u32, u32),
    step: f32,
    /// Length drawn for rays that miss everything: twice the scene's diagonal.
    pub reach: f32,
    /// Bumped on every change that restarts rendering.
    generation: u64,
    /// The viewport's size in pixels, set when drawing.
    pub view_size: (u32, u32),
    worker: worker::Handle,
    /// The newest pass.
    pub frame: Option<Box<Snapshot>>,
    pub select_mode: bool,
    pub selected: Option<Selected>,
    tree: Option<((Selected, u64), PixelTree)>,
    /// Open folds of the debug pane.
    pub expanded: HashSet<usize>,
    /// The debug pane's cursor line and first visible line.
    pub debug_cursor: usize,
    pub debug_top: usize,
    /// Visible lines of the debug pane, set when drawing.
    pub debug_height: usize,
    pub show_rays: bool,
    pub overlay: Overlay,
    pub level: usize,
    pub status: String,
    pub popup: Option<Popup>,
    export: Option<export::Job>,
    /// The stability battery's result, while it runs.
    stability: Option<std::sync::mpsc::Receiver<Result<Vec<stability::Row>>>>,
    /// Where PNG exports go: the directory the TUI was started in.
    pub export_dir: PathBuf,
    pub rebuilding: bool,
    pub bytes_per_sec: f64,
    bytes_mark: (Instant, u64),
    /// Generation and time of the last pass that asked for a redraw.
    shown: (u64, Instant),
    /// Where the image is drawn on screen, set when drawing (for mouse clicks).
    pub viewport: Rect,
    pub debug_area: Rect,
    pub quit: bool,
    /// The `--reference` image, if any.
    pub reference: Option<Arc<Reference>>,
    /// The view size for which the status line last said how to make the
    /// reference exact.
    resample_noted: Option<(u32, u32)>,
}

impl App {
    /// `reference` is a linear .hdr image of the scene from its own camera
    /// with the features the TUI starts with; the true error is measured
    /// against it while the view is that one.
    pub fn new(p: Prepared, color: ColorMode, reference: Option<&Path>) -> Result<App> {
        let scene = Arc::new(p.scene);
        let bvh = Arc::new(p.bvh);
        let home = scene.camera;
        let reference = match reference {
            Some(path) => {
                let (width, height, image) = load_reference(path)?;
                Some(Arc::new(Reference {
                    name: path.display().to_string(),
                    width,
                    height,
                    image,
                    camera: home,
                    features: p.plan.features,
                }))
            }
            None => None,
        };
        let worker = worker::spawn(Worker::new(
            scene.clone(),
            bvh.clone(),
            p.seed,
            reference.clone(),
        ))?;
        let status = format!(
            "{}: {} triangles, {} lights. Press ? for help.{}{}",
            scene.name,
            scene.geometry.triangle_count(),
            scene.lights.len(),
            match scene.warnings.len() {
                0 => String::new(),
                n => format!(" {n} load warnings (printed above the TUI)."),
            },
            match &reference {
                Some(r) => format!(
                    " Reference {} ({}x{}): true error shown at the start view (r returns).",
                    r.name, r.width, r.height
                ),
                None => String::new(),
            }
        );
        Ok(App {
            step: MOVE_STEP * (home.eye - home.target).length().max(1e-6),
            reach: 2.0 * scene.bounds().extent().length(),
            builder: scene.settings.builder,
            features: p.plan.features,
            plan: p.plan,
            seed: p.seed,
            home,
            camera: home,
            color,
            export_size: (p.width, p.height),
            generation: 0,
            view_size: (0, 0),
            worker,
            frame: None,
            select_mode: false,
            selected: None,
            tree: None,
            expanded: HashSet::new(),
            debug_cursor: 0,
            debug_top: 0,
            debug_height: 1,
            show_rays: false,
            overlay: Overlay::Off,
            level: 0,
            status,
            popup: None,
            export: None,
            stability: None,
            export_dir: std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
            rebuilding: false,
            bytes_per_sec: 0.0,
            bytes_mark: (Instant::now(), 0),
            shown: (0, Instant::now()),
            viewport: Rect::default(),
            debug_area: Rect::default(),
            quit: false,
            scene,
            bvh,
            reference,
            resample_noted: None,
        })
    }

    pub fn mode(&self) -> Mode {
        if self.select_mode {
            Mode::Select
        } else {
            Mode::View
        }
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The newest pass when it shows the current view.
    pub fn current_frame(&self) -> Option<&Snapshot> {
        self.frame
            .as_deref()
            .filter(|f| f.generation == self.generation)
    }

    /// Sets the viewport size in pixels; a change restarts rendering.
    pub fn set_view_size(&mut self, w: u32, h: u32) {
        if self.view_size != (w, h) {
            self.view_size = (w, h);
            if let Some(s) = &mut self.selected {
                s.x = s.x.min(w.saturating_sub(1));
                s.y = s.y.min(h.saturating_sub(1));
            }
            self.send_view();
        }
    }

    fn send_view(&mut self) {
        self.generation += 1;
        self.worker.send(Cmd::View(
            self.generation,
            View {
                camera: self.camera,
                features: self.features,
                width: self.view_size.0,
                height: self.view_size.1,
            },
        ));
    }

    pub fn handle_event(&mut self, ev: &Event) {
        match ev {
            Event::Key(k) => {
                if let Some(key) = Key::from_event(k) {
                    self.handle_key(key);
                }
            }
            Event::Mouse(m) => {
                let inside = |r: Rect| {
                    m.column >= r.x
                        && m.column < r.x + r.width
                        && m.row >= r.y
                        && m.row < r.y + r.height
                };
                match m.kind {
                    MouseEventKind::Down(MouseButton::Left) if inside(self.viewport) => {
                        let (w, h) = self.view_size;
                        let x = (m.column - self.viewport.x) as u32 * w
                            / self.viewport.width.max(1) as u32;
                        let y = (m.row - self.viewport.y) as u32 * 2 * h
                            / (2 * self.viewport.height.max(1) as u32);
                        self.select(x, y, 0);
                    }
                    MouseEventKind::ScrollDown if inside(self.debug_area) => {
                        self.act(Action::Line(3))
                    }
                    MouseEventKind::ScrollUp if inside(self.debug_area) => {
                        self.act(Action::Line(-3))
                    }
                    _ => {}
                }
            }
            _ => {}
        }
    }

    pub fn handle_key(&mut self, key: Key) {
        if let Some(p) = &mut self.popup {
            // The popup takes scrolling keys; Esc and ? close it.
            match key {
                Key::Up | Key::Char('k') | Key::Char('[') => p.scroll = p.scroll.saturating_sub(1),
                Key::Down | Key::Char('j') | Key::Char(']') => p.scroll += 1,
                Key::PageUp => p.scroll = p.scroll.saturating_sub(10),
                Key::PageDown => p.scroll += 10,
                Key::Esc | Key::Char('?') => self.popup = None,
                Key::Char('q') | Key::Ctrl('c') => self.quit = true,
                _ => {}
            }
            return;
        }
        if let Some(a) = keys::action(key, self.mode()) {
            self.act(a);
        }
    }

    pub fn act(&mut self, a: Action) {
        match a {
            Action::Orbit(yaw, pitch) => {
                self.camera
                    .orbit(yaw as f32 * ORBIT_STEP, pitch as f32 * ORBIT_STEP);
                self.send_view();
            }
            Action::Move(r, u, f) => {
                let s = self.step;
                self.camera.pan(r as f32 * s, u as f32 * s, f as f32 * s);
                self.send_view();
            }
            Action::Fov(d) => {
                self.camera.vfov =
                    (self.camera.vfov + d as f32 * FOV_STEP).clamp(FOV_RANGE.0, FOV_RANGE.1);
                self.status = format!("field of view {:.0}°", self.camera.vfov);
                self.send_view();
            }
            Action::ResetView => {
                self.camera = self.home;
                self.status = "view reset".into();
                self.send_view();
            }
            Action::Toggle(f) => self.toggle(f),
            Action::SwitchBuilder => {
                self.builder = match self.builder {
                    Builder::Sah => Builder::Median,
                    Builder::Median => Builder::Sah,
                };
                self.generation += 1;
                self.rebuilding = true;
                self.worker
                    .send(Cmd::Builder(self.generation, self.builder));
                self.status = format!("rebuilding the BVH with the {} builder...", self.builder);
            }
            Action::SelectMode => {
                self.select_mode = !self.select_mode;
                if self.select_mode && self.selected.is_none() {
                    let (w, h) = self.view_size;
                    self.select(w / 2, h / 2, 0);
                }
                self.status = if self.select_mode {
                    "select mode: hjkl or arrows move the cursor, v or Esc leaves".into()
                } else {
                    "view mode".into()
                };
            }
            Action::Back => {
                self.select_mode = false;
                self.popup = None;
            }
            Action::Cursor(dx, dy) => {
                let (w, h) = self.view_size;
                let s = self.selected.unwrap_or(Selected {
                    x: w / 2,
                    y: h / 2,
                    sample: 0,
                });
                let x = (s.x as i64 + dx as i64).clamp(0, w.saturating_sub(1) as i64) as u32;
                let y = (s.y as i64 + dy as i64).clamp(0, h.saturating_sub(1) as i64) as u32;
                self.select(x, y, 0);
            }
            Action::Fold => self.fold(),
            Action::Line(n) => self.move_debug_cursor(n as i64),
            Action::Page(n) => self.move_debug_cursor(n as i64 * self.debug_height.max(1) as i64),
            Action::Worst(w) => self.jump_to_worst(w),
            Action::Rays => {
                self.show_rays = !self.show_rays;
                self.status = match (self.show_rays, self.selected) {
                    (false, _) => "rays off".into(),
                    (true, Some(_)) => {
                        "rays of the selected pixel: shadow rays red when occluded, white when clear"
                            .into()
                    }
                    (true, None) => "rays on: select a pixel (v, or click) to see its rays".into(),
                };
            }
            Action::Overlay => {
                self.overlay = self.overlay.next();
                self.status = format!("BVH overlay: {}", self.overlay_name());
            }
            Action::Level(d) => {
                let max = self.bvh.stats.depth.saturating_sub(1) as i64;
                self.level = (self.level as i64 + d as i64).clamp(0, max) as usize;
                self.overlay = Overlay::Level;
                self.status = format!("BVH overlay: {}", self.overlay_name());
            }
            Action::SavePng => self.save_png(),
            Action::Stability => self.run_stability(),
            Action::Help => {
                self.popup = match self.popup {
                    Some(_) => None,
                    None => Some(help_popup()),
                }
            }
            Action::Quit => self.quit = true,
        }
    }

    pub fn overlay_name(&self) -> String {
        match self.overlay {
            Overlay::Off => "off".into(),
            Overlay::Level => format!("boxes of level {}", self.level),
            Overlay::Leaves => "leaf boxes".into(),
            Overlay::HeatNodes => "heat map of nodes visited".into(),
            Overlay::HeatTests => "heat map of triangle tests".into(),
        }
    }

    /// The `x` key: runs the stability battery on this scene in the
    /// background; the table opens in a popup when it is done.
    fn run_stability(&mut self) {
        if self.stability.is_some() {
            self.status = "the stability battery is already running".into();
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let scene = self.scene.clone();
        std::thread::spawn(move || {
            let rows = stability::run_battery_on(&scene, &stability::Options::default());
            // The receiver is gone only when the TUI has quit.
            let _ = tx.send(rows);
        });
        self.stability = Some(rx);
        self.status = "running the stability battery...".into();
    }

    /// Opens the battery's table once it has arrived; true when it did.
    fn poll_stability(&mut self) -> bool {
        let Some(rx) = &self.stability else {
            return false;
        };
        let result = match rx.try_recv() {
            Ok(r) => r,
            Err(std::sync::mpsc::TryRecvError::Empty) => return false,
            Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                Err(anyhow::anyhow!("the battery stopped unexpectedly"))
            }
        };
        self.stability = None;
        match result {
            Ok(rows) => {
                let failed = rows.iter().filter(|r| !r.pass).count();
                self.status = format!(
                    "stability battery: {} of {} cases passed",
                    rows.len() - failed,
                    rows.len()
                );
                self.popup = Some(Popup {
                    title: format!("stability battery: {} ({failed} failed)", self.scene.name),
                    lines: stability::format_table(&rows)
                        .lines()
                        .map(str::to_string)
                        .collect(),
                    scroll: 0,
                });
            }
            Err(e) => self.status = format!("stability battery failed: {e:#}"),
        }
        true
    }

    pub fn feature_state(&self, f: Feature) -> FeatureState {
        if !self.features.on(f) {
            return FeatureState::Off;
        }
        if let Some(why) = not_needed(&self.scene, f) {
            return FeatureState::NotNeeded(why);
        }
        match f {
            Feature::Glossy if !self.plan.reflections => FeatureState::Needs(Feature::Reflections),
            Feature::Bilinear if !self.plan.textures => FeatureState::Needs(Feature::Textures),
            _ => FeatureState::On,
        }
    }

    fn toggle(&mut self, f: Feature) {
        self.features.toggle(f);
        let plan = Plan::new(&self.scene, self.features);
        let same = plan
            .stages
            .iter()
            .map(|s| s.on)
            .eq(self.plan.stages.iter().map(|s| s.on));
        self.plan = plan;
        let state = if self.features.on(f) { "on" } else { "off" };
        self.status = match not_needed(&self.scene, f) {
            Some(why) => format!(
                "{} {state}: not needed: {why}, so the image does not change",
                f.name()
            ),
            None if same => format!("{} {state}: no change to the image", f.name()),
            None => format!("{} {state}", f.name()),
        };
        if !same {
            self.send_view();
        }
    }

    pub fn select(&mut self, x: u32, y: u32, sample: u32) {
        let (w, h) = self.view_size;
        if w == 0 || h == 0 {
            return;
        }
        self.selected = Some(Selected {
            x: x.min(w - 1),
            y: y.min(h - 1),
            sample,
        });
        self.debug_cursor = 0;
        self.debug_top = 0;
        self.expanded.clear();
    }

    fn jump_to_worst(&mut self, w: Worst) {
        let Some(f) = self.current_frame().filter(|f| !f.coarse) else {
            self.status = "no pass has finished for this view yet".into();
            return;
        };
        let i = match w {
            Worst::Nan => 0,
            Worst::Variance => 1,
            Worst::Brightest => 2,
        };
        let (found, spp) = (f.worst[i], f.spp);
        let what = match w {
            Worst::Nan => "NaN/Inf sample",
            Worst::Variance => "highest variance",
            Worst::Brightest => "brightest",
        };
        match found {
            Some((x, y, k)) => {
                self.select(x, y, k);
                self.status = format!("worst pixel ({what}): ({x}, {y}), sample {k}");
            }
            None => {
                self.status = format!("no pixel had a NaN or infinite sample in {spp} spp");
            }
        }
    }

    /// The selected pixel's ray tree, replayed when the pixel or the view changed.
    pub fn tree(&mut self) -> Option<&PixelTree> {
        let s = self.selected?;
        let key = (s, self.generation);
        if self.tree.as_ref().map(|t| t.0) != Some(key) {
            let t = worker::tracer(
                &self.scene,
                &self.bvh,
                &self.plan,
                &self.camera,
                self.view_size,
                self.seed,
            );
            self.tree = Some((key, inspect_pixel(&t, s.x, s.y, s.sample)));
        }
        let frame = self
            .frame
            .as_deref()
            .filter(|f| f.generation == self.generation && !f.coarse);
        let tree = &mut self.tree.as_mut()?.1;
        // The pixel's colour before and after bloom comes from the film.
        if let Some((f, pre)) = frame.and_then(|f| f.pre_bloom.as_ref().map(|p| (f, p))) {
            let i = (s.y * f.width + s.x) as usize;
            if let (Some(b), Some(a)) = (pre.get(i), f.image.get(i)) {
                tree.pixel_before_bloom = Some(*b);
                tree.pixel_after_bloom = Some(*a);
            }
        }
        Some(tree)
    }

    pub fn debug_lines(&mut self) -> Vec<TreeLine> {
        let expanded = self.expanded.clone();
        match self.tree() {
            Some(t) => lines(t, &|id| expanded.contains(&id)),
            None => Vec::new(),
        }
    }

    fn move_debug_cursor(&mut self, n: i64) {
        let len = self.debug_lines().len() as i64;
        self.debug_cursor = (self.debug_cursor as i64 + n).clamp(0, (len - 1).max(0)) as usize;
    }

    /// Toggles the first fold at or below the debug cursor.
    fn fold(&mut self) {
        let lines = self.debug_lines();
        let found = lines
            .iter()
            .enumerate()
            .skip(self.debug_cursor)
            .find_map(|(i, l)| l.fold.map(|(id, _)| (i, id)));
        match found {
            Some((i, id)) => {
                if !self.expanded.remove(&id) {
                    self.expanded.insert(id);
                }
                self.debug_cursor = i;
            }
            None => self.status = "nothing to fold below the debug cursor".into(),
        }
    }

    fn save_png(&mut self) {
        if self.export.is_some() {
            self.status = "an export is already running".into();
            return;
        }
        match export::Job::start(export::Request {
            scene: self.scene.clone(),
            bvh: self.bvh.clone(),
            camera: self.camera,
            features: self.features,
            size: self.export_size,
            seed: self.seed,
            dir: self.export_dir.clone(),
        }) {
            Ok(job) => self.export = Some(job),
            Err(e) => self.status = format!("cannot export: {e:#}"),
        }
    }

    /// Export progress for the status line.
    pub fn export_progress(&self) -> Option<String> {
        self.export.as_ref().map(|j| {
            format!(
                "exporting {}x{} PNG: {}/{} spp",
                j.size.0,
                j.size.1,
                j.done_spp(),
                j.target_spp
            )
        })
    }

    /// Takes what the worker and the export have sent; true when the screen
    /// needs redrawing. Fails when the worker has stopped.
    pub fn poll(&mut self) -> Result<bool> {
        let mut changed = false;
        loop {
            match self.worker.rx.try_recv() {
                Ok(m) => changed |= self.on_msg(m),
                Err(std::sync::mpsc::TryRecvError::Empty) => break,
                Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                    bail!("the render worker stopped unexpectedly")
                }
            }
        }
        changed |= self.poll_stability();
        if let Some(job) = &self.export {
            changed = true;
            if let Some(r) = job.poll() {
                self.status = match r {
                    Ok(s) => format!(
                        "saved {} ({}x{}, {} spp, {:.1} s)",
                        s.path.display(),
                        job.size.0,
                        job.size.1,
                        s.spp,
                        s.seconds
                    ),
                    Err(e) => format!("export failed: {e:#}"),
                };
                self.export = None;
            }
        }
        Ok(changed)
    }

    /// Takes a message from the worker; true when the screen should be
    /// redrawn for it.
    fn on_msg(&mut self, m: Msg) -> bool {
        match m {
            Msg::Frame(f) => {
                // Late passes change the image less and less: they are shown
                // less often, which saves terminal bandwidth.
                let due = f.coarse
                    || f.done
                    || f.generation != self.shown.0
                    || self.shown.1.elapsed() >= refresh_interval(f.spp);
                if due {
                    self.shown = (f.generation, Instant::now());
                }
                self.note_resampling(&f);
                self.frame = Some(f);
                due
            }
            Msg::Bvh(b) => {
                self.status = format!(
                    "BVH rebuilt with the {} builder in {:.1} ms",
                    b.stats.builder, b.stats.build_ms
                );
                self.bvh = b;
                self.rebuilding = false;
                self.tree = None;
                self.level = self.level.min(self.bvh.stats.depth.saturating_sub(1));
                true
            }
        }
    }

    /// Says once per view size how to render a reference that compares
    /// exactly: resampling it adds error wherever an edge falls inside a
    /// reference pixel.
    fn note_resampling(&mut self, f: &Snapshot) {
        let (Truth::Compared { exact: false, .. }, Some(r)) = (f.truth, &self.reference) else {
            return;
        };
        if self.resample_noted == Some((f.width, f.height)) {
            return;
        }
        self.resample_noted = Some((f.width, f.height));
        let k = ((r.width as f64 / f.width as f64).round() as u32).max(1);
        self.status = format!(
            "For an exact true error render the reference at {}x{} ({k}x the {}x{} view): this {}x{} one is resampled, which adds error at edges.",
            k * f.width,
            k * f.height,
            f.width,
            f.height,
            r.width,
            r.height,
        );
    }

    /// Waits until a full pass of the current view has arrived; false on timeout.
    pub fn wait_frame(&mut self, timeout: Duration) -> Result<bool> {
        let end = Instant::now() + timeout;
        loop {
            if self.current_frame().is_some_and(|f| !f.coarse) && !self.rebuilding {
                return Ok(true);
            }
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(false);
            }
            match self.worker.rx.recv_timeout(left) {
                Ok(m) => {
                    self.on_msg(m);
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => return Ok(false),
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    bail!("the render worker stopped unexpectedly")
                }
            }
        }
    }

    /// Updates the bytes-per-second readout from the terminal writer's
    /// total, once a second; true when the readout changed.
    pub fn note_bytes(&mut self, total: u64) -> bool {
        let (since, base) = self.bytes_mark;
        let dt = since.elapsed().as_secs_f64();
        if dt < 1.0 {
            return false;
        }
        let rate = total.saturating_sub(base) as f64 / dt;
        self.bytes_mark = (Instant::now(), total);
        let changed = rate != self.bytes_per_sec;
        self.bytes_per_sec = rate;
        changed
    }

    /// Stops an export in progress; says so when there was one.
    pub fn cancel_export(&mut self) -> bool {
        self.export.take().is_some()
    }
}

/// How often a pass at `spp` samples per pixel is worth showing: every
/// frame up to 32 spp, then less often as each pass changes less, up to
/// twice a second.
fn refresh_interval(spp: u32) -> Duration {
    Duration::from_millis((33 * spp as u64 / 32).min(500))
}

/// The help, generated from the key table.
fn help_popup() -> Popup {
    let w = keys::ROWS
        .iter()
        .map(|r| keys::keys_label(r).chars().count())
        .max()
        .unwrap_or(0);
    let mut lines: Vec<String> = keys::ROWS
        .iter()
        .map(|r| format!("{:w$}  {}", keys::keys_label(r), r.help))
        .collect();
    lines.push(String::new());
    lines.push("mouse: click a pixel to inspect it; the wheel scrolls the debug pane".into());
    Popup {
        title: "keys (↑↓ scroll, Esc closes)".into(),
        lines,
        scroll: 0,
    }
}
