//! Temporary files beside an output, renamed over it once written: names
//! that never collide (a random part, tried again when taken, where a
//! process id alone repeats: in a container rayterm is often PID 1), each
//! locked while its writer lives, so stale ones left by a killed writer
//! are told apart and removed.

use std::fs::{self, File, OpenOptions};
use std::hash::{BuildHasher, Hash, Hasher};
use std::io;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::{Path, PathBuf};

/// Bytes of a file name kept whole in the names made from it: with the
/// rest of a temporary's or a lock's name it stays within the 255 bytes
/// (`NAME_MAX`) a file name may have.
const KEPT: usize = 200;

/// The folder `path` goes in.
pub(crate) fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// `path`'s file name as the names made from it hold it: whole when
/// short, else its first bytes and a hash of all of it.
pub(crate) fn short_name(path: &Path) -> String {
    let name = path
        .file_name()
        .map_or("image".into(), |n| n.to_string_lossy());
    if name.len() <= KEPT {
        return name.into_owned();
    }
    let mut cut = KEPT - 17;
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    let mut h = std::hash::DefaultHasher::new();
    name.hash(&mut h);
    format!("{}~{:016x}", &name[..cut], h.finish())
}

/// Takes `f`'s lock without waiting: `false` when another holds it. A
/// lock dies with its process, however it ends.
pub(crate) fn try_lock(f: &File) -> io::Result<bool> {
    // SAFETY: flock on a descriptor this file owns.
    match unsafe { libc::flock(f.as_raw_fd(), libc::LOCK_EX | libc::LOCK_NB) } {
        0 => Ok(true),
        _ => match io::Error::last_os_error() {
            e if e.kind() == io::ErrorKind::WouldBlock => Ok(false),
            e => Err(e),
        },
    }
}

/// A random number, fresh for every call.
fn random() -> u32 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static CALLS: AtomicU64 = AtomicU64::new(0);
    // Randomly keyed for each process, and a count within it.
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u64(CALLS.fetch_add(1, Ordering::Relaxed));
    h.finish() as u32
}

/// A new temporary file beside `path`, `.NAME.PID-RANDOM.tmp`, created
/// exclusively and locked.
pub(crate) fn create(path: &Path) -> io::Result<(PathBuf, File)> {
    let name = short_name(path);
    let mut tries = 0;
    loop {
        let tmp = path.with_file_name(format!(
            ".{name}.{}-{:08x}.tmp",
            std::process::id(),
            random()
        ));
        let made = OpenOptions::new()
            .write(true)
            .create_new(true)
            .custom_flags(libc::O_CLOEXEC)
            .open(&tmp);
        match made {
            Ok(f) => {
                try_lock(&f)?;
                return Ok((tmp, f));
            }
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && tries < 16 => tries += 1,
            Err(e) => return Err(e),
        }
    }
}

/// Removes the temporary files of `path` that a dead writer left: named as
/// [`create`] names them (or `.NAME.PID.tmp`, as earlier versions did), of
/// a process that no longer runs or has this process's id, and unlocked.
/// Whatever cannot be checked is left alone.
pub(crate) fn remove_stale(path: &Path) {
    let (dir, name) = (folder(path), short_name(path));
    let prefix = format!(".{name}.");
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let file = entry.file_name();
        let Some(middle) = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix)?.strip_suffix(".tmp"))
        else {
            continue;
        };
        let (pid, rest) = middle.split_once('-').unwrap_or((middle, "0"));
        let (Ok(pid), true) = (
            pid.parse::<i32>(),
            rest.chars().all(|c| c.is_ascii_hexdigit()),
        ) else {
            continue;
        };
        // SAFETY: kill with signal 0 sends nothing; it asks whether the
        // process exists.
        let gone = unsafe { libc::kill(pid, 0) } != 0
            && io::Error::last_os_error().raw_os_error() == Some(libc::ESRCH);
        if !(gone || pid as u32 == std::process::id()) {
            continue;
        }
        let stale = OpenOptions::new()
            .read(true)
            .custom_flags(libc::O_NOFOLLOW | libc::O_NONBLOCK | libc::O_CLOEXEC)
            .open(entry.path());
        if let Ok(f) = stale {
            let regular = f.metadata().is_ok_and(|m| m.is_file());
            if regular && try_lock(&f).unwrap_or(false) {
                let _ = fs::remove_file(entry.path());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_names_are_cut_with_a_hash() {
        let long = "x".repeat(254) + ".png";
        let a = short_name(Path::new(&long));
        assert!(a.len() <= KEPT && a.starts_with("xxx"), "{a}");
        let b = short_name(Path::new(&("x".repeat(254) + ".exr")));
        assert_ne!(a, b);
        assert_eq!(short_name(Path::new("d/a.png")), "a.png");
        // A cut never splits a character.
        let wide = "é".repeat(200);
        assert!(short_name(Path::new(&wide)).len() <= KEPT);
    }

    #[test]
    fn names_are_fresh_and_stale_files_of_dead_writers_go() {
        let d = std::env::temp_dir().join(format!("rayterm-tmp-{}", std::process::id()));
        fs::create_dir_all(&d).unwrap();
        let target = d.join("x.png");
        let (a, fa) = create(&target).unwrap();
        let (b, _fb) = create(&target).unwrap();
        assert_ne!(a, b);
        // Left by a writer with this process's id, as a container's PID 1
        // after a restart; and by one that is gone.
        let mine = d.join(format!(".x.png.{}.tmp", std::process::id()));
        fs::write(&mine, b"old").unwrap();
        let gone = d.join(".x.png.2147483646-0badcafe.tmp");
        fs::write(&gone, b"old").unwrap();
        let other = d.join(".y.png.2147483646.tmp");
        fs::write(&other, b"not x's").unwrap();
        drop(fa);
        remove_stale(&target);
        let mut left: Vec<_> = fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        left.sort();
        // The unlocked one of this process's goes too: its writer is done.
        let mut want = vec![b, other];
        want.sort();
        assert_eq!(left, want);
        fs::remove_dir_all(d).unwrap();
    }
}
