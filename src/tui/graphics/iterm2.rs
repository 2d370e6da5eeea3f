//! iTerm2 inline images: a PNG, base64, shown over a given number of cells
//! from the cursor.

use std::io::Write;

use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::ImageEncoder;

/// The `w x h` sRGB pixels as an inline image over `cols x rows` cells.
pub(crate) fn encode(px: &[[u8; 3]], w: usize, h: usize, (cols, rows): (u16, u16)) -> Vec<u8> {
    let mut png = Vec::new();
    let encoder = PngEncoder::new_with_quality(&mut png, CompressionType::Fast, FilterType::Sub);
    if encoder
        .write_image(
            px.as_flattened(),
            w as u32,
            h as u32,
            image::ExtendedColorType::Rgb8,
        )
        .is_err()
    {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(png.len() * 4 / 3 + 96);
    let _ = write!(
        out,
        "\x1b]1337;File=inline=1;size={};width={cols};height={rows};preserveAspectRatio=0:",
        png.len()
    );
    out.extend_from_slice(STANDARD.encode(&png).as_bytes());
    out.push(0x07);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_png_inside_is_the_image() {
        let (w, h) = (20, 9);
        let px: Vec<[u8; 3]> = (0..w * h).map(|i| [i as u8, 3, (255 - i) as u8]).collect();
        let data = encode(&px, w, h, (10, 3));
        let head = b"\x1b]1337;File=inline=1;";
        assert!(data.starts_with(head));
        let colon = data.iter().position(|&c| c == b':').unwrap();
        assert!(String::from_utf8_lossy(&data[..colon]).contains("width=10;height=3"));
        let png = STANDARD.decode(&data[colon + 1..data.len() - 1]).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (w as u32, h as u32));
        assert_eq!(img.into_raw(), px.as_flattened());
    }
}
