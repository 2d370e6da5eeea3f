//! OpenEXR with 32-bit float RGB channels: every f32 stored exactly, so a
//! reference carries no error of its own format; and images of any named
//! f32 and u32 channels with text attributes, which partial films are
//! (through the `exr` crate).

use std::collections::HashMap;
use std::io::{BufReader, Seek};
use std::path::Path;

use anyhow::{bail, Result};
use exr::prelude::{ReadChannels, ReadLayers, SpecificChannels, WritableImage};
use glam::Vec3;

/// `img` encoded as OpenEXR, f32 R, G and B, losslessly compressed.
pub fn encode(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
    if img.len() != width as usize * height as usize {
        bail!("{} pixels for a {width}x{height} image", img.len());
    }
    let w = width as usize;
    let channels = SpecificChannels::rgb(|exr::math::Vec2(x, y): exr::math::Vec2<usize>| {
        let c = img[y * w + x];
        (c.x, c.y, c.z)
    });
    let image = exr::image::Image::from_channels((w, height as usize), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes.into_inner())
}

/// Reads the R, G and B channels of an OpenEXR image's first layer as f32,
/// refusing sizes beyond [`super::MAX_DECODED_BYTES`] before decoding.
pub fn read(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    let err = |e: exr::error::Error| anyhow::anyhow!("{}: {e}", path.display());
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
        .from_buffered(file)
        .map_err(err)?;
    let size = image.layer_data.size;
    let (_, pixels) = image.layer_data.channel_data.pixels;
    Ok((size.0 as u32, size.1 as u32, pixels))
}

/// One channel's samples, row-major.
#[derive(Clone, Debug, PartialEq)]
pub enum Samples {
    F32(Vec<f32>),
    U32(Vec<u32>),
}

/// An image of named channels and text attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Channels {
    pub width: u32,
    pub height: u32,
    pub channels: HashMap<String, Samples>,
    pub attributes: HashMap<String, String>,
}

/// `c` encoded as OpenEXR: one layer, its channels uncompressed (a merge
/// reads them back with no decompression on the way); attribute values
/// that are not Latin-1 have those characters replaced by `?`
/// ([`stored_text`]).
pub fn encode_channels(c: &Channels) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let (w, h) = (c.width as usize, c.height as usize);
    let mut list = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (name, s) in &c.channels {
        let samples = match s {
            Samples::F32(v) => FlatSamples::F32(v.clone()),
            Samples::U32(v) => FlatSamples::U32(v.clone()),
        };
        let len = match s {
            Samples::F32(v) => v.len(),
            Samples::U32(v) => v.len(),
        };
        if len != w * h {
            bail!("channel {name}: {len} samples for a {w}x{h} image");
        }
        list.push(AnyChannel::new(text(name), samples));
    }
    let mut attributes = LayerAttributes::default();
    for (k, v) in &c.attributes {
        attributes
            .other
            .insert(text(k), AttributeValue::Text(text(v)));
    }
    let encoding = Encoding {
        compression: Compression::Uncompressed,
        ..Encoding::default()
    };
    let layer = Layer::new((w, h), attributes, encoding, AnyChannels::sort(list));
    let mut bytes = std::io::Cursor::new(Vec::new());
    Image::from_layer(layer)
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes.into_inner())
}

fn text(s: &str) -> exr::meta::attribute::Text {
    exr::meta::attribute::Text::new_or_none(stored_text(s)).unwrap_or_default()
}

/// `s` as an attribute reads back: characters beyond Latin-1 become `?`.
pub fn stored_text(s: &str) -> String {
    s.chars()
        .map(|c| if (c as u32) < 256 { c } else { '?' })
        .collect()
}

/// The size and text attributes of an image of named channels, from its
/// header alone; `admit` sees the size and channel count the header
/// declares and may refuse them.
pub fn read_header(
    path: &Path,
    admit: &dyn Fn(u32, u32, usize) -> Result<()>,
) -> Result<(u32, u32, HashMap<String, String>)> {
    let mut file = BufReader::new(super::open(path)?);
    header(path, &mut file, admit)
}

/// Reads the one flat layer's header from `file`, leaving it wherever the
/// header ends.
fn header(
    path: &Path,
    file: &mut BufReader<std::fs::File>,
    admit: &dyn Fn(u32, u32, usize) -> Result<()>,
) -> Result<(u32, u32, HashMap<String, String>)> {
    let meta =
        exr::meta::MetaData::read_from_buffered(file, false).map_err(|e| unreadable(path, e))?;
    let [h] = meta.headers.as_slice() else {
        bail!(
            "{}: {} layers; expected one",
            path.display(),
            meta.headers.len()
        );
    };
    if h.deep {
        bail!("{}: deep data; expected a flat image", path.display());
    }
    let (w, hh) = (clamp(h.layer_size.0), clamp(h.layer_size.1));
    admit(w, hh, h.channels.list.len())?;
    Ok((w, hh, texts(&h.own_attributes.other)))
}

fn clamp(v: usize) -> u32 {
    v.min(u32::MAX as usize) as u32
}

fn unreadable(path: &Path, e: exr::error::Error) -> anyhow::Error {
    anyhow::anyhow!("{}: not a readable OpenEXR file ({e})", path.display())
}

/// The text attributes among `a`.
fn texts(
    a: &HashMap<exr::meta::attribute::Text, exr::meta::attribute::AttributeValue>,
) -> HashMap<String, String> {
    a.iter()
        .filter_map(|(k, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect()
}

/// Reads an image of named channels (one flat layer, f32 and u32 samples)
/// and its text attributes; `admit` sees the size and channel count the
/// header declares and may refuse them before anything is decoded.
pub fn read_channels(
    path: &Path,
    admit: &dyn Fn(u32, u32, usize) -> Result<()>,
) -> Result<Channels> {
    use exr::prelude::*;
    let err = |e: exr::error::Error| unreadable(path, e);
    let mut file = BufReader::new(super::open(path)?);
    header(path, &mut file, admit)?;
    file.rewind()?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(file)
        .map_err(err)?;
    let layer = image.layer_data;
    let mut out = Channels {
        width: clamp(layer.size.0),
        height: clamp(layer.size.1),
        ..Channels::default()
    };
    for ch in layer.channel_data.list {
        let s = match ch.sample_data {
            FlatSamples::F32(v) => Samples::F32(v),
            FlatSamples::U32(v) => Samples::U32(v),
            FlatSamples::F16(_) => bail!("{}: channel {} is half float", path.display(), ch.name),
        };
        out.channels.insert(ch.name.to_string(), s);
    }
    out.attributes = texts(&layer.attributes.other);
    Ok(out)
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
