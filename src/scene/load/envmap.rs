//! Environment maps read from files, and the environment light the
//! command line asks for (`--env`): a map decoded by what its bytes hold,
//! texels that cannot be radiance read as 0.

use std::io::Cursor;
use std::path::Path;
use std::sync::Arc;

use anyhow::{anyhow, bail, Context, Result};
use glam::Vec3;
use image::ImageDecoder;

use super::source::{FileKind, Source};
use crate::memory;
use crate::scene::envlight::{EnvLight, DISTRIBUTION_BYTES};
use crate::scene::show::show;
use crate::scene::texture::{image_error, Encoding, Texture, Wrap, TEXEL_BYTES, TEXTURE_BUDGET};
use crate::words::{clip_quotes, count, quoted};

/// The formats a map may be in, as messages list them.
const MAP_FORMATS: &str = "Radiance .hdr, OpenEXR .exr, PNG, JPEG or WebP";

/// The first bytes of every OpenEXR file.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The map file at `path`, read through `src`; errors name the file.
/// Texel values that cannot be radiance (negative, not finite) are
/// read as 0, with a warning.
pub(crate) fn read(src: &dyn Source, path: &Path, warnings: &mut Vec<String>) -> Result<EnvLight> {
    let bytes = src.read(path, FileKind::Image)?;
    let shown = crate::words::path(path);
    let mut texture = decode(&shown, &bytes)
        .map_err(|e| anyhow!("{shown}: {}", clip_quotes(&format!("{e:#}"))))?;
    let bad = clean(Arc::make_mut(&mut texture.texels).as_mut_slice());
    if bad > 0 {
        warnings.push(format!(
            "{shown}: {} negative or not finite: read as 0",
            count(bad as u64, "texel value", "texel values")
        ));
    }
    Ok(EnvLight::from_map(texture))
}

/// An environment light as the command line asks for it (`--env`,
/// `--env-strength`, `--env-rotate`), checked and read as the scene opens.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvRequest {
    /// A map file, a grey level (`0.5`) or a linear colour (`0.2,0.3,0.5`).
    pub(crate) given: String,
    pub(crate) strength: f32,
    /// Degrees about +Y.
    pub(crate) rotate: f32,
}

impl EnvRequest {
    /// The light asked for, a map read through `src`.
    pub(crate) fn light(&self, src: &dyn Source, warnings: &mut Vec<String>) -> Result<EnvLight> {
        let show = |x: f32| show(x as f64);
        if !(self.strength >= 0.0 && self.strength.is_finite()) {
            bail!(
                "--env-strength {}: the strength must be a finite number, 0 or more",
                show(self.strength)
            );
        }
        if !self.rotate.is_finite() {
            bail!(
                "--env-rotate {}: the rotation must be a finite number of degrees",
                show(self.rotate)
            );
        }
        let given = quoted(&self.given);
        let light = match colour(&self.given) {
            Some(c) => EnvLight::constant(c.map_err(|why| anyhow!("--env {given}: {why}"))?),
            None => read(src, Path::new(&self.given), warnings)
                .with_context(|| format!("--env {given}"))?,
        };
        Ok(light.scaled(self.strength).rotated(self.rotate))
    }
}

/// `--env` as a colour: one number (grey) or three (R, G, B); `None` when
/// it is not numbers (then it names a file).
fn colour(s: &str) -> Option<Result<Vec3, String>> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().ok())
        .collect::<Option<_>>()?;
    let c = match parts[..] {
        [grey] => Vec3::splat(grey),
        [r, g, b] => Vec3::new(r, g, b),
        _ => {
            return Some(Err(format!(
                "a colour is one number (grey) or three (R,G,B), not {}",
                parts.len()
            )))
        }
    };
    Some(match c.is_finite() && c.min_element() >= 0.0 {
        true => Ok(c),
        false => Err("a colour's components must be finite numbers, 0 or more".into()),
    })
}

/// Channels that cannot be radiance (negative, NaN, infinite) made 0;
/// returns how many texels had one.
fn clean(texels: &mut [Vec3]) -> usize {
    let mut bad = 0;
    for t in texels {
        if !(t.is_finite() && t.min_element() >= 0.0) {
            *t = Vec3::from_array(t.to_array().map(|c| match c.is_finite() {
                true => c.max(0.0),
                false => 0.0,
            }));
            bad += 1;
        }
    }
    bad
}

/// Refuses a `w` x `h` map whose decoding takes `decoding` bytes when it
/// and the map's texels and distribution would take more than
/// [`TEXTURE_BUDGET`] or the memory available.
fn check_size(w: u64, h: u64, decoding: u64) -> Result<()> {
    if w == 0 || h == 0 {
        bail!("the image has no pixels ({w}x{h})");
    }
    let kept = (w.saturating_mul(h)).saturating_mul(TEXEL_BYTES + DISTRIBUTION_BYTES);
    memory::check(
        &format!("a {w}x{h} environment map"),
        decoding.saturating_add(kept),
        Some((TEXTURE_BUDGET, "per texture")),
    )
}

/// A map's texels from its file's bytes, by what the bytes hold: OpenEXR
/// and Radiance HDR as they are, PNG, JPEG and WebP sRGB-decoded. A map
/// too large ([`check_size`]) is refused before it is decoded.
fn decode(name: &str, bytes: &[u8]) -> Result<Texture> {
    if bytes.starts_with(&EXR_MAGIC) {
        return decode_exr(name, bytes);
    }
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| anyhow!("{e}"))?;
    let Some(format) = reader.format() else {
        bail!("not an image rayterm reads as an environment map ({MAP_FORMATS})");
    };
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(TEXTURE_BUDGET);
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(image_error)?;
    let (w, h) = decoder.dimensions();
    let linear = format == image::ImageFormat::Hdr;
    let converted = match (linear, decoder.color_type()) {
        (true, image::ColorType::Rgb32F) | (false, image::ColorType::Rgb8) => 0,
        (true, _) => TEXEL_BYTES,
        (false, _) => 3,
    };
    let texels = w as u64 * h as u64;
    check_size(
        w as u64,
        h as u64,
        decoder.total_bytes() + texels * converted,
    )?;
    let img = image::DynamicImage::from_decoder(decoder).map_err(image_error)?;
    if !linear {
        return Ok(Texture::from_image(name, img, Encoding::Srgb));
    }
    let rgb = img.into_rgb32f();
    Ok(Texture {
        name: name.to_string(),
        width: w,
        height: h,
        texels: Arc::new(rgb.pixels().map(|p| Vec3::from(p.0)).collect()),
        wrap: [Wrap::Repeat; 2],
        tint: Vec3::ONE,
        uv: Default::default(),
    })
}

/// The R, G and B channels of an OpenEXR map's first layer that has them,
/// as f32.
fn decode_exr(name: &str, bytes: &[u8]) -> Result<Texture> {
    let err = |e: exr::error::Error| anyhow!("{}", clip_quotes(&e.to_string()));
    let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(err)?;
    for layer in &meta.headers {
        let (w, h) = (layer.layer_size.0 as u64, layer.layer_size.1 as u64);
        // The decoder's samples of every channel, at most 4 bytes each.
        let channels = layer.channels.list.len() as u64;
        check_size(w, h, w.saturating_mul(h).saturating_mul(4 * channels))?;
    }
    let (w, h, texels) = crate::raster::openexr::rgb(Cursor::new(bytes)).map_err(err)?;
    Ok(Texture {
        name: name.to_string(),
        width: w as u32,
        height: h as u32,
        texels: Arc::new(texels),
        wrap: [Wrap::Repeat; 2],
        tint: Vec3::ONE,
        uv: Default::default(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_decode_by_their_bytes() {
        let px = [Vec3::new(0.5, 1.0, 2.0), Vec3::new(4.0, 0.25, 0.0)];
        let hdr = crate::raster::hdr::encode(2, 1, &px).unwrap();
        let t = decode("m.hdr", &hdr).unwrap();
        assert_eq!((t.width, t.height, &t.texels[..]), (2, 1, &px[..]));
        let exr = crate::raster::openexr::encode(1, 2, &px).unwrap();
        let t = decode("m.exr", &exr).unwrap();
        assert_eq!((t.width, t.height, &t.texels[..]), (1, 2, &px[..]));
        // PNG is sRGB: 188 is about a half of linear light.
        let png = image::RgbImage::from_pixel(1, 1, image::Rgb([188, 188, 188]));
        let mut bytes = Vec::new();
        png.write_to(&mut Cursor::new(&mut bytes), image::ImageFormat::Png)
            .unwrap();
        let t = decode("m.png", &bytes).unwrap();
        assert!((t.texels[0].x - 0.5).abs() < 0.01, "{}", t.texels[0]);
        let e = decode("m.hdr", b"not an image").unwrap_err().to_string();
        assert!(e.contains("not an image"), "{e}");
        // A header asking for 200000 x 100000 texels is refused before them.
        let huge = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 200000\n";
        let e = format!("{:#}", decode("m.hdr", huge).unwrap_err());
        assert!(
            e.contains("200000x100000 environment map would need"),
            "{e}"
        );
        // Cut short: an error, no panic.
        let e = decode("m.hdr", &hdr[..hdr.len() - 2]).unwrap_err();
        assert!(!e.to_string().is_empty());
        let e = decode("m.exr", &exr[..exr.len() / 2]).unwrap_err();
        assert!(!e.to_string().is_empty());
    }

    #[test]
    fn loading_names_the_file_and_cleans_what_cannot_be_radiance() {
        use super::super::source::Memory;
        let px = [
            Vec3::new(-1.0, 1.0, 2.0),
            Vec3::new(f32::INFINITY, 0.5, f32::NAN),
        ];
        let exr = crate::raster::openexr::encode(2, 1, &px).unwrap();
        let src = Memory::default()
            .with("sky.exr", exr)
            .with("bad.hdr", b"#?RADIANCE\n".to_vec());
        let mut warnings = Vec::new();
        let l = read(&src, Path::new("sky.exr"), &mut warnings).unwrap();
        let t = l.map().unwrap();
        assert_eq!(
            t.texels[..],
            [Vec3::new(0.0, 1.0, 2.0), Vec3::new(0.0, 0.5, 0.0)]
        );
        assert_eq!(
            warnings,
            ["sky.exr: 2 texel values negative or not finite: read as 0"]
        );
        let e = format!(
            "{:#}",
            read(&src, Path::new("bad.hdr"), &mut warnings).unwrap_err()
        );
        assert!(e.starts_with("bad.hdr: "), "{e}");
        let e = format!(
            "{:#}",
            read(&src, Path::new("no.hdr"), &mut warnings).unwrap_err()
        );
        assert!(e.contains("no.hdr") && e.contains("not found"), "{e}");
    }

    #[test]
    fn the_command_line_gives_a_colour_or_a_file_and_refuses_what_is_not_light() {
        let src = super::super::source::Memory::default();
        let ask = |given: &str, strength: f32, rotate: f32| {
            let r = EnvRequest {
                given: given.into(),
                strength,
                rotate,
            };
            r.light(&src, &mut Vec::new()).map_err(|e| format!("{e:#}"))
        };
        let l = ask("0.5", 2.0, 0.0).unwrap();
        assert_eq!((l.color(), l.strength()), (Some(Vec3::splat(0.5)), 2.0));
        assert_eq!(l.eval(Vec3::Y), Vec3::ONE);
        let l = ask(" 0.2, 0.3,0.5", 1.0, 45.0).unwrap();
        assert_eq!(
            (l.color(), l.rotation()),
            (Some(Vec3::new(0.2, 0.3, 0.5)), 45.0)
        );
        for (given, strength, rotate, says) in [
            ("-0.5", 1.0, 0.0, "--env -0.5: a colour's components"),
            (
                "0.1,nan,0.2",
                1.0,
                0.0,
                "--env 0.1,nan,0.2: a colour's components",
            ),
            ("1,2", 1.0, 0.0, "one number (grey) or three (R,G,B), not 2"),
            ("0.5", -1.0, 0.0, "--env-strength -1: the strength must be"),
            ("0.5", f32::NAN, 0.0, "--env-strength NaN"),
            ("0.5", 1.0, f32::INFINITY, "--env-rotate inf"),
            (
                "sky.hdr",
                1.0,
                0.0,
                "--env sky.hdr: cannot read image sky.hdr: not found",
            ),
        ] {
            let e = ask(given, strength, rotate).unwrap_err();
            assert!(e.contains(says), "{given}: {e}");
        }
    }
}
