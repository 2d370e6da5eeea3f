//! PNG export of the current view at full resolution, in a background thread
//! so the TUI stays responsive; the file is written atomically under a fresh
//! name.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

use anyhow::{bail, Context, Result};

use super::worker::tracer;
use crate::bvh::Bvh;
use crate::render::{output, pass, post, Features, Film, Plan};
use crate::scene::{Camera, Scene};

/// What to export.
pub struct Request {
    pub scene: Arc<Scene>,
    pub bvh: Arc<Bvh>,
    pub camera: Camera,
    pub features: Features,
    pub size: (u32, u32),
    pub seed: u64,
    /// Where the file goes.
    pub dir: PathBuf,
}

/// A finished export.
pub struct Saved {
    pub path: PathBuf,
    pub spp: u32,
    pub seconds: f64,
}

/// An export in progress.
pub struct Job {
    pub size: (u32, u32),
    /// Samples per pixel the image gets.
    pub target_spp: u32,
    done_spp: Arc<AtomicU32>,
    cancel: Arc<AtomicBool>,
    result: Receiver<Result<Saved>>,
    thread: Option<JoinHandle<()>>,
}

/// A file-name-safe stem from a scene name, which may be a path.
pub fn stem(scene_name: &str) -> String {
    let base = Path::new(scene_name)
        .file_stem()
        .map_or(scene_name.into(), |s| s.to_string_lossy());
    let s: String = base
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '-'
            }
        })
        .collect();
    if s.is_empty() {
        "scene".into()
    } else {
        s
    }
}

impl Job {
    /// Starts rendering `r` to `rayterm-<scene>-NNN.png` at the scene's spp
    /// (one pass when nothing is sampled).
    pub fn start(r: Request) -> Result<Job> {
        let plan = Plan::new(&r.scene, r.features);
        let target_spp = if plan.deterministic {
            1
        } else {
            r.scene.settings.spp.max(1)
        };
        let done_spp = Arc::new(AtomicU32::new(0));
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, result) = mpsc::channel();
        let (done, stop) = (done_spp.clone(), cancel.clone());
        let size = r.size;
        let thread = std::thread::Builder::new()
            .name("rayterm-export".into())
            .spawn(move || {
                let _ = tx.send(render(&r, &plan, target_spp, &done, &stop));
            })
            .context("cannot start the export thread")?;
        Ok(Job {
            size,
            target_spp,
            done_spp,
            cancel,
            result,
            thread: Some(thread),
        })
    }

    pub fn done_spp(&self) -> u32 {
        self.done_spp.load(Ordering::Relaxed)
    }

    /// The result once the export has finished.
    pub fn poll(&self) -> Option<Result<Saved>> {
        match self.result.try_recv() {
            Ok(r) => Some(r),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => {
                Some(Err(anyhow::anyhow!("the export thread stopped")))
            }
        }
    }
}

impl Drop for Job {
    /// Stops an unfinished export (between rows) and waits for its thread.
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::SeqCst);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn render(
    r: &Request,
    plan: &Plan,
    spp: u32,
    done: &AtomicU32,
    stop: &AtomicBool,
) -> Result<Saved> {
    let start = Instant::now();
    let (w, h) = r.size;
    let t = tracer(&r.scene, &r.bvh, plan, &r.camera, r.size, r.seed);
    let mut film = Film::new(w, h);
    let cancel = || stop.load(Ordering::Relaxed);
    for k in 0..spp {
        pass::render_pass(&t, &mut film, 1, &cancel);
        if cancel() {
            bail!("export cancelled");
        }
        done.store(k + 1, Ordering::Relaxed);
    }
    let mut img = film.image();
    if plan.bloom {
        post::bloom(&mut img, w as usize, h as usize, &r.scene.settings.bloom);
    }
    let path = output::fresh_name(&r.dir, &format!("rayterm-{}", stem(&r.scene.name)));
    output::save_png_atomic(&post::to_rgb8(&img, w, h), &path)?;
    Ok(Saved {
        path,
        spp,
        seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_are_safe_file_names() {
        assert_eq!(stem("cornell"), "cornell");
        assert_eq!(stem("/work/data/bunny.obj"), "bunny");
        assert_eq!(stem("teapot:32"), "teapot-32");
        assert_eq!(stem(""), "scene");
    }
}
