//! The kitty graphics protocol: RGB pixels, zlib-compressed, base64 in
//! chunks of 4096 bytes, placed at the cursor over a given number of cells,
//! above the text: images under text take a path of kitty's that leaves
//! changed glyphs drawn over their old ones (seen with Mesa's software
//! OpenGL), so the bands under text (a popup) are deleted instead.

use std::io::Write;

use base64::engine::general_purpose::STANDARD;
use base64::Engine;
use flate2::write::ZlibEncoder;
use flate2::Compression;

/// The largest payload per escape sequence the protocol allows.
const CHUNK: usize = 4096;
/// Above the text.
const Z: i32 = 1;

/// Image `id` (replacing any earlier one of that id): the `w x h` sRGB
/// pixels shown over `cols x rows` cells from the cursor, which stays.
pub(crate) fn encode(
    px: &[[u8; 3]],
    w: usize,
    h: usize,
    (cols, rows): (u16, u16),
    id: u32,
) -> Vec<u8> {
    let mut z = ZlibEncoder::new(Vec::with_capacity(w * h), Compression::fast());
    let _ = z.write_all(px.as_flattened());
    let compressed = z.finish().unwrap_or_default();
    let b64 = STANDARD.encode(compressed);
    let mut out = Vec::with_capacity(b64.len() + b64.len() / CHUNK * 16 + 96);
    let chunks: Vec<&[u8]> = b64.as_bytes().chunks(CHUNK).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let more = (i + 1 < chunks.len()) as u8;
        if i == 0 {
            let _ = write!(
                out,
                "\x1b_Ga=T,f=24,o=z,s={w},v={h},i={id},p=1,c={cols},r={rows},C=1,q=2,z={Z},m={more};"
            );
        } else {
            let _ = write!(out, "\x1b_Gm={more};");
        }
        out.extend_from_slice(chunk);
        out.extend_from_slice(b"\x1b\\");
    }
    out
}

/// Deletes image `id` and its placements.
pub(crate) fn delete(id: u32) -> Vec<u8> {
    format!("\x1b_Ga=d,d=I,i={id},q=2\x1b\\").into_bytes()
}

/// Decodes the images in `data` (for tests): id, size and pixels of each
/// complete transmission, in order.
#[cfg(test)]
pub(crate) fn decode(data: &[u8]) -> Vec<(u32, usize, usize, Vec<[u8; 3]>)> {
    use std::io::Read;
    let mut images = Vec::new();
    let mut current: Option<(u32, usize, usize, Vec<u8>)> = None;
    let mut rest = data;
    while let Some(start) = rest.windows(3).position(|w| w == b"\x1b_G") {
        let body_start = start + 3;
        let Some(len) = rest[body_start..].windows(2).position(|w| w == b"\x1b\\") else {
            break;
        };
        let body = &rest[body_start..body_start + len];
        rest = &rest[body_start + len + 2..];
        let (keys, payload) = match body.iter().position(|&c| c == b';') {
            Some(i) => (&body[..i], &body[i + 1..]),
            None => (body, &b""[..]),
        };
        let keys = String::from_utf8_lossy(keys);
        let get = |k: &str| {
            keys.split(',')
                .find_map(|kv| kv.strip_prefix(k).and_then(|v| v.strip_prefix('=')))
                .and_then(|v| v.parse::<usize>().ok())
        };
        if keys.contains("a=T") {
            current = Some((
                get("i").unwrap_or(0) as u32,
                get("s").unwrap_or(0),
                get("v").unwrap_or(0),
                Vec::new(),
            ));
        }
        if let Some(c) = current.as_mut() {
            c.3.extend_from_slice(payload);
        }
        if get("m") == Some(0) {
            if let Some((id, w, h, b64)) = current.take() {
                let Ok(z) = STANDARD.decode(&b64) else {
                    continue;
                };
                let mut raw = Vec::new();
                if flate2::read::ZlibDecoder::new(&z[..])
                    .read_to_end(&mut raw)
                    .is_err()
                {
                    continue;
                }
                let px = raw.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
                images.push((id, w, h, px));
            }
        }
    }
    images
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_come_back_exactly_in_chunks() {
        let (w, h) = (301, 97);
        let px: Vec<[u8; 3]> = (0..w * h)
            .map(|i| [(i * 7) as u8, (i * 13 / w) as u8, (i % 251) as u8])
            .collect();
        let data = encode(&px, w, h, (40, 6), 7);
        // Several chunks, each within the protocol's limit.
        let n = data.windows(3).filter(|w| w == b"\x1b_G").count();
        assert!(n > 1, "{n}");
        for body in data.split(|&c| c == 0x1b) {
            assert!(body.len() <= CHUNK + 128);
        }
        let got = decode(&data);
        assert_eq!(got.len(), 1);
        assert_eq!((got[0].0, got[0].1, got[0].2), (7, w, h));
        assert!(got[0].3 == px);
    }
}
