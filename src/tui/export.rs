//! PNG export of the current view at full resolution, in a background thread
//! so the TUI stays responsive; the file is written atomically under a fresh
//! name.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;
use std::thread::JoinHandle;

use anyhow::{bail, Context, Result};

use crate::interrupt::Cancel;
use crate::raster::output;
use crate::render::Job;
use crate::render::{post, Ended, Needs, Plan, Session, Stop};
use crate::scene::Camera;

/// What to export: the session's scene with its seed, seen from `camera`
/// with `plan`, at `size`.
pub(crate) struct Request {
    pub(crate) session: Session,
    pub(crate) camera: Camera,
    pub(crate) plan: Plan,
    pub(crate) size: (u32, u32),
    /// Where the file goes.
    pub(crate) dir: PathBuf,
}

/// A finished export.
pub(crate) struct Saved {
    pub(crate) path: PathBuf,
    pub(crate) spp: u32,
    pub(crate) seconds: f64,
}

/// An export in progress.
pub(crate) struct Export {
    pub(crate) size: (u32, u32),
    /// Samples per pixel the image gets.
    pub(crate) target_spp: u32,
    /// Samples per pixel of the passes done, and rows of the pass in
    /// flight done, of passes of `pass_spp`.
    done_spp: Arc<AtomicU32>,
    rows: Arc<AtomicU32>,
    pass_spp: u32,
    cancel: Arc<AtomicBool>,
    result: Receiver<Result<Saved>>,
    thread: Option<JoinHandle<()>>,
}

/// A file-name-safe stem from a scene name, which may be a path.
pub(crate) fn stem(scene_name: &str) -> String {
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

impl Export {
    /// Starts rendering `r` to `rayterm-<scene>-NNN.png` at the scene's spp
    /// (one pass when nothing is sampled).
    pub(crate) fn start(r: Request) -> Result<Export> {
        let target_spp = if r.plan.deterministic {
            1
        } else {
            r.session.scene.settings.spp.max(1)
        };
        // Read for nothing but its image: as `rayterm render` makes one.
        let size = r.size;
        let rows = Arc::new(AtomicU32::new(0));
        let job = Job::new(size.0, size.1, &r.plan, Stop::spp(target_spp))
            .needs(Needs::Image)
            .passes_for_stop()
            .rows_done(rows.clone());
        let pass_spp = job.samples_per_pass();
        let done_spp = Arc::new(AtomicU32::new(0));
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, result) = mpsc::channel();
        let (done, stop, counted) = (done_spp.clone(), cancel.clone(), rows.clone());
        let thread = std::thread::Builder::new()
            .name("rayterm-export".into())
            .spawn(move || {
                let _ = tx.send(render(&r, job, counted, &done, &stop));
            })
            .context("cannot start the export thread")?;
        Ok(Export {
            size,
            target_spp,
            done_spp,
            rows,
            pass_spp,
            cancel,
            result,
            thread: Some(thread),
        })
    }

    /// Samples per pixel done, counting the rows of the pass in flight.
    pub(crate) fn done_spp(&self) -> u32 {
        let done = self.done_spp.load(Ordering::Relaxed);
        let rows = self.rows.load(Ordering::Relaxed) as u64;
        // The last pass may be shorter than the others.
        let pass = self.pass_spp.min(self.target_spp.saturating_sub(done)) as u64;
        done + (pass * rows / self.size.1.max(1) as u64) as u32
    }

    /// The result once the export has finished.
    pub(crate) fn poll(&self) -> Option<Result<Saved>> {
        match self.result.try_recv() {
            Ok(r) => Some(r),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => {
                Some(Err(anyhow::anyhow!("the export thread stopped")))
            }
        }
    }
}

impl Drop for Export {
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
    job: Job,
    rows: Arc<AtomicU32>,
    done: &AtomicU32,
    stop: &AtomicBool,
) -> Result<Saved> {
    let s = &r.session;
    let (w, h) = r.size;
    let tracer = s.tracer_for(&r.plan, &r.camera, r.size);
    let cancel = || stop.load(Ordering::Relaxed);
    let mut p = job.start();
    let o = p.run(&tracer, Cancel::When(&cancel), |film, _| {
        // Rows count the next pass's from here.
        rows.store(0, Ordering::Relaxed);
        done.store(film.spp, Ordering::Relaxed)
    });
    if o.ended == Ended::Cancelled {
        bail!("export cancelled");
    }
    let shown = post::display(p.film().image(), w, h, &r.plan, &s.scene.settings.bloom);
    let path = output::fresh_name(&r.dir, &format!("rayterm-{}", stem(&s.scene.name)));
    crate::raster::write_png(&path, &post::to_rgb8(&shown.image, w, h))?;
    Ok(Saved {
        path,
        spp: p.film().spp,
        seconds: o.seconds,
    })
}

/// The export size for a view of `view` pixels: `asked` (`--size`) when
/// given, else the view's shape with the long side of `scene` (the scene's
/// size), so the picture shows what the view shows.
pub(crate) fn size_for(
    view: (u32, u32),
    asked: Option<(u32, u32)>,
    scene: (u32, u32),
) -> (u32, u32) {
    if let Some(s) = asked {
        return s;
    }
    let (vw, vh) = (view.0.max(1) as f64, view.1.max(1) as f64);
    let long = scene.0.max(scene.1) as f64;
    let (w, h) = if vw >= vh {
        (long, long * vh / vw)
    } else {
        (long * vw / vh, long)
    };
    ((w.round() as u32).max(1), (h.round() as u32).max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exports_keep_the_views_shape() {
        assert_eq!(size_for((114, 64), None, (800, 800)), (800, 449));
        assert_eq!(size_for((64, 114), None, (1280, 720)), (719, 1280));
        assert_eq!(
            size_for((114, 64), Some((300, 200)), (800, 800)),
            (300, 200)
        );
    }

    /// An export is the picture a film of statistics gives, at any spp:
    /// in one summarised pass up to `ONE_PASS_SPP`, in blocks beyond.
    #[test]
    fn an_export_is_the_picture_of_its_samples() {
        use crate::render::SceneRequest;
        let (size, dir) = ((12, 8), std::env::temp_dir());
        let session = Session::open(&SceneRequest {
            size: Some(size),
            ..SceneRequest::new("cornell-area")
        })
        .unwrap()
        .0;
        for spp in [1, 3, 16, 40, 300] {
            let session = Session {
                scene: Arc::new(crate::scene::Scene {
                    settings: crate::scene::Settings {
                        spp,
                        ..session.scene.settings.clone()
                    },
                    ..(*session.scene).clone()
                }),
                ..session.clone()
            };
            let r = Request {
                camera: session.camera,
                plan: session.plan.clone(),
                session: session.clone(),
                size,
                dir: dir.clone(),
            };
            let job = Export::start(r).unwrap();
            let saved = loop {
                match job.poll() {
                    Some(s) => break s.unwrap(),
                    None => std::thread::sleep(std::time::Duration::from_millis(5)),
                }
            };
            assert_eq!((saved.spp, job.done_spp()), (spp, spp));
            let png = image::open(&saved.path).unwrap().into_rgb8();
            std::fs::remove_file(&saved.path).unwrap();
            let film = crate::render::Progressive::render(&session.tracer(), spp);
            let s = &session.scene.settings;
            let shown = post::display(film.image(), size.0, size.1, &session.plan, &s.bloom);
            assert_eq!(
                png,
                post::to_rgb8(&shown.image, size.0, size.1),
                "{spp} spp"
            );
        }
    }

    #[test]
    fn stems_are_safe_file_names() {
        assert_eq!(stem("cornell"), "cornell");
        assert_eq!(stem("/work/data/bunny.obj"), "bunny");
        assert_eq!(stem("teapot:32"), "teapot-32");
        assert_eq!(stem(""), "scene");
    }
}
