//! Work the TUI runs in the background besides rendering: PNG exports and
//! the stability battery. Each reports back through [`Jobs::poll`].

use std::path::PathBuf;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;

use anyhow::Result;

use super::export;
use super::popup::Popup;
use crate::render::{Plan, Session};
use crate::report::stability;
use crate::scene::{Camera, Scene};

pub(crate) struct Jobs {
    /// Where PNG exports go: the directory the TUI was started in.
    pub(crate) export_dir: PathBuf,
    /// The export size `--size` asked for; otherwise exports take the
    /// view's shape at the scene's size.
    pub(crate) export_size: Option<(u32, u32)>,
    export: Option<export::Export>,
    /// The stability battery's result, while it runs.
    stability: Option<Receiver<Result<Vec<stability::Row>>>>,
}

/// What finished jobs have to say.
pub(crate) struct Finished {
    pub(crate) status: Option<String>,
    pub(crate) popup: Option<Popup>,
}

impl Jobs {
    pub(crate) fn new() -> Jobs {
        Jobs {
            export_dir: std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
            export_size: None,
            export: None,
            stability: None,
        }
    }

    /// Starts exporting what `camera` sees of `session` with `plan`, in the
    /// shape of a `view_size` view, unless an export is running; what the
    /// status line says when it did not start (once started, the export's
    /// progress is on the status line).
    pub(crate) fn export(
        &mut self,
        session: &Session,
        camera: Camera,
        plan: &Plan,
        view_size: (u32, u32),
    ) -> Option<String> {
        if self.export.is_some() {
            return Some("an export is already running".into());
        }
        let scene_size = (session.width, session.height);
        let r = export::Request {
            session: session.clone(),
            camera,
            plan: plan.clone(),
            size: export::size_for(view_size, self.export_size, scene_size),
            dir: self.export_dir.clone(),
        };
        match export::Export::start(r) {
            Ok(job) => {
                self.export = Some(job);
                None
            }
            Err(e) => Some(format!("cannot export: {e:#}")),
        }
    }

    /// Export progress for the status line.
    pub(crate) fn export_progress(&self) -> Option<String> {
        self.export.as_ref().map(|j| {
            format!(
                "exporting this view as a {}x{} PNG: {}/{} spp",
                j.size.0,
                j.size.1,
                j.done_spp(),
                j.target_spp
            )
        })
    }

    /// Stops an export in progress; says so when there was one.
    pub(crate) fn cancel_export(&mut self) -> bool {
        self.export.take().is_some()
    }

    /// Runs the stability battery on `scene` in the background; the status
    /// line's text.
    pub(crate) fn stability(&mut self, scene: Arc<Scene>) -> String {
        if self.stability.is_some() {
            return "the stability battery is already running".into();
        }
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let rows = stability::run_battery_on(&scene, &stability::Options::default(), &());
            // The receiver is gone only when the TUI has quit.
            let _ = tx.send(rows);
        });
        self.stability = Some(rx);
        "running the stability battery...".into()
    }

    pub(crate) fn busy(&self) -> bool {
        self.export.is_some() || self.stability.is_some()
    }

    /// Collects what has finished; `None` when nothing has.
    pub(crate) fn poll(&mut self, scene_name: &str) -> Option<Finished> {
        if let Some(job) = &self.export {
            if let Some(r) = job.poll() {
                let status = match r {
                    Ok(s) => format!(
                        "saved {} ({}x{}, {} spp, {:.1} s)",
                        s.path.display(),
                        job.size.0,
                        job.size.1,
                        s.spp,
                        s.seconds
                    ),
                    Err(e) => format!("export failed: {e:#}"),
                };
                self.export = None;
                return Some(Finished {
                    status: Some(status),
                    popup: None,
                });
            }
        }
        let rx = self.stability.as_ref()?;
        let result = match rx.try_recv() {
            Ok(r) => r,
            Err(TryRecvError::Empty) => return None,
            Err(TryRecvError::Disconnected) => {
                Err(anyhow::anyhow!("the battery stopped unexpectedly"))
            }
        };
        self.stability = None;
        Some(match result {
            Ok(rows) => {
                let failed = rows.iter().filter(|r| !r.pass).count();
                Finished {
                    status: Some(format!(
                        "stability battery: {} of {} cases passed",
                        rows.len() - failed,
                        rows.len()
                    )),
                    popup: Some({
                        let table = stability::format_table(&rows);
                        let mut p = Popup::new(
                            format!("stability battery: {scene_name} ({failed} failed)"),
                            table.lines().map(str::to_string).collect(),
                        )
                        .with_header(1);
                        p.last_column = table.find("detail");
                        p
                    }),
                }
            }
            Err(e) => Finished {
                status: Some(format!("stability battery failed: {e:#}")),
                popup: None,
            },
        })
    }
}
