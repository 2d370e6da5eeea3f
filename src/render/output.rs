//! Writing images so that no half-written file is ever left behind.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

/// Encodes `img` as PNG into a temporary file beside `path`, syncs it and
/// renames it into place.
pub fn save_png_atomic(img: &image::RgbImage, path: &Path) -> Result<()> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().context("output path has no file name")?;
    let tmp = dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    ));
    let result = (|| -> Result<()> {
        let mut f = std::io::BufWriter::new(
            std::fs::File::create(&tmp)
                .with_context(|| format!("cannot create {}", tmp.display()))?,
        );
        img.write_to(&mut f, image::ImageFormat::Png)
            .with_context(|| format!("cannot encode {}", path.display()))?;
        let f = f.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
            .with_context(|| format!("cannot rename to {}", path.display()))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `stem-N.png` for the first N that does not exist yet, in `dir`.
pub fn fresh_name(dir: &Path, stem: &str) -> PathBuf {
    (1..)
        .map(|n| dir.join(format!("{stem}-{n:03}.png")))
        .find(|p| !p.exists())
        .expect("an unused file name exists")
}
