//! The TUI's speed: milliseconds per progressive pass through the worker's
//! code path, and bytes written to the terminal per frame.

use std::io;
use std::time::Instant;

use anyhow::{bail, Result};
use ratatui::layout::Size;
use ratatui::Terminal;
use serde::Serialize;

use super::color::ColorMode;
use super::term::screen::Screen;
use super::widgets::paint_view;
use super::worker::{Cmd, Msg, RenderView, Worker};
use crate::render::{Film, SceneRequest, Session};
use crate::report::stats::median;

/// What [`measure_pass`] measured.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct TuiPassStats {
    pub(crate) scene: String,
    pub(crate) triangles: usize,
    /// Image size in pixels: the terminal's columns by twice its rows.
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) threads: usize,
    /// Full passes measured (fewer than asked when the scene is exact after one).
    pub(crate) passes: u32,
    /// The first pass, which also counts BVH work for the panel.
    pub(crate) first_pass_ms: f64,
    /// Render time of the later passes, which grow as the worker's do
    /// ([`Job::growing`](crate::render::Job::growing)).
    pub(crate) pass_ms_mean: f64,
    pub(crate) pass_ms_median: f64,
    pub(crate) pass_ms_min: f64,
    /// Whole worker step of the later passes: render, error estimate,
    /// worst pixels and snapshot.
    pub(crate) step_ms_mean: f64,
    pub(crate) mrays_per_s: f64,
    /// The samples of the later passes traced again in one pass, each
    /// pixel's together as a one-shot render of the same counts does: the
    /// rate the passes' `mrays_per_s` is measured against.
    pub(crate) one_shot_mrays_per_s: f64,
    /// The film's mean samples per pixel after the last pass.
    pub(crate) spp_mean: f64,
    /// Bytes written to the terminal for the first frame (every cell) and
    /// per later frame (changed cells only), in truecolor and 256 colours.
    pub(crate) first_frame_bytes: u64,
    pub(crate) frame_bytes_mean: f64,
    pub(crate) frame_bytes_mean_256: f64,
}

/// A terminal of `cols x rows` that counts what it would write.
type Counting = Terminal<Screen<io::Sink>>;

fn counting_terminal(cols: u16, rows: u16) -> Result<Counting> {
    Ok(Terminal::new(Screen::new(
        io::sink(),
        Some(Size::new(cols, rows)),
    )?)?)
}

/// Renders `passes` progressive passes of the scene `req` asks for at the
/// size of a `cols x rows` terminal (two pixels per cell), with the
/// request's plan, and draws each into a counting terminal filled by the
/// viewport.
pub(crate) fn measure_pass(
    req: &SceneRequest,
    cols: u16,
    rows: u16,
    passes: u32,
) -> Result<TuiPassStats> {
    if cols == 0 || rows == 0 || passes == 0 {
        bail!("measure_pass needs a non-empty terminal and at least one pass");
    }
    let (width, height) = (cols as u32, rows as u32 * 2);
    // The worker's film, and two terminals' two buffers of cells, a cell
    // for each two pixels.
    let cell = std::mem::size_of::<ratatui::buffer::Cell>() as u64;
    crate::render::session::check_film(width, height, Film::BYTES_PER_PIXEL + 2 * cell)?;
    let (s, _) = Session::open(req)?;
    let scene = s.scene.clone();
    let mut worker = Worker::new(scene.clone(), s.bvh.clone(), s.seed, None);
    worker.apply(Cmd::View(
        1,
        Box::new(RenderView {
            camera: s.camera,
            plan: s.plan.clone(),
            width,
            height,
            pixel_aspect: 1.0,
        }),
    ));
    let mut term = counting_terminal(cols, rows)?;
    let mut term256 = counting_terminal(cols, rows)?;
    let (mut pass_ms, mut step_ms, mut frame_bytes, mut frame_bytes_256) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut rays, mut spp_mean) = (Vec::new(), 0.0);
    // Samples per pixel after the first full pass, which is left out of
    // the passes' rate (it also counts BVH work for the panel), and so of
    // the one-pass rate they are compared with.
    let mut first_spp = 0;
    while (pass_ms.len() as u32) < passes {
        let start = Instant::now();
        let s = match worker.step(
            crate::interrupt::Cancel::Never,
            crate::interrupt::Cancel::Never,
        ) {
            Some(Msg::Frame(s)) => s,
            Some(_) => continue,
            None => break,
        };
        let step = start.elapsed().as_secs_f64() * 1e3;
        if s.coarse {
            continue;
        }
        if pass_ms.is_empty() {
            first_spp = s.spp;
        }
        pass_ms.push(s.pass_ms);
        step_ms.push(step);
        rays.push(s.mrays * s.pass_ms * 1e3);
        spp_mean = s.spp_mean;
        for (t, mode, out) in [
            (&mut term, ColorMode::Truecolor, &mut frame_bytes),
            (&mut term256, ColorMode::Palette256, &mut frame_bytes_256),
        ] {
            t.draw(|f| {
                let area = f.area();
                paint_view(f.buffer_mut(), area, &s, mode);
            })?;
            out.push(t.backend_mut().pump(usize::MAX)?.0 as u64);
        }
    }
    if pass_ms.is_empty() {
        bail!("no pass was rendered");
    }
    let later = |v: &[f64]| -> Vec<f64> {
        if v.len() > 1 {
            v[1..].to_vec()
        } else {
            v.to_vec()
        }
    };
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut sorted = later(&pass_ms);
    sorted.sort_by(f64::total_cmp);
    let later_bytes = |v: &[u64]| -> f64 {
        let v: Vec<f64> = v.iter().map(|&b| b as f64).collect();
        mean(&later(&v))
    };
    let pass_mean = mean(&sorted);
    let from = if pass_ms.len() > 1 { first_spp } else { 0 };
    let once = worker.retrace(from).map_or(0.0, |p| p.mrays_per_s());
    Ok(TuiPassStats {
        scene: scene.name.clone(),
        triangles: scene.geometry.triangle_count(),
        width,
        height,
        threads: rayon::current_num_threads(),
        passes: pass_ms.len() as u32,
        first_pass_ms: pass_ms[0],
        pass_ms_mean: pass_mean,
        pass_ms_median: median(&mut sorted.clone()),
        pass_ms_min: sorted[0],
        step_ms_mean: mean(&later(&step_ms)),
        mrays_per_s: later(&rays).iter().sum::<f64>() / (later(&pass_ms).iter().sum::<f64>() * 1e3),
        one_shot_mrays_per_s: once,
        spp_mean,
        first_frame_bytes: frame_bytes[0],
        frame_bytes_mean: later_bytes(&frame_bytes),
        frame_bytes_mean_256: later_bytes(&frame_bytes_256),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn measures_passes_and_bytes() {
        let s = measure_pass(&SceneRequest::new("cornell"), 40, 12, 3).unwrap();
        assert_eq!((s.width, s.height, s.passes), (40, 24, 3));
        assert!(s.pass_ms_mean > 0.0 && s.mrays_per_s > 0.0 && s.one_shot_mrays_per_s > 0.0);
        // The first frame paints every cell: at least the half block per cell.
        assert!(
            s.first_frame_bytes >= 40 * 12 * 3,
            "{}",
            s.first_frame_bytes
        );
        assert!(s.frame_bytes_mean <= s.first_frame_bytes as f64);
    }
}
