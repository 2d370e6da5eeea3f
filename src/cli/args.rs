//! The CLI's arguments (clap derive).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::render::Feature;
use crate::scene::Builder;

#[derive(Parser, Debug)]
#[command(
    name = "rayterm",
    version,
    about = "A ray tracer that lives in the terminal"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

impl Cli {
    pub fn threads(&self) -> Option<usize> {
        match &self.command {
            Command::Render(a) => a.threads,
            Command::Bench(a) => a.global_threads(),
            Command::Scenes | Command::Inspect(_) => None,
        }
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to a PNG file.
    Render(RenderArgs),
    /// List the built-in scenes.
    Scenes,
    /// Print the ray tree of one pixel: every ray the renderer traced for it.
    Inspect(InspectArgs),
    /// Measure speed: the benchmark table, the shared ray workload, scaling.
    Bench(super::bench::BenchArgs),
}

/// `WxH`, e.g. `1280x720`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .map_err(|_| format!("bad width in '{s}'"))?;
    let h: u32 = h
        .trim()
        .parse()
        .map_err(|_| format!("bad height in '{s}'"))?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(format!("size '{s}' must be between 1x1 and 16384x16384"));
    }
    Ok((w, h))
}

/// Options shared by every command that renders a scene.
#[derive(Args, Debug, Clone)]
pub struct SceneOpts {
    /// Built-in name (see `rayterm scenes`), a .toml scene file or a .obj mesh.
    pub scene: String,
    /// Image size, WIDTHxHEIGHT (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    pub size: Option<(u32, u32)>,
    /// BVH builder (default: the scene's, else sah).
    #[arg(long, value_enum)]
    pub builder: Option<Builder>,
    /// Turn a feature off (repeatable).
    #[arg(long = "no", value_enum, value_name = "FEATURE")]
    pub off: Vec<Feature>,
    /// Seed of the random numbers; the same seed gives the same image.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run every enabled stage even where the scene does not need it.
    #[arg(long)]
    pub no_plan: bool,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneOpts,
    /// Output PNG.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Samples per pixel (default: the scene's).
    #[arg(long, conflicts_with_all = ["time", "target_error"])]
    pub spp: Option<u32>,
    /// Keep adding passes until this many seconds have passed.
    #[arg(long, conflicts_with = "target_error")]
    pub time: Option<f64>,
    /// Keep adding passes until the mean relative standard error is below this.
    #[arg(long)]
    pub target_error: Option<f64>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Print the scene plan (stage, on/off, reason) before rendering.
    #[arg(long)]
    pub explain: bool,
}

/// `X,Y`, e.g. `400,300`.
pub fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not X,Y"))?;
    let x = x.trim().parse().map_err(|_| format!("bad x in '{s}'"))?;
    let y = y.trim().parse().map_err(|_| format!("bad y in '{s}'"))?;
    Ok((x, y))
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Worst {
    /// The first pixel with a NaN or infinite sample.
    Nan,
    /// The pixel whose samples vary most.
    Variance,
    /// The brightest pixel.
    Brightest,
}

#[derive(Args, Debug)]
pub struct InspectArgs {
    #[command(flatten)]
    pub scene: SceneOpts,
    /// The pixel, X,Y from the top left.
    #[arg(long, value_parser = parse_pixel, conflicts_with = "worst")]
    pub pixel: Option<(u32, u32)>,
    /// Jump to the worst pixel by this measure instead.
    #[arg(long, value_enum)]
    pub worst: Option<Worst>,
    /// Sample index to replay.
    #[arg(long, default_value_t = 0)]
    pub sample: u32,
    /// Samples per pixel rendered to find the worst pixel.
    #[arg(long, default_value_t = 16)]
    pub spp: u32,
    /// Print JSON (schema in the README) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Show every light sample instead of folding long lists.
    #[arg(long)]
    pub expand: bool,
}
