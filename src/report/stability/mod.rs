//! The numerical stability battery (`rayterm stability`): scale and offset,
//! watertightness, grazing rays, degenerate geometry, stiff shading,
//! reintersection and input hygiene. Every case measures one figure and
//! passes when it is at most its limit, so CI can run the battery and the
//! TUI can show the same table.

pub(crate) mod degenerate;
pub mod grazing;
pub mod hygiene;
pub mod reintersect;
pub mod scale;
pub mod stiff;
pub mod topology;
pub mod watertight;

use std::time::Instant;

use super::Progress;
use anyhow::{bail, Context, Result};
use serde::Serialize;

pub use degenerate::degenerate;
pub use grazing::grazing;
pub use hygiene::hygiene;
pub use reintersect::reintersection;
pub use scale::{scale_offset, Transform, TRANSFORMS};
pub use stiff::stiff_shading;
pub use topology::{Crossing, Topology};
pub use watertight::{escapes, watertight, Escapes};

/// One case of the battery: the figure measured, its limit, and whether it
/// passed (`figure <= limit`; a NaN figure fails).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    pub case: String,
    pub(crate) figure: f64,
    pub(crate) limit: f64,
    pub pass: bool,
    /// What was counted, in words (e.g. "0 of 9216 shadow rays").
    pub detail: String,
}

impl Row {
    pub(crate) fn at_most(
        case: impl Into<String>,
        figure: f64,
        limit: f64,
        detail: impl Into<String>,
    ) -> Self {
        Self {
            case: case.into(),
            figure,
            limit,
            pass: figure <= limit,
            detail: detail.into(),
        }
    }

    /// A count that must be zero.
    pub(crate) fn zero(case: impl Into<String>, count: u64, detail: impl Into<String>) -> Self {
        Self::at_most(case, count as f64, 0.0, detail)
    }
}

/// Sizes of the battery. The defaults run in about a second on two cores;
/// the tests use smaller ones.
#[derive(Clone, Debug)]
pub struct Options {
    /// Image size of the rendered cases.
    pub width: u32,
    pub height: u32,
    /// Random rays per watertightness, grazing and reintersection case.
    pub rays: u32,
    /// Segments per patch edge of the teapot in the watertightness cases.
    pub teapot_segments: u32,
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            width: 96,
            height: 96,
            rays: 20_000,
            teapot_segments: 8,
            seed: 1,
        }
    }
}

/// Runs every case on `scene_spec` (the scale and offset cases use it; the
/// others use their own geometry) and returns the rows in table order.
pub fn run_battery(scene_spec: &str, o: &Options) -> Result<Vec<Row>> {
    run_battery_shown(scene_spec, o, &())
}

/// As [`run_battery`], saying which group of cases runs to `progress`.
fn run_battery_shown(scene_spec: &str, o: &Options, progress: &dyn Progress) -> Result<Vec<Row>> {
    let scene = crate::scene::load::open(scene_spec, &Default::default())?.scene;
    run_battery_on(&scene, o, progress)
}

/// Peak memory of the battery per pixel of its images, and more per worker
/// thread (the transforms render in parallel): 215, 248 and 340 bytes
/// measured at 1, 2 and 4 threads (`/usr/bin/time`, 128x128 against
/// 384x384), rounded up.
const BYTES_PER_PIXEL: u64 = 200;
const BYTES_PER_PIXEL_THREAD: u64 = 48;

/// As [`run_battery`], on a scene already loaded (the TUI's), saying
/// which group of cases runs to `progress`.
pub(crate) fn run_battery_on(
    scene: &crate::scene::Scene,
    o: &Options,
    progress: &dyn Progress,
) -> Result<Vec<Row>> {
    // Below this, pixel centres sit on the scene's symmetry lines and edges
    // fill whole pixels, so image differences measure ties, not precision.
    if o.width < 16 || o.height < 16 {
        bail!("the stability battery needs images of at least 16x16");
    }
    let threads = rayon::current_num_threads() as u64;
    crate::memory::check(
        &format!("the stability battery at {}x{}", o.width, o.height),
        o.width as u64 * o.height as u64 * (BYTES_PER_PIXEL + BYTES_PER_PIXEL_THREAD * threads),
        None,
    )?;
    crate::scene::check_reach(scene)?;
    type Group<'a> = (&'static str, Box<dyn Fn() -> Result<Vec<Row>> + 'a>);
    let groups: [Group; 7] = [
        (
            "scale and offset cases",
            Box::new(|| scale_offset(scene, o)),
        ),
        ("watertightness cases", Box::new(|| watertight(o))),
        ("grazing cases", Box::new(|| grazing(o))),
        ("degenerate geometry cases", Box::new(|| degenerate(o))),
        ("stiff shading cases", Box::new(|| stiff_shading(o))),
        ("reintersection cases", Box::new(|| reintersection(o))),
        ("input hygiene cases", Box::new(hygiene)),
    ];
    progress.begin(Some(groups.len() as u64));
    let mut rows = Vec::new();
    for (what, run) in &groups {
        progress.doing(what);
        let found = run().context(*what);
        progress.step();
        match found {
            Ok(r) => rows.extend(r),
            Err(e) => {
                progress.end();
                return Err(e);
            }
        }
    }
    progress.end();
    Ok(rows)
}

/// A figure as the table prints it: counts as integers, others with four
/// significant digits.
pub(crate) fn format_figure(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x == x.trunc() && x.abs() < 1e12 {
        format!("{x:.0}")
    } else if (1e-3..1e4).contains(&x.abs()) {
        format!("{x:.4}")
    } else {
        format!("{x:.3e}")
    }
}

/// The table: case, figure, limit, pass/fail and what was counted.
pub fn format_table(rows: &[Row]) -> String {
    let cw = rows.iter().map(|r| r.case.len()).max().unwrap_or(4).max(4);
    let figs: Vec<(String, String)> = rows
        .iter()
        .map(|r| (format_figure(r.figure), format_figure(r.limit)))
        .collect();
    let fw = figs.iter().map(|f| f.0.len()).max().unwrap_or(6).max(6);
    let lw = figs.iter().map(|f| f.1.len()).max().unwrap_or(5).max(5);
    let mut out = format!(
        "{:cw$}  {:>fw$}  {:>lw$}  {:6}  detail\n",
        "case", "figure", "limit", "result"
    );
    for (r, (f, l)) in rows.iter().zip(figs) {
        out.push_str(&format!(
            "{:cw$}  {f:>fw$}  {l:>lw$}  {:6}  {}\n",
            r.case,
            if r.pass { "pass" } else { "FAIL" },
            r.detail
        ));
    }
    out
}

/// Runs the battery and prints its table (or JSON); the returned flag is
/// whether every case passed.
pub(crate) fn run_and_print(
    scene_spec: &str,
    o: &Options,
    json: bool,
    progress: &dyn Progress,
) -> Result<bool> {
    let start = Instant::now();
    let rows = run_battery_shown(scene_spec, o, progress)?;
    let failed = rows.iter().filter(|r| !r.pass).count();
    if json {
        crate::outln!("{}", serde_json::to_string_pretty(&rows)?)?;
    } else {
        crate::out!("{}", format_table(&rows))?;
        crate::outln!(
            "{} of {} cases passed in {:.2} s ({}x{}, {} rays per random case)",
            rows.len() - failed,
            rows.len(),
            start.elapsed().as_secs_f64(),
            o.width,
            o.height,
            o.rays
        )?;
    }
    Ok(failed == 0)
}
