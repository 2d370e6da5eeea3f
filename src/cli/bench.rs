//! `rayterm bench`: the benchmark table, `bench rays` (the shared ray
//! workload, one JSON line) and `bench scaling`.

use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use super::args::{parse_size, parse_threads};
use super::progress::ReportBar;
use crate::bvh::Simd;
use crate::render::SceneRequest;
use crate::report::{bench, scaling, workload};
use crate::scene::Builder;

#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct BenchArgs {
    #[command(subcommand)]
    pub(crate) command: Option<BenchCommand>,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub(crate) json: bool,
    /// Repetitions of every build and frame; medians are reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) reps: u32,
    /// Worker threads (default: all cores; at most 4x the cores).
    #[arg(long, value_parser = parse_threads)]
    pub(crate) threads: Option<u32>,
    /// Frame size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "800x800")]
    pub(crate) size: (u32, u32),
    /// Measure these scenes instead of the built-ins and the shared meshes (repeatable).
    #[arg(long = "scene", value_name = "SCENE", value_parser = super::args::scene_spec())]
    pub(crate) scenes: Vec<String>,
}

#[derive(Subcommand, Debug)]
pub(crate) enum BenchCommand {
    /// The ray workload of BENCHMARKS.md (camera, shadow and diffuse rays) on
    /// one mesh: prints one JSON line, comparable with other ray tracers on the same rays.
    Rays(RaysArgs),
    /// Build and trace teapot:N from ~1k to ~4M triangles; fit the growth.
    Scaling(ScalingArgs),
    /// Progressive passes of the TUI at a terminal's size, through its render
    /// worker: pass time and bytes written to the terminal per frame.
    Tui(TuiBenchArgs),
}

#[derive(Args, Debug)]
pub(crate) struct TuiBenchArgs {
    /// Built-in name, .toml scene file or mesh file (.obj, .ply, .stl, .gltf, .glb).
    #[arg(default_value = "cornell", value_parser = super::args::scene_spec())]
    pub(crate) scene: String,
    /// Terminal size, COLUMNSxROWS (two pixels per cell vertically).
    #[arg(long, value_parser = parse_size, default_value = "160x48")]
    pub(crate) terminal: (u32, u32),
    /// Passes to measure.
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) passes: u32,
    /// How light is followed [default: as `tui` would: the scene's, else
    /// the plan's choice].
    #[arg(long, value_enum)]
    pub(crate) integrator: Option<crate::scene::Integrator>,
}

#[derive(Args, Debug)]
pub(crate) struct RaysArgs {
    /// A mesh file (or any scene: its triangles, with the workload's auto camera).
    #[arg(value_parser = super::args::scene_spec())]
    pub(crate) mesh: String,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "1024x768")]
    pub(crate) size: (u32, u32),
    /// Threads for the build and the tracing (at most 4x the cores).
    #[arg(long, default_value_t = 1, value_parser = parse_threads)]
    pub(crate) threads: u32,
    #[arg(long, value_enum, default_value_t = Builder::Sah)]
    pub(crate) builder: Builder,
    /// Fresh builds and traces; medians are reported.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) reps: u32,
    /// Make the camera and shadow rays before the timer and trace each ray
    /// set once untimed before the timed pass, as the tinybvh harness does
    /// (by default they are made in the timed loop, as the Embree harness
    /// makes them).
    #[arg(long)]
    pub(crate) rays_first: bool,
    /// Trace the primary rays in packets of 8x8 pixel tiles and the shadow
    /// rays of each tile's hits together (one origin each: the eye, the
    /// light); diffuse rays one by one.
    #[arg(long)]
    pub(crate) packets: bool,
    /// The SIMD kernels to walk with (default: the widest this CPU has), to
    /// compare them on one machine.
    #[arg(long, value_enum)]
    pub(crate) simd: Option<Simd>,
}

#[derive(Args, Debug)]
pub(crate) struct ScalingArgs {
    /// Largest N of teapot:N (4.2M triangles at 256, 16.8M at 512).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(4..=1024))]
    pub(crate) max_n: u32,
    #[arg(long, value_enum, default_value_t = Builder::Sah)]
    pub(crate) builder: Builder,
    /// Worker threads (default: all cores; at most 4x the cores).
    #[arg(long, value_parser = parse_threads)]
    pub(crate) threads: Option<u32>,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub(crate) json: bool,
}

impl BenchArgs {
    /// Threads for the global pool; `bench rays` makes its own.
    pub(crate) fn global_threads(&self) -> Option<usize> {
        match &self.command {
            None => self.threads.map(|n| n as usize),
            Some(BenchCommand::Scaling(a)) => a.threads.map(|n| n as usize),
            Some(BenchCommand::Rays(_)) | Some(BenchCommand::Tui(_)) => None,
        }
    }
}

pub(crate) fn run(a: BenchArgs) -> Result<ExitCode> {
    match a.command {
        None => {
            let o = bench::BenchOptions {
                width: a.size.0,
                height: a.size.1,
                reps: a.reps as usize,
                scenes: a.scenes,
                ..Default::default()
            };
            let r = bench::run(&o, rayon::current_num_threads(), &ReportBar::new())?;
            if a.json {
                crate::outln!("{}", serde_json::to_string_pretty(&r)?)?;
            } else {
                crate::out!("{}", bench::to_text(&r))?;
            }
        }
        Some(BenchCommand::Rays(r)) => rays(r)?,
        Some(BenchCommand::Tui(t)) => {
            let (cols, rows) = t.terminal;
            let cols = u16::try_from(cols).context("--terminal: too many columns")?;
            let rows = u16::try_from(rows).context("--terminal: too many rows")?;
            let req = SceneRequest {
                integrator: t.integrator,
                ..SceneRequest::new(&t.scene)
            };
            let stats = crate::tui::bench::measure_pass(&req, cols, rows, t.passes)?;
            crate::outln!("{}", serde_json::to_string_pretty(&stats)?)?;
        }
        Some(BenchCommand::Scaling(s)) => {
            let o = scaling::ScalingOptions {
                max_n: s.max_n,
                builder: s.builder,
                ..Default::default()
            };
            let r = scaling::run(&o, rayon::current_num_threads(), &ReportBar::new())?;
            if s.json {
                crate::outln!("{}", serde_json::to_string_pretty(&r)?)?;
            } else {
                crate::out!("{}", scaling::to_text(&r))?;
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn rays(a: RaysArgs) -> Result<()> {
    let simd = a.simd.unwrap_or(Simd::detect()).on_this_cpu()?;
    let s = super::load_scene(&a.mesh)?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads as usize)
        .build()
        .with_context(|| format!("cannot set up {} threads", a.threads))?;
    let o = workload::RaysOptions {
        width: a.size.0,
        height: a.size.1,
        threads: a.threads as usize,
        builder: a.builder,
        reps: a.reps as usize,
        rays_first: a.rays_first,
        packets: a.packets,
        simd,
    };
    let r = pool.install(|| workload::run(&a.mesh, &s.geometry, &o));
    crate::outln!("{}", serde_json::to_string(&r)?)?;
    Ok(())
}
