//! Animations from frames of one size: GIF and APNG, looping forever.
//!
//! A GIF holds 256 colours: one palette for every frame (their colours
//! where there are no more, else NeuQuant over pixels of all), so that a colour does not jump from frame to
//! frame as per-frame palettes would make it, and no dither, which would
//! shimmer as the picture turns. APNG keeps the frames' 24-bit colours.

use std::collections::HashMap;

use anyhow::{bail, Result};

/// Frames of `width` x `height` RGB pixels, shown `fps` a second.
pub(crate) struct Frames<'a> {
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) fps: u32,
    pub(crate) rgb: &'a [Vec<u8>],
}

impl Frames<'_> {
    fn check(&self) -> Result<()> {
        let n = self.width as usize * self.height as usize * 3;
        if self.rgb.is_empty() || self.rgb.iter().any(|f| f.len() != n) {
            bail!("an animation needs frames of one size");
        }
        if self.fps == 0 || self.fps > 100 {
            bail!("an animation shows from 1 to 100 frames a second");
        }
        Ok(())
    }
}

/// The frames as an animated GIF.
pub(crate) fn gif(f: &Frames) -> Result<Vec<u8>> {
    f.check()?;
    let (Ok(w), Ok(h)) = (u16::try_from(f.width), u16::try_from(f.height)) else {
        bail!(
            "a GIF is at most 65535 pixels on a side, not {}x{}; write an .apng",
            f.width,
            f.height
        );
    };
    let palette = Palette::of(f.rgb);
    let mut bytes = Vec::new();
    {
        let mut e = gif::Encoder::new(&mut bytes, w, h, &palette.colours()).map_err(gif_error)?;
        e.set_repeat(gif::Repeat::Infinite).map_err(gif_error)?;
        // GIF counts delays in hundredths of a second.
        let delay = (100.0 / f.fps as f64).round().max(1.0) as u16;
        for rgb in f.rgb {
            let indices: Vec<u8> = rgb.chunks_exact(3).map(|p| palette.index(p)).collect();
            let frame = gif::Frame {
                width: w,
                height: h,
                delay,
                buffer: indices.into(),
                ..gif::Frame::default()
            };
            e.write_frame(&frame).map_err(gif_error)?;
        }
    }
    Ok(bytes)
}

/// One palette for all the frames: their own colours when there are 256
/// or fewer, else NeuQuant's 256 from at most about a million of their
/// pixels (evenly spaced, so every frame is seen).
enum Palette {
    Exact(HashMap<[u8; 3], u8>),
    Learned(color_quant::NeuQuant),
}

impl Palette {
    fn of(frames: &[Vec<u8>]) -> Palette {
        let pixels = || frames.iter().flat_map(|f| f.chunks_exact(3));
        let mut exact = HashMap::new();
        for p in pixels() {
            let n = exact.len();
            exact.entry([p[0], p[1], p[2]]).or_insert(n as u8);
            if exact.len() > 256 {
                break;
            }
        }
        // `or_insert` numbered each colour as it came; 257 means too many.
        if exact.len() <= 256 {
            return Palette::Exact(exact);
        }
        const SAMPLES: usize = 1 << 20;
        let count: usize = frames.iter().map(|f| f.len() / 3).sum();
        let step = count.div_ceil(SAMPLES).max(1);
        let mut rgba = Vec::with_capacity(4 * count.div_ceil(step));
        for p in pixels().step_by(step) {
            rgba.extend_from_slice(&[p[0], p[1], p[2], 255]);
        }
        // Sample factor 10: NeuQuant's balance of speed and quality.
        Palette::Learned(color_quant::NeuQuant::new(10, 256, &rgba))
    }

    /// The palette as GIF stores it: RGB triples, by index.
    fn colours(&self) -> Vec<u8> {
        match self {
            Palette::Exact(m) => {
                let mut c = vec![0; 3 * m.len().max(2)];
                for (rgb, &i) in m {
                    c[3 * i as usize..3 * i as usize + 3].copy_from_slice(rgb);
                }
                c
            }
            Palette::Learned(q) => q.color_map_rgb(),
        }
    }

    fn index(&self, p: &[u8]) -> u8 {
        match self {
            Palette::Exact(m) => m[&[p[0], p[1], p[2]]],
            Palette::Learned(q) => q.index_of(&[p[0], p[1], p[2], 255]) as u8,
        }
    }
}

fn gif_error(e: gif::EncodingError) -> anyhow::Error {
    anyhow::anyhow!("encoding the GIF: {e}")
}

/// The frames as an animated PNG.
pub(crate) fn apng(f: &Frames) -> Result<Vec<u8>> {
    f.check()?;
    let mut bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut bytes, f.width, f.height);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.set_animated(f.rgb.len() as u32, 0).map_err(png_error)?;
        e.set_frame_delay(1, f.fps as u16).map_err(png_error)?;
        let mut w = e.write_header().map_err(png_error)?;
        for rgb in f.rgb {
            w.write_image_data(rgb).map_err(png_error)?;
        }
        w.finish().map_err(png_error)?;
    }
    Ok(bytes)
}

fn png_error(e: png::EncodingError) -> anyhow::Error {
    anyhow::anyhow!("encoding the PNG: {e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three 4x2 frames: red, green, then a gradient.
    fn frames() -> Vec<Vec<u8>> {
        let mut grad = Vec::new();
        for i in 0..8u8 {
            grad.extend_from_slice(&[i * 30, 255 - i * 30, 128]);
        }
        vec![[255, 0, 0].repeat(8), [0, 255, 0].repeat(8), grad]
    }

    #[test]
    fn apng_frames_read_back_exactly() {
        let rgb = frames();
        let bytes = apng(&Frames {
            width: 4,
            height: 2,
            fps: 10,
            rgb: &rgb,
        })
        .unwrap();
        let mut d = png::Decoder::new(std::io::Cursor::new(&bytes))
            .read_info()
            .unwrap();
        let info = d.info();
        let ctl = info.animation_control.unwrap();
        assert_eq!((ctl.num_frames, ctl.num_plays), (3, 0));
        let mut buf = vec![0; d.output_buffer_size().unwrap()];
        for want in &rgb {
            d.next_frame(&mut buf).unwrap();
            let fc = d.info().frame_control.unwrap();
            assert_eq!((fc.delay_num, fc.delay_den), (1, 10));
            assert_eq!(&buf[..24], &want[..]);
        }
    }

    /// Decodes a GIF's frames as RGB, checking that they use one palette
    /// and show `delay` hundredths of a second each.
    fn decoded(bytes: &[u8], delay: u16) -> Vec<Vec<u8>> {
        let mut o = gif::DecodeOptions::new();
        o.set_color_output(gif::ColorOutput::RGBA);
        let mut d = o.read_info(std::io::Cursor::new(bytes)).unwrap();
        assert!(d.global_palette().is_some());
        let mut frames = Vec::new();
        while let Some(f) = d.read_next_frame().unwrap() {
            assert!(f.palette.is_none());
            assert_eq!(f.delay, delay);
            frames.push(
                f.buffer
                    .chunks_exact(4)
                    .flat_map(|p| [p[0], p[1], p[2]])
                    .collect(),
            );
        }
        frames
    }

    #[test]
    fn a_gif_of_few_colours_keeps_them_exactly() {
        let rgb = frames();
        let f = Frames {
            width: 4,
            height: 2,
            fps: 25,
            rgb: &rgb,
        };
        assert_eq!(decoded(&gif(&f).unwrap(), 4), rgb);
    }

    #[test]
    fn a_gif_of_many_colours_comes_close_in_one_palette() {
        // Two 64x64 frames of smooth shading, as pictures have: colours
        // on a plane of the cube, 4,096 a frame.
        let (w, h) = (64u32, 64u32);
        let frame = |shift: u32| -> Vec<u8> {
            (0..w * h)
                .flat_map(|i| {
                    let (x, y) = (i % w, i / w);
                    let (x, y) = ((x + shift) % w, y);
                    [(4 * x) as u8, (2 * (x + y)) as u8, (4 * y) as u8]
                })
                .collect()
        };
        let rgb = vec![frame(0), frame(32)];
        let f = Frames {
            width: w,
            height: h,
            fps: 10,
            rgb: &rgb,
        };
        let back = decoded(&gif(&f).unwrap(), 10);
        assert_eq!(back.len(), 2);
        for (got, want) in back.iter().zip(&rgb) {
            let err: u64 = got
                .iter()
                .zip(want)
                .map(|(a, b)| a.abs_diff(*b) as u64)
                .sum();
            let mean = err as f64 / want.len() as f64;
            // 256 colours over the plane lie about 18 apart, so a pixel is
            // some 5 off (NeuQuant: 6.8); a palette or mapping gone wrong
            // is off by tens.
            assert!(mean < 8.0, "mean error {mean}");
        }
    }

    #[test]
    fn frames_of_two_sizes_are_refused() {
        let rgb = vec![vec![0; 24], vec![0; 21]];
        let f = Frames {
            width: 4,
            height: 2,
            fps: 10,
            rgb: &rgb,
        };
        assert!(gif(&f).is_err() && apng(&f).is_err());
    }
}
