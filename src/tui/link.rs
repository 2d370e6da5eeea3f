//! The app's link to the render worker: the generation of the newest
//! request, the newest pass and BVH overlay it sent back, and when a pass is
//! worth redrawing for.

use std::sync::mpsc::{RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

use anyhow::{bail, Result};

use super::worker::{self, Cmd, Msg, OverlayFrame, PixelFrame, PixelRequest, RenderView, Snapshot};
use crate::scene::Builder;
use crate::viz;

pub(crate) struct RenderLink {
    worker: worker::Handle,
    /// Bumped on every change that restarts rendering, and when.
    generation: u64,
    pub(crate) started: Instant,
    /// The newest pass.
    pub(crate) frame: Option<Box<Snapshot>>,
    /// The newest BVH overlay.
    pub(crate) overlay: Option<Box<OverlayFrame>>,
    /// The newest pixel overlay, and the last one asked for.
    pub(crate) pixel: Option<Box<PixelFrame>>,
    asked_pixel: Option<PixelRequest>,
    /// Generation and time of the last pass that asked for a redraw.
    shown: (u64, Instant),
    /// A BVH rebuild is under way.
    pub(crate) rebuilding: bool,
}

impl RenderLink {
    pub(crate) fn new(worker: worker::Handle) -> Self {
        Self {
            worker,
            generation: 0,
            started: Instant::now(),
            frame: None,
            overlay: None,
            pixel: None,
            asked_pixel: None,
            shown: (0, Instant::now()),
            rebuilding: false,
        }
    }

    pub(crate) fn generation(&self) -> u64 {
        self.generation
    }

    /// Renders `view` from now on, cancelling the pass in flight.
    pub(crate) fn send_view(&mut self, view: RenderView) {
        self.generation += 1;
        self.started = Instant::now();
        self.worker.send(Cmd::View(self.generation, Box::new(view)));
    }

    /// Rebuilds the BVH, then renders the current view again.
    pub(crate) fn rebuild(&mut self, builder: Builder) {
        self.generation += 1;
        self.started = Instant::now();
        self.rebuilding = true;
        self.worker.send(Cmd::Builder(self.generation, builder));
    }

    /// Keeps `view` of the whole image drawn over every view or into
    /// every pass (none: no view).
    pub(crate) fn set_image_view(&mut self, view: Option<viz::View>) {
        self.overlay = None;
        self.worker.send(Cmd::ImageView(view));
    }

    /// Keeps the selected pixel's overlay `p` drawn (none: no overlay);
    /// asks the worker only when it changed.
    pub(crate) fn set_pixel(&mut self, p: Option<PixelRequest>) {
        if self.asked_pixel != p {
            self.asked_pixel = p;
            self.worker.send(Cmd::Pixel(p));
        }
    }

    /// The pixel overlay when it is the one asked for, drawn for the
    /// current view.
    pub(crate) fn current_pixel(&self) -> Option<&PixelFrame> {
        self.pixel
            .as_deref()
            .filter(|p| p.generation == self.generation && Some(p.request) == self.asked_pixel)
    }

    /// The newest pass when it shows the current view.
    pub(crate) fn current_frame(&self) -> Option<&Snapshot> {
        self.frame
            .as_deref()
            .filter(|f| f.generation == self.generation)
    }

    /// The newest full (not coarse) pass of the current view.
    pub(crate) fn full_frame(&self) -> Option<&Snapshot> {
        self.current_frame().filter(|f| !f.coarse)
    }

    /// The overlay when it was drawn for the current view.
    pub(crate) fn current_overlay(&self) -> Option<&OverlayFrame> {
        self.overlay
            .as_deref()
            .filter(|o| o.generation == self.generation)
    }

    /// (rows done, rows, seconds) of a pass of the current view that has
    /// run longer than [`SLOW_PASS`].
    pub(crate) fn slow_pass(&self) -> Option<(u32, u32, f64)> {
        let (generation, done, rows, secs) = self.worker.progress.current()?;
        (generation == self.generation && secs >= SLOW_PASS).then_some((done, rows, secs))
    }

    /// The next message from the worker, if one is waiting. Fails when the
    /// worker has stopped.
    pub(crate) fn try_recv(&self) -> Result<Option<Msg>> {
        match self.worker.rx.try_recv() {
            Ok(m) => Ok(Some(m)),
            Err(TryRecvError::Empty) => Ok(None),
            Err(TryRecvError::Disconnected) => bail!("the render worker stopped unexpectedly"),
        }
    }

    /// Waits up to `timeout` for the next message.
    pub(crate) fn recv_timeout(&self, timeout: Duration) -> Result<Option<Msg>> {
        match self.worker.rx.recv_timeout(timeout) {
            Ok(m) => Ok(Some(m)),
            Err(RecvTimeoutError::Timeout) => Ok(None),
            Err(RecvTimeoutError::Disconnected) => {
                bail!("the render worker stopped unexpectedly")
            }
        }
    }

    /// Keeps a pass; true when it is worth redrawing for. Late passes change
    /// the image less and less, so they are shown less often, which saves
    /// terminal bandwidth.
    pub(crate) fn keep_frame(&mut self, f: Box<Snapshot>) -> bool {
        let due = f.coarse
            || f.done
            || f.generation != self.shown.0
            || self.shown.1.elapsed() >= refresh_interval(f.spp);
        if due {
            self.shown = (f.generation, Instant::now());
        }
        self.frame = Some(f);
        due
    }
}

/// A pass running longer than this gets a progress readout.
pub(crate) const SLOW_PASS: f64 = 0.5;

/// How often a pass at `spp` samples per pixel is worth showing: every
/// frame up to 32 spp, then less often as each pass changes less, up to
/// twice a second.
fn refresh_interval(spp: u32) -> Duration {
    Duration::from_millis((33 * spp as u64 / 32).min(500))
}
