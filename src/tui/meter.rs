//! What the terminal output measured, as the Render panel shows it, and
//! how often a slow pass's progress is redrawn.

use std::time::{Duration, Instant};

use super::term::output::Figures;

/// How often the progress of a slow pass is redrawn.
const PROGRESS_EVERY: Duration = Duration::from_millis(250);

/// The output's figures and rates for the Render panel.
pub(crate) struct Meter {
    /// What the terminal output measured (see [`super::term::output`]).
    figures: Figures,
    /// Bytes and pictures per second written to the terminal, and the
    /// (time, figures) they were last taken at.
    bytes_per_sec: f64,
    frames_per_sec: f64,
    mark: (Instant, Figures),
    /// When a slow pass's progress was last shown.
    progress_shown: Instant,
}

impl Default for Meter {
    fn default() -> Meter {
        Meter {
            figures: Figures::default(),
            bytes_per_sec: 0.0,
            frames_per_sec: 0.0,
            mark: (Instant::now(), Figures::default()),
            progress_shown: Instant::now(),
        }
    }
}

/// Seconds from `started` to `at`, if that was for view `generation`.
fn since((shown, at): (u64, Instant), generation: u64, started: Instant) -> Option<f64> {
    (shown == generation).then(|| at.saturating_duration_since(started).as_secs_f64())
}

impl Meter {
    /// Takes the terminal output's figures; the rates are updated once a
    /// second. True when a readout changed.
    pub(crate) fn note(&mut self, figures: Figures) -> bool {
        let picture_changed =
            (figures.picture, figures.sharp) != (self.figures.picture, self.figures.sharp);
        self.figures = figures;
        let (since, base) = self.mark;
        let dt = since.elapsed().as_secs_f64();
        if dt < 1.0 {
            return picture_changed;
        }
        let bytes = figures.written.saturating_sub(base.written) as f64 / dt;
        let frames = figures.frames.saturating_sub(base.frames) as f64 / dt;
        self.mark = (Instant::now(), figures);
        let changed = bytes != self.bytes_per_sec || frames != self.frames_per_sec;
        self.bytes_per_sec = bytes;
        self.frames_per_sec = frames;
        changed || picture_changed
    }

    pub(crate) fn bytes_per_sec(&self) -> f64 {
        self.bytes_per_sec
    }

    pub(crate) fn frames_per_sec(&self) -> f64 {
        self.frames_per_sec
    }

    /// The link's measured rate in bytes per second, once known.
    pub(crate) fn link_rate(&self) -> Option<f64> {
        self.figures.link_rate
    }

    /// Seconds from `started` until the first full picture of view
    /// `generation` was on screen.
    pub(crate) fn shown_in(&self, generation: u64, started: Instant) -> Option<f64> {
        since(self.figures.picture?, generation, started)
    }

    /// The same for the first sharp picture: later where a coarse one was
    /// sent first over a slow link.
    pub(crate) fn sharp_in(&self, generation: u64, started: Instant) -> Option<f64> {
        since(self.figures.sharp?, generation, started)
    }

    /// Whether a slow pass's progress is due to be shown again; it counts
    /// as shown.
    pub(crate) fn progress_due(&mut self) -> bool {
        let due = self.progress_shown.elapsed() >= PROGRESS_EVERY;
        if due {
            self.progress_shown = Instant::now();
        }
        due
    }
}
