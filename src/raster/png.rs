//! PNG pictures.

use anyhow::Result;

/// `img` encoded as PNG.
pub(crate) fn encode(img: &image::RgbImage) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    img.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    // The image crate's errors repeat their source; one line reads better.
    .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes)
}
