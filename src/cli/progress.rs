//! What `render` says of its progress on standard error: indicatif's bar
//! on a terminal; elsewhere (a batch job's log, where a bar draws nothing)
//! a line at every tenth of the render and every few seconds, or one JSON
//! object a line for whatever parses the log.

use std::io::IsTerminal;
use std::ops::Range;
use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;

use crate::interrupt::{self, Cancel};
use crate::render::{Ended, Film, Job, Session, Stop, Tracer};
use crate::report;

/// `--progress`: how a render reports on standard error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum ProgressMode {
    /// The bar on a terminal, lines elsewhere.
    Auto,
    Bar,
    /// A line at every tenth and every few seconds.
    Lines,
    /// One JSON object a line.
    Json,
    /// Nothing but warnings and errors.
    None,
}

/// A film of `spp` samples a pixel (the image under a debug view, or
/// where `inspect` looks for the worst pixel), with the progress a render
/// shows; `None` when a signal stopped it.
pub(crate) fn film(s: &Session, t: &Tracer, spp: u32, progress: ProgressMode) -> Option<Film> {
    let stop = Stop::spp(spp);
    let report = Reporter::new(progress, &stop, s.plan.deterministic, 0);
    report.begin(&Begin {
        scene: &s.scene.name,
        size: (s.width, s.height),
        samples: None,
        total: Some(spp),
        resumed: None,
        frames: None,
    });
    interrupt::flag();
    let mut p = Job::of(t, stop).start();
    let outcome = p.run(t, Cancel::Signal, |film, _| report.at(film.spp_range().1));
    if outcome.ended == Ended::Cancelled {
        report.abandon();
        crate::noteln!("interrupted: nothing written");
        return None;
    }
    report.finish(p.film().spp_range().1);
    Some(p.into_film())
}

/// The longest a log goes without a progress line.
const PERIOD: Duration = Duration::from_secs(5);
/// The shortest time between two lines: tenths of a fast render are not
/// worth a line each.
const GAP: Duration = Duration::from_secs(1);

enum Out {
    Bar(ProgressBar),
    Lines,
    Json,
    Quiet,
}

/// What a render is, said once before its first pass.
pub(crate) struct Begin<'a> {
    pub(crate) scene: &'a str,
    pub(crate) size: (u32, u32),
    /// The samples of a part, and the spp the whole render is to have.
    pub(crate) samples: Option<Range<u32>>,
    pub(crate) total: Option<u32>,
    /// The film resumed from, its samples and the seconds they took.
    pub(crate) resumed: Option<(&'a Path, Range<u32>, f64)>,
    /// A turntable's frames; `total` then counts all of their samples.
    pub(crate) frames: Option<u32>,
}

/// A render's progress reporter; its methods may be called from any
/// thread.
pub(crate) struct Reporter {
    out: Out,
    start: Instant,
    /// The samples per pixel the render ends at, when it is a fixed number.
    total: Option<f64>,
    /// The samples per pixel the film held before this run.
    before: f64,
    /// `--time` left to this run.
    seconds: Option<f64>,
    state: Mutex<State>,
}

struct State {
    /// When the last line was printed, and the tenth it reached.
    said: Option<(Instant, u32)>,
    /// The estimate the last pass gave of a render to a time or an error:
    /// its words, and the seconds it leaves.
    estimate: Option<(String, Option<f64>)>,
}

impl Reporter {
    /// A reporter for a render to `stop` of a film holding `before` spp.
    pub(crate) fn new(mode: ProgressMode, stop: &Stop, exact: bool, before: u32) -> Reporter {
        let fixed = stop.seconds.is_none() && stop.error.is_none();
        let mode = match mode {
            ProgressMode::Auto if std::io::stderr().is_terminal() => ProgressMode::Bar,
            ProgressMode::Auto => ProgressMode::Lines,
            m => m,
        };
        let out = match mode {
            ProgressMode::Bar => Out::Bar(bar(stop, exact)),
            ProgressMode::Lines => Out::Lines,
            ProgressMode::Json => Out::Json,
            _ => Out::Quiet,
        };
        Reporter {
            out,
            start: Instant::now(),
            total: stop.spp.filter(|_| fixed).map(f64::from),
            before: before as f64,
            seconds: stop.seconds,
            state: Mutex::new(State {
                said: None,
                estimate: None,
            }),
        }
    }

    /// Whether anything is reported.
    pub(crate) fn quiet(&self) -> bool {
        matches!(self.out, Out::Quiet)
    }

    /// The samples per pixel the render ends at, where fixed (a bar's
    /// length).
    pub(crate) fn length(&self) -> Option<u64> {
        match &self.out {
            Out::Bar(b) => b.length(),
            _ => self.total.map(|t| t as u64),
        }
    }

    /// Says what renders, and where a resumed render resumed from.
    pub(crate) fn begin(&self, b: &Begin) {
        let (w, h) = b.size;
        match &self.out {
            Out::Quiet => {}
            Out::Json => {
                let mut o = json!({
                    "event": "start",
                    "scene": b.scene,
                    "width": w,
                    "height": h,
                    "total_spp": b.total,
                });
                if let Some(r) = &b.samples {
                    o["samples"] = json!([r.start, r.end]);
                }
                if let Some(n) = b.frames {
                    o["frames"] = json!(n);
                }
                if let Some((path, r, s)) = &b.resumed {
                    o["resumed_from"] = json!({
                        "file": path.display().to_string(),
                        "samples": [r.start, r.end],
                        "seconds": s,
                    });
                }
                line(&o.to_string());
            }
            out => {
                let resumed = b.resumed.as_ref().map(|(path, r, s)| {
                    format!(
                        "resumed from {}, which holds samples {}..{} ({} of rendering)",
                        crate::words::path(path),
                        r.start,
                        r.end,
                        crate::words::ms(s * 1e3)
                    )
                });
                if matches!(out, Out::Bar(_)) {
                    if let Some(r) = resumed {
                        line(&r);
                    }
                    return;
                }
                let mut text = format!("render: {} at {w}x{h}", b.scene);
                if let Some(n) = b.frames {
                    text += &format!(", a turntable of {n} frames");
                }
                match (&b.samples, b.total) {
                    (None, Some(t)) if b.frames.is_some() => {
                        text += &format!(", {} spp a frame", t / b.frames.unwrap_or(1))
                    }
                    (Some(r), Some(t)) => {
                        text += &format!(", samples {}..{} of {t} spp", r.start, r.end)
                    }
                    (Some(r), None) => text += &format!(", samples {}..{}", r.start, r.end),
                    (None, Some(t)) => text += &format!(", {t} spp"),
                    (None, None) => {}
                }
                if let Some(r) = resumed {
                    text += &format!("; {r}");
                }
                line(&text);
            }
        }
    }

    /// The estimate a pass of a render to a time or an error gave.
    pub(crate) fn estimate(&self, text: String, left: Option<f64>) {
        if let Out::Bar(b) = &self.out {
            b.set_message(text.clone());
        }
        if let Ok(mut s) = self.state.lock() {
            s.estimate = Some((text, left));
        }
    }

    /// The film now holds `spp` samples per pixel (a fraction within a
    /// pass); a line is printed when one is due.
    pub(crate) fn at(&self, spp: f64) {
        let (percent, left) = self.figures(spp, self.start.elapsed().as_secs_f64());
        match &self.out {
            Out::Quiet => {}
            Out::Bar(b) => b.set_position(spp as u64),
            out => {
                let Ok(mut s) = self.state.lock() else {
                    return;
                };
                let now = Instant::now();
                let tenth = percent.map_or(0, |p| (p / 10.0) as u32);
                let due = match s.said {
                    None => spp > self.before,
                    Some((at, t)) => now - at >= PERIOD || (tenth > t && now - at >= GAP),
                };
                if !due {
                    return;
                }
                s.said = Some((now, tenth));
                let estimate = s.estimate.clone();
                drop(s);
                let elapsed = self.start.elapsed().as_secs_f64();
                let left = estimate.as_ref().map_or(left, |e| e.1.or(left));
                if matches!(out, Out::Json) {
                    let o = json!({
                        "event": "progress",
                        "percent": percent.map(|p| (p * 10.0).round() / 10.0),
                        "spp": (spp * 100.0).round() / 100.0,
                        "total_spp": self.total,
                        "elapsed_s": (elapsed * 1e3).round() / 1e3,
                        "remaining_s": left.map(|l| (l * 1e3).round() / 1e3),
                    });
                    line(&o.to_string());
                    return;
                }
                let mut text = String::from("progress: ");
                match (percent, self.total) {
                    (Some(p), Some(t)) => text += &format!("{p:.0}% ({spp:.0}/{t} spp)"),
                    (Some(p), None) => text += &format!("{p:.0}% ({spp:.0} spp)"),
                    (None, _) => text += &format!("{spp:.0} spp"),
                }
                text += &format!(", {} elapsed", crate::words::ms(elapsed * 1e3));
                match estimate {
                    Some((words, _)) => text += &format!(", {words}"),
                    None => {
                        if let Some(l) = left {
                            text += &format!(", about {} left", crate::words::ms(l * 1e3));
                        }
                    }
                }
                line(&text);
            }
        }
    }

    /// A checkpoint was written: said in JSON each time, in lines when
    /// `tell` (the first, and those SIGUSR1 asked for).
    pub(crate) fn checkpoint(&self, path: &Path, samples: Range<u32>, tell: bool) {
        match &self.out {
            Out::Json => line(
                &json!({
                    "event": "checkpoint",
                    "file": path.display().to_string(),
                    "samples": [samples.start, samples.end],
                })
                .to_string(),
            ),
            Out::Lines if tell => line(&format!(
                "checkpoint: {} holds samples {}..{}",
                crate::words::path(path),
                samples.start,
                samples.end
            )),
            Out::Bar(b) if tell => b.println(format!(
                "checkpoint: {} holds samples {}..{}",
                crate::words::path(path),
                samples.start,
                samples.end
            )),
            _ => {}
        }
    }

    /// The render ended with every sample it was to take.
    pub(crate) fn finish(&self, spp: f64) {
        let elapsed = self.start.elapsed().as_secs_f64();
        match &self.out {
            Out::Bar(b) => b.finish_and_clear(),
            Out::Lines => line(&format!(
                "progress: done, {spp:.0} spp, {} elapsed",
                crate::words::ms(elapsed * 1e3)
            )),
            Out::Json => line(
                &json!({
                    "event": "done",
                    "spp": (spp * 100.0).round() / 100.0,
                    "elapsed_s": (elapsed * 1e3).round() / 1e3,
                })
                .to_string(),
            ),
            Out::Quiet => {}
        }
    }

    /// The render stopped short: the bar is left as it is.
    pub(crate) fn abandon(&self) {
        if let Out::Bar(b) = &self.out {
            b.abandon();
        }
    }

    /// The percentage done `elapsed` seconds into the run, where a fixed
    /// spp or a time says, and the seconds a fixed spp leaves at this
    /// run's rate.
    fn figures(&self, spp: f64, elapsed: f64) -> (Option<f64>, Option<f64>) {
        let by_time = self
            .seconds
            .map(|t| 100.0 * (elapsed / t.max(1e-9)).min(1.0));
        match self.total {
            Some(t) => {
                let done = spp - self.before;
                let left = (done > 0.0).then(|| elapsed / done * (t - spp).max(0.0));
                (Some(100.0 * (spp / t.max(1.0)).min(1.0)), left)
            }
            None => (by_time, None),
        }
    }
}

/// A line on standard error.
fn line(text: &str) {
    crate::noteln!("{text}");
}

fn bar(stop: &Stop, exact: bool) -> ProgressBar {
    match stop.spp {
        Some(n) if !exact && stop.seconds.is_none() && stop.error.is_none() => {
            ProgressBar::new(n as u64).with_style(
                ProgressStyle::with_template("{bar:40} {pos}/{len} spp  {elapsed} (eta {eta})")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            )
        }
        _ => ProgressBar::new_spinner().with_style(
            ProgressStyle::with_template("{spinner} {pos} spp  {elapsed}  {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        ),
    }
}

/// A report's progress ([`report::Progress`]) as indicatif draws it: a bar
/// when the steps are known, else a spinner with the time so far.
pub(crate) struct ReportBar(ProgressBar);

impl ReportBar {
    pub(crate) fn new() -> Self {
        ReportBar(ProgressBar::hidden())
    }
}

impl report::Progress for ReportBar {
    fn begin(&self, steps: Option<u64>) {
        let style = match steps {
            Some(n) => {
                self.0.set_length(n);
                ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
            }
            None => ProgressStyle::with_template("{spinner} {elapsed} {msg}"),
        };
        self.0
            .set_style(style.unwrap_or_else(|_| ProgressStyle::default_bar()));
        self.0
            .set_draw_target(indicatif::ProgressDrawTarget::stderr());
        if steps.is_none() {
            self.0.enable_steady_tick(Duration::from_millis(200));
        }
    }

    fn doing(&self, what: &str) {
        self.0.set_message(what.to_string());
    }

    fn step(&self) {
        self.0.inc(1);
    }

    fn end(&self) {
        self.0.finish_and_clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fixed_render_reports_its_fraction_and_the_time_left() {
        let r = Reporter::new(ProgressMode::None, &Stop::spp(64), false, 16);
        // 16 spp done in this run in 2 s: 32 more take twice as long.
        assert_eq!(r.figures(32.0, 2.0), (Some(50.0), Some(4.0)));
        assert_eq!(r.figures(16.0, 2.0).1, None, "nothing done yet, no rate");
        assert_eq!(r.figures(64.0, 8.0), (Some(100.0), Some(0.0)));
        // A render to a time is as far along as its time.
        let timed = Reporter::new(ProgressMode::None, &Stop::seconds(10.0), false, 0);
        assert_eq!(timed.figures(4.0, 2.5), (Some(25.0), None));
        assert_eq!(timed.figures(9.0, 12.0).0, Some(100.0));
    }
}
