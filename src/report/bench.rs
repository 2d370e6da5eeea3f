//! `rayterm bench`: the performance table. For each scene, both builders'
//! build time and tree statistics, and the time of one fixed frame with each
//! BVH and without one (brute force, where it finishes in reasonable time).

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use rayon::prelude::*;
use serde::Serialize;

use super::stats::median;
use super::{Machine, Progress};
use crate::bvh::{self, Bvh};
use crate::interrupt::Cancel;
use crate::render::{Feature, Features, Film, Job, Plan, PlanPolicy, RayCounter, Stop, Tracer};
use crate::scene::{self, Builder, Scene};

/// Meshes up to this size get the full-sweep SAH reference (it is O(n log² n)).
const FULL_SWEEP_MAX: usize = 300_000;

/// Built-in scenes in the table, before the shared meshes.
pub(crate) const BUILTIN: &[&str] = &["cornell", "teapot", "mirrors"];

#[derive(Clone, Debug)]
pub(crate) struct BenchOptions {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) reps: usize,
    /// Brute-force frames estimated to take longer than this are skipped.
    pub(crate) brute_limit_s: f64,
    /// Scenes to measure; the built-ins and the shared meshes when empty.
    pub(crate) scenes: Vec<String>,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            width: 800,
            height: 800,
            reps: 5,
            brute_limit_s: 5.0,
            scenes: Vec::new(),
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct BenchReport {
    pub(crate) machine: Machine,
    pub(crate) frame: String,
    pub(crate) reps: usize,
    pub(crate) scenes: Vec<SceneRow>,
    /// The plan against `--no-plan` on `cornell`.
    pub(crate) plan: Option<PlanRow>,
    pub(crate) notes: Vec<String>,
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct SceneRow {
    pub(crate) scene: String,
    pub(crate) triangles: usize,
    pub(crate) builds: Vec<BuildRow>,
    pub(crate) brute_force: Brute,
    /// SAH cost of the binned SAH tree over that of a full-sweep SAH tree
    /// (both counting leaves in packets of four, the builder's objective).
    pub(crate) sah_vs_full_sweep: Option<f64>,
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct BuildRow {
    pub(crate) builder: String,
    pub(crate) build_ms: f64,
    pub(crate) levels: usize,
    pub(crate) leaves: usize,
    pub(crate) max_leaf: usize,
    pub(crate) mean_leaf: f64,
    pub(crate) sah_cost: f64,
    pub(crate) render_ms: f64,
    pub(crate) rays: u64,
    pub(crate) mrays_s: f64,
}

#[derive(Clone, Debug, Serialize)]
#[serde(tag = "status", rename_all = "lowercase")]
pub(crate) enum Brute {
    Measured {
        render_ms: f64,
        rays: u64,
        mrays_s: f64,
    },
    Skipped {
        estimated_s: f64,
    },
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct PlanRow {
    pub(crate) scene: String,
    pub(crate) plan_ms: f64,
    pub(crate) no_plan_ms: f64,
    /// `no_plan_ms / plan_ms`: how much faster the plan makes the frame.
    pub(crate) speedup: f64,
}

/// The frame's features: shadows and reflections, nothing sampled, so every
/// run traces the same rays.
pub fn frame_features() -> Features {
    Features::all().without(&[
        Feature::Supersampling,
        Feature::Glossy,
        Feature::SoftShadows,
        Feature::Bloom,
    ])
}

/// Runs the table on the current rayon pool.
pub(crate) fn run(
    o: &BenchOptions,
    threads: usize,
    progress: &dyn Progress,
) -> Result<BenchReport> {
    // Each scene's frame is a film of full statistics.
    crate::render::session::check_film(o.width, o.height, Film::BYTES_PER_PIXEL)?;
    let mut notes = Vec::new();
    let specs: Vec<String> = if o.scenes.is_empty() {
        let mut v: Vec<String> = BUILTIN.iter().map(|s| s.to_string()).collect();
        match super::shared_meshes_dir() {
            Some(dir) => v.extend(shared_objs(&dir)),
            None => notes.push(
                "../shared/data/meshes not found (looked beside the current directory, \
                 the executable and the crate): the optional bench meshes (the bunny...) \
                 skipped; BENCHMARKS.md says what that folder holds"
                    .to_string(),
            ),
        }
        v
    } else {
        o.scenes.clone()
    };
    progress.begin(Some(specs.len() as u64));
    let mut scenes = Vec::new();
    let mut plan = None;
    for spec in &specs {
        progress.doing(spec);
        let scene = scene::load::open(spec, &Default::default())?.scene;
        scenes.push(scene_row(spec, &scene, o, progress));
        if spec == "cornell" {
            progress.doing("cornell: plan against --no-plan");
            plan = Some(plan_row(&scene, o));
        }
        progress.step();
    }
    progress.end();
    Ok(BenchReport {
        machine: Machine::current(threads),
        frame: format!(
            "{}x{}, 1 spp, shadows and reflections, nothing sampled",
            o.width, o.height
        ),
        reps: o.reps,
        scenes,
        plan,
        notes,
    })
}

/// The `.obj` files of `dir`, sorted by name.
fn shared_objs(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .map(|p| p.display().to_string())
        .collect();
    v.sort();
    v
}

fn scene_row(spec: &str, scene: &Scene, o: &BenchOptions, progress: &dyn Progress) -> SceneRow {
    let plan = Plan::new(scene, frame_features(), PlanPolicy::Prune);
    let reps = o.reps.max(1);
    let mut builds = Vec::new();
    let mut last = None;
    for builder in [Builder::Median, Builder::Sah] {
        progress.doing(&format!("{spec}: {builder} build"));
        let mut ms = Vec::new();
        let mut bvh = None;
        for _ in 0..reps {
            let b = bvh::build(&scene.geometry, builder);
            ms.push(b.stats.build_ms);
            bvh = Some(b);
        }
        let Some(bvh) = bvh else { continue };
        progress.doing(&format!("{spec}: {builder} render"));
        let (render_ms, rays) = frame_ms(scene, &bvh, &plan, o, reps);
        let s = &bvh.stats;
        builds.push(BuildRow {
            builder: builder.to_string(),
            build_ms: median(&mut ms),
            levels: s.depth,
            leaves: s.leaves,
            max_leaf: s.max_leaf,
            mean_leaf: s.mean_leaf,
            sah_cost: s.sah_cost,
            render_ms,
            rays,
            mrays_s: rays as f64 / render_ms.max(1e-9) / 1e3,
        });
        last = Some(bvh);
    }
    let tris = scene.geometry.triangle_count();
    let sah_vs_full_sweep = match &last {
        Some(bvh) if tris <= FULL_SWEEP_MAX => {
            progress.doing(&format!("{spec}: full-sweep SAH reference"));
            let sweep = bvh::build_full_sweep(&scene.geometry);
            Some(bvh.packet_sah_cost() / sweep.packet_sah_cost().max(f64::MIN_POSITIVE))
        }
        _ => None,
    };
    progress.doing(&format!("{spec}: brute force"));
    let brute_force = match last {
        Some(bvh) => brute(scene, &bvh, o),
        None => Brute::Skipped { estimated_s: 0.0 },
    };
    SceneRow {
        scene: spec.to_string(),
        triangles: tris,
        builds,
        brute_force,
        sah_vs_full_sweep,
    }
}

/// Median time of `reps` frames and the rays of one.
fn frame_ms(scene: &Scene, bvh: &Bvh, plan: &Plan, o: &BenchOptions, reps: usize) -> (f64, u64) {
    let tracer = Tracer::new(scene, bvh, plan, scene.camera.frame(o.width, o.height), 1);
    let mut ms = Vec::new();
    let mut rays = 0;
    for _ in 0..reps {
        let mut p = Job::of(&tracer, Stop::spp(1)).start();
        if let Some(pass) = p.pass(&tracer, Cancel::Never) {
            ms.push(pass.ms);
            rays = pass.rays;
        }
    }
    (median(&mut ms), rays)
}

/// The frame without the BVH, when an estimate from a sample of pixels says
/// it finishes within the limit.
fn brute(scene: &Scene, bvh: &Bvh, o: &BenchOptions) -> Brute {
    let plan = Plan::new(
        scene,
        frame_features().without(&[Feature::Bvh]),
        PlanPolicy::Prune,
    );
    let tracer = Tracer::new(scene, bvh, &plan, scene.camera.frame(o.width, o.height), 1);
    let total = o.width as usize * o.height as usize;
    // About 4e7 triangle tests per primary ray sample: a fraction of a second.
    // At least 64 pixels, or all of a smaller frame.
    let n = (4e7 / scene.geometry.triangle_count().max(1) as f64)
        .max(64.0)
        .min(total as f64) as usize;
    let stride = total / n;
    let start = Instant::now();
    (0..n).into_par_iter().for_each(|i| {
        let p = i * stride + stride / 2;
        let (x, y) = ((p % o.width as usize) as u32, (p / o.width as usize) as u32);
        tracer.sample(x, y, 0, &mut RayCounter::default());
    });
    let estimated_s = start.elapsed().as_secs_f64() * total as f64 / n as f64;
    if estimated_s > o.brute_limit_s {
        return Brute::Skipped { estimated_s };
    }
    let reps = if estimated_s > 1.0 { 1 } else { o.reps.max(1) };
    let (render_ms, rays) = frame_ms(scene, bvh, &plan, o, reps);
    Brute::Measured {
        render_ms,
        rays,
        mrays_s: rays as f64 / render_ms.max(1e-9) / 1e3,
    }
}

fn plan_row(scene: &Scene, o: &BenchOptions) -> PlanRow {
    let bvh = bvh::build(&scene.geometry, Builder::Sah);
    let reps = o.reps.max(1);
    let with = Plan::new(scene, frame_features(), PlanPolicy::Prune);
    let without = Plan::new(scene, frame_features(), PlanPolicy::Everything);
    // Interleave the two so drift in machine load hits both alike.
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        a.push(frame_ms(scene, &bvh, &with, o, 1).0);
        b.push(frame_ms(scene, &bvh, &without, o, 1).0);
    }
    let (plan_ms, no_plan_ms) = (median(&mut a), median(&mut b));
    PlanRow {
        scene: scene.name.clone(),
        plan_ms,
        no_plan_ms,
        speedup: no_plan_ms / plan_ms.max(1e-9),
    }
}

/// The report as a text table.
pub(crate) fn to_text(r: &BenchReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "rayterm bench: {}", r.machine);
    let _ = writeln!(s, "frame: {}; medians of {} runs", r.frame, r.reps);
    let _ = writeln!(
        s,
        "SAH cost: node 1, triangle 1; vs sweep: the SAH tree's cost over a full-sweep SAH build's\n"
    );
    let name_w = r
        .scenes
        .iter()
        .map(|x| short_name(&x.scene).len())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(
        s,
        "{:name_w$} {:>9}  {:7} {:>9} {:>6} {:>7} {:>4} {:>5} {:>8} {:>9} {:>10} {:>8}",
        "scene",
        "triangles",
        "builder",
        "build ms",
        "levels",
        "leaves",
        "max",
        "mean",
        "SAH cost",
        "vs sweep",
        "render ms",
        "Mrays/s"
    );
    for sc in &r.scenes {
        for (i, b) in sc.builds.iter().enumerate() {
            let (name, tris) = if i == 0 {
                (short_name(&sc.scene), sc.triangles.to_string())
            } else {
                ("", String::new())
            };
            let sweep = match sc.sah_vs_full_sweep {
                Some(r) if b.builder == "sah" => format!("{:+.1}%", (r - 1.0) * 100.0),
                _ => "-".to_string(),
            };
            let _ = writeln!(
                s,
                "{name:name_w$} {tris:>9}  {:7} {:>9.2} {:>6} {:>7} {:>4} {:>5.2} {:>8.2} {sweep:>9} {:>10.1} {:>8.2}",
                b.builder,
                b.build_ms,
                b.levels,
                b.leaves,
                b.max_leaf,
                b.mean_leaf,
                b.sah_cost,
                b.render_ms,
                b.mrays_s
            );
        }
        let none = match &sc.brute_force {
            Brute::Measured {
                render_ms, mrays_s, ..
            } => format!(
                "{:>9} {:>6} {:>7} {:>4} {:>5} {:>8} {:>9} {render_ms:>10.1} {mrays_s:>8.2}",
                "-", "-", "-", "-", "-", "-", "-"
            ),
            Brute::Skipped { estimated_s } => {
                format!("skipped: estimated {estimated_s:.0} s")
            }
        };
        let _ = writeln!(s, "{:name_w$} {:>9}  {:7} {none}", "", "", "none");
    }
    if let Some(p) = &r.plan {
        let _ = writeln!(
            s,
            "\nplan ({}): {:.1} ms with the plan, {:.1} ms with --no-plan: {:.2}x",
            p.scene, p.plan_ms, p.no_plan_ms, p.speedup
        );
    }
    for n in &r.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

/// A path's file name; built-in names as they are.
fn short_name(spec: &str) -> &str {
    Path::new(spec)
        .file_name()
        .and_then(|f| f.to_str())
        .unwrap_or(spec)
}
