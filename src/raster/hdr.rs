//! Radiance `.hdr` (RGBE): 8-bit mantissas sharing one exponent per pixel,
//! so a stored value is off by up to half a step, `2^(e-9)` where `2^e`
//! bounds the pixel's largest channel: up to 0.2-0.4 % of it. Fine for
//! viewing; not a reference for errors below that (OpenEXR is exact).

use std::io::BufReader;
use std::path::Path;

use anyhow::Result;
use glam::Vec3;
use image::codecs::hdr::{HdrDecoder, HdrEncoder};
use image::{ImageDecoder, Rgb};

/// The largest value RGBE holds: mantissa 255 with the largest exponent.
const MAX: f64 = 255.0 * (1u128 << 119) as f64;

/// `c` rounded to the nearest value RGBE can hold (negative and NaN
/// channels to 0, values beyond its range to its largest): the encoder
/// truncates, so it gets values it stores exactly.
pub(crate) fn quantise(c: Vec3) -> Vec3 {
    let c = c
        .as_dvec3()
        .to_array()
        .map(|x| if x > 0.0 { x.min(MAX) } else { 0.0 });
    let mx = c[0].max(c[1]).max(c[2]);
    if mx == 0.0 {
        return Vec3::ZERO;
    }
    // mx = f 2^e with f in [0.5, 1); mantissas are multiples of 2^(e-8).
    let mut e = ((mx.to_bits() >> 52) & 0x7ff) as i32 - 1022;
    if (mx * exp2(8 - e)).round() >= 256.0 {
        e += 1;
    }
    // Radiance's exponent byte is e + 128, at least 1.
    if e + 128 < 1 {
        return Vec3::ZERO;
    }
    let step = exp2(e - 8);
    let q = c.map(|x| ((x / step).round().min(255.0) * step) as f32);
    Vec3::from_array(q)
}

fn exp2(e: i32) -> f64 {
    (e as f64).exp2()
}

/// The rounding step of a stored pixel: `2^(e-8)` for its largest channel.
pub(crate) fn step(c: Vec3) -> f32 {
    let q = quantise(c);
    let mx = q.max_element() as f64;
    if mx == 0.0 {
        return 0.0;
    }
    let e = ((mx.to_bits() >> 52) & 0x7ff) as i32 - 1022;
    exp2(e - 8) as f32
}

/// `img` encoded as Radiance HDR, each pixel rounded to nearest.
pub(crate) fn encode(width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
    let px: Vec<Rgb<f32>> = img.iter().map(|&c| Rgb(quantise(c).to_array())).collect();
    let mut bytes = Vec::new();
    HdrEncoder::new(&mut bytes)
        .encode(&px, width as usize, height as usize)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(bytes)
}

/// Reads a Radiance HDR image, refusing sizes beyond
/// [`super::MAX_DECODED_BYTES`] before decoding.
pub(crate) fn read(path: &Path) -> Result<(u32, u32, Vec<Vec3>)> {
    // The image crate's errors repeat their source in their message; one
    // line without the chain reads better.
    let flat = |e: image::ImageError| match e {
        image::ImageError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            anyhow::anyhow!("{}: the Radiance HDR image ends early", path.display())
        }
        e => anyhow::anyhow!(
            "{}: {}",
            path.display(),
            crate::words::clip_quotes(&e.to_string())
        ),
    };
    let file = super::open(path)?;
    let dec = HdrDecoder::new(BufReader::new(file)).map_err(flat)?;
    let (w, h) = dec.dimensions();
    // The decoder's f32 RGB and the Vec3 copy.
    super::check_size(path, w, h, 24)?;
    let mut buf = vec![0u8; dec.total_bytes() as usize];
    dec.read_image(&mut buf).map_err(flat)?;
    let px = buf
        .chunks_exact(12)
        .map(|c| {
            let f = |i: usize| f32::from_ne_bytes(c[i..i + 4].try_into().expect("4 bytes"));
            Vec3::new(f(0), f(4), f(8))
        })
        .collect();
    Ok((w, h, px))
}

/// The image as a trip through a `.hdr` file leaves it.
#[cfg(test)]
pub(crate) fn round_trip(img: &[Vec3]) -> Vec<Vec3> {
    img.iter().map(|&c| quantise(c)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An empty file, a header alone and pixels cut short say the image
    /// ends early, naming the file (where the decoder's own words were
    /// "failed to fill whole buffer").
    #[test]
    fn a_truncated_image_says_so() {
        let d = std::env::temp_dir().join(format!("rayterm-hdr-cut-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        let whole = encode(8, 8, &[Vec3::splat(0.5); 64]).unwrap();
        // The header, its blank line and the dimensions line.
        let blank = whole.windows(2).position(|w| w == b"\n\n").unwrap() + 2;
        let header = blank + whole[blank..].iter().position(|&b| b == b'\n').unwrap() + 1;
        for len in [0, header, whole.len() - 3] {
            let p = d.join(format!("cut-{len}.hdr"));
            std::fs::write(&p, &whole[..len]).unwrap();
            let e = format!("{:#}", read(&p).unwrap_err());
            assert!(
                e.ends_with(".hdr: the Radiance HDR image ends early"),
                "{len}: {e}"
            );
        }
        std::fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn rounding_is_to_nearest_within_half_a_step() {
        // The case that lost 1 %: a largest channel just below a power of
        // two used to push the exponent up and truncate the others.
        let c = Vec3::new(0.4995, 0.3037, 0.3037);
        let q = quantise(c);
        assert!((q.y - 0.3037).abs() <= step(c) / 2.0, "{q}");
        let mut r = crate::geometry::sampling::Rng::for_sample(1, 2, 3);
        for i in 0..100_000 {
            let scale = (i % 60) as f32 - 30.0;
            let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * scale.exp2();
            let q = quantise(c);
            let half = step(c) / 2.0;
            assert!(
                ((q - c).abs()).max_element() <= half,
                "{c} -> {q}, half step {half}"
            );
        }
        assert_eq!(quantise(Vec3::new(-1.0, f32::NAN, 0.0)), Vec3::ZERO);
        assert!(quantise(Vec3::splat(f32::INFINITY)).is_finite());
    }

    #[test]
    fn a_file_round_trip_is_within_half_a_step_and_unbiased() {
        let img: Vec<Vec3> = (0..64)
            .map(|i| {
                Vec3::new(
                    0.013 * i as f32,
                    0.5 + 0.001 * i as f32,
                    3.7 / (i + 1) as f32,
                )
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("rayterm-hdr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("r.hdr");
        crate::raster::write_linear(&p, 8, 8, &img).unwrap();
        let (w, h, back) = read(&p).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!((w, h), (8, 8));
        assert_eq!(back, round_trip(&img));
        let mut bias = 0.0;
        for (a, b) in img.iter().zip(&back) {
            assert!(
                (*a - *b).abs().max_element() <= step(*a) / 2.0,
                "{a} -> {b}"
            );
            bias += (b.y - a.y) as f64 / a.y as f64;
        }
        assert!(
            (bias / 64.0).abs() < 1e-3,
            "mean relative bias {}",
            bias / 64.0
        );
    }

    #[test]
    fn a_tiny_header_declaring_a_huge_image_is_refused() {
        let dir = std::env::temp_dir().join(format!("rayterm-hdr-big-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("big.hdr");
        std::fs::write(
            &p,
            "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n",
        )
        .unwrap();
        let e = read(&p).unwrap_err().to_string();
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(
            e.contains("big.hdr") && e.contains("100000x100000") && e.contains("GiB"),
            "{e}"
        );
    }
}
