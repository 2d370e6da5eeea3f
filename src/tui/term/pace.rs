//! How much may be written to the terminal now. Each chunk of output ends
//! with a cursor position request (`CSI 6n`); the terminal answers it only
//! once it has processed everything before it, so the answers say what
//! the whole way to the screen (ssh, a slow link, a multiplexer) has
//! absorbed. Output waits while more than about the link's bandwidth-delay
//! product plus [`QUEUE`] is unanswered: nothing queues up behind what
//! the user will type next.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The request each chunk ends with.
pub(crate) const PROBE: &[u8] = b"\x1b[6n";
/// Unanswered output allowed beyond the link's round trip.
const QUEUE: Duration = Duration::from_millis(150);
/// Bounds on the unanswered bytes: the first chunks, and always.
const INITIAL: usize = 16 << 10;
const MIN: usize = 4 << 10;
const MAX: usize = 4 << 20;
/// Chunks up to this size, written to an idle link, measure the round trip.
const CLEAN: usize = 512;
/// The bandwidth is measured over this much busy time (and at most this
/// many chunks): long enough that a burst a buffer lets through at once
/// does not count as the link's speed.
const HISTORY: f64 = 3.0;
const SAMPLES: usize = 256;
/// A terminal that has not answered the first request by then never will.
const NO_ANSWER: Duration = Duration::from_secs(3);

#[derive(Debug, Default)]
pub(crate) struct Pacer {
    /// Chunks written and not yet answered: bytes, when they were written
    /// and the unanswered bytes then, this chunk's included.
    outstanding: VecDeque<(usize, Instant, usize)>,
    in_flight: usize,
    /// Bytes answered so far.
    acked: u64,
    last_ack: Option<Instant>,
    /// Bytes per second the link delivers while busy, from the (bytes,
    /// busy seconds) of the last chunks.
    rate: Option<f64>,
    samples: VecDeque<(f64, f64)>,
    min_rtt: Option<Duration>,
    /// Whether any request was answered; if none is within [`NO_ANSWER`]
    /// of the first, output is no longer paced.
    answered: bool,
    first: Option<Instant>,
    unpaced: bool,
}

impl Pacer {
    /// Bytes that may be written now.
    pub(crate) fn room(&self) -> usize {
        if self.unpaced {
            return usize::MAX;
        }
        self.limit().saturating_sub(self.in_flight)
    }

    /// The unanswered bytes allowed: what the link delivers in a round
    /// trip plus [`QUEUE`].
    pub(crate) fn limit(&self) -> usize {
        match self.rate {
            Some(rate) => {
                let rtt = self.min_rtt.unwrap_or_default();
                let bytes = rate * (rtt + QUEUE).as_secs_f64();
                (bytes as usize).clamp(MIN, MAX)
            }
            None => INITIAL,
        }
    }

    /// Whether output waits for answers.
    pub(crate) fn paced(&self) -> bool {
        !self.unpaced
    }

    /// A chunk of `bytes` (its request included) was written at `now`.
    pub(crate) fn sent(&mut self, bytes: usize, now: Instant) {
        if self.unpaced {
            self.acked += bytes as u64;
            return;
        }
        self.first.get_or_insert(now);
        self.in_flight += bytes;
        self.outstanding.push_back((bytes, now, self.in_flight));
    }

    /// The terminal answered the oldest request at `now`.
    pub(crate) fn answered(&mut self, now: Instant) {
        let Some((bytes, sent, backlog)) = self.outstanding.pop_front() else {
            return;
        };
        self.answered = true;
        self.in_flight -= bytes;
        self.acked += bytes as u64;
        // The round trip, from small chunks written to an idle link (the
        // first request is one; what is written after it does not delay
        // its answer): larger ones also wait for the link.
        if bytes <= CLEAN && backlog == bytes {
            let rtt = now.saturating_duration_since(sent);
            self.min_rtt = Some(self.min_rtt.map_or(rtt, |m| m.min(rtt)));
        }
        // The link carried this chunk from when it reached it (written a
        // round trip's worth of answer earlier) or the previous one was
        // through, whichever is later, until now less the answer's way back.
        let rtt = self.min_rtt.unwrap_or_default();
        let start = self.last_ack.map_or(sent + rtt, |a| a.max(sent + rtt));
        let busy = now.saturating_duration_since(start).as_secs_f64().max(1e-4);
        self.last_ack = Some(now);
        if bytes > CLEAN {
            // Bytes over busy time of the last few seconds of sending.
            self.samples.push_back((bytes as f64, busy));
            while self.samples.len() > SAMPLES
                || self.samples.iter().skip(1).map(|s| s.1).sum::<f64>() > HISTORY
            {
                self.samples.pop_front();
            }
            let (b, t) = self
                .samples
                .iter()
                .fold((0.0, 0.0), |(b, t), s| (b + s.0, t + s.1));
            // And no more than the backlog this chunk joined took to go
            // through: the link slowing down shows there first.
            let drained = now.saturating_duration_since(sent + rtt).as_secs_f64();
            let backlog_rate = backlog as f64 / drained.max(1e-4);
            self.rate = Some((b / t).min(backlog_rate));
        }
    }

    /// Stops pacing when the terminal answers no requests.
    pub(crate) fn check(&mut self, now: Instant) {
        if !self.answered
            && !self.unpaced
            && self
                .first
                .is_some_and(|f| now.saturating_duration_since(f) > NO_ANSWER)
        {
            self.unpaced = true;
            self.forget();
        }
    }

    /// Takes every unanswered request as answered: after a stop, their
    /// answers may have gone to the shell, and output must not wait for
    /// them.
    pub(crate) fn forget(&mut self) {
        self.acked += self.in_flight as u64;
        self.in_flight = 0;
        self.outstanding.clear();
    }

    /// Bytes the terminal has processed (all written ones when unpaced).
    pub(crate) fn acked(&self) -> u64 {
        self.acked
    }

    /// Requests not yet answered.
    pub(crate) fn waiting(&self) -> usize {
        self.outstanding.len()
    }

    /// The link's delivery rate in bytes per second, once measured.
    pub(crate) fn rate(&self) -> Option<f64> {
        self.rate
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A link of `rate` bytes per second and `rtt` seconds: a chunk is
    /// answered when all bytes before it went through plus the round trip.
    struct Link {
        rate: f64,
        rtt: f64,
        /// When the link is free again, in seconds.
        free: f64,
        answers: VecDeque<f64>,
        /// Bytes an idle link lets through at once (a throttle's bucket).
        burst: f64,
    }

    impl Link {
        fn send(&mut self, at: f64, bytes: usize) {
            let credit = ((at - self.free).max(0.0) * self.rate).min(self.burst);
            let slow = (bytes as f64 - credit).max(0.0);
            self.free = self.free.max(at) + slow / self.rate;
            self.answers.push_back(self.free + self.rtt);
        }
    }

    /// Writes as much as the pacer allows, whenever it allows, for
    /// `seconds`; returns the most that was ever unanswered (in seconds of
    /// the link) and the pacer.
    fn run(rate: f64, rtt: f64, seconds: f64) -> (f64, Pacer) {
        let t0 = Instant::now();
        let at = |s: f64| t0 + Duration::from_secs_f64(s);
        let mut link = Link {
            rate,
            rtt,
            free: 0.0,
            answers: VecDeque::new(),
            burst: 0.0,
        };
        let mut p = Pacer::default();
        // The first request, alone, measures the round trip.
        link.send(0.0, PROBE.len());
        p.sent(PROBE.len(), at(0.0));
        let mut now = link.answers.pop_front().unwrap();
        p.answered(at(now));
        let mut worst = 0f64;
        while now < seconds {
            let room = p.room();
            if room > 0 {
                let bytes = room.min(64 << 10);
                link.send(now, bytes);
                p.sent(bytes, at(now));
                worst = worst.max(p.in_flight as f64 / rate);
            }
            // The next answer.
            let Some(next) = link.answers.pop_front() else {
                break;
            };
            now = next;
            p.answered(at(now));
        }
        (worst, p)
    }

    #[test]
    fn a_slow_link_is_measured_and_not_flooded() {
        for (rate, rtt) in [(32e3, 0.002), (32e3, 0.1), (200e3, 0.05), (10e6, 0.001)] {
            let (worst, p) = run(rate, rtt, 3.0);
            let est = p.rate().unwrap();
            assert!(
                (est - rate).abs() < 0.15 * rate,
                "{rate} B/s, {rtt} s: estimated {est}"
            );
            // Never much more unanswered than a round trip and the queue
            // allowance (the first chunks excepted on the slowest links).
            let bound = (rtt + 0.2).max(INITIAL as f64 / rate + 0.01);
            assert!(worst <= bound, "{rate} B/s, {rtt} s: {worst} s queued");
        }
    }

    #[test]
    fn a_terminal_that_never_answers_is_not_waited_for() {
        let t0 = Instant::now();
        let mut p = Pacer::default();
        p.sent(INITIAL, t0);
        assert_eq!(p.room(), 0);
        p.check(t0 + Duration::from_secs(1));
        assert_eq!(p.room(), 0);
        p.check(t0 + Duration::from_secs(4));
        assert_eq!(p.room(), usize::MAX);
        assert_eq!(p.acked(), INITIAL as u64);
    }

    #[test]
    fn a_burst_after_a_pause_is_not_taken_for_the_links_speed() {
        let t0 = Instant::now();
        let at = |s: f64| t0 + Duration::from_secs_f64(s);
        let rate = 32e3;
        let mut link = Link {
            rate,
            rtt: 0.01,
            free: 0.0,
            answers: VecDeque::new(),
            burst: 128e3,
        };
        let mut p = Pacer::default();
        link.send(0.0, PROBE.len());
        p.sent(PROBE.len(), at(0.0));
        let mut now = link.answers.pop_front().unwrap();
        p.answered(at(now));
        // Busy for 3 s, idle for 5 s (the bucket fills), busy for 5 s.
        let mut worst = [0f64; 2];
        for (phase, (from, to)) in [(now, 3.0), (8.0, 13.0)].into_iter().enumerate() {
            now = now.max(from);
            let mut sent: VecDeque<f64> = VecDeque::new();
            while now < to {
                let room = p.room();
                if room > 0 {
                    link.send(now, room.min(64 << 10));
                    p.sent(room.min(64 << 10), at(now));
                    sent.push_back(now);
                }
                let next = link.answers.pop_front().unwrap();
                // How long output waited in the link beyond the round trip:
                // what a key typed now would wait for.
                let waited = next - sent.pop_front().unwrap() - link.rtt;
                worst[phase] = worst[phase].max(waited);
                now = next;
                p.answered(at(now));
            }
            while let Some(next) = link.answers.pop_front() {
                p.answered(at(next));
                now = next;
            }
        }
        // The first chunk takes INITIAL / rate; after the pause, the
        // bucket's burst must not raise the queue much above QUEUE.
        assert!(worst[0] < 0.6, "{worst:?} s");
        assert!(worst[1] < 0.4, "{worst:?} s");
    }

    #[test]
    fn the_first_request_measures_the_round_trip_whatever_follows_it() {
        let t0 = Instant::now();
        let mut p = Pacer::default();
        p.sent(PROBE.len(), t0);
        // The first frame goes out before the answer comes.
        p.sent(INITIAL - PROBE.len(), t0 + Duration::from_millis(1));
        p.answered(t0 + Duration::from_millis(40));
        assert_eq!(p.min_rtt, Some(Duration::from_millis(40)));
        p.answered(t0 + Duration::from_millis(540));
        // About 32 kB/s: the limit is a round trip and the queue allowance.
        let rate = p.rate().unwrap();
        assert!((rate - 32e3).abs() < 2e3, "{rate}");
        let want = (rate * 0.19) as usize;
        assert!(p.limit().abs_diff(want.max(MIN)) < 100, "{}", p.limit());
    }
}
