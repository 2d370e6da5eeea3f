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

/// The 8-bit RGB pixels of the PNG at `path` (grey, alpha and 16 bits
/// made so), with its size; its declared size is checked before decoding.
pub(crate) fn read_rgb(path: &std::path::Path) -> Result<(u32, u32, Vec<u8>)> {
    let named = |e: png::DecodingError| anyhow::anyhow!("{}: {e}", crate::words::path(path));
    let file = std::io::BufReader::new(super::open(path)?);
    let mut d = png::Decoder::new(file);
    d.set_transformations(png::Transformations::normalize_to_color8());
    let mut r = d
        .read_info()
        .map_err(|e| anyhow::anyhow!("{}: not a PNG picture ({e})", crate::words::path(path)))?;
    let (w, h) = (r.info().width, r.info().height);
    super::check_size(path, w, h, 4)?;
    let mut buf = vec![0; r.output_buffer_size().unwrap_or(0)];
    let f = r.next_frame(&mut buf).map_err(named)?;
    let px = &buf[..f.buffer_size()];
    let rgb = match f.color_type {
        png::ColorType::Rgb => px.to_vec(),
        png::ColorType::Rgba => px
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect(),
        png::ColorType::Grayscale => px.iter().flat_map(|&g| [g, g, g]).collect(),
        png::ColorType::GrayscaleAlpha => px
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0]])
            .collect(),
        png::ColorType::Indexed => anyhow::bail!(
            "{}: an indexed PNG was not expanded",
            crate::words::path(path)
        ),
    };
    Ok((w, h, rgb))
}
