//! A file one process at a time writes again and again (a render's
//! checkpoint): claimed by a lock on `.NAME.lock` beside it, since the file
//! itself is replaced at every write. The system releases the lock when
//! its process ends, however it ends, so a crashed render's claim never
//! blocks the next; the lock file goes when the claim is dropped.

use std::fs::{self, File, OpenOptions};
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use super::output::reason;
use super::temporary::{short_name, try_lock};

#[derive(Debug)]
pub(crate) struct Claim {
    lock: PathBuf,
    _file: File,
}

impl Claim {
    /// Claims `path` for this process; an error naming it when another
    /// process holds it.
    pub(crate) fn take(path: &Path) -> Result<Claim> {
        let lock = path.with_file_name(format!(".{}.lock", short_name(path)));
        let cannot = |e: std::io::Error| {
            anyhow::anyhow!(
                "cannot claim {} (with {}): {}",
                path.display(),
                lock.display(),
                reason(&e)
            )
        };
        loop {
            let file = OpenOptions::new()
                .write(true)
                .create(true)
                .truncate(false)
                .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
                .open(&lock)
                .map_err(cannot)?;
            // Never a link (refused by the open), a FIFO or a device.
            if !file.metadata().map_err(cannot)?.is_file() {
                bail!(
                    "cannot claim {}: {} is not a regular file",
                    path.display(),
                    lock.display()
                );
            }
            if !try_lock(&file).map_err(cannot)? {
                bail!(
                    "{} is being written by another render (it holds {}); wait for it to \
                     end, or name another file",
                    path.display(),
                    lock.display()
                );
            }
            // The claim of a render that ended removes the lock file: one
            // locked after that must be the file the name holds now.
            let held = file.metadata().map_err(cannot)?;
            match fs::symlink_metadata(&lock) {
                Ok(m) if (m.dev(), m.ino()) == (held.dev(), held.ino()) => {
                    crate::interrupt::claiming(Some(&lock));
                    return Ok(Claim { lock, _file: file });
                }
                _ => continue,
            }
        }
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        // Removed while still locked: a render waiting on it then finds
        // its name gone, and takes a new one.
        crate::interrupt::claiming(None);
        let _ = fs::remove_file(&self.lock);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_claim_at_a_time_and_none_left_behind() {
        let d = std::env::temp_dir().join(format!("rayterm-claim-{}", std::process::id()));
        fs::create_dir_all(&d).unwrap();
        let ck = d.join("ck.exr");
        let first = Claim::take(&ck).unwrap();
        let e = Claim::take(&ck).unwrap_err().to_string();
        assert!(
            e.contains("ck.exr is being written by another render"),
            "{e}"
        );
        drop(first);
        assert_eq!(fs::read_dir(&d).unwrap().count(), 0);
        // A lock file left by a killed process holds no lock.
        fs::write(d.join(".ck.exr.lock"), b"").unwrap();
        let again = Claim::take(&ck).unwrap();
        drop(again);
        assert_eq!(fs::read_dir(&d).unwrap().count(), 0);
        fs::remove_dir_all(d).unwrap();
    }
}
