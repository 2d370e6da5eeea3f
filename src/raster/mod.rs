//! Images as data: drawing onto them ([`canvas`]), measuring them against
//! a reference ([`metrics`], [`resample`]), and image files, the
//! one place rayterm reads and writes them: PNG for
//! pictures, OpenEXR (32-bit float) and Radiance `.hdr` (8-bit mantissas)
//! for linear images such as references, GIF and APNG for turntables
//! ([`animation`]). Every write goes through
//! [`Output`] (regular files replaced atomically, devices written in place),
//! and every read checks the size an image declares before decoding it.

pub(crate) mod animation;
pub(crate) mod canvas;
pub(crate) mod claim;
pub(crate) mod flat_exr;
pub(crate) mod hdr;
pub(crate) mod metrics;
pub mod openexr;
pub(crate) mod output;
pub mod png;
pub mod reference;
pub(crate) mod resample;
mod temporary;

use std::path::Path;

use anyhow::{bail, Result};

use crate::memory::bytes;
use glam::Vec3;

pub use output::{ImageFormat, Output};

/// The most memory a decoded image may take (1 GiB): a header declaring more
/// is refused before anything is allocated.
pub(crate) const MAX_DECODED_BYTES: u64 = 1 << 30;

/// Refuses a `width x height` image of `bytes_per_pixel` decoded bytes per
/// pixel beyond [`MAX_DECODED_BYTES`], naming `path` and the memory needed.
pub(crate) fn check_size(path: &Path, width: u32, height: u32, bytes_per_pixel: u64) -> Result<()> {
    let need = width as u64 * height as u64 * bytes_per_pixel;
    if need > MAX_DECODED_BYTES {
        bail!(
            "{}: a {width}x{height} image would need {} to decode; rayterm reads images up \
             to {}",
            path.display(),
            bytes(need),
            bytes(MAX_DECODED_BYTES)
        );
    }
    Ok(())
}

/// Opens `path` for reading, refusing anything but a regular file (a FIFO
/// would hang, a device would read forever), before it is opened and once
/// open (it may have been replaced in between); the error names the file,
/// as every reader's does.
fn open(path: &Path) -> Result<std::fs::File> {
    use std::os::unix::fs::OpenOptionsExt;
    let cannot = |e: std::io::Error| {
        let why = match e.kind() {
            std::io::ErrorKind::NotFound => "not found".to_string(),
            _ => output::reason(&e),
        };
        anyhow::anyhow!("cannot read {}: {why}", crate::words::path(path))
    };
    let regular = |m: std::fs::Metadata| match m.is_file() {
        true => Ok(()),
        false => Err(anyhow::anyhow!(
            "cannot read {}: not a regular file",
            crate::words::path(path)
        )),
    };
    regular(std::fs::metadata(path).map_err(cannot)?)?;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(cannot)?;
    regular(file.metadata().map_err(cannot)?)?;
    Ok(file)
}

/// Formats for linear (unclamped, untoned) images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Linear {
    /// OpenEXR, 32-bit float RGB: exact.
    Exr,
    /// Radiance RGBE: 8-bit mantissas sharing an exponent, rounded to
    /// nearest (see [`hdr`]).
    Hdr,
}

impl Linear {
    /// The format an output or input path names by its extension.
    pub(crate) fn of(path: &Path) -> Option<Linear> {
        let ext = path.extension()?.to_str()?;
        if ext.eq_ignore_ascii_case("exr") {
            Some(Linear::Exr)
        } else if ext.eq_ignore_ascii_case("hdr") {
            Some(Linear::Hdr)
        } else {
            None
        }
    }
}

/// A linear image, row-major from the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// `width * height` of them.
    pub(crate) pixels: Vec<Vec3>,
    pub(crate) format: Linear,
}

impl Image {
    pub fn pixels(&self) -> &[Vec3] {
        &self.pixels
    }
}

/// Reads a linear image, in the format its extension names.
pub fn read_linear(path: &Path) -> Result<Image> {
    let format = Linear::of(path).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: a linear image must be OpenEXR (.exr) or Radiance HDR (.hdr)",
            path.display()
        )
    })?;
    let (width, height, pixels) = match format {
        Linear::Exr => openexr::read(path)?,
        Linear::Hdr => hdr::read(path)?,
    };
    if width == 0 || height == 0 {
        bail!(
            "{}: the image has no pixels ({width}x{height})",
            path.display()
        );
    }
    Ok(Image {
        width,
        height,
        pixels,
        format,
    })
}

/// Writes a linear image, in the format its extension names.
pub fn write_linear(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<()> {
    let out = Output::check(path, &[], &[ImageFormat::Exr, ImageFormat::Hdr])?;
    out.write(&out.format.encode_linear(width, height, pixels)?)
}

/// Writes a picture as PNG.
pub(crate) fn write_png(path: &Path, img: &image::RgbImage) -> Result<()> {
    Output::check(path, &[], &[ImageFormat::Png])?.write(&png::encode(img)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_read_in_binary_units() {
        let e = check_size(Path::new("big.hdr"), 100_000, 100_000, 12).unwrap_err();
        assert_eq!(
            e.to_string(),
            "big.hdr: a 100000x100000 image would need 112 GiB to decode; rayterm reads \
             images up to 1.00 GiB"
        );
        assert!(check_size(Path::new("ok.hdr"), 4096, 4096, 12).is_ok());
    }
}
