//! TermOutput to the terminal as the link allows: the [`Screen`]'s changed
//! cells in chunks the [`Pacer`] makes room for, and which pictures have
//! reached the screen (every cell written since they were drawn, and the
//! terminal has answered for those bytes), for the frame rate and the time
//! a view took to appear.

use std::collections::VecDeque;
use std::io::{self, Write};
use std::time::Instant;

use super::pace::{Pacer, PROBE};
use super::screen::Screen;

/// What the viewport showed in a draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Shown {
    pub(crate) generation: u64,
    /// A full-resolution pass (not the coarse preview, not an older view).
    pub(crate) full: bool,
    /// Sent at full resolution: not a coarse image sent first over a slow
    /// link.
    pub(crate) sharp: bool,
}

/// The output's figures, for the Render panel.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Figures {
    /// Bytes written so far.
    pub(crate) written: u64,
    /// Pictures that reached the screen so far.
    pub(crate) frames: u64,
    /// The link's measured delivery rate in bytes per second.
    pub(crate) link_rate: Option<f64>,
    /// The first full picture of a view to reach the screen (coarse or
    /// sharp): its generation and when.
    pub(crate) picture: Option<(u64, Instant)>,
    /// The first sharp one.
    pub(crate) sharp: Option<(u64, Instant)>,
}

#[derive(Default)]
pub(crate) struct TermOutput {
    pub(crate) pacer: Pacer,
    /// Draws not yet on screen in full: the screen's sweep count and the
    /// pieces queued when drawn, and what they showed.
    drawn: VecDeque<(u64, u64, Shown)>,
    /// Pieces of output written after the cells (images), each followed by
    /// a request; how many were queued, and written (or dropped) so far.
    pieces: VecDeque<Vec<u8>>,
    queued: u64,
    sent_pieces: u64,
    /// Pictures written in full, waiting for the terminal's answer: the
    /// bytes written by then.
    landing: VecDeque<(u64, Shown)>,
    figures: Figures,
}

impl TermOutput {
    /// Starts pacing: the first request measures the round trip.
    pub(crate) fn start<W: Write>(
        &mut self,
        screen: &mut Screen<W>,
        now: Instant,
    ) -> io::Result<()> {
        screen.send(PROBE)?;
        self.pacer.sent(PROBE.len(), now);
        Ok(())
    }

    /// A frame showing `shown` was drawn into the screen.
    pub(crate) fn drawn<W: Write>(&mut self, screen: &Screen<W>, shown: Shown) {
        self.drawn.push_back((screen.swept(), self.queued, shown));
    }

    /// Queues pieces (images) to follow the cells.
    pub(crate) fn queue(&mut self, pieces: Vec<Vec<u8>>) {
        self.queued += pieces.len() as u64;
        self.pieces.extend(pieces);
    }

    /// Queues pieces to go before any other.
    pub(crate) fn queue_first(&mut self, pieces: Vec<Vec<u8>>) {
        self.queued += pieces.len() as u64;
        for p in pieces.into_iter().rev() {
            self.pieces.push_front(p);
        }
    }

    /// Drops the pieces not yet written (leaving: the images they hold
    /// would outlive the TUI); draws waiting for them wait no longer.
    pub(crate) fn drop_pieces(&mut self) {
        self.sent_pieces += self.pieces.len() as u64;
        self.pieces.clear();
    }

    /// Whether every queued piece has been written.
    pub(crate) fn pieces_written(&self) -> bool {
        self.pieces.is_empty()
    }

    /// The terminal answered a request.
    pub(crate) fn answered(&mut self, now: Instant) {
        self.pacer.answered(now);
        self.land(now);
    }

    /// Writes what the pacer has room for, then notes which pictures are
    /// on screen.
    pub(crate) fn pump<W: Write>(
        &mut self,
        screen: &mut Screen<W>,
        now: Instant,
    ) -> io::Result<()> {
        self.pacer.check(now);
        while screen.pending() {
            let room = self.pacer.room();
            if room == 0 {
                break;
            }
            let (n, _) = screen.pump(room.saturating_sub(PROBE.len()).max(1))?;
            let mut sent = n;
            if self.pacer.paced() {
                screen.send(PROBE)?;
                sent += PROBE.len();
            }
            self.pacer.sent(sent, now);
        }
        // Then the pieces, once the cells are written.
        while !screen.pending() && self.pacer.room() > 0 {
            let Some(piece) = self.pieces.pop_front() else {
                break;
            };
            screen.send(&piece)?;
            let mut sent = piece.len();
            if self.pacer.paced() {
                screen.send(PROBE)?;
                sent += PROBE.len();
            }
            self.pacer.sent(sent, now);
            self.sent_pieces += 1;
        }
        // A draw is written in full once every cell has been swept since
        // (or nothing differs any more) and its pieces are written.
        let mut covered = None;
        while let Some(&(at, pieces, shown)) = self.drawn.front() {
            let cells = !screen.pending() || screen.swept() >= at + screen.cells() as u64;
            if !cells || self.sent_pieces < pieces {
                break;
            }
            self.drawn.pop_front();
            covered = Some(shown);
        }
        if let Some(shown) = covered {
            self.landing.push_back((screen.written(), shown));
        }
        self.land(now);
        self.figures.written = screen.written();
        self.figures.link_rate = self.pacer.rate();
        Ok(())
    }

    /// Pictures whose bytes the terminal has answered for are on screen.
    fn land(&mut self, now: Instant) {
        while let Some(&(bytes, shown)) = self.landing.front() {
            if self.pacer.acked() < bytes {
                break;
            }
            self.landing.pop_front();
            self.figures.frames += 1;
            let new =
                |first: Option<(u64, Instant)>| first.is_none_or(|(g, _)| g != shown.generation);
            if shown.full && new(self.figures.picture) {
                self.figures.picture = Some((shown.generation, now));
            }
            if shown.full && shown.sharp && new(self.figures.sharp) {
                self.figures.sharp = Some((shown.generation, now));
            }
        }
    }

    pub(crate) fn figures(&self) -> Figures {
        self.figures
    }

    /// Whether requests are still unanswered.
    pub(crate) fn waiting(&self) -> bool {
        self.pacer.paced() && self.pacer.waiting() > 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ratatui::layout::Size;
    use ratatui::style::Style;
    use ratatui::Terminal;
    use std::time::Duration;

    #[test]
    fn a_picture_lands_when_every_cell_is_written_and_answered() {
        let mut t =
            Terminal::new(Screen::new(Vec::new(), Some(Size::new(40, 10))).unwrap()).unwrap();
        let mut out = TermOutput::default();
        let t0 = Instant::now();
        out.start(t.backend_mut(), t0).unwrap();
        let shown = Shown {
            generation: 1,
            full: true,
            sharp: true,
        };
        t.draw(|f| {
            for y in 0..10 {
                f.buffer_mut().set_string(
                    0,
                    y,
                    "x".repeat(40),
                    Style::new().fg(ratatui::style::Color::Indexed(200)),
                );
            }
        })
        .unwrap();
        out.drawn(t.backend(), shown);
        out.pump(t.backend_mut(), t0).unwrap();
        // Written (the first chunk's room covers it) but not answered yet.
        assert!(!t.backend().pending());
        assert_eq!(out.figures().frames, 0);
        assert!(out.figures().picture.is_none());
        // Each chunk ended with a request; answering all lands the picture.
        let later = t0 + Duration::from_millis(30);
        while out.waiting() {
            out.answered(later);
        }
        assert_eq!(out.figures().frames, 1);
        assert_eq!(out.figures().picture, Some((1, later)));
        assert_eq!(out.figures().sharp, Some((1, later)));
        let written = String::from_utf8_lossy(t.backend_mut().writer()).into_owned();
        assert!(written.starts_with("\x1b[6n"), "{written:?}");
        assert!(written.ends_with("\x1b[6n"), "{written:?}");
    }
}
