//! Reports that measure rayterm: the benchmark table, the shared ray
//! workload (side by side with other tracers) and how cost grows with size.

pub mod bench;
pub mod converge;
pub mod scaling;
pub mod stability;
pub mod workload;

use std::path::{Path, PathBuf};

use serde::Serialize;

/// The machine a figure was measured on.
#[derive(Clone, Debug, Serialize)]
pub struct Machine {
    pub cpu: String,
    /// Threads the measurement used.
    pub threads: usize,
    /// Logical CPUs of the machine.
    pub cpus: usize,
}

impl Machine {
    pub fn current(threads: usize) -> Self {
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
            threads,
            cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
        }
    }
}

impl std::fmt::Display for Machine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}, {} thread{} of {} CPU{}",
            self.cpu,
            self.threads,
            if self.threads == 1 { "" } else { "s" },
            self.cpus,
            if self.cpus == 1 { "" } else { "s" }
        )
    }
}

/// The shared test meshes (`../shared/data/meshes`), looked for beside the
/// current directory, the executable's directories and the crate.
pub fn shared_meshes_dir() -> Option<PathBuf> {
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

/// Least-squares slope and intercept of `y` against `x`, and the r² of the fit.
pub fn fit_line(x: &[f64], y: &[f64]) -> Option<(f64, f64, f64)> {
    let n = x.len().min(y.len());
    if n < 2 {
        return None;
    }
    let (x, y) = (&x[..n], &y[..n]);
    let mx = x.iter().sum::<f64>() / n as f64;
    let my = y.iter().sum::<f64>() / n as f64;
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let syy: f64 = y.iter().map(|b| (b - my) * (b - my)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let slope = sxy / sxx;
    let r2 = if syy > 0.0 {
        sxy * sxy / (sxx * syy)
    } else {
        1.0
    };
    Some((slope, my - slope * mx, r2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_recovers_a_line() {
        let x = [1.0, 2.0, 3.0, 4.0];
        let y: Vec<f64> = x.iter().map(|v| 2.5 * v - 1.0).collect();
        let (s, i, r2) = fit_line(&x, &y).unwrap();
        assert!((s - 2.5).abs() < 1e-12 && (i + 1.0).abs() < 1e-12 && (r2 - 1.0).abs() < 1e-12);
        assert!(fit_line(&[1.0, 1.0], &[2.0, 3.0]).is_none());
    }

    #[test]
    fn median_of_odd_and_even() {
        assert_eq!(workload::median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(workload::median(&mut [4.0, 1.0, 2.0, 3.0]), 2.5);
        assert_eq!(workload::median(&mut []), 0.0);
    }
}
