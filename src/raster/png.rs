//! PNG pictures.

use std::path::Path;

use anyhow::Result;

/// Encodes `img` as PNG, atomically ([`super::atomic::write`]).
pub fn save_png_atomic(img: &image::RgbImage, path: &Path) -> Result<()> {
    super::atomic::write(path, |w| {
        // The image crate's errors repeat their source; one line reads better.
        img.write_to(w, image::ImageFormat::Png)
            .map_err(|e| anyhow::anyhow!("{e}"))
    })
}
