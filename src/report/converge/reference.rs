//! Reference images (linear OpenEXR or Radiance .hdr, read and written by
//! [`crate::raster`]), the floor a reference's format puts under the errors
//! measured against it, and the cache key that decides when a rendered one
//! can be reused.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Result;
use glam::Vec3;

use super::luminance;
use crate::color::LUMA;
use crate::raster::{self, Linear};
use crate::render::content::{self, Fnv};
use crate::render::Plan;
use crate::scene::Scene;

/// Saves a linear image atomically, as OpenEXR or .hdr by its extension.
pub fn save_reference(path: &Path, width: u32, height: u32, img: &[Vec3]) -> Result<()> {
    raster::write_linear(path, width, height, img)
}

/// The attribute a cached reference carries its [`reference_key`] in.
const KEY: &str = "rayterm.reference";

/// Caches a rendered reference as OpenEXR, with the key of what it is of.
pub(super) fn save_cached(
    path: &Path,
    key: u64,
    width: u32,
    height: u32,
    img: &[Vec3],
) -> Result<()> {
    let bytes =
        raster::openexr::encode_noted(width, height, img, Some((KEY, &format!("{key:016x}"))))?;
    raster::Output::check(path, &[], &[raster::ImageFormat::Exr])?.write(&bytes)
}

/// A cached reference of `key` at `width` x `height`; an error saying why
/// not when the file is of something else (its name is no proof: a cache
/// is a folder anyone may copy files into) or unreadable.
pub(super) fn load_cached(path: &Path, key: u64, width: u32, height: u32) -> Result<Vec<Vec3>> {
    let held = raster::openexr::note(path, KEY)?;
    if held.as_deref() != Some(format!("{key:016x}").as_str()) {
        anyhow::bail!(
            "it is of another scene or settings (its key is {}, this study's {key:016x})",
            held.map_or("missing".into(), |k| crate::words::quoted(&k))
        );
    }
    let (w, h, img) = raster::reference::load_reference(path)?;
    if (w, h) != (width, height) {
        anyhow::bail!("it is {w}x{h}, the study {width}x{height}");
    }
    Ok(img)
}

/// The relative error (root relMSE, as `converge` measures it) that
/// storing `img` in `format` adds by itself: rounding to a step `s` is an
/// error of variance `s²/12` per channel. Errors measured against such a
/// reference cannot fall below it. Zero for OpenEXR (f32 rounding is some
/// 1e-8).
pub(crate) fn format_floor(format: Linear, img: &[Vec3]) -> f64 {
    if format == Linear::Exr || img.is_empty() {
        return 0.0;
    }
    let w2 = LUMA.as_dvec3().length_squared();
    let sum: f64 = img
        .iter()
        .map(|&c| {
            let s = raster::hdr::step(c) as f64;
            let l = luminance(c);
            w2 * s * s / 12.0 / (l * l + crate::render::film::REL_EPS)
        })
        .sum();
    (sum / img.len() as f64).sqrt()
}

/// `$XDG_CACHE_HOME/rayterm`, else `~/.cache/rayterm`.
pub(crate) fn default_cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("rayterm"))
}

/// Everything that decides a reference's pixels.
pub(super) fn reference_key(
    scene: &Scene,
    plan: &Plan,
    width: u32,
    height: u32,
    spp: u32,
    seed: u64,
) -> u64 {
    let mut h = Fnv::new();
    let _ = write!(
        h,
        "rayterm reference 2 {:016x} {width}x{height} {spp} {seed}",
        content::scene_hash(scene, plan)
    );
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hdr_has_a_floor_and_exr_none() {
        let img: Vec<Vec3> = (0..64)
            .map(|i| Vec3::splat(0.1 + 0.01 * i as f32))
            .collect();
        assert_eq!(format_floor(Linear::Exr, &img), 0.0);
        let f = format_floor(Linear::Hdr, &img);
        // Half a step is 1/512 to 1/256 of a pixel: about 0.1 % rms.
        assert!((5e-4..3e-3).contains(&f), "{f}");
    }
}
