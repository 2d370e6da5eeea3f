//! The TUI's state and what every action does to it. The state is split by
//! concern (render choice, camera, display, render link, inspector pane,
//! overlays, status line, jobs, popup, output meter, reference);
//! [`App::update`] applies the layout before each draw, and drawing (see
//! `widgets`) only reads. Rendering happens in the worker.

use std::path::Path;
use std::time::{Duration, Instant};

use anyhow::Result;
use ratatui::crossterm::event::{Event, MouseButton, MouseEventKind};
use ratatui::layout::Rect;

use super::camera::CameraControl;
use super::color::ColorMode;
use super::display::Display;
use super::inspector::Inspector;
use super::jobs::Jobs;
use super::keys::{self, Action, Key, Mode};
use super::layout::Layout;
use super::link::RenderLink;
use super::meter::Meter;
use super::overlays::Overlays;
use super::popup::{self, Popup};
use super::reference::ReferenceImage;
use super::render_choice::RenderChoice;
use super::status::Status;
use super::term::output::Figures;
use super::worker::{self, Msg, PixelRequest, RenderView, Snapshot, Worker};
use crate::render::{Decision, Feature, Session, Tracer, Worst};
use crate::scene::Projection;
use crate::viz;
use crate::words;

pub struct App {
    /// The scene, its BVH (kept in step with the worker's) and seed; its
    /// size is the export size.
    pub(crate) session: Session,
    pub(crate) choice: RenderChoice,
    pub(crate) camera: CameraControl,
    pub display: Display,
    pub(crate) link: RenderLink,
    pub(crate) inspector: Inspector,
    pub(crate) overlays: Overlays,
    pub(crate) status: Status,
    pub(crate) popup: Option<Popup>,
    pub(crate) jobs: Jobs,
    pub(crate) meter: Meter,
    pub(crate) reference: ReferenceImage,
    pub(crate) quit: bool,
    /// Ctrl-Z asked the event loop to give the terminal back and stop.
    pub(crate) suspend: bool,
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
        let reference = ReferenceImage::load(reference, home, &session.plan)?;
        let scene = &session.scene;
        let worker = worker::spawn(Worker::new(
            scene.clone(),
            session.bvh.clone(),
            session.seed,
            reference.shared(),
        ))?;
        Ok(App {
            choice: RenderChoice::new(session.plan.clone(), scene.settings.builder),
            camera: CameraControl::new(home),
            display: Display::new(color),
            link: RenderLink::new(worker),
            inspector: Inspector::default(),
            overlays: Overlays::default(),
            status: Status::new(reference.greeting(), warnings),
            popup: None,
            jobs: Jobs::new(),
            meter: Meter::default(),
            quit: false,
            suspend: false,
            reference,
            session,
        })
    }

    pub(crate) fn mode(&self) -> Mode {
        if self.popup.is_some() {
            Mode::Popup
        } else if self.inspector.select_mode {
            Mode::Select
        } else {
            Mode::View
        }
    }

    /// Puts `text` on the status line for a while.
    pub(crate) fn say(&mut self, text: impl Into<String>) {
        self.status.say(text);
    }

    /// What the status line shows: the newest message while it lasts, else
    /// the state (scene, mode, warnings).
    pub(crate) fn status_line(&self) -> String {
        self.status
            .line(&self.session.scene, self.inspector.select_mode)
    }

    pub(crate) fn generation(&self) -> u64 {
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
        self.display.layout = Layout::compute(area, self);
        let l = self.display.layout;
        if !l.too_small {
            if let Some(before) = self.display.fit_view() {
                self.inspector.rescale(before, self.display.view_size());
                self.send_view();
            }
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

    fn send_view(&mut self) {
        let (width, height) = self.display.view_size();
        self.link.send_view(RenderView {
            camera: self.camera.camera,
            plan: self.choice.plan().clone(),
            width,
            height,
            pixel_aspect: self.display.view_aspect(),
        });
    }

    /// The pixel overlay to keep drawn: the view chosen with `o`, of the
    /// selected pixel, for the one-ray views of the ray at the debug cursor.
    pub(crate) fn pixel_request(&self) -> Option<PixelRequest> {
        let view = self.overlays.pixel?;
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
        let size = self.display.view_size();
        let s = &self.session;
        let frame = self
            .camera
            .camera
            .frame(size.0, size.1)
            .stretched(self.display.view_aspect());
        let tracer = Tracer::new(&s.scene, &s.bvh, self.choice.plan(), frame, s.seed);
        let frame = self
            .link
            .full_frame()
            .filter(|f| (f.width, f.height) == size);
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

    pub(crate) fn handle_event(&mut self, ev: &Event) {
        match ev {
            Event::Key(k) => {
                if let Some(key) = Key::from_event(k) {
                    self.handle_key(key);
                }
            }
            Event::Mouse(m) => match m.kind {
                MouseEventKind::Down(MouseButton::Left) => {
                    if let Some((x, y)) = self.display.layout.pixel_at(m.column, m.row) {
                        self.select(x, y, 0);
                    }
                }
                MouseEventKind::ScrollDown if self.display.layout.in_debug(m.column, m.row) => {
                    self.act(Action::Line(3))
                }
                MouseEventKind::ScrollUp if self.display.layout.in_debug(m.column, m.row) => {
                    self.act(Action::Line(-3))
                }
                _ => {}
            },
            _ => {}
        }
    }

    pub(crate) fn handle_key(&mut self, key: Key) {
        if let Some(a) = keys::action(key, self.mode()) {
            self.act(a);
        }
    }

    pub(crate) fn act(&mut self, a: Action) {
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
                let (said, changed) = self.choice.change_depth(d);
                self.say(said);
                if changed {
                    self.send_view();
                }
            }
            Action::SwitchBuilder => {
                let builder = self.choice.switch_builder();
                self.link.rebuild(builder);
                self.say(format!("rebuilding the BVH with the {builder} builder..."));
            }
            Action::FullScreen => {
                let a = &mut self.display.arrangement;
                a.full_screen = !a.full_screen;
                let full = a.full_screen;
                self.say(if full {
                    "full screen: f brings the panels back"
                } else {
                    "panels back"
                });
            }
            Action::TreePane => {
                let a = &mut self.display.arrangement;
                a.pane = a.pane.next();
                a.full_screen = false;
                let said = a.pane.name();
                self.say(said);
            }
            Action::Legend => {
                let items = crate::tui::widgets::viewport::legend(self);
                let mut p = Popup::new(
                    "legend".into(),
                    match (
                        items.is_empty(),
                        self.overlays.pixel.or(self.overlays.image),
                    ) {
                        (false, _) => items,
                        (true, Some(_)) => {
                            vec!["the overlay is still being drawn: O again in a moment".into()]
                        }
                        (true, None) => vec![
                            "no overlay on the view (o: pixel overlays, g: view overlays)".into(),
                        ],
                    },
                );
                p.wrap_indent = Some(2);
                self.popup = Some(p);
            }
            Action::SelectMode => {
                let s = &mut self.inspector;
                s.select_mode = !s.select_mode;
                if s.select_mode && s.selected.is_none() {
                    let (w, h) = self.display.view_size();
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
                let (w, h) = self.display.view_size();
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
                let view = self.overlays.next_pixel();
                let name = view.map_or("off".into(), viz::View::title);
                self.say(match (view, self.inspector.selected) {
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
                let view = self.overlays.next_image();
                self.overlay_changed(view);
            }
            Action::Level(d) => {
                let view = self.overlays.move_level(d, self.session.bvh.stats.depth);
                self.overlay_changed(view);
            }
            Action::SavePng => self.save_png(),
            Action::Stability => {
                let said = self.jobs.stability(self.session.scene.clone());
                self.say(said);
            }
            Action::Help => self.popup = Some(popup::help()),
            Action::Warnings => {
                self.popup = Some(self.status.warnings_popup(&self.session.scene.name))
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

    fn overlay_changed(&mut self, view: Option<viz::View>) {
        self.link.set_image_view(view);
        let name = view.map_or("off".into(), viz::View::title);
        self.say(format!("view overlay: {name}"));
    }

    /// The decision the Features panel shows for `f`.
    pub(crate) fn feature_state(&self, f: Feature) -> Decision {
        self.choice.decision(f)
    }

    fn toggle(&mut self, f: Feature) {
        let (said, changed) = self.choice.toggle(f, &self.session);
        self.say(said);
        if changed {
            self.send_view();
        }
    }

    pub(crate) fn select(&mut self, x: u32, y: u32, sample: u32) {
        self.inspector
            .select(x, y, sample, self.display.view_size());
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
        let said = self.jobs.export(
            &self.session,
            self.camera.camera,
            self.choice.plan(),
            self.display.view_size(),
        );
        match said {
            Some(s) => self.say(s),
            None => self.status.clear(),
        }
    }

    /// Takes what the worker and the jobs have sent; true when the screen
    /// needs redrawing. Fails when the worker has stopped.
    pub(crate) fn poll(&mut self) -> Result<bool> {
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
        if self.link.slow_pass().is_some() && self.meter.progress_due() {
            changed = true;
        }
        // A message that has just run its time gives way to the state.
        changed |= self.status.expire();
        Ok(changed)
    }

    /// Takes a message from the worker; true when the screen should be
    /// redrawn for it.
    fn on_msg(&mut self, m: Msg) -> bool {
        match m {
            Msg::Frame(f) => {
                if let Some(note) = self.reference.resampling_note(&f) {
                    self.say(note);
                }
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
                self.overlays.fit_level(self.session.bvh.stats.depth);
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
                // The legend shows beneath the view; a failure says why here.
                if let Err(e) = &p.layer {
                    self.say(format!("pixel overlay: {e}"));
                }
                self.link.pixel = Some(p);
                true
            }
        }
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

    /// Takes the terminal output's figures; true when a readout changed.
    pub(crate) fn note_output(&mut self, figures: Figures) -> bool {
        self.meter.note(figures)
    }

    /// Seconds from the start of the current view (a camera move, a
    /// toggle, the launch) until its first full picture was on screen.
    pub(crate) fn view_shown_in(&self) -> Option<f64> {
        self.meter.shown_in(self.generation(), self.link.started)
    }

    /// The same until it was on screen at full resolution.
    pub(crate) fn view_sharp_in(&self) -> Option<f64> {
        self.meter.sharp_in(self.generation(), self.link.started)
    }

    /// Whether nothing more will change on screen without input.
    pub(crate) fn idle(&self) -> bool {
        self.current_frame().is_some_and(|f| f.done) && !self.jobs.busy()
    }
}
