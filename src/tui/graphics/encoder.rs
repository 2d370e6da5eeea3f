//! Encodes planned bands on a thread of its own, so that compressing and
//! quantizing a large picture never holds up keys or drawing. One plan at
//! a time: the event loop plans the next picture once the last is back.

use std::sync::mpsc::{channel, Receiver, Sender};
use std::thread;

use super::bands::{Batch, EncodedBand};

pub(crate) struct Encoder {
    tx: Sender<Batch>,
    rx: Receiver<Vec<EncodedBand>>,
    busy: bool,
}

impl Encoder {
    /// Starts the thread; it ends when the encoder is dropped.
    pub(crate) fn spawn() -> std::io::Result<Encoder> {
        let (tx, jobs) = channel::<Batch>();
        let (done, rx) = channel();
        thread::Builder::new()
            .name("encoder".into())
            .spawn(move || {
                for plan in jobs {
                    if done.send(plan.encode()).is_err() {
                        break;
                    }
                }
            })?;
        Ok(Encoder {
            tx,
            rx,
            busy: false,
        })
    }

    /// Whether a plan is being encoded.
    pub(crate) fn busy(&self) -> bool {
        self.busy
    }

    /// Hands `plan` to the thread.
    pub(crate) fn start(&mut self, plan: Batch) {
        self.busy = self.tx.send(plan).is_ok();
    }

    /// The pieces of the plan, once encoded.
    pub(crate) fn done(&mut self) -> Option<Vec<EncodedBand>> {
        let pieces = self.rx.try_recv().ok()?;
        self.busy = false;
        Some(pieces)
    }
}
