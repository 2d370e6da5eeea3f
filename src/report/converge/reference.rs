//! Reference images as Radiance .hdr (rounded, not truncated), and the
//! cache key that decides when a rendered one can be reused.

use std::fmt::Write as _;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use glam::Vec3;
use image::codecs::hdr::{HdrDecoder, HdrEncoder};
use image::Rgb;

use crate::render::Plan;
use crate::scene::{Environment, Scene};

/// Radiance's RGBE truncates the mantissa; adding half a step first makes
/// it round, so a stored reference is unbiased.
fn round_for_rgbe(c: Vec3) -> Rgb<f32> {
    let mx = c.max_element();
    if mx <= 0.0 || !mx.is_finite() {
        return Rgb([c.x.max(0.0), c.y.max(0.0), c.z.max(0.0)]);
    }
    let half = (mx.log2().floor() + 1.0).exp2() / 512.0;
    let r = |v: f32| if v > 0.0 { v + half } else { 0.0 };
    Rgb([r(c.x), r(c.y), r(c.z)])
}

pub fn encode_hdr(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
    let px: Vec<Rgb<f32>> = img.iter().map(|&c| round_for_rgbe(c)).collect();
    let mut bytes = Vec::new();
    HdrEncoder::new(&mut bytes)
        .encode(&px, width as usize, height as usize)
        .context("encoding Radiance HDR")?;
    Ok(bytes)
}

fn decode_hdr(bytes: &[u8]) -> Result<(u32, u32, Vec<Vec3>)> {
    // The image crate's errors repeat their source in their message; one
    // line without the chain reads better.
    let flat = |e: image::ImageError| anyhow::anyhow!("{e}");
    let img = image::DynamicImage::from_decoder(HdrDecoder::new(Cursor::new(bytes)).map_err(flat)?)
        .map_err(flat)?;
    let rgb = match img {
        image::DynamicImage::ImageRgb32F(i) => i,
        other => other.to_rgb32f(),
    };
    let (w, h) = rgb.dimensions();
    let px = rgb.pixels().map(|p| Vec3::from_array(p.0)).collect();
    Ok((w, h, px))
}

/// Loads a linear reference image (Radiance .hdr), row-major from the top.
pub fn load_reference(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let bytes =
        std::fs::read(path).with_context(|| format!("cannot read reference {}", path.display()))?;
    decode_hdr(&bytes).with_context(|| {
        format!(
            "{} is not a Radiance .hdr image (a reference must be linear)",
            path.display()
        )
    })
}

/// Saves a linear image as Radiance .hdr, atomically (temporary file, rename).
pub fn save_reference(path: &Path, width: u32, height: u32, img: &[Vec3]) -> Result<()> {
    let bytes = encode_hdr(width, height, img)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let tmp = path.with_extension(format!("{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).with_context(|| format!("cannot write {}", tmp.display()))?;
    std::fs::rename(&tmp, path).with_context(|| {
        let _ = std::fs::remove_file(&tmp);
        format!("cannot rename to {}", path.display())
    })
}

/// What an image looks like after a trip through a .hdr file.
pub(super) fn quantised(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<Vec3>> {
    Ok(decode_hdr(&encode_hdr(width, height, img)?)?.2)
}

/// `$XDG_CACHE_HOME/rayterm`, else `~/.cache/rayterm`.
pub fn default_cache_dir() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache")))?;
    Some(base.join("rayterm"))
}

/// FNV-1a, 64 bit: a hash that stays the same across builds, for cache names.
struct Fnv(u64);

impl Fnv {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ x as u64).wrapping_mul(0x100_0000_01b3);
        }
    }

    fn vec3s(&mut self, v: &[Vec3]) {
        for c in v {
            for x in c.to_array() {
                self.bytes(&x.to_bits().to_le_bytes());
            }
        }
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
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
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    let _ = write!(
        h,
        "rayterm reference 1 {} {width}x{height} {spp} {seed} {:?} {} {:?} {:?} {:?} {:?} {:?}",
        env!("CARGO_PKG_VERSION"),
        plan.features,
        plan.explain(),
        scene.settings,
        scene.lights,
        scene.materials,
        scene.camera,
        scene.meshes,
    );
    let g = &scene.geometry;
    h.vec3s(&g.positions);
    h.vec3s(&g.normals);
    for uv in &g.uvs {
        h.bytes(&uv.x.to_bits().to_le_bytes());
        h.bytes(&uv.y.to_bits().to_le_bytes());
    }
    for (i, (&m, &o)) in g.indices.iter().zip(g.tri_material.iter().zip(&g.tri_mesh)) {
        let _ = write!(h, "{i:?}{m},{o};");
    }
    let mut textures: Vec<_> = scene.textures.iter().collect();
    match &scene.environment {
        Environment::Color(c) => {
            let _ = write!(h, "env {c:?}");
        }
        Environment::CubeMap(cube) => textures.extend(cube.faces.iter()),
    }
    for t in textures {
        let _ = write!(h, "tex {}x{}", t.width, t.height);
        h.vec3s(&t.texels);
    }
    h.0
}

#[cfg(test)]
mod tests {
    use super::super::luminance;
    use super::*;

    #[test]
    fn hdr_round_trip_rounds_to_within_half_a_step() {
        let img: Vec<Vec3> = (0..64)
            .map(|i| {
                Vec3::new(
                    0.013 * i as f32,
                    0.5 + 0.001 * i as f32,
                    3.7 / (i + 1) as f32,
                )
            })
            .collect();
        let back = quantised(8, 8, &img).unwrap();
        let mut bias = 0.0;
        for (a, b) in img.iter().zip(&back) {
            // One RGBE step is at most 1/128 of the largest component.
            let step = a.max_element() / 128.0;
            assert!((*a - *b).abs().max_element() <= step, "{a} -> {b}");
            bias += (luminance(*b) - luminance(*a)) / luminance(*a).max(1e-3);
        }
        assert!(
            (bias / 64.0).abs() < 1e-3,
            "mean relative bias {}",
            bias / 64.0
        );
    }
}
