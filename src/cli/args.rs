//! The CLI's arguments (clap derive).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use super::progress::ProgressMode;
use crate::render::{Feature, Features, PlanPolicy, SceneRequest, Worst};
use crate::scene::load::{up::Up, EnvRequest};
use crate::scene::{Builder, Integrator, MAX_DEPTH};
use crate::tui::color::ColorMode;
use crate::tui::graphics::symbols::SymbolsArg;
use crate::tui::graphics::GraphicsArg;
use crate::viz::DebugSpec;

#[derive(Parser, Debug)]
#[command(
    name = "rayterm",
    version,
    about = "A ray tracer that lives in the terminal"
)]
pub(crate) struct Cli {
    /// Without a command, the TUI opens on the Cornell box.
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

impl Cli {
    pub(crate) fn threads(&self) -> Option<usize> {
        match &self.command {
            Some(Command::Render(a)) => a.threads.map(|n| n as usize),
            Some(Command::Converge(a)) => a.threads.map(|n| n as usize),
            Some(Command::Bench(a)) => a.global_threads(),
            _ => None,
        }
    }
}

#[derive(Subcommand, Debug)]
pub(crate) enum Command {
    /// Render a scene to PNG, EXR or HDR (by the extension), or a turntable to GIF or APNG.
    Render(RenderArgs),
    /// Join PNG frames (`render --frame K/N`, one job each) into a GIF or
    /// APNG that loops, in the order given.
    Animate(AnimateArgs),
    /// Merge the partial films of a split render into one image.
    ///
    /// The parts (from `render --part K/N` or `--samples A..B`) must come
    /// from the same scene, size and seed, and may not overlap; the image is
    /// the one a single render of all their samples makes, post-processed
    /// the same way.
    Merge(MergeArgs),
    /// List the files a scene reads, one a line.
    ///
    /// The scene file, meshes, material libraries, textures, glTF buffers
    /// and images, environment maps: what a job on another machine needs
    /// beside the scene (`parallel --basefile`, rsync, a container).
    Inputs(InputsArgs),
    /// List the built-in scenes.
    Scenes,
    /// Print the ray tree of one pixel: every ray the renderer traced for it.
    Inspect(InspectArgs),
    /// Measure error against run time: reference, budgets, strategy comparison.
    ///
    /// Renders the scene (at 64x64 unless --size says otherwise) at each
    /// budget, several seeds each, against a reference image; reports time,
    /// Mrays/s, RMSE, relMSE and the film's own error estimate, and compares
    /// sampling strategies at equal time.
    Converge(ConvergeArgs),
    /// Explore a scene in the terminal (the default command).
    Tui(TuiArgs),
    /// Run the numerical stability battery; exits non-zero when a case fails.
    Stability(StabilityArgs),
    /// Measure speed: the benchmark table, the shared ray workload, scaling.
    Bench(super::bench::BenchArgs),
}

/// A scene argument as text: names and paths are read as UTF-8, and one
/// that is not is refused naming it (clap's own error names no argument).
pub(crate) fn scene_spec() -> impl clap::builder::TypedValueParser<Value = String> {
    use clap::builder::TypedValueParser;
    clap::builder::OsStringValueParser::new().try_map(|s| {
        s.into_string().map_err(|s| {
            format!(
                "{} is not UTF-8 text; rename the file, or link to it under a UTF-8 name",
                std::path::Path::new(&s).display()
            )
        })
    })
}

/// `WxH`, e.g. `1280x720`.
pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), String> {
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

/// The most samples per pixel any render takes.
pub(crate) use crate::render::partial::MAX_SPP;

/// `A..B`: sample indices A to B-1, within 0..MAX_SPP.
pub(crate) fn parse_samples(s: &str) -> Result<std::ops::Range<u32>, String> {
    let (a, b) = s
        .split_once("..")
        .ok_or_else(|| format!("'{s}' is not A..B (sample indices A to B-1)"))?;
    let num = |v: &str, what: &str| -> Result<u32, String> {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n <= MAX_SPP)
            .ok_or_else(|| format!("the {what} of '{s}' is not a whole number from 0 to {MAX_SPP}"))
    };
    let (a, b) = (num(a, "start")?, num(b, "end")?);
    if a >= b {
        return Err(format!("'{s}' is empty: the end must be above the start"));
    }
    Ok(a..b)
}

/// `K/N`: the K-th of N equal ranges of samples, 1 <= K <= N.
pub(crate) fn parse_part(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = s
        .split_once('/')
        .ok_or_else(|| format!("'{s}' is not K/N (part K of N)"))?;
    let k: u32 = k.trim().parse().map_err(|_| format!("bad K in '{s}'"))?;
    let n: u32 = n.trim().parse().map_err(|_| format!("bad N in '{s}'"))?;
    if n == 0 || k == 0 || k > n {
        return Err(format!(
            "part '{s}': K must be from 1 to N, and N at least 1"
        ));
    }
    Ok((k, n))
}

/// A thread count from 1 to four times the machine's cores: more only
/// slows the machine down.
pub(crate) fn parse_threads(s: &str) -> Result<u32, String> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let max = 4 * cores;
    let n: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number of threads"))?;
    if n == 0 || n > max {
        return Err(format!(
            "{n} threads: use 1 to {max} (four times this machine's {cores} cores)"
        ));
    }
    Ok(n as u32)
}

/// Options shared by every command that renders a scene.
#[derive(Args, Debug, Clone)]
pub(crate) struct SceneOpts {
    /// Built-in name (see `rayterm scenes`), a .toml scene file or a mesh file
    /// (.obj, .ply, .stl, .gltf, .glb).
    #[arg(default_value = "cornell", value_parser = scene_spec())]
    pub(crate) scene: String,
    /// Image size, WIDTHxHEIGHT (default: the scene's).
    #[arg(long, value_parser = parse_size)]
    pub(crate) size: Option<(u32, u32)>,
    /// BVH builder (default: the scene's, else sah).
    #[arg(long, value_enum)]
    pub(crate) builder: Option<Builder>,
    /// Turn a feature off (repeatable).
    #[arg(long = "no", value_enum, value_name = "FEATURE")]
    pub(crate) off: Vec<Feature>,
    /// Seed of the random numbers; the same seed gives the same image.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// Run every enabled stage even where the scene does not need it.
    #[arg(long)]
    pub(crate) no_plan: bool,
    /// Samples per area light per shading point (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub(crate) light_samples: Option<u32>,
    /// Glossy reflection directions per glossy hit (default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub(crate) glossy_samples: Option<u32>,
    /// How light is followed [default: the scene file's, else path for
    /// scenes with metallic-roughness (glTF) materials, whitted otherwise].
    #[arg(long, value_enum)]
    pub(crate) integrator: Option<Integrator>,
    /// The most bounces after the camera ray [default: the scene's, 5].
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(0..=MAX_DEPTH as i64))]
    pub(crate) max_depth: Option<u32>,
    /// Independent uniform samples instead of jittered (stratified) ones.
    #[arg(long)]
    pub(crate) independent: bool,
    /// Look through this camera of a glTF file (its node's name, its own
    /// name, or its number from 1) instead of the first.
    #[arg(long, value_name = "NAME")]
    pub(crate) camera: Option<String>,
    /// Let glTF files read files outside their folder (absolute paths,
    /// file: URIs, `..` out of it), which they may not unless told.
    #[arg(long)]
    pub(crate) allow_outside: bool,
    /// A mesh file's up axis (x, y, z, -x, -y, -z), turned to rayterm's +Y:
    /// STL files are Z-up unless told, OBJ, PLY and glTF Y-up.
    #[arg(long, value_name = "AXIS", allow_hyphen_values = true)]
    pub(crate) up: Option<Up>,
    /// An environment light in place of the scene's environment (any
    /// scene): an equirectangular map (.hdr, .exr, .png, .jpg), a grey
    /// level (0.5) or a linear colour (0.2,0.3,0.5).
    #[arg(long, value_name = "MAP|GREY|R,G,B", allow_hyphen_values = true)]
    pub(crate) env: Option<String>,
    /// What the environment light is multiplied by [default: 1].
    #[arg(long, value_name = "F", requires = "env", allow_hyphen_values = true)]
    pub(crate) env_strength: Option<f32>,
    /// Degrees the environment light turns about +Y, counter-clockwise
    /// seen from above [default: 0].
    #[arg(
        long,
        value_name = "DEGREES",
        requires = "env",
        allow_hyphen_values = true
    )]
    pub(crate) env_rotate: Option<f32>,
    /// The SIMD kernels the BVH walks with (default: the widest this CPU
    /// has): every level finds the same hits, so a picture, or a part of a
    /// split render, is the same bit for bit on any x86-64 machine that
    /// runs this build.
    #[arg(long, value_enum)]
    pub(crate) simd: Option<crate::bvh::Simd>,
}

impl SceneOpts {
    /// What these options ask the session for.
    pub(crate) fn request(&self) -> SceneRequest {
        SceneRequest {
            spec: self.scene.clone(),
            size: self.size,
            builder: self.builder,
            features: Features::all().without(&self.off),
            policy: if self.no_plan {
                PlanPolicy::Everything
            } else {
                PlanPolicy::Prune
            },
            seed: self.seed,
            light_samples: self.light_samples,
            glossy_samples: self.glossy_samples,
            integrator: self.integrator,
            max_depth: self.max_depth,
            independent: self.independent,
            camera: self.camera.clone(),
            allow_outside: self.allow_outside,
            up: self.up,
            env: self.env.as_ref().map(|given| EnvRequest {
                given: given.clone(),
                strength: self.env_strength.unwrap_or(1.0),
                rotate: self.env_rotate.unwrap_or(0.0),
            }),
            simd: self.simd,
            check_film: true,
        }
    }
}

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("budget").args(["time", "target_error"]).multiple(true)))]
pub(crate) struct RenderArgs {
    #[command(flatten)]
    pub(crate) scene: SceneOpts,
    /// Output: .png (the picture, after bloom), or the linear film before
    /// bloom as .exr (OpenEXR, 32-bit float, exact) or .hdr (Radiance, 8-bit
    /// mantissas): a reference for `converge` and `tui`. Checked before
    /// rendering.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Samples per pixel (default: the scene's).
    #[arg(long, conflicts_with_all = ["time", "target_error"],
          value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub(crate) spp: Option<u32>,
    /// Add passes until this many seconds have passed (may be combined with
    /// --target-error: whichever comes first).
    #[arg(long)]
    pub(crate) time: Option<f64>,
    /// Add passes until the estimated relative error is below this (0.01
    /// for 1 %).
    #[arg(long)]
    pub(crate) target_error: Option<f64>,
    /// The most samples per pixel --time and --target-error may add
    /// [default: 4096].
    #[arg(long, requires = "budget",
          value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub(crate) max_spp: Option<u32>,
    /// Give every pixel the same samples with --time or --target-error too,
    /// where a sampled scene is otherwise rendered adaptively: after 4 spp,
    /// samples go where the error is (docs/adaptive.md).
    #[arg(long, requires = "budget")]
    pub(crate) uniform: bool,
    /// Worker threads (default: all cores; at most 4x the cores).
    #[arg(long, value_parser = parse_threads)]
    pub(crate) threads: Option<u32>,
    /// Print the scene plan (stage, on/off, reason) before rendering.
    #[arg(long)]
    pub(crate) explain: bool,
    /// After the render, trace the samples it took again in one pass, each
    /// pixel's together as `--spp N` would, and print that rate beside the
    /// render's: what its passes cost against a one-shot render of the same
    /// samples (BENCHMARKS.md).
    #[arg(long, conflicts_with_all = ["debug", "part", "checkpoint", "resume"])]
    pub(crate) compare_one_shot: bool,
    /// Write a debug view instead: bvh-level:K (boxes of level K over the
    /// image), bvh-leaves, bvh-heat (nodes visited per pixel) or
    /// bvh-heat:tests; bloom (the pixels over the threshold and their glow);
    /// ray:X,Y[:VIEW[:N]] (pixel X,Y's rays, or VIEW: colour, lights,
    /// traversal, normals, texture, environment, glossy, samples; N picks
    /// the ray of traversal, normals, texture and environment); samples:X,Y
    /// (a zoom of the pixel's samples).
    #[arg(long, value_name = "VIEW", conflicts_with_all = ["time", "target_error"])]
    pub(crate) debug: Option<DebugSpec>,
    /// Render only sample indices A to B-1 of every pixel and write a
    /// partial film (-o part.exr) for `rayterm merge`.
    #[arg(long, value_name = "A..B", value_parser = parse_samples,
          conflicts_with_all = ["spp", "time", "target_error", "debug"])]
    pub(crate) samples: Option<std::ops::Range<u32>>,
    /// Render part K of N equal sample ranges of --spp (default: the
    /// scene's) and write a partial film (-o part.exr) for `rayterm merge`.
    /// Parts are uniform.
    #[arg(long, value_name = "K/N", value_parser = parse_part,
          conflicts_with_all = ["samples", "time", "target_error", "debug"])]
    pub(crate) part: Option<(u32, u32)>,
    /// Write the film so far to this partial film (.exr) every few seconds,
    /// at the end, and when stopped by Ctrl-C or SIGTERM, atomically. An
    /// existing FILE is only continued (--resume FILE), never replaced.
    /// Partial films are uniform: the render is too.
    #[arg(long, value_name = "FILE.exr", conflicts_with = "debug")]
    pub(crate) checkpoint: Option<PathBuf>,
    /// Write these beside the picture in the EXR output, as channels
    /// albedo.R/G/B, normal.X/Y/Z and Z: what each pixel's camera rays
    /// first hit (its colour, its normal, its distance).
    #[arg(long, value_enum, value_delimiter = ',', value_name = "albedo,normal,depth",
          conflicts_with_all = ["debug", "samples", "part", "checkpoint", "resume"])]
    pub(crate) aov: Vec<crate::render::aov::Aov>,
    /// Continue from a checkpoint (or a part) of this same render: its
    /// samples are kept, and rendering goes on to the requested spp, time
    /// or error, uniformly.
    #[arg(long, value_name = "FILE.exr", conflicts_with = "debug")]
    pub(crate) resume: Option<PathBuf>,
    /// Seconds between checkpoints [default: 5]; the first is written
    /// after the first pass, and SIGUSR1 asks for one at the end of the
    /// pass in flight.
    #[arg(long, value_name = "SECONDS", requires = "checkpoint", value_parser = parse_seconds,
          allow_hyphen_values = true)]
    pub(crate) checkpoint_every: Option<f64>,
    /// Progress on standard error: a bar on a terminal and lines elsewhere
    /// (auto), a bar, lines (every tenth and every few seconds), json (one
    /// object a line) or none.
    #[arg(long, value_enum, value_name = "HOW", default_value = "auto")]
    pub(crate) progress: ProgressMode,
    /// Print what the render will take (triangles, the BVH, the film, the
    /// checkpoints, the peak memory) and render nothing.
    #[arg(long, conflicts_with_all = ["debug", "compare_one_shot"])]
    pub(crate) dry_run: bool,
    /// Render a turntable: the camera orbits its target once, about its up
    /// axis, in FRAMES frames, each rendered as one picture is (--spp,
    /// --time or --target-error a frame), into a looping animation: -o
    /// .gif (256 colours, one palette) or .apng (24-bit; a .png is one too).
    #[arg(long, value_name = "FRAMES", value_parser = clap::value_parser!(u32).range(2..=3600),
          conflicts_with_all = ["frame", "debug", "samples", "part", "checkpoint", "resume",
                                "aov", "compare_one_shot", "dry_run"])]
    pub(crate) turntable: Option<u32>,
    /// Render frame K of an N-frame turntable as one picture, for a job
    /// array (any other option applies to it); `rayterm animate` joins the
    /// frames. Frame 1 is the scene's own camera.
    #[arg(long, value_name = "K/N", value_parser = parse_frame)]
    pub(crate) frame: Option<(u32, u32)>,
    /// Frames a second of a --turntable animation [default: 15].
    #[arg(long, requires = "turntable", value_parser = clap::value_parser!(u32).range(1..=100))]
    pub(crate) fps: Option<u32>,
}

/// `K/N`: frame K of an N-frame turntable, 1 <= K <= N, 2 <= N <= 3600.
fn parse_frame(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("'{s}' is not K/N (frame K of an N-frame turntable, N from 2 to 3600)");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (u32, u32) = match (k.trim().parse(), n.trim().parse()) {
        (Ok(k), Ok(n)) => (k, n),
        _ => return Err(bad()),
    };
    if !(2..=3600).contains(&n) || k == 0 || k > n {
        return Err(bad());
    }
    Ok((k, n))
}

#[derive(Args, Debug)]
pub(crate) struct AnimateArgs {
    /// The frames, PNG pictures of one size, in the order they show.
    #[arg(required = true)]
    pub(crate) frames: Vec<PathBuf>,
    /// Output: .gif (256 colours, one palette) or .apng (24-bit; a .png
    /// is one too).
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Frames a second.
    #[arg(long, default_value_t = super::turntable::DEFAULT_FPS,
          value_parser = clap::value_parser!(u32).range(1..=100))]
    pub(crate) fps: u32,
}

/// A number of seconds above zero.
fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(t) if t > 0.0 && t.is_finite() => Ok(t),
        _ => Err(format!("'{s}' is not a number of seconds above zero")),
    }
}

#[derive(Args, Debug)]
pub(crate) struct MergeArgs {
    /// Partial films, in any order.
    #[arg(required = true, value_name = "PART")]
    pub(crate) parts: Vec<PathBuf>,
    /// Output: .png (the picture, after bloom), .exr or .hdr (the linear
    /// film before bloom), as `render` writes them.
    #[arg(short, long)]
    pub(crate) output: PathBuf,
    /// Write the image even when ranges of samples are missing (it has
    /// fewer samples, and says so): a preview of the parts there are.
    #[arg(long)]
    pub(crate) allow_missing: bool,
    /// Write the merged parts as one partial film (.exr), which merges
    /// again with the parts still to come into the same image (a staged
    /// merge); their samples must follow one another.
    #[arg(long, conflicts_with = "allow_missing")]
    pub(crate) partial: bool,
    /// Check first that the parts were rendered from this scene as it
    /// loads here (with the options they record), and say which of its
    /// files differ where they were not.
    #[arg(long, value_name = "SCENE", value_parser = scene_spec())]
    pub(crate) check: Option<String>,
}

#[derive(Args, Debug)]
pub(crate) struct InputsArgs {
    #[command(flatten)]
    pub(crate) scene: SceneOpts,
}

/// `X,Y`, e.g. `400,300`.
pub(crate) fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s
        .split_once(',')
        .ok_or_else(|| format!("'{s}' is not X,Y"))?;
    let x = x.trim().parse().map_err(|_| format!("bad x in '{s}'"))?;
    let y = y.trim().parse().map_err(|_| format!("bad y in '{s}'"))?;
    Ok((x, y))
}

#[derive(Args, Debug)]
#[command(group(clap::ArgGroup::new("which").args(["pixel", "worst"]).required(true)))]
pub(crate) struct InspectArgs {
    #[command(flatten)]
    pub(crate) scene: SceneOpts,
    /// The pixel, X,Y from the top left.
    #[arg(long, value_parser = parse_pixel, conflicts_with = "worst")]
    pub(crate) pixel: Option<(u32, u32)>,
    /// Jump to the worst pixel by this measure instead.
    #[arg(long, value_enum)]
    pub(crate) worst: Option<Worst>,
    /// Sample index to replay.
    #[arg(long, default_value_t = 0)]
    pub(crate) sample: u32,
    /// Samples per pixel of the image rendered to find the worst pixel
    /// (default 16) and, when bloom runs, for the pixel's value before and
    /// after bloom (default 1).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64))]
    pub(crate) spp: Option<u32>,
    /// Print JSON (schema in docs/inspect-json.md) instead of text.
    #[arg(long)]
    pub(crate) json: bool,
    /// Show every light sample instead of folding long lists.
    #[arg(long)]
    pub(crate) expand: bool,
}

#[derive(Args, Debug)]
#[command(mut_arg("size", |a| a.help("Image size, WIDTHxHEIGHT [default: 64x64]")))]
pub(crate) struct ConvergeArgs {
    #[command(flatten)]
    pub(crate) scene: SceneOpts,
    /// Reference image (OpenEXR .exr, or Radiance .hdr with its 8-bit
    /// mantissas' floor) instead of a rendered or cached one.
    #[arg(long)]
    pub(crate) reference: Option<PathBuf>,
    /// Samples per pixel of a rendered reference [default: 64x the largest
    /// --spp budget, at most 1024].
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=MAX_SPP as i64), conflicts_with = "reference")]
    pub(crate) reference_spp: Option<u32>,
    /// Budgets in samples per pixel, comma separated.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1,2,4,8,16",
        conflicts_with = "times"
    )]
    pub(crate) spp: Vec<u32>,
    /// Budgets in seconds instead, comma separated.
    #[arg(long, value_delimiter = ',')]
    pub(crate) times: Vec<f64>,
    /// Independent runs (seeds) per budget.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=64))]
    pub(crate) seeds: u32,
    /// Relative error (root relMSE) the conclusion is about.
    #[arg(long, default_value_t = 0.01)]
    pub(crate) target: f64,
    /// Only the scene's own settings: no strategy comparison.
    #[arg(long)]
    pub(crate) no_compare: bool,
    /// Measure the scene's settings with adaptive sampling (spp budgets are
    /// the mean over pixels).
    #[arg(long)]
    pub(crate) adaptive: bool,
    /// Write every measured point as CSV.
    #[arg(long)]
    pub(crate) csv: Option<PathBuf>,
    /// Write a log-log plot of error against time as PNG.
    #[arg(long)]
    pub(crate) plot: Option<PathBuf>,
    /// Where rendered references are cached [default: $XDG_CACHE_HOME/rayterm,
    /// else ~/.cache/rayterm].
    #[arg(long)]
    pub(crate) cache_dir: Option<PathBuf>,
    /// Worker threads (default: all cores; at most 4x the cores).
    #[arg(long, value_parser = parse_threads)]
    pub(crate) threads: Option<u32>,
}

#[derive(Args, Debug)]
#[command(mut_arg("size", |a| {
    a.help("Size of PNG exports (p), WIDTHxHEIGHT (default: the scene's); the view fills the terminal")
}))]
pub(crate) struct TuiArgs {
    #[command(flatten)]
    pub(crate) scene: SceneOpts,
    /// Colours (default: RAYTERM_COLOR, else `color` in
    /// ~/.config/rayterm/config.toml, else truecolor when the terminal says
    /// it has 24-bit colour, or when it does not answer and COLORTERM or
    /// the terminfo entry of TERM says so, else 256 with dithering).
    #[arg(long, value_enum)]
    pub(crate) color: Option<ColorMode>,
    /// Block symbols for the viewport: half blocks (1x2 pixels per cell,
    /// every terminal), quadrants (2x2), sextants (2x3, Unicode 13) or
    /// octants (2x4, Unicode 16; few fonts have them), or auto: the densest
    /// set the terminal is known to draw itself, whatever its font
    /// [default: RAYTERM_SYMBOLS, else `symbols` in the config file, else
    /// auto].
    #[arg(long, value_enum)]
    pub(crate) symbols: Option<SymbolsArg>,
    /// Pixel graphics for the viewport: ask the terminal (auto, within a
    /// second; block symbols when it has no protocol, or inside tmux
    /// without allow-passthrough), a protocol, or block symbols only. A
    /// protocol named here is used even where the terminal does not claim
    /// it (the status line says so) [default: RAYTERM_GRAPHICS, else
    /// `graphics` in the config file, else auto].
    #[arg(long, value_enum)]
    pub(crate) graphics: Option<GraphicsArg>,
    /// A converged image of the scene (OpenEXR .exr or Radiance .hdr, e.g.
    /// from `rayterm render --spp 1024 -o ref.exr`, best at a whole multiple
    /// of the view's size): the true error is shown beside the estimate
    /// while the camera and features are the starting ones.
    #[arg(long, value_name = "FILE.exr")]
    pub(crate) reference: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub(crate) struct StabilityArgs {
    /// Scene for the scale and offset cases.
    #[arg(default_value = "cornell", value_parser = scene_spec())]
    pub(crate) scene: String,
    /// Image size of the rendered cases, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_size, default_value = "96x96")]
    pub(crate) size: (u32, u32),
    /// Print the rows as JSON instead of a table.
    #[arg(long)]
    pub(crate) json: bool,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::PlanPolicy;

    #[test]
    fn no_command_means_the_tui() {
        assert!(Cli::try_parse_from(["rayterm"]).unwrap().command.is_none());
        let cli =
            Cli::try_parse_from(["rayterm", "tui", "teapot", "--color", "16", "--no", "bloom"]);
        match cli.unwrap().command {
            Some(Command::Tui(a)) => {
                assert_eq!(a.scene.scene, "teapot");
                assert_eq!(a.color, Some(crate::tui::color::ColorMode::Ansi16));
                assert_eq!(a.scene.off, vec![Feature::Bloom]);
            }
            other => panic!("{other:?}"),
        }
        let Some(Command::Tui(a)) = Cli::try_parse_from(["rayterm", "tui"]).unwrap().command else {
            panic!("tui parses");
        };
        assert_eq!((a.scene.scene.as_str(), a.scene.seed), ("cornell", 1));
    }

    #[test]
    fn no_plan_reaches_the_request() {
        let Some(Command::Tui(a)) = Cli::try_parse_from(["rayterm", "tui", "cornell", "--no-plan"])
            .unwrap()
            .command
        else {
            panic!("tui parses");
        };
        assert_eq!(a.scene.request().policy, PlanPolicy::Everything);
    }
}
