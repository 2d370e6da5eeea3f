//! The side panels: BVH statistics, feature toggles and render progress
//! with its error chart.

use ratatui::layout::{Constraint, Layout, Rect};
use ratatui::style::{Color, Modifier, Style};
use ratatui::symbols::Marker;
use ratatui::text::{Line, Span};
use ratatui::widgets::{Axis, Block, Borders, Chart, Dataset, GraphType, Paragraph};
use ratatui::Frame;

use super::fit;
use crate::render::plan::not_needed;
use crate::render::{Decision, Feature};
use crate::tui::app::App;
use crate::tui::keys::{self, Action};
use crate::tui::popup::wrap;
use crate::tui::worker::{Snapshot, Truth, CONVERGED_BELOW};
use crate::words::{self, si};

fn panel(title: String) -> Block<'static> {
    Block::new()
        .borders(Borders::TOP)
        .title(title)
        .title_style(Style::new().add_modifier(Modifier::BOLD))
}

pub(crate) fn bvh(f: &mut Frame, area: Rect, app: &App) {
    let s = &app.session.bvh.stats;
    let title = if app.link.rebuilding {
        format!(" BVH: rebuilding with {}... ", app.choice.builder())
    } else {
        format!(" BVH: {}, {} triangles ", s.builder, s.triangles)
    };
    let room = area.width as usize;
    let per_ray = match app.current_frame().and_then(|f| f.per_ray) {
        Some(p) if app.choice.plan().bvh => {
            let long = format!(
                "per ray: {:.1} wide nodes, {:.1} triangle tests",
                p.nodes, p.triangle_tests
            );
            if long.chars().count() <= room {
                long
            } else {
                format!(
                    "ray: {:.1} wide nodes {:.1} tests",
                    p.nodes, p.triangle_tests
                )
            }
        }
        _ if !app.choice.plan().bvh => "per ray: BVH off (brute force)".into(),
        _ => "per ray: measuring...".into(),
    };
    let text = vec![
        Line::from(fit::joined(
            &[
                ("binary:".into(), 1),
                (
                    format!("{} nodes {} leaves depth {}", s.nodes, s.leaves, s.depth),
                    0,
                ),
            ],
            " ",
            room,
        )),
        Line::from(format!(
            "leaf max {} mean {:.1} SAH {:.1}",
            s.max_leaf, s.mean_leaf, s.sah_cost
        )),
        Line::from(format!(
            "build {}, {} tris/s",
            words::ms(s.build_ms),
            si(s.triangles_per_second())
        )),
        Line::from(per_ray),
    ];
    let inner = panel(String::new()).inner(area);
    fit::check("BVH title", &Line::raw(&title), area.width);
    fit::check_all(
        "BVH panel",
        &text[..text.len().min(inner.height as usize)],
        inner,
    );
    f.render_widget(Paragraph::new(text).block(panel(title)), area);
}

/// The features panel's lines for a panel `width` wide. With `wrap`, a
/// reason too long for the line goes on its own indented line; without,
/// reasons too long take their short form.
pub(crate) fn feature_lines(app: &App, width: u16, wrap: bool) -> Vec<Line<'static>> {
    let mut lines = Vec::new();
    let dim = Style::new().fg(Color::DarkGray);
    let yellow = Style::new().fg(Color::Yellow);
    for feat in Feature::ALL {
        let key = keys::key_for(Action::Toggle(feat)).map_or(" ".into(), |k| k.label());
        // The state, and why it is not running: a feature switched off the
        // scene would not need anyway keeps its reason.
        let scene_reason = not_needed(&app.session.scene, feat);
        let (state, why, style) = match app.feature_state(feat) {
            Decision::On => ("on".to_string(), None, Style::new().fg(Color::Green)),
            Decision::Off => ("off".to_string(), scene_reason, dim),
            Decision::NotNeeded(why) => ("not needed:".to_string(), Some(why), yellow),
            Decision::Needs(g) => (format!("off: needs {}", g.name()), None, yellow),
        };
        let name = format!(" {:<14} ", feat.name());
        let head = Span::styled(key, Style::new().add_modifier(Modifier::BOLD));
        let room = (width as usize).saturating_sub(1 + name.len());
        let with = |reason: &str| match why {
            Some(_) if state == "off" => format!("off ({reason})"),
            Some(_) => format!("{state} {reason}"),
            None => state.clone(),
        };
        let full = with(why.map_or("", |w| w.long()));
        let line = if full.chars().count() <= room {
            full
        } else if let (true, Some(w)) = (wrap, why) {
            lines.push(Line::from(vec![
                head.clone(),
                Span::raw(name.clone()),
                Span::styled(state.clone(), style),
            ]));
            lines.push(Line::from(Span::styled(format!("  {}", w.long()), style)));
            continue;
        } else {
            // Narrow: the short reason, which says as much in fewer words.
            // "needs textures" alone still says it is off.
            let bare = state.strip_prefix("off: ").unwrap_or(&state).to_string();
            let short = why.map_or(bare, |w| match state.as_str() {
                "off" => format!("off ({})", w.short()),
                _ => w.short().to_string(),
            });
            short
        };
        lines.push(Line::from(vec![
            head,
            Span::raw(name),
            Span::styled(line, style),
        ]));
    }
    lines
}

pub(crate) fn features(f: &mut Frame, area: Rect, lines: Vec<Line<'static>>) {
    fit::check_all("Features panel", &lines, panel(String::new()).inner(area));
    f.render_widget(
        Paragraph::new(lines).block(panel(" Features ".into())),
        area,
    );
}

/// What goes to the terminal: bytes and pictures per second, the link's
/// measured rate, and how long the view took to appear.
fn output_lines(app: &App, room: usize) -> Vec<Line<'static>> {
    let mut v = vec![Line::from(fit::joined(
        &[
            (format!("terminal {}B/s", si(app.meter.bytes_per_sec())), 0),
            (format!("{:.1} frames/s", app.meter.frames_per_sec()), 1),
        ],
        " · ",
        room,
    ))];
    let link = app.meter.link_rate().map(|r| format!("link {}B/s", si(r)));
    // Over a slow link pixel graphics show a coarse picture first, and
    // 24-bit colour one in 256 colours.
    let (first, coarse, sharp) = match app.display.pixels {
        Some(_) => ("", ", coarse", "sharp"),
        None => (" in 256 colours", " in 256 colours", "24-bit"),
    };
    let shown = app.view_shown_in().map(|s| {
        let at = words::ms(s * 1e3);
        match app.view_sharp_in() {
            Some(t) if t > s => {
                format!("view shown in {at}{first}, {sharp} {}", words::ms(t * 1e3))
            }
            None => format!("view shown in {at}{coarse}"),
            Some(_) => format!("view shown in {at}"),
        }
    });
    v.extend(link.into_iter().chain(shown).map(Line::from));
    v
}

/// The render panel's lines for a panel `room` columns wide, the most
/// telling first: where the panel is short, the last ones go.
fn render_lines(app: &App, room: usize) -> Vec<Line<'static>> {
    let bytes = output_lines(app, room);
    let mut text = match app.current_frame() {
        None => [vec![Line::from("starting...")], bytes].concat(),
        Some(s) if s.coarse => [
            vec![Line::from(format!(
                "coarse preview in {}",
                words::ms(s.pass_ms)
            ))],
            bytes,
        ]
        .concat(),
        Some(s) => {
            let error = match s.error {
                _ if s.exact => "error: exact (nothing sampled)".to_string(),
                None => words::error_unknown(s.spp).replacen("error ", "error: ", 1),
                Some(e) => format!("error {:.2}% (estimated)", e * 100.0),
            };
            let done = if s.done && !s.exact { " (done)" } else { "" };
            let spp = match s.converged {
                Some(_) => format!("{:.1} spp mean{done}", s.spp_mean),
                None => format!("{} spp{done}", s.spp),
            };
            let mut v = vec![
                Line::from(fit::joined(
                    &[(spp, 0), (format!("{}/pass", words::ms(s.pass_ms)), 1)],
                    " · ",
                    room,
                )),
                Line::from(error),
            ];
            if let Some(c) = s.converged {
                v.push(Line::from(format!(
                    "{:.0}% of pixels below {}%",
                    c * 100.0,
                    CONVERGED_BELOW * 100.0
                )));
            }
            v.push(Line::from(fit::joined(
                &[
                    (words::rays_per_s(s.mrays * 1e6), 0),
                    (words::ms(s.elapsed * 1e3), 0),
                ],
                " · ",
                room,
            )));
            if s.bad_samples > 0 {
                v.push(Line::styled(
                    format!("{} NaN/Inf samples (n finds one)", s.bad_samples),
                    Style::new().fg(Color::Red),
                ));
            }
            if app.reference.loaded() {
                v.extend(truth_lines(s));
            }
            v.extend(bytes);
            v
        }
    };
    if let Some((done, rows, secs)) = app.link.slow_pass() {
        text.insert(
            0,
            Line::styled(
                format!(
                    "pass: {}% of rows ({done}/{rows}) · {secs:.1} s",
                    done as u64 * 100 / rows.max(1) as u64
                ),
                Style::new().fg(Color::Yellow),
            ),
        );
    }
    // Lines too long for the panel wrap under themselves.
    text.into_iter()
        .flat_map(|l| {
            let style = l.style;
            let one = l.to_string();
            wrap(&one, room, 2)
                .into_iter()
                .map(move |r| Line::styled(r, style))
        })
        .collect()
}

pub(crate) fn render(f: &mut Frame, area: Rect, app: &App) {
    let block = panel(" Render ".into());
    let inner = block.inner(area);
    f.render_widget(block, area);
    let mut text = render_lines(app, inner.width as usize);
    text.truncate(inner.height as usize);
    let [text_area, chart_area] =
        Layout::vertical([Constraint::Length(text.len() as u16), Constraint::Min(0)]).areas(inner);
    fit::check_all("Render panel", &text, inner);
    f.render_widget(Paragraph::new(text), text_area);
    if chart_area.height >= 6 {
        if let Some(s) = app
            .current_frame()
            .filter(|s| s.history.len() >= 2 || s.true_history.len() >= 2)
        {
            error_chart(f, chart_area, &s.history, &s.true_history);
        }
    }
}

/// The true error against the `--reference` image and how it was taken,
/// or why there is none.
fn truth_lines(s: &Snapshot) -> Vec<Line<'static>> {
    let dim = Style::new().fg(Color::DarkGray);
    let na = |why: &str| vec![Line::styled(format!("true: {why}"), dim)];
    match (s.truth, s.true_error) {
        (Truth::Compared { coverage, exact }, Some(e)) => {
            let mut lines = vec![Line::styled(
                format!("error {:.2}% (true)", e * 100.0),
                Style::new().fg(Color::Yellow),
            )];
            let mut how = Vec::new();
            if !exact {
                how.push("resampled".to_string());
            }
            if coverage < 1.0 {
                how.push(format!("{:.0}% of view", coverage * 100.0));
            }
            if !how.is_empty() {
                lines.push(Line::styled(format!("  {}", how.join(", ")), dim));
            }
            lines
        }
        (Truth::Compared { .. }, None) => na("after the first pass"),
        (Truth::CameraMoved, _) => na("camera moved (r resets)"),
        (Truth::FeaturesChanged, _) => na("features differ from the reference's"),
        (Truth::NoOverlap, _) => na("reference outside the view"),
        (Truth::NoReference, _) => na("no reference"),
    }
}

/// Decades spanning `lo..hi` (log10 values), at least one wide.
fn decades(lo: f64, hi: f64) -> [f64; 2] {
    let (a, b) = (lo.floor(), hi.ceil());
    if b > a {
        [a, b]
    } else {
        [a, a + 1.0]
    }
}

/// `10^e` formatted with `unit`, e.g. `0.1s`, `10%`.
fn decade_label(e: f64, unit: &str) -> String {
    let v = 10f64.powf(e);
    if e < 0.0 {
        format!("{v:.*}{unit}", (-e) as usize)
    } else {
        format!("{v:.0}{unit}")
    }
}

/// Error (%) against elapsed seconds, both on log axes: the estimate, and
/// the true error when a reference is loaded.
fn error_chart(f: &mut Frame, area: Rect, estimate: &[(f64, f64)], truth: &[(f64, f64)]) {
    let log = |h: &[(f64, f64)]| -> Vec<(f64, f64)> {
        h.iter()
            .filter(|(t, e)| *t > 0.0 && *e > 0.0)
            .map(|(t, e)| (t.log10(), (e * 100.0).log10()))
            .collect()
    };
    let (est, tru) = (log(estimate), log(truth));
    let all = || est.iter().chain(&tru);
    let bounds = |k: fn(&(f64, f64)) -> f64| {
        all().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(k(p)), b.max(k(p)))
        })
    };
    let ((x0, x1), (y0, y1)) = (bounds(|p| p.0), bounds(|p| p.1));
    if !(x0.is_finite() && y0.is_finite()) {
        return;
    }
    let (xb, yb) = (decades(x0, x1), decades(y0, y1));
    let labels = |b: [f64; 2], unit: &str| -> Vec<String> {
        (b[0] as i32..=b[1] as i32)
            .map(|e| decade_label(e as f64, unit))
            .collect()
    };
    // A legend only when there are two lines to tell apart.
    let named = !tru.is_empty();
    let line = |name: &'static str, color: Color, data| {
        let d = Dataset::default()
            .marker(Marker::Braille)
            .graph_type(GraphType::Line)
            .style(Style::new().fg(color))
            .data(data);
        if named {
            d.name(name)
        } else {
            d
        }
    };
    let mut sets = vec![line("estimate", Color::Cyan, &est)];
    if named {
        sets.push(line("true", Color::Yellow, &tru));
    }
    let chart = Chart::new(sets)
        .hidden_legend_constraints((Constraint::Ratio(1, 2), Constraint::Ratio(1, 2)))
        .x_axis(
            Axis::default()
                .title("time")
                .bounds(xb)
                .labels(labels(xb, "s")),
        )
        .y_axis(
            Axis::default()
                .title("error")
                .bounds(yb)
                .labels(labels(yb, "%")),
        );
    f.render_widget(chart, area);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decade_labels() {
        assert_eq!(decade_label(-2.0, "s"), "0.01s");
        assert_eq!(decade_label(0.0, "%"), "1%");
        assert_eq!(decade_label(1.0, "%"), "10%");
        assert_eq!(decades(-0.5, 0.3), [-1.0, 1.0]);
        assert_eq!(decades(2.0, 2.0), [2.0, 3.0]);
    }
}
