//! Where scene files come from: the file system, or the files compiled into
//! the binary for the built-in scenes. Both go through the same loaders.

use std::path::{Component, Path, PathBuf};

pub trait Source: Sync {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>>;
}

pub struct Disk;

impl Source for Disk {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        std::fs::read(path)
    }
}

/// Files embedded in the binary, keyed by their path under `data/`.
pub struct Embedded(pub &'static [(&'static str, &'static [u8])]);

impl Source for Embedded {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let key = normalize(path);
        self.0
            .iter()
            .find(|(name, _)| Path::new(name) == key)
            .map(|(_, bytes)| bytes.to_vec())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not a built-in file"))
    }
}

/// Removes `.` and resolves `..` lexically (embedded paths have no symlinks).
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

/// Resolves a path written inside a file at `base`: relative to its folder,
/// with Windows backslashes accepted.
pub fn resolve(base: &Path, written: &str) -> PathBuf {
    let cleaned = written.trim().trim_matches('"').replace('\\', "/");
    let p = Path::new(&cleaned);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        normalize(&base.parent().unwrap_or(Path::new("")).join(p))
    }
}

/// Files held in memory, keyed by path: scenes built or mutated in code (the
/// stability battery, tests, fuzzing) load through the ordinary loaders.
#[derive(Clone, Debug, Default)]
pub struct Memory(pub Vec<(PathBuf, Vec<u8>)>);

impl Memory {
    pub fn with(mut self, path: &str, bytes: impl Into<Vec<u8>>) -> Self {
        self.0.push((normalize(Path::new(path)), bytes.into()));
        self
    }
}

impl Source for Memory {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let key = normalize(path);
        self.0
            .iter()
            .find(|(p, _)| *p == key)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
    }
}
