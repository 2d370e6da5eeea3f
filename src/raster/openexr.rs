//! OpenEXR with 32-bit float RGB channels (through the `exr` crate): every
//! f32 stored exactly, so a reference carries no error of its own format.

use std::io::{BufReader, Seek};
use std::path::Path;

use anyhow::{bail, Result};
use exr::prelude::{ReadChannels, ReadLayers, SpecificChannels, Text, WritableImage};
use glam::Vec3;

/// `img` encoded as OpenEXR, f32 R, G and B, losslessly compressed.
pub fn encode(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
    encode_noted(width, height, img, None)
}

/// [`encode`], with a text attribute `(name, value)` saying what the image
/// is of (a cached reference: the key of its scene and settings).
pub(crate) fn encode_noted(
    width: u32,
    height: u32,
    img: &[Vec3],
    note: Option<(&str, &str)>,
) -> Result<Vec<u8>> {
    if img.len() != width as usize * height as usize {
        bail!("{} pixels for a {width}x{height} image", img.len());
    }
    let w = width as usize;
    let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let c = img[y * w + x];
        (c.x, c.y, c.z)
    });
    let mut image = exr::image::Image::from_channels((w, height as usize), channels);
    if let Some((name, value)) = note {
        let text = |t: &str| {
            exr::meta::attribute::Text::new_or_none(t)
                .ok_or_else(|| anyhow::anyhow!("{t} cannot be an OpenEXR attribute"))
        };
        image.attributes.other.insert(
            text(name)?,
            exr::meta::attribute::AttributeValue::Text(text(value)?),
        );
    }
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes.into_inner())
}

/// [`encode`] with more channels beside R, G and B: `(name, plane)` pairs,
/// each plane a value per pixel (an EXR orders its channels by name).
pub(crate) fn encode_with(
    width: u32,
    height: u32,
    img: &[Vec3],
    more: Vec<(&str, Vec<f32>)>,
) -> Result<Vec<u8>> {
    use exr::prelude::{AnyChannel, AnyChannels, Encoding, FlatSamples, Layer, LayerAttributes};
    let n = width as usize * height as usize;
    if img.len() != n || more.iter().any(|(_, p)| p.len() != n) {
        bail!("planes of another size than a {width}x{height} image");
    }
    let text = |t: &str| {
        Text::new_or_none(t).ok_or_else(|| anyhow::anyhow!("{t} cannot be an OpenEXR channel"))
    };
    let mut list = Vec::new();
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let plane = img.iter().map(|p| p[c]).collect();
        list.push(AnyChannel::new(text(name)?, FlatSamples::F32(plane)));
    }
    for (name, plane) in more {
        list.push(AnyChannel::new(
            text(name)?,
            FlatSamples::F32(plane.clone()),
        ));
    }
    let channels = AnyChannels::sort(list.into());
    let layer = Layer::new(
        (width as usize, height as usize),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        channels,
    );
    let image = exr::image::Image::from_layer(layer);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes.into_inner())
}

/// The text attribute `name` of the OpenEXR image at `path` (see
/// [`encode_noted`]), read from its header alone; `None` where it has none.
pub(crate) fn note(path: &Path, name: &str) -> Result<Option<String>> {
    let err = |e: exr::error::Error| {
        let e = crate::words::clip_quotes(&e.to_string());
        anyhow::anyhow!("{}: {e}", path.display())
    };
    let mut file = BufReader::new(super::open(path)?);
    let meta = exr::meta::MetaData::read_from_buffered(&mut file, false).map_err(err)?;
    // Written with the image's attributes, read back with the layer's.
    let value = meta.headers.first().and_then(|h| {
        let mut all = (h.own_attributes.other.iter()).chain(&h.shared_attributes.other);
        match all.find(|(k, _)| Text::eq(k, name))? {
            (_, exr::meta::attribute::AttributeValue::Text(t)) => Some(t.to_string()),
            _ => None,
        }
    });
    Ok(value)
}

/// Reads the R, G and B channels of an OpenEXR image's first layer as f32,
/// refusing sizes beyond [`super::MAX_DECODED_BYTES`] before decoding.
pub(crate) fn read(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let err = |e: exr::error::Error| {
        let e = crate::words::clip_quotes(&e.to_string());
        anyhow::anyhow!("{}: {e}", path.display())
    };
    let mut file = BufReader::new(super::open(path)?);
    let meta = exr::meta::MetaData::read_from_buffered(&mut file, false).map_err(err)?;
    for h in meta.headers.iter() {
        let (w, hh) = (h.layer_size.0, h.layer_size.1);
        let clamp = |v: usize| v.min(u32::MAX as usize) as u32;
        // The decoder's samples of every channel and the Vec3 copy.
        let per_pixel = 12 + 4 * h.channels.list.len() as u64;
        super::check_size(path, clamp(w), clamp(hh), per_pixel)?;
    }
    file.rewind()?;
    let (w, h, pixels) = rgb(file).map_err(err)?;
    Ok((w as u32, h as u32, pixels))
}

/// The R, G and B channels of the first layer that has them, as f32, with
/// its width and height: the caller has checked the sizes.
pub(crate) fn rgb(
    reader: impl std::io::BufRead + Seek,
) -> exr::error::Result<(usize, usize, Vec<Vec3>)> {
    let image = exr::image::read::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size, _| (size.0, vec![Vec3::ZERO; size.0 * size.1]),
            |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b): (f32, f32, f32)| {
                px[pos.1 * *w + pos.0] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(reader)?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.0, size.1, pixels))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_round_trip_is_bit_exact_for_finite_f32() {
        let mut r = crate::geometry::sampling::Rng::for_sample(4, 5, 6);
        let (w, h) = (37, 23);
        let mut img: Vec<Vec3> = (0..w * h)
            .map(|_| {
                let mut f = || {
                    f32::from_bits(r.next_u32() & 0x7f7f_ffff)
                        * if r.next_u32().is_multiple_of(2) {
                            1.0
                        } else {
                            -1.0
                        }
                };
                Vec3::new(f(), f(), f())
            })
            .collect();
        img[0] = Vec3::new(0.0, -0.0, f32::MAX);
        img[1] = Vec3::new(f32::MIN_POSITIVE, 1e-45, 0.30370);
        assert!(img.iter().all(|c| c.is_finite()));
        let dir = std::env::temp_dir().join(format!("rayterm-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("r.exr");
        crate::raster::write_linear(&p, w, h, &img).unwrap();
        let (rw, rh, back) = read(&p).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((rw, rh), (w, h));
        for (a, b) in img.iter().zip(&back) {
            let bits = |v: &Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(a), bits(b));
        }
    }
}
