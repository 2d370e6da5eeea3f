//! Sixel images: a palette per image (median cut, as many colours as the
//! terminal has registers, up to 256), ordered dithering between the two
//! nearest entries, and run-length encoded sixel rows.
//!
//! Written here rather than taken from a crate: the encoders on crates.io
//! either fix the palette at 256 colours (xterm's VT340 emulation has 16
//! registers) or bring a k-means quantizer with them, and the dithering is
//! the one the 256- and 16-colour modes use.

use std::io::Write;

use crate::tui::color::dither;

/// Most colour registers used.
pub(crate) const MAX_COLOURS: usize = 256;

/// A picture's palette and the nearest entry for every colour.
pub(crate) struct Palette {
    colours: Vec<[u8; 3]>,
    nearest: Nearest,
}

impl Palette {
    /// At most `colours` entries chosen for `px`.
    pub(crate) fn new(px: &[[u8; 3]], colours: usize) -> Palette {
        let colours = median_cut(px, colours);
        Palette {
            nearest: Nearest::new(&colours),
            colours,
        }
    }

    /// The palette index of every pixel of the `w`-wide image, dithered.
    pub(crate) fn quantize(&self, px: &[[u8; 3]], w: usize) -> Vec<u8> {
        px.iter()
            .enumerate()
            .map(|(i, &c)| {
                dither(
                    c,
                    (i % w) as u32,
                    (i / w) as u32,
                    |p| self.nearest.get(p),
                    |k| self.colours[k as usize],
                )
            })
            .collect()
    }

    /// The palette index of every pixel, each the nearest entry (no
    /// dithering: blocks of one colour stay one colour).
    pub(crate) fn nearest(&self, px: &[[u8; 3]]) -> Vec<u8> {
        px.iter()
            .map(|c| self.nearest.get(c.map(|v| v as i32)))
            .collect()
    }
}

/// Pixels of one colour bin (5 bits per channel): their sum and count.
#[derive(Clone, Copy)]
struct Bin {
    sum: [u64; 3],
    count: u64,
}

impl Bin {
    fn colour(&self) -> [u8; 3] {
        self.sum
            .map(|v| ((v + self.count / 2) / self.count.max(1)) as u8)
    }
}

/// A palette of at most [`MAX_COLOURS`] sRGB colours for `px`, by median
/// cut over a histogram of all its pixels: rare colours (the cursor's
/// marks, rays) keep a box of their own once the common ones are split.
fn median_cut(px: &[[u8; 3]], colours: usize) -> Vec<[u8; 3]> {
    let colours = colours.clamp(2, MAX_COLOURS);
    let mut bins = vec![
        Bin {
            sum: [0; 3],
            count: 0
        };
        1 << 15
    ];
    for p in px {
        let b =
            &mut bins[(p[0] as usize >> 3) << 10 | (p[1] as usize >> 3) << 5 | p[2] as usize >> 3];
        for (sum, &v) in b.sum.iter_mut().zip(p) {
            *sum += v as u64;
        }
        b.count += 1;
    }
    let used: Vec<Bin> = bins.into_iter().filter(|b| b.count > 0).collect();
    if used.is_empty() {
        return vec![[0; 3]];
    }
    // Split the box with the widest channel range (weighted by how many
    // pixels it holds) at the weighted median of that channel.
    let score = |b: &Vec<Bin>| {
        let (c, range) = widest(b);
        let count: u64 = b.iter().map(|e| e.count).sum();
        (range as u64 * count.min(1 << 12), c)
    };
    let mut boxes = vec![(score(&used), used)];
    while boxes.len() < colours {
        let Some(i) = (0..boxes.len()).max_by_key(|&i| boxes[i].0 .0) else {
            break;
        };
        let ((s, c), mut b) = boxes.swap_remove(i);
        if s == 0 {
            boxes.push(((s, c), b));
            break;
        }
        b.sort_unstable_by_key(|e| e.colour()[c]);
        let half: u64 = b.iter().map(|e| e.count).sum::<u64>() / 2;
        let mut acc = 0;
        let at = b
            .iter()
            .position(|e| {
                acc += e.count;
                acc > half
            })
            .unwrap_or(0)
            .clamp(1, b.len() - 1);
        let upper = b.split_off(at);
        boxes.push((score(&b), b));
        boxes.push((score(&upper), upper));
    }
    boxes
        .iter()
        .map(|(_, b)| {
            let total = b.iter().fold(
                Bin {
                    sum: [0; 3],
                    count: 0,
                },
                |a, e| Bin {
                    sum: [0, 1, 2].map(|c| a.sum[c] + e.sum[c]),
                    count: a.count + e.count,
                },
            );
            total.colour()
        })
        .collect()
}

/// The channel with the widest range in `b`, and the range.
fn widest(b: &[Bin]) -> (usize, u8) {
    (0..3)
        .map(|c| {
            let (lo, hi) = b.iter().fold((255u8, 0u8), |(lo, hi), e| {
                let v = e.colour()[c];
                (lo.min(v), hi.max(v))
            });
            (c, hi.saturating_sub(lo))
        })
        .max_by_key(|&(_, r)| r)
        .unwrap_or((0, 0))
}

/// The nearest palette entry for every colour at 5 bits per channel.
struct Nearest {
    table: Vec<u8>,
}

impl Nearest {
    fn new(palette: &[[u8; 3]]) -> Nearest {
        let table = (0..1usize << 15)
            .map(|k| {
                let c = [(k >> 10) & 31, (k >> 5) & 31, k & 31].map(|v| (v * 255 / 31) as i32);
                (0..palette.len())
                    .min_by_key(|&i| {
                        let p = palette[i];
                        (0..3).map(|j| (c[j] - p[j] as i32).pow(2)).sum::<i32>()
                    })
                    .unwrap_or(0) as u8
            })
            .collect();
        Nearest { table }
    }

    fn get(&self, c: [i32; 3]) -> u8 {
        let q = c.map(|v| (v.clamp(0, 255) as usize * 31 + 127) / 255);
        self.table[q[0] << 10 | q[1] << 5 | q[2]]
    }
}

/// A whole sixel image (DCS ... ST) of the `w x h` image whose pixels are
/// the entries `index` of `palette`.
pub(crate) fn encode(index: &[u8], w: usize, h: usize, palette: &Palette) -> Vec<u8> {
    let palette = &palette.colours;
    let mut out = Vec::with_capacity(w * h / 2);
    // P2 = 1: pixels left unset keep what is under them.
    let _ = write!(out, "\x1bP0;1;0q\"1;1;{w};{h}");
    // Only the entries used: a band of a picture uses a few of them.
    let mut used = vec![false; palette.len()];
    for &k in index {
        used[k as usize] = true;
    }
    for (i, p) in palette.iter().enumerate().filter(|(i, _)| used[*i]) {
        let pct = p.map(|v| (v as u32 * 100 + 127) / 255);
        let _ = write!(out, "#{i};2;{};{};{}", pct[0], pct[1], pct[2]);
    }
    let mut row = vec![0u8; w];
    for y0 in (0..h).step_by(6) {
        let rows = (h - y0).min(6);
        let mut present = vec![false; palette.len()];
        for y in y0..y0 + rows {
            for &k in &index[y * w..y * w + w] {
                present[k as usize] = true;
            }
        }
        let mut first = true;
        for (k, _) in present.iter().enumerate().filter(|(_, p)| **p) {
            for (x, r) in row.iter_mut().enumerate() {
                let mut bits = 0u8;
                for dy in 0..rows {
                    if index[(y0 + dy) * w + x] as usize == k {
                        bits |= 1 << dy;
                    }
                }
                *r = 63 + bits;
            }
            if !first {
                out.push(b'$');
            }
            first = false;
            let _ = write!(out, "#{k}");
            run_length(&mut out, &row);
        }
        out.push(b'-');
    }
    out.extend_from_slice(b"\x1b\\");
    out
}

/// Sixel characters with runs of four or more as `!n` and the character.
fn run_length(out: &mut Vec<u8>, row: &[u8]) {
    let mut i = 0;
    while i < row.len() {
        let c = row[i];
        let n = row[i..].iter().take_while(|&&d| d == c).count();
        if n >= 4 {
            let _ = write!(out, "!{n}");
            out.push(c);
        } else {
            out.extend(std::iter::repeat_n(c, n));
        }
        i += n;
    }
}

/// A decoded sixel image: width, height, and each pixel if set.
#[cfg(test)]
pub(crate) type Decoded = (usize, usize, Vec<Option<[u8; 3]>>);

/// Decodes a sixel image as a terminal draws it (for tests): the pixels
/// set, `None` where none was.
#[cfg(test)]
pub(crate) fn decode(data: &[u8]) -> Option<Decoded> {
    let start = data.windows(2).position(|w| w == b"\x1bP")?;
    let q = start + data[start..].iter().position(|&c| c == b'q')?;
    let end = q + data[q..].windows(2).position(|w| w == b"\x1b\\")?;
    let body = &data[q + 1..end];
    let mut registers = vec![[0u8; 3]; MAX_COLOURS];
    let (mut w, mut h) = (0usize, 0usize);
    let mut px: Vec<Option<[u8; 3]>> = Vec::new();
    let (mut x, mut y, mut colour) = (0usize, 0usize, 0usize);
    let mut i = 0;
    let number = |i: &mut usize| -> Vec<usize> {
        let mut nums = vec![0usize];
        while *i < body.len() && (body[*i].is_ascii_digit() || body[*i] == b';') {
            if body[*i] == b';' {
                nums.push(0);
            } else {
                let n = nums.last_mut().unwrap();
                *n = *n * 10 + (body[*i] - b'0') as usize;
            }
            *i += 1;
        }
        nums
    };
    while i < body.len() {
        let c = body[i];
        i += 1;
        match c {
            b'"' => {
                let n = number(&mut i);
                (w, h) = (*n.get(2)?, *n.get(3)?);
                px = vec![None; w * h];
            }
            b'#' => {
                let n = number(&mut i);
                colour = n[0].min(MAX_COLOURS - 1);
                if n.len() >= 5 && n[1] == 2 {
                    registers[colour] =
                        [n[2], n[3], n[4]].map(|v| ((v.min(100) * 255 + 50) / 100) as u8);
                }
            }
            b'!' => {
                let n = number(&mut i)[0];
                let s = *body.get(i)?;
                i += 1;
                for _ in 0..n {
                    put(&mut px, w, h, x, y, s, registers[colour]);
                    x += 1;
                }
            }
            b'$' => x = 0,
            b'-' => {
                x = 0;
                y += 6;
            }
            63..=126 => {
                put(&mut px, w, h, x, y, c, registers[colour]);
                x += 1;
            }
            _ => {}
        }
    }
    Some((w, h, px))
}

#[cfg(test)]
fn put(px: &mut [Option<[u8; 3]>], w: usize, h: usize, x: usize, y: usize, s: u8, rgb: [u8; 3]) {
    for dy in 0..6 {
        if (s - 63) >> dy & 1 == 1 && x < w && y + dy < h {
            px[(y + dy) * w + x] = Some(rgb);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_few_colours_come_back_exactly() {
        let (w, h) = (37, 20);
        let colours = [[255, 0, 0], [0, 128, 255], [20, 20, 20], [250, 250, 200]];
        let px: Vec<[u8; 3]> = (0..w * h)
            .map(|i| colours[(i % w / 10 + i / w / 7) % 4])
            .collect();
        let palette = Palette::new(&px, 16);
        let data = encode(&palette.quantize(&px, w), w, h, &palette);
        // Only the four colours used are defined.
        assert_eq!(data.windows(3).filter(|w| w == b";2;").count(), 4);
        let (dw, dh, got) = decode(&data).unwrap();
        assert_eq!((dw, dh), (w, h));
        for (g, p) in got.iter().zip(&px) {
            // Palette entries are whole percentages: within 2 levels.
            let g = g.expect("every pixel is set");
            assert!((0..3).all(|c| g[c].abs_diff(p[c]) <= 2), "{g:?} vs {p:?}");
        }
    }

    #[test]
    fn the_palette_has_as_many_colours_as_asked() {
        let px: Vec<[u8; 3]> = (0..256 * 64)
            .map(|i| [(i % 256) as u8, (i / 256 * 4) as u8, 128])
            .collect();
        for n in [2, 16, 256] {
            assert_eq!(median_cut(&px, n).len(), n);
        }
        assert_eq!(median_cut(&[[7, 7, 7]; 100], 16).len(), 1);
    }
}
