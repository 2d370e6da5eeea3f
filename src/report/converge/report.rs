//! The study as text (tables, slopes, the conclusion) and as CSV.

use std::fmt::Write as _;

use super::{Reach, RunLimit, Series, Study};

/// How far past the largest budget an extrapolated sample count is given.
const FAR: f64 = 1000.0;

fn pct(x: f64) -> String {
    format!("{:.3} %", 100.0 * x)
}

/// Number with three significant digits.
fn sig3(x: f64) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let digits = (2 - x.abs().log10().floor() as i32).max(0) as usize;
    format!("{x:.digits$}")
}

/// Up to three significant digits, without trailing zeros: `1`, `0.5`.
pub(super) fn short(x: f64) -> String {
    let s = sig3(x);
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

impl Study {
    /// Times the strategies are compared at: the scene's own budgets.
    pub(crate) fn comparison_times(&self) -> Vec<f64> {
        self.series
            .first()
            .map(|s| {
                s.points
                    .iter()
                    .map(|p| match p.budget {
                        RunLimit::Seconds(t) => t,
                        RunLimit::Spp(_) => p.seconds,
                    })
                    .collect()
            })
            .unwrap_or_default()
    }

    /// The strategy that reaches the target first, and where.
    pub(crate) fn fastest_to_target(&self) -> Option<(&Series, Reach)> {
        self.series
            .iter()
            .filter_map(|s| s.reach(self.target).map(|r| (s, r)))
            .min_by(|a, b| a.1.seconds.total_cmp(&b.1.seconds))
    }

    /// The conclusion, in a sentence or two.
    pub fn conclusion(&self) -> String {
        let size = format!("{}x{}", self.width, self.height);
        if self.exact {
            let e = self.series[0].points[0].rel_err();
            return if e == 0.0 {
                "Nothing in this scene is sampled: one pass is exact (error 0), so no more passes, budgets or reference renders are needed.".to_string()
            } else {
                format!(
                    "Nothing in this scene is sampled: one pass is final, yet it differs from the given reference by {} relative error.",
                    pct(e)
                )
            };
        }
        let t = format!("{} %", short(100.0 * self.target));
        let main = &self.series[0];
        let how = |s: &Series, r: &Reach| {
            let measured = s.points.iter().map(|p| p.spp).fold(0.0, f64::max);
            // Three decades past the data, a straight line says little.
            if !r.measured && r.spp > FAR * measured {
                return format!(
                    "more than {:.0} spp ({FAR:.0}x the largest budget) by extrapolation, beyond what these budgets can tell",
                    FAR * measured
                );
            }
            format!(
                "about {:.0} spp, {:.2} s at {size} on this machine ({})",
                r.spp.ceil(),
                r.seconds,
                if r.measured {
                    "measured"
                } else {
                    "extrapolated"
                }
            )
        };
        let mut out = match main.reach(self.target) {
            Some(r) => format!(
                "To reach {t} error with the scene's settings ({}) you need {}.",
                main.label,
                how(main, &r)
            ),
            // One point has no slope: the fault is the budgets', not the reference's.
            None if main.points.len() < 2 => format!(
                "One budget ({:.0} spp) cannot show how fast the error falls: give two or more for a sample count for {t}.",
                main.points.first().map_or(0.0, |p| p.spp)
            ),
            None => format!(
                "The scene's settings ({}) show no falling error, so no sample count for {t} can be given.{}",
                main.label,
                // A given reference (no spp of its own) may be of something else.
                if self.reference.spp.is_none() {
                    " Is the reference an image of this scene, camera and size?"
                } else {
                    ""
                }
            ),
        };
        if self.series.len() > 1 {
            match self.fastest_to_target() {
                Some((s, _)) if std::ptr::eq(s, main) => {
                    out += " None of the other settings compared gets there sooner.";
                }
                Some((s, r)) => {
                    let _ = write!(
                        out,
                        " {} ({}) gets there first: {}.",
                        s.label,
                        s.strategy.options(self.uses),
                        how(s, &r)
                    );
                }
                None => {}
            }
        }
        out
    }

    /// The text report: per-budget table, slopes, the equal-time comparison
    /// and the conclusion.
    pub fn text(&self) -> String {
        let mut o = String::new();
        let runs = if self.exact {
            "one pass".to_string()
        } else {
            format!(
                "{} seed{} per budget",
                self.seeds,
                if self.seeds == 1 { "" } else { "s" }
            )
        };
        let _ = writeln!(
            o,
            "converge {} at {}x{}, {runs}",
            self.scene, self.width, self.height
        );
        let _ = writeln!(
            o,
            "reference: {}{}{}",
            self.reference.source,
            self.reference
                .spp
                .map(|s| format!(", {s} spp"))
                .unwrap_or_default(),
            if self.reference.seconds > 0.0 {
                format!(", {:.1} s", self.reference.seconds)
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            o,
            "errors on luminance: rel err = sqrt(relMSE), relMSE = mean (x - ref)^2 / (ref^2 + 0.01); est = the film's own estimate (- = unknown: below 2 samples per pixel)"
        );
        if self.series.len() > 1 {
            let _ = writeln!(
                o,
                "strategies: Ln = n samples per area light a hit (--light-samples n), Gn = n glossy directions a hit (--glossy-samples n), jittered or independent samples (--independent), adaptive = passes go to the pixels with the most error, path or whitted = the integrator"
            );
        }
        o.push('\n');
        for (i, s) in self.series.iter().enumerate() {
            if i > 0 && self.series.len() > 1 && i == 1 {
                let _ = writeln!(o, "compared strategies:");
            }
            let _ = writeln!(
                o,
                "{}{}:",
                s.label,
                if i == 0 {
                    " (the scene's settings)"
                } else if s.strategy.integrator != self.series[0].strategy.integrator {
                    " (another integrator converges to its own image: against this reference its error levels off)"
                } else {
                    ""
                }
            );
            let _ = writeln!(
                o,
                "  {:>8} {:>8} {:>9} {:>8} {:>10} {:>10} {:>10} {:>10} {:>8}",
                "budget",
                "spp",
                "time s",
                "Mrays/s",
                "RMSE",
                "relMSE",
                "rel err",
                "est err",
                "est/true"
            );
            for p in &s.points {
                let _ = writeln!(
                    o,
                    "  {:>8} {:>8} {:>9.4} {:>8.2} {:>10.3e} {:>10.3e} {:>10} {:>10} {:>8}",
                    p.budget.to_string(),
                    sig3(p.spp),
                    p.seconds,
                    p.mrays_per_s(),
                    p.rmse,
                    p.rel_mse,
                    pct(p.rel_err()),
                    p.est_err().map(pct).unwrap_or_else(|| "-".into()),
                    p.ratio()
                        .map(|r| format!("{r:.2}"))
                        .unwrap_or_else(|| "-".into()),
                );
            }
            if !self.exact {
                let slope = |x: Option<f64>| x.map(|v| format!("{v:.2}")).unwrap_or("-".into());
                let time = match s.slope_time() {
                    Some(t) => format!("{t:.2} against log(time)"),
                    None => format!(
                        "none against log(time) (runs under {} ms time the timer more than the method)",
                        super::MIN_TIMED * 1e3
                    ),
                };
                let _ = writeln!(
                    o,
                    "  slope of log(rel err) (-0.5: plain Monte Carlo): {} against log(spp), {time}\n",
                    slope(s.slope_spp())
                );
            }
        }
        if self.series.len() > 1 {
            let w = self
                .series
                .iter()
                .map(|s| s.label.len())
                .max()
                .unwrap_or(0)
                .max(10);
            let _ = write!(o, "rel err at equal time (* = lowest):\n  {:>9}", "time s");
            for s in &self.series {
                let _ = write!(o, " {:>w$}", s.label);
            }
            o.push('\n');
            for t in self.comparison_times() {
                let errs: Vec<Option<f64>> = self.series.iter().map(|s| s.error_at(t)).collect();
                let best = errs.iter().flatten().copied().fold(f64::INFINITY, f64::min);
                let _ = write!(o, "  {t:>9.4}");
                for e in &errs {
                    let cell = match e {
                        Some(e) => format!("{}{}", pct(*e), if *e == best { "*" } else { " " }),
                        None => "- ".into(),
                    };
                    let _ = write!(o, " {cell:>w$}");
                }
                o.push('\n');
            }
            let _ = writeln!(
                o,
                "  (interpolated in log-log between each strategy's measured points; - = outside them)\n"
            );
        }
        for n in &self.notes {
            let _ = writeln!(o, "note: {n}");
        }
        let _ = writeln!(o, "{}", self.conclusion());
        o
    }

    /// Every measured point as CSV, one row per strategy and budget.
    pub fn csv(&self) -> String {
        let mut o = String::from(
            "strategy,light_samples,glossy_samples,stratified,budget,seeds,spp,seconds,mrays_per_s,rmse,rel_mse,rel_err,est_rel_mse,est_over_true\n",
        );
        let opt = |x: Option<f64>| x.map(|v| format!("{v:e}")).unwrap_or_default();
        for s in &self.series {
            for p in &s.points {
                let _ = writeln!(
                    o,
                    "{},{},{},{},{},{},{},{},{},{:e},{:e},{:e},{},{}",
                    s.label,
                    s.strategy.light_samples,
                    s.strategy.glossy_samples,
                    s.strategy.stratify,
                    p.budget.to_string().replace(' ', ""),
                    self.seeds,
                    p.spp,
                    p.seconds,
                    p.mrays_per_s(),
                    p.rmse,
                    p.rel_mse,
                    p.rel_err(),
                    opt(p.est_rel_mse),
                    opt(p.ratio()),
                );
            }
        }
        o
    }
}
