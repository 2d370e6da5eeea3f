//! Reference images: a linear image (OpenEXR or Radiance .hdr) that errors
//! are measured against, refused where a pixel is not finite.

use std::path::Path;

use anyhow::{bail, Context, Result};
use glam::Vec3;

/// Loads a linear reference image (.exr or .hdr by its extension),
/// row-major from the top.
/// Every pixel must be finite (see [`check_finite`]).
pub fn load_reference(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let img = super::read_linear(path)
        .with_context(|| format!("cannot load the reference {}", path.display()))?;
    check_finite(path, img.width, &img.pixels)?;
    Ok((img.width, img.height, img.pixels))
}

/// Refuses a reference read from `path` (`width` pixels a row) with a
/// pixel that is NaN or infinite: every error measured against it would
/// be NaN.
pub(crate) fn check_finite(path: &Path, width: u32, pixels: &[Vec3]) -> Result<()> {
    match pixels.iter().position(|p| !p.is_finite()) {
        Some(i) => {
            let w = width.max(1) as usize;
            bail!(
                "cannot use the reference {}: pixel ({}, {}) is {}; a reference must be finite",
                path.display(),
                i % w,
                i / w,
                pixels[i]
            )
        }
        None => Ok(()),
    }
}
