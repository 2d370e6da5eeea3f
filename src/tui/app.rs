//! The TUI's state and what every action does to it. The state is split by
//! concern (camera, render link, inspector pane, BVH overlay, jobs, popup);
//! [`App::update`] applies the layout before each draw, and drawing (see
//! `widgets`) only reads. Rendering happens in the worker.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Result;
use ratatui::crossterm::event::{Event, MouseButton, MouseEventKind};
use ratatui::layout::Rect;

use super::camera::CameraControl;
use super::color::ColorMode;
use super::export;
use super::graphics::symbols::Symbols;
use super::graphics::PixelMode;
use super::inspector::Inspector;
use super::jobs::Jobs;
use super::keys::{self, Action, Key, Mode};
use super::layout::Layout;
use super::link::RenderLink;
use super::popup::{self, Popup};
use super::term::output::Figures;
use super::worker::{self, Msg, PixelRequest, Reference, Snapshot, Truth, View, Worker};
use crate::raster::reference::load_reference;
use crate::render::{Decision, Feature, Features, Plan, Session, Tracer, Worst};
use crate::scene::{Builder, Projection};
use crate::viz::{self, image_views, PIXEL_VIEWS};
use crate::words;

/// How long a status message stays before the status line shows the
/// state again.
const MESSAGE_LIFE: Duration = Duration::from_secs(8);

/// How often the progress of a slow pass is redrawn.
const PROGRESS_EVERY: Duration = Duration::from_millis(250);

pub struct App {
    /// The scene, its BVH (kept in step with the worker's) and seed; its
    /// size is the export size.
    pub session: Session,
    pub features: Features,
    /// The plan of `features`: the one the worker, exports and the
    /// inspector use.
    pub plan: Plan,
    pub builder: Builder,
    pub camera: CameraControl,
    pub color: ColorMode,
    /// The block symbols the viewport is drawn with, unless a pixel
    /// protocol shows it.
    pub symbols: Symbols,
    pub pixels: Option<PixelMode>,
    /// A cell's size in screen pixels: what the terminal said, else 8x16.
    pub cell: (u32, u32),
    /// A view pixel's width over its height on screen, as last sent.
    view_aspect: f64,
    pub link: RenderLink,
    /// The viewport's size in pixels, from the layout.
    pub view_size: (u32, u32),
    pub inspector: Inspector,
    /// The selected pixel's overlay drawn into the view (`o` cycles them).
    pub pixel_view: Option<viz::View>,
    /// The view of the whole image over the viewport or in its place (`g`
    /// cycles them).
    pub image_view: Option<viz::View>,
    /// The BVH level whose boxes `g` shows (`.` and `,` change it).
    pub level: usize,
    /// The newest message for the status line, and when it was said; it
    /// gives way to the state line after [`MESSAGE_LIFE`].
    pub status: String,
    status_at: Instant,
    pub popup: Option<Popup>,
    pub jobs: Jobs,
    /// Where PNG exports go: the directory the TUI was started in.
    pub export_dir: PathBuf,
    /// The export size `--size` asked for; otherwise exports take the
    /// view's shape at the scene's size.
    pub export_size: Option<(u32, u32)>,
    /// What the terminal output measured (see [`term::output`]).
    pub output: Figures,
    /// Bytes and pictures per second written to the terminal, and the
    /// (time, figures) they were last taken at.
    pub bytes_per_sec: f64,
    pub frames_per_sec: f64,
    output_mark: (Instant, Figures),
    /// The layout of the last update.
    pub layout: Layout,
    /// When a slow pass's progress was last shown.
    progress_shown: Instant,
    pub quit: bool,
    /// Ctrl-Z asked the event loop to give the terminal back and stop.
    pub suspend: bool,
    /// The `--reference` image, if any.
    pub reference: Option<Arc<Reference>>,
    /// The view size for which the status line last said how to make the
    /// reference exact.
    resample_noted: Option<(u32, u32)>,
    /// What loading the scene warned about.
    pub warnings: Vec<String>,
}

impl App {
    /// `reference` is a linear image of the scene from its own camera with
    /// the features the TUI starts with; the true error is measured against
    /// it while the view is that one.
    pub fn new(
        session: Session,
        warnings: Vec<String>,
        color: ColorMode,
        reference: Option<&Path>,
    ) -> Result<App> {
        let home = session.camera;
        let plan = session.plan.clone();
        let reference = match reference {
            Some(path) => {
                let (width, height, image) = load_reference(path)?;
                Some(Arc::new(Reference {
                    name: path.display().to_string(),
                    width,
                    height,
                    image,
                    camera: home,
                    plan: plan.clone(),
                }))
            }
            None => None,
        };
        let scene = &session.scene;
        let worker = worker::spawn(Worker::new(
            scene.clone(),
            session.bvh.clone(),
            session.seed,
            reference.clone(),
        ))?;
        let status = match &reference {
            Some(r) => format!(
                "Reference {} ({}x{}): the true error is shown at the start view (r returns to it).",
                r.name, r.width, r.height
            ),
            None => String::new(),
        };
        Ok(App {
            builder: scene.settings.builder,
            features: plan.features,
            plan,
            camera: CameraControl::new(home),
            color,
            symbols: Symbols::Half,
            pixels: None,
            cell: (8, 16),
            view_aspect: 1.0,
            link: RenderLink::new(worker),
            view_size: (0, 0),
            inspector: Inspector::default(),
            pixel_view: None,
            image_view: None,
            level: 0,
            status,
            status_at: Instant::now(),
            popup: None,
            jobs: Jobs::default(),
            export_dir: std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
            export_size: None,
            output: Figures::default(),
            bytes_per_sec: 0.0,
            frames_per_sec: 0.0,
            output_mark: (Instant::now(), Figures::default()),
            layout: Layout::default(),
            progress_shown: Instant::now(),
            quit: false,
            suspend: false,
            reference,
            resample_noted: None,
            warnings,
            session,
        })
    }

    pub fn mode(&self) -> Mode {
        if self.popup.is_some() {
            Mode::Popup
        } else if self.inspector.select_mode {
            Mode::Select
        } else {
            Mode::View
        }
    }

    /// Puts `text` on the status line for a while.
    pub fn say(&mut self, text: impl Into<String>) {
        self.status = text.into();
        self.status_at = Instant::now();
    }

    /// What the status line shows: the newest message while it lasts, else
    /// the state (scene, mode, warnings).
    pub fn status_line(&self) -> String {
        if !self.status.is_empty() && self.status_at.elapsed() < MESSAGE_LIFE {
            return self.status.clone();
        }
        let scene = &self.session.scene;
        let mut parts = vec![format!(
            "{}: {}, {}",
            scene.name,
            words::count(
                scene.geometry.triangle_count() as u64,
                "triangle",
                "triangles"
            ),
            words::count(scene.lights.len() as u64, "light", "lights")
        )];
        if self.inspector.select_mode {
            parts.push("select mode (v or Esc leaves)".into());
        }
        if !self.warnings.is_empty() {
            parts.push(format!(
                "{} (W lists them)",
                words::count(self.warnings.len() as u64, "load warning", "load warnings")
            ));
        }
        parts.push("? help".into());
        parts.join(" · ")
    }

    pub fn generation(&self) -> u64 {
        self.link.generation()
    }

    /// The newest pass when it shows the current view.
    pub fn current_frame(&self) -> Option<&Snapshot> {
        self.link.current_frame()
    }

    /// Lays the screen out for a terminal of `area` and brings the state in
    /// line with it: the view size (a change restarts rendering), the
    /// inspector's tree and lines, the popup's rows. Called before each
    /// draw; drawing then only reads.
    pub fn update(&mut self, area: Rect) {
        self.layout = Layout::compute(area, self);
        let l = self.layout;
        if !l.too_small {
            self.set_view_size(l.view_size(), self.pixel_aspect());
            self.inspector.height = l.debug_text.height.max(1) as usize;
            self.inspector.width = l.debug_text.width as usize;
        }
        self.refresh_inspector();
        self.link.set_pixel(self.pixel_request());
        if let Some(p) = &mut self.popup {
            let width = l.main.width.saturating_sub(6);
            p.set_width(width as usize);
            let rows = l.popup(p).height.saturating_sub(2);
            p.set_visible(rows as usize);
        }
    }

    fn set_view_size(&mut self, size: (u32, u32), aspect: f64) {
        if self.view_size != size || self.view_aspect != aspect {
            self.inspector.rescale(self.view_size, size);
            self.view_size = size;
            self.view_aspect = aspect;
            self.send_view();
        }
    }

    /// A view pixel's width over its height on screen: the cell's over the
    /// grid of pixels in it, so that every symbol set and pixel protocol
    /// shows the scene in the same proportions.
    pub fn pixel_aspect(&self) -> f64 {
        let (cw, ch) = self.pixels.map_or(self.cell, |m| m.cell);
        let (gx, gy) = self.layout.grid;
        (cw as f64 * gy as f64) / (ch.max(1) as f64 * gx.max(1) as f64)
    }

    fn send_view(&mut self) {
        self.link.send_view(View {
            camera: self.camera.camera,
            plan: self.plan.clone(),
            width: self.view_size.0,
            height: self.view_size.1,
            pixel_aspect: self.view_aspect,
        });
    }

    /// The pixel overlay to keep drawn: the view chosen with `o`, of the
    /// selected pixel, for the one-ray views of the ray at the debug cursor.
    pub fn pixel_request(&self) -> Option<PixelRequest> {
        let view = self.pixel_view?;
        let s = self.inspector.selected?;
        Some(PixelRequest {
            x: s.x,
            y: s.y,
            sample: s.sample,
            view,
            ray: if view.one_ray() {
                self.inspector.cursor_ray()
            } else {
                None
            },
            spp: self.session.scene.settings.spp,
        })
    }

    /// Replays the selected pixel's tree through the plan and camera the
    /// worker renders with, and takes its values before and after bloom
    /// from the newest pass.
    fn refresh_inspector(&mut self) {
        let (w, h) = self.view_size;
        let s = &self.session;
        let frame = self.camera.camera.frame(w, h).stretched(self.view_aspect);
        let tracer = Tracer::new(&s.scene, &s.bvh, &self.plan, frame, s.seed);
        let frame = self
            .link
            .full_frame()
            .filter(|f| (f.width, f.height) == self.view_size);
        let shown = frame.map(|f| {
            (
                crate::render::post::Displayed {
                    image: f.image.clone(),
                    before_bloom: f.pre_bloom.clone(),
                },
                f.spp,
            )
        });
        self.inspector.refresh(
            &tracer,
            self.link.generation(),
            shown.as_ref().map(|(d, spp)| (d, *spp)),
        );
    }

    pub fn handle_event(&mut self, ev: &Event) {
        match ev {
            Event::Key(k) => {
                if let Some(key) = Key::from_event(k) {
                    self.handle_key(key);
                }
            }
            Event::Mouse(m) => match m.kind {
                MouseEventKind::Down(MouseButton::Left) => {
                    if let Some((x, y)) = self.layout.pixel_at(m.column, m.row) {
                        self.select(x, y, 0);
                    }
                }
                MouseEventKind::ScrollDown if self.layout.in_debug(m.column, m.row) => {
                    self.act(Action::Line(3))
                }
                MouseEventKind::ScrollUp if self.layout.in_debug(m.column, m.row) => {
                    self.act(Action::Line(-3))
                }
                _ => {}
            },
            _ => {}
        }
    }

    pub fn handle_key(&mut self, key: Key) {
        if let Some(a) = keys::action(key, self.mode()) {
            self.act(a);
        }
    }

    pub fn act(&mut self, a: Action) {
        match a {
            Action::Orbit(yaw, pitch) => {
                self.camera.orbit(yaw, pitch);
                self.status.clear();
                self.send_view();
            }
            Action::Move(r, u, f) => {
                self.camera.pan(r, u, f);
                self.status.clear();
                self.send_view();
            }
            Action::Fov(d) => {
                let zoomed = self.camera.zoom(d);
                self.say(match zoomed {
                    Projection::Perspective { vfov } => format!("field of view {vfov:.0}°"),
                    Projection::Orthographic { half_height } => {
                        format!(
                            "view height {}",
                            crate::words::significant(2.0 * half_height as f64)
                        )
                    }
                });
                self.send_view();
            }
            Action::ResetView => {
                self.camera.reset();
                self.say("view reset");
                self.send_view();
            }
            Action::Toggle(f) => self.toggle(f),
            Action::Depth(d) => {
                let max = crate::scene::MAX_DEPTH as i64;
                let depth = (self.plan.max_depth as i64 + d as i64).clamp(0, max) as u32;
                let what = if self.plan.path { "path" } else { "ray tree" };
                if depth == self.plan.max_depth {
                    self.say(format!(
                        "maximum depth {depth}: the {what} cannot go further"
                    ));
                } else {
                    self.plan = self.plan.clone().with_max_depth(depth);
                    self.say(format!("maximum depth {depth}: bounces a {what} takes"));
                    self.send_view();
                }
            }
            Action::SwitchBuilder => {
                self.builder = match self.builder {
                    Builder::Sah => Builder::Median,
                    Builder::Median => Builder::Sah,
                };
                self.link.rebuild(self.builder);
                self.say(format!(
                    "rebuilding the BVH with the {} builder...",
                    self.builder
                ));
            }
            Action::SelectMode => {
                let s = &mut self.inspector;
                s.select_mode = !s.select_mode;
                if s.select_mode && s.selected.is_none() {
                    let (w, h) = self.view_size;
                    self.select(w / 2, h / 2, 0);
                }
                self.say(if self.inspector.select_mode {
                    "select mode: hjkl or arrows move the cursor, v or Esc leaves"
                } else {
                    "view mode"
                });
            }
            Action::Back => {
                self.inspector.select_mode = false;
                self.status.clear();
            }
            Action::Cursor(dx, dy) => {
                let (w, h) = self.view_size;
                let (x, y) = self
                    .inspector
                    .selected
                    .map_or((w / 2, h / 2), |s| (s.x, s.y));
                let x = (x as i64 + dx as i64).clamp(0, w.saturating_sub(1) as i64) as u32;
                let y = (y as i64 + dy as i64).clamp(0, h.saturating_sub(1) as i64) as u32;
                self.select(x, y, 0);
            }
            Action::Fold => {
                self.refresh_inspector();
                if !self.inspector.fold() {
                    self.say("nothing to fold below the debug cursor");
                }
            }
            Action::Line(n) => {
                self.refresh_inspector();
                self.inspector.move_cursor(n as i64);
            }
            Action::Page(n) => {
                self.refresh_inspector();
                let page = self.inspector.height.max(1) as i64;
                self.inspector.move_cursor(n as i64 * page);
            }
            Action::Worst(w) => self.jump_to_worst(w),
            Action::PixelOverlay => {
                self.pixel_view = viz::View::next(&PIXEL_VIEWS, self.pixel_view);
                let name = self.pixel_view.map_or("off".into(), viz::View::title);
                self.say(match (self.pixel_view, self.inspector.selected) {
                    (Some(_), None) => {
                        format!("pixel overlay: {name}: select a pixel (v, or click) to see it")
                    }
                    (Some(v), Some(_)) if v.one_ray() => format!(
                        "pixel overlay: {name}, of the ray at the debug cursor ([ and ] move it)"
                    ),
                    _ => format!("pixel overlay: {name}"),
                });
            }
            Action::Overlay => {
                self.image_view = viz::View::next(&image_views(self.level), self.image_view);
                self.overlay_changed();
            }
            Action::Level(d) => {
                let max = self.session.bvh.stats.depth.saturating_sub(1) as i64;
                self.level = (self.level as i64 + d as i64).clamp(0, max) as usize;
                self.image_view = Some(viz::View::Level(self.level));
                self.overlay_changed();
            }
            Action::SavePng => self.save_png(),
            Action::Stability => {
                let said = self.jobs.stability(self.session.scene.clone());
                self.say(said);
            }
            Action::Help => self.popup = Some(popup::help()),
            Action::Warnings => {
                self.popup = Some(Popup::new(
                    format!(
                        "{} loading {}",
                        words::count(self.warnings.len() as u64, "warning", "warnings"),
                        self.session.scene.name
                    ),
                    if self.warnings.is_empty() {
                        vec!["the scene loaded without warnings".into()]
                    } else {
                        self.warnings.clone()
                    },
                ))
            }
            Action::ScrollPopup(n) => {
                if let Some(p) = &mut self.popup {
                    p.scroll_by(n as i64);
                }
            }
            Action::PagePopup(n) => {
                if let Some(p) = &mut self.popup {
                    let page = p.visible as i64;
                    p.scroll_by(n as i64 * page);
                }
            }
            Action::ClosePopup => self.popup = None,
            Action::Suspend => self.suspend = true,
            Action::Quit => self.quit = true,
        }
    }

    fn overlay_changed(&mut self) {
        self.link.set_image_view(self.image_view);
        let name = self.image_view.map_or("off".into(), viz::View::title);
        self.say(format!("view overlay: {name}"));
    }

    /// The decision the Features panel shows for `f`.
    pub fn feature_state(&self, f: Feature) -> Decision {
        self.plan.decision(f)
    }

    fn toggle(&mut self, f: Feature) {
        self.features.toggle(f);
        let plan = self
            .session
            .plan_for(self.features)
            .with_max_depth(self.plan.max_depth);
        let same = plan.same_stages(&self.plan);
        let state = if self.features.on(f) { "on" } else { "off" };
        self.say(
            match crate::render::plan::not_needed(&self.session.scene, f) {
                Some(why) if plan.policy == crate::render::PlanPolicy::Prune => format!(
                    "{} {state}: not needed: {}, so the image does not change",
                    f.name(),
                    why.long()
                ),
                _ if same => format!("{} {state}: no change to the image", f.name()),
                _ => format!("{} {state}", f.name()),
            },
        );
        self.plan = plan;
        if !same {
            self.send_view();
        }
    }

    pub fn select(&mut self, x: u32, y: u32, sample: u32) {
        self.inspector.select(x, y, sample, self.view_size);
        self.refresh_inspector();
    }

    fn jump_to_worst(&mut self, w: Worst) {
        let Some(f) = self.link.full_frame() else {
            self.say("no pass has finished for this view yet");
            return;
        };
        let (found, spp) = (f.worst.get(w), f.spp);
        let what = match w {
            Worst::Nan => "NaN/Inf sample",
            Worst::Variance => "highest variance",
            Worst::Brightest => "brightest",
        };
        match found {
            Some((x, y, k)) => {
                self.select(x, y, k);
                self.say(format!("worst pixel ({what}): ({x}, {y}), sample {k}"));
            }
            None if w == Worst::Nan => {
                self.say(format!(
                    "no pixel had a NaN or infinite sample in {spp} spp"
                ));
            }
            None if f.exact => {
                self.say("no pixel varies: nothing in this view is sampled, the image is exact");
            }
            None => {
                self.say(format!("no pixel varies between samples in {spp} spp"));
            }
        }
    }

    fn save_png(&mut self) {
        let scene_size = (self.session.width, self.session.height);
        let size = export::size_for(self.view_size, self.export_size, scene_size);
        let said = self.jobs.export(export::Request {
            session: self.session.clone(),
            camera: self.camera.camera,
            plan: self.plan.clone(),
            size,
            dir: self.export_dir.clone(),
        });
        self.say(said);
    }

    /// Takes what the worker and the jobs have sent; true when the screen
    /// needs redrawing. Fails when the worker has stopped.
    pub fn poll(&mut self) -> Result<bool> {
        let mut changed = false;
        while let Some(m) = self.link.try_recv()? {
            changed |= self.on_msg(m);
        }
        if let Some(done) = self.jobs.poll(&self.session.scene.name) {
            if let Some(s) = done.status {
                self.say(s);
            }
            if let Some(p) = done.popup {
                self.popup = Some(p);
            }
            changed = true;
        }
        changed |= self.jobs.busy();
        // A slow pass shows its progress a few times a second.
        if self.link.slow_pass().is_some() && self.progress_shown.elapsed() >= PROGRESS_EVERY {
            self.progress_shown = Instant::now();
            changed = true;
        }
        // A message that has just run its time gives way to the state.
        if !self.status.is_empty() && self.status_at.elapsed() >= MESSAGE_LIFE {
            self.status.clear();
            changed = true;
        }
        Ok(changed)
    }

    /// Takes a message from the worker; true when the screen should be
    /// redrawn for it.
    fn on_msg(&mut self, m: Msg) -> bool {
        match m {
            Msg::Frame(f) => {
                self.note_resampling(&f);
                self.link.keep_frame(f)
            }
            Msg::Bvh(b) => {
                self.say(format!(
                    "BVH rebuilt with the {} builder in {}",
                    b.stats.builder,
                    words::ms(b.stats.build_ms)
                ));
                self.session.bvh = b;
                self.link.rebuilding = false;
                let depth = self.session.bvh.stats.depth;
                self.level = self.level.min(depth.saturating_sub(1));
                true
            }
            Msg::Overlay(o) => {
                if let Err(e) = &o.layer {
                    self.say(format!("BVH overlay: {e}"));
                }
                self.link.overlay = Some(o);
                true
            }
            Msg::Pixel(p) => {
                // The title may cut the legend short: the status line has
                // the whole width.
                let name = p.request.view.title();
                match &p.layer {
                    Err(e) => self.say(format!("pixel overlay: {e}")),
                    Ok((_, legend)) if p.generation == self.link.generation() => {
                        self.say(format!("{name}: {legend}"))
                    }
                    Ok(_) => {}
                }
                self.link.pixel = Some(p);
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
        self.say(format!(
            "For an exact true error render the reference at {}x{} ({k}x the {}x{} view): this {}x{} one is resampled, which adds error at edges.",
            k * f.width,
            k * f.height,
            f.width,
            f.height,
            r.width,
            r.height,
        ));
    }

    /// Waits until a full pass of the current view has arrived; false on timeout.
    pub fn wait_frame(&mut self, timeout: Duration) -> Result<bool> {
        let end = Instant::now() + timeout;
        loop {
            if self.link.full_frame().is_some() && !self.link.rebuilding {
                return Ok(true);
            }
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Ok(false);
            }
            if let Some(m) = self.link.recv_timeout(left)? {
                self.on_msg(m);
            }
        }
    }

    /// Takes the terminal output's figures; the rates are updated once a
    /// second. True when a readout changed.
    pub fn note_output(&mut self, figures: Figures) -> bool {
        let picture_changed = figures.picture != self.output.picture;
        self.output = figures;
        let (since, base) = self.output_mark;
        let dt = since.elapsed().as_secs_f64();
        if dt < 1.0 {
            return picture_changed;
        }
        let bytes = figures.written.saturating_sub(base.written) as f64 / dt;
        let frames = figures.frames.saturating_sub(base.frames) as f64 / dt;
        self.output_mark = (Instant::now(), figures);
        let changed = bytes != self.bytes_per_sec || frames != self.frames_per_sec;
        self.bytes_per_sec = bytes;
        self.frames_per_sec = frames;
        changed || picture_changed
    }

    /// Seconds from the start of the current view (a camera move, a
    /// toggle, the launch) until its first full picture was on screen.
    pub fn view_shown_in(&self) -> Option<f64> {
        let (generation, at) = self.output.picture?;
        (generation == self.generation()).then(|| {
            at.saturating_duration_since(self.link.started)
                .as_secs_f64()
        })
    }

    /// Whether nothing more will change on screen without input.
    pub fn idle(&self) -> bool {
        self.current_frame().is_some_and(|f| f.done) && !self.jobs.busy()
    }
}
