//! Reports that measure rayterm: the benchmark table, the shared ray
//! workload (side by side with other tracers) and how cost grows with size.

pub mod bench;
pub mod converge;
pub mod scaling;
pub mod stability;
pub mod stats;
pub mod workload;

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::bvh::Simd;

/// How a long report says what it is doing: the CLI shows it (a bar, or a
/// spinner when the steps are not known ahead); `&()` shows nothing.
pub trait Progress: Sync {
    /// The work has `steps` steps; `None` when not known ahead.
    fn begin(&self, _steps: Option<u64>) {}
    /// What it is doing now.
    fn doing(&self, _what: &str) {}
    /// One more step done.
    fn step(&self) {}
    /// Done: whatever was shown goes away.
    fn end(&self) {}
}

impl Progress for () {}

/// The machine a figure was measured on.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct Machine {
    pub(crate) cpu: String,
    /// The SIMD kernels the walks used: the widest the CPU has.
    pub(crate) simd: Simd,
    /// Threads the measurement used.
    pub(crate) threads: usize,
    /// Logical CPUs of the machine.
    pub(crate) cpus: usize,
}

impl Machine {
    pub(crate) fn current(threads: usize) -> Self {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|s| {
                s.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split_once(':'))
                    .map(|(_, v)| v.trim().to_string())
            })
            .unwrap_or_else(|| std::env::consts::ARCH.to_string());
        Machine {
            cpu,
            simd: Simd::detect(),
            threads,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

impl std::fmt::Display for Machine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}), {} thread{} of {} CPU{}",
            self.cpu,
            self.simd,
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            self.cpus,
            if self.cpus == 1 { "" } else { "s" }
        )
    }
}

/// The shared test meshes (`../shared/data/meshes`), looked for beside the
/// current directory, the executable's directories and the crate.
pub(crate) fn shared_meshes_dir() -> Option<PathBuf> {
    let rel = Path::new("../shared/data/meshes");
    let mut bases: Vec<PathBuf> = Vec::new();
    if let Ok(cwd) = std::env::current_dir() {
        bases.push(cwd);
    }
    if let Ok(exe) = std::env::current_exe() {
        bases.extend(exe.ancestors().skip(1).map(Path::to_path_buf));
    }
    bases.push(PathBuf::from(env!("CARGO_MANIFEST_DIR")));
    bases.into_iter().map(|b| b.join(rel)).find(|p| p.is_dir())
}
