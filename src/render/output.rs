//! Where rendered pictures go: the atomic PNG writer lives with the other
//! image files in [`crate::raster`].

use std::path::{Path, PathBuf};

pub use crate::raster::save_png_atomic;

/// `stem-N.png` for the first N that does not exist yet, in `dir`.
pub fn fresh_name(dir: &Path, stem: &str) -> PathBuf {
    (1..)
        .map(|n| dir.join(format!("{stem}-{n:03}.png")))
        .find(|p| !p.exists())
        .expect("an unused file name exists")
}
