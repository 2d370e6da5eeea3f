//! The status line: the newest message while it lasts, else the state
//! (scene, mode, load warnings).

use std::time::{Duration, Instant};

use super::popup::Popup;
use crate::scene::Scene;
use crate::words;

/// How long a status message stays before the status line shows the
/// state again.
const MESSAGE_LIFE: Duration = Duration::from_secs(8);

/// The status line's message and the load warnings it counts.
pub(crate) struct Status {
    /// The newest message, and when it was said; it gives way to the
    /// state after [`MESSAGE_LIFE`].
    message: String,
    said_at: Instant,
    /// What loading the scene warned about.
    warnings: Vec<String>,
}

impl Status {
    pub(crate) fn new(message: String, warnings: Vec<String>) -> Status {
        Status {
            message,
            said_at: Instant::now(),
            warnings,
        }
    }

    /// Puts `text` on the status line for a while.
    pub(crate) fn say(&mut self, text: impl Into<String>) {
        self.message = text.into();
        self.said_at = Instant::now();
    }

    /// Drops the message: the state shows again.
    pub(crate) fn clear(&mut self) {
        self.message.clear();
    }

    /// The newest message, even one that has run its time.
    pub(crate) fn message(&self) -> &str {
        &self.message
    }

    fn lasts(&self) -> bool {
        !self.message.is_empty() && self.said_at.elapsed() < MESSAGE_LIFE
    }

    /// Drops a message that has just run its time; true when there was one.
    pub(crate) fn expire(&mut self) -> bool {
        let ran_out = !self.message.is_empty() && !self.lasts();
        if ran_out {
            self.message.clear();
        }
        ran_out
    }

    /// What the status line shows: the message while it lasts, else the
    /// state of `scene`, in select mode or not.
    pub(crate) fn line(&self, scene: &Scene, select_mode: bool) -> String {
        if self.lasts() {
            return self.message.clone();
        }
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
        if select_mode {
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

    /// The popup with the newest message in full (the status line may
    /// shorten it) and the load warnings of the scene `name`.
    pub(crate) fn warnings_popup(&self, name: &str) -> Popup {
        let mut lines = Vec::new();
        if !self.message.is_empty() {
            lines.push(format!("last message: {}", self.message));
            lines.push(String::new());
        }
        if self.warnings.is_empty() {
            lines.push("the scene loaded without warnings".into());
        } else {
            lines.extend(self.warnings.iter().cloned());
        }
        let mut p = Popup::new(
            format!(
                "{} loading {name}",
                words::count(self.warnings.len() as u64, "warning", "warnings"),
            ),
            lines,
        );
        p.wrap_indent = Some(2);
        p
    }
}
