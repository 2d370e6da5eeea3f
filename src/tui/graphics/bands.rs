//! The picture sent as images of a few cell rows each: a band is sent
//! again only when its pixels changed, is left out (deleted, for kitty)
//! while text lies over it (a popup, a message), and each band is a piece
//! of output of its own, so that output is paced between bands.
//!
//! Choosing the bands ([`Bands::plan`]) is cheap and happens in the event
//! loop; encoding them ([`Batch::encode`]) is not, and happens on the
//! encoder's thread. Pieces that come back for bands changed meanwhile
//! (text over them, the screen cleared, another layout) are dropped by
//! [`Bands::accept`] and the bands planned again.

use std::hash::{Hash, Hasher};
use std::io::Write;
use std::sync::Arc;

use ratatui::layout::Rect;

use super::{iterm2, kitty, passthrough, sixel, PixelMode, Protocol};

/// Cell rows per band.
pub(crate) const BAND_ROWS: u16 = 2;
/// Kitty image ids of the bands start here: two per band, used in turn, so
/// that a band's new image is complete before its old one is deleted (one
/// id replaced in place shows nothing until the new image has arrived).
const KITTY_ID: u32 = 0x5254_0000;

/// Kitty id `turn` (0 or 1) of band `b`.
fn kitty_id(b: usize, turn: bool) -> u32 {
    KITTY_ID + 2 * b as u32 + turn as u32
}

/// Deletes both of band `b`'s kitty images.
fn kitty_delete(mode: &PixelMode, b: usize) -> Vec<u8> {
    let mut out = wrap(mode, &kitty::delete(kitty_id(b, false)));
    out.extend(wrap(mode, &kitty::delete(kitty_id(b, true))));
    out
}

/// A picture for the viewport: sRGB pixels, `w x h`, over the cells `area`.
pub(crate) struct Picture<'a> {
    pub(crate) px: &'a [[u8; 3]],
    pub(crate) w: u32,
    pub(crate) h: u32,
    pub(crate) area: Rect,
    /// Shrunk for a slow link (see [`super::coarse_factor`]): sixel gives
    /// each of its pixels one colour, undithered, which sends in far fewer
    /// bytes than the dithered picture scaled up.
    pub(crate) coarse: bool,
}

/// The area and image size a set of bands is for.
type Target = (Rect, u32, u32);

#[derive(Default)]
pub(crate) struct Bands {
    /// Per band, a hash of the pixels on screen or on their way there
    /// (`None`: not on screen).
    sent: Vec<Option<u64>>,
    /// Per band, how often it was taken off the screen: pieces encoded
    /// before then are stale.
    epoch: Vec<u64>,
    /// Per band, deleted while pieces were still queued: one of them may
    /// show it again, so it is deleted again with the next picture.
    late: Vec<bool>,
    /// Per band, which of its two kitty ids the newest image has.
    turn: Vec<bool>,
    layout: Option<Target>,
    /// The most bands any layout had: kitty ids in use up to there.
    most: usize,
}

/// Bands to encode: each with its pixels, and for sixel the whole picture
/// the palette is made for.
pub(crate) struct Batch {
    mode: PixelMode,
    layout: Target,
    jobs: Vec<Job>,
    picture: Option<Arc<Vec<[u8; 3]>>>,
    coarse: bool,
}

struct Job {
    band: usize,
    epoch: u64,
    /// The kitty id of the band's image.
    turn: bool,
    /// Where the band goes on the screen (0-based), and its cells.
    at: (u16, u16),
    cells: (u16, u16),
    w: usize,
    h: usize,
    px: Vec<[u8; 3]>,
}

/// One encoded band: output of its own.
pub(crate) struct EncodedBand {
    band: usize,
    epoch: u64,
    layout: Target,
    rows: (u16, u16),
    bytes: Vec<u8>,
}

impl Batch {
    pub(crate) fn is_empty(&self) -> bool {
        self.jobs.is_empty()
    }

    /// The bands as images in the mode's protocol, each starting with a
    /// cursor move to its place.
    pub(crate) fn encode(self) -> Vec<EncodedBand> {
        let mode = self.mode;
        // One palette for the picture's sixel bands.
        let palette = self
            .picture
            .as_ref()
            .map(|px| sixel::Palette::new(px, mode.colours));
        self.jobs
            .into_iter()
            .map(|job| {
                let (w, h) = (job.w, job.h);
                let id = kitty_id(job.band, job.turn);
                let image = match (mode.protocol, &palette) {
                    (Protocol::Kitty, _) => {
                        let mut image = kitty::encode(&job.px, w, h, job.cells, id);
                        image.extend(kitty::delete(kitty_id(job.band, !job.turn)));
                        image
                    }
                    (Protocol::Iterm2, _) => iterm2::encode(&job.px, w, h, job.cells),
                    (Protocol::Sixel, Some(palette)) => {
                        // Sixel pixels are the terminal's: scale to the cells.
                        let (sw, sh) = (
                            job.cells.0 as usize * mode.cell.0 as usize,
                            job.cells.1 as usize * mode.cell.1 as usize,
                        );
                        let index = if self.coarse {
                            scale(&palette.nearest(&job.px), w, h, sw, sh)
                        } else {
                            palette.quantize(&scale(&job.px, w, h, sw, sh), sw)
                        };
                        sixel::encode(&index, sw, sh, palette)
                    }
                    (Protocol::Sixel, None) => Vec::new(),
                };
                let mut bytes = Vec::with_capacity(image.len() + 32);
                match (mode.passthrough, mode.pane) {
                    // tmux moves its terminal's cursor only when it next
                    // draws: the image carries its own move there, in that
                    // terminal's cells, with the cursor saved and restored.
                    (true, Some((x, y))) => {
                        let mut seq = Vec::with_capacity(image.len() + 24);
                        let (row, col) = (
                            y as u32 + job.at.1 as u32 + 1,
                            x as u32 + job.at.0 as u32 + 1,
                        );
                        let _ = write!(seq, "\x1b7\x1b[{row};{col}H");
                        seq.extend(image);
                        seq.extend(b"\x1b8");
                        bytes.extend(wrap(&mode, &seq));
                    }
                    _ => {
                        let _ = write!(bytes, "\x1b[{};{}H", job.at.1 + 1, job.at.0 + 1);
                        bytes.extend(wrap(&mode, &image));
                    }
                }
                EncodedBand {
                    band: job.band,
                    epoch: job.epoch,
                    layout: self.layout,
                    rows: (job.at.1, job.at.1 + job.cells.1),
                    bytes,
                }
            })
            .collect()
    }
}

impl Bands {
    /// Forgets what is on screen (the screen was cleared).
    pub(crate) fn forget(&mut self) {
        for b in 0..self.sent.len() {
            self.off(b);
        }
    }

    /// Whether a band of the area is not on screen, with no text over it.
    pub(crate) fn holes(&self, covered: impl Fn(u16) -> bool) -> bool {
        let Some((area, ..)) = self.layout else {
            return false;
        };
        self.sent.iter().enumerate().any(|(b, s)| {
            let top = area.y + b as u16 * BAND_ROWS;
            let bottom = (top + BAND_ROWS).min(area.y + area.height);
            s.is_none() && !(top..bottom).any(&covered)
        })
    }

    /// Band `b` is not on screen.
    fn off(&mut self, b: usize) -> bool {
        self.epoch[b] += 1;
        self.sent[b].take().is_some()
    }

    /// Forgets the bands over rows `rows` of the screen (text was written
    /// there, over a sixel or iTerm2 image).
    pub(crate) fn overwritten(&mut self, mode: &PixelMode, rows: &[bool]) {
        if mode.protocol == Protocol::Kitty {
            // Kitty keeps images apart from the text.
            return;
        }
        let Some((area, ..)) = self.layout else {
            return;
        };
        for b in 0..self.sent.len() {
            let top = area.y + b as u16 * BAND_ROWS;
            let bottom = (top + BAND_ROWS).min(area.y + area.height);
            if (top..bottom).any(|r| rows.get(r as usize).copied().unwrap_or(false)) {
                self.off(b);
            }
        }
    }

    /// Deletes the kitty images on rows text now lies over (a popup
    /// opened), at once rather than with the next picture: they are drawn
    /// above the text. `queued`: pieces are still to be written.
    pub(crate) fn uncover(
        &mut self,
        mode: &PixelMode,
        queued: bool,
        covered: impl Fn(u16) -> bool,
    ) -> Vec<Vec<u8>> {
        let mut out = Vec::new();
        let Some((area, ..)) = self.layout else {
            return out;
        };
        if mode.protocol != Protocol::Kitty {
            return out;
        }
        for b in 0..self.sent.len() {
            let top = area.y + b as u16 * BAND_ROWS;
            let bottom = (top + BAND_ROWS).min(area.y + area.height);
            if self.sent[b].is_some() && (top..bottom).any(&covered) && self.off(b) {
                out.push(kitty_delete(mode, b));
                self.late[b] = queued;
            }
        }
        out
    }

    /// What brings the screen to `pic`: output to write now (deleting kitty
    /// images), and the changed bands to encode. `covered(row)` says
    /// whether text lies over a screen row of the area; such bands are not
    /// shown. The bands planned count as sent.
    pub(crate) fn plan(
        &mut self,
        mode: &PixelMode,
        pic: &Picture,
        covered: impl Fn(u16) -> bool,
    ) -> (Vec<Vec<u8>>, Batch) {
        let mut now = Vec::new();
        let area = pic.area;
        let layout = (area, pic.w, pic.h);
        let count = area.height.div_ceil(BAND_ROWS) as usize;
        // Another size of the same area (a coarse picture, then the sharp
        // one) replaces the bands one by one: none goes blank meanwhile.
        let same_area = self.layout.is_some_and(|(a, ..)| a == area);
        self.layout = Some(layout);
        if !same_area {
            now.extend(self.clear(mode));
            self.sent = vec![None; count];
            self.epoch = vec![0; count];
            self.late = vec![false; count];
            self.turn = vec![false; count];
            self.most = self.most.max(count);
        }
        let mut plan = Batch {
            mode: *mode,
            layout,
            jobs: Vec::new(),
            picture: None,
            coarse: pic.coarse,
        };
        if area.width == 0 || pic.w == 0 || pic.h == 0 || pic.px.len() < (pic.w * pic.h) as usize {
            return (now, plan);
        }
        for b in 0..count {
            let top = b as u16 * BAND_ROWS;
            let rows = BAND_ROWS.min(area.height - top);
            if (area.y + top..area.y + top + rows).any(&covered) {
                let late = std::mem::take(&mut self.late[b]);
                if (self.off(b) || late) && mode.protocol == Protocol::Kitty {
                    now.push(kitty_delete(mode, b));
                }
                continue;
            }
            // The band's pixel rows in the picture.
            let y0 = (top as u64 * pic.h as u64 / area.height as u64) as u32;
            let y1 = ((top + rows) as u64 * pic.h as u64 / area.height as u64) as u32;
            let rows_px = &pic.px[(y0 * pic.w) as usize..(y1 * pic.w) as usize];
            let mut hasher = std::collections::hash_map::DefaultHasher::new();
            (pic.w, pic.h, pic.coarse).hash(&mut hasher);
            rows_px.as_flattened().hash(&mut hasher);
            let hash = hasher.finish();
            if self.sent[b] == Some(hash) || y1 == y0 {
                continue;
            }
            self.sent[b] = Some(hash);
            self.turn[b] = !self.turn[b];
            plan.jobs.push(Job {
                band: b,
                epoch: self.epoch[b],
                turn: self.turn[b],
                at: (area.x, area.y + top),
                cells: (area.width, rows),
                w: pic.w as usize,
                h: (y1 - y0) as usize,
                px: rows_px.to_vec(),
            });
        }
        if mode.protocol == Protocol::Sixel && !plan.jobs.is_empty() {
            plan.picture = Some(Arc::new(pic.px.to_vec()));
        }
        (now, plan)
    }

    /// The pieces still right for the screen, as output; bands changed
    /// since they were planned (or now under text, per `covered`) are
    /// planned again next time. Returns whether any piece was dropped.
    pub(crate) fn accept(
        &mut self,
        pieces: Vec<EncodedBand>,
        covered: impl Fn(u16) -> bool,
    ) -> (Vec<Vec<u8>>, bool) {
        let mut out = Vec::with_capacity(pieces.len());
        let mut dropped = false;
        for p in pieces {
            let current = self.layout == Some(p.layout) && self.epoch.get(p.band) == Some(&p.epoch);
            if !current {
                dropped = true;
                continue;
            }
            if (p.rows.0..p.rows.1).any(&covered) {
                self.off(p.band);
                dropped = true;
                continue;
            }
            out.push(p.bytes);
        }
        (out, dropped)
    }

    /// The output that brings the screen to `pic` at once (encoded here).
    #[cfg(test)]
    pub(crate) fn update(
        &mut self,
        mode: &PixelMode,
        pic: &Picture,
        covered: impl Fn(u16) -> bool,
    ) -> Vec<Vec<u8>> {
        let (mut out, plan) = self.plan(mode, pic, &covered);
        out.extend(self.accept(plan.encode(), &covered).0);
        out
    }

    /// Removes what is on screen (kitty images outlive the text): every
    /// band's image, since one written before it was taken off may still
    /// show.
    pub(crate) fn clear(&mut self, mode: &PixelMode) -> Vec<Vec<u8>> {
        for b in 0..self.sent.len() {
            self.off(b);
            self.late[b] = false;
        }
        Self::delete(mode, 0..self.sent.len())
    }

    /// Removes every image any layout showed, on leaving: deletes queued
    /// with a new layout may not have been written.
    pub(crate) fn leave(&mut self, mode: &PixelMode) -> Vec<u8> {
        self.clear(mode);
        Self::delete(mode, 0..self.most).concat()
    }

    fn delete(mode: &PixelMode, bands: std::ops::Range<usize>) -> Vec<Vec<u8>> {
        match mode.protocol {
            Protocol::Kitty => bands.map(|b| kitty_delete(mode, b)).collect(),
            _ => Vec::new(),
        }
    }
}

fn wrap(mode: &PixelMode, seq: &[u8]) -> Vec<u8> {
    if mode.passthrough {
        // Kitty's chunks are wrapped one by one: tmux limits a passthrough.
        if mode.protocol == Protocol::Kitty {
            let mut out = Vec::with_capacity(seq.len() * 2);
            for part in seq.split_inclusive(|&c| c == b'\\') {
                out.extend(passthrough(part));
            }
            return out;
        }
        return passthrough(seq);
    }
    seq.to_vec()
}

/// Nearest-neighbour scaling of a `w x h` image to `sw x sh`.
fn scale<T: Copy>(px: &[T], w: usize, h: usize, sw: usize, sh: usize) -> Vec<T> {
    if (w, h) == (sw, sh) {
        return px.to_vec();
    }
    let mut out = Vec::with_capacity(sw * sh);
    for y in 0..sh {
        let row = (y * h / sh.max(1)).min(h.saturating_sub(1)) * w;
        for x in 0..sw {
            out.push(px[row + (x * w / sw.max(1)).min(w.saturating_sub(1))]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mode(protocol: Protocol) -> PixelMode {
        PixelMode {
            protocol,
            cell: (4, 8),
            colours: 256,
            passthrough: false,
            pane: None,
            max: None,
        }
    }

    fn picture(w: u32, h: u32, seed: u32) -> Vec<[u8; 3]> {
        (0..w * h)
            .map(|i| [(i % w * 5) as u8, (i / w * 3) as u8, (seed * 40) as u8])
            .collect()
    }

    #[test]
    fn kitty_bands_decode_to_the_picture_and_only_changes_are_sent() {
        let m = mode(Protocol::Kitty);
        let area = Rect::new(3, 2, 20, 7);
        let (w, h) = (80, 56);
        let px = picture(w, h, 1);
        let pic = Picture {
            px: &px,
            w,
            h,
            area,
            coarse: false,
        };
        let mut bands = Bands::default();
        let pieces = bands.update(&m, &pic, |_| false);
        assert_eq!(pieces.len(), 4, "7 rows in bands of 2");
        // Decoded and stacked, the bands are the picture, exactly.
        let mut got = Vec::new();
        for p in &pieces {
            let images = kitty::decode(p);
            assert_eq!(images.len(), 1);
            assert_eq!(images[0].1, w as usize);
            got.extend_from_slice(&images[0].3);
        }
        assert!(got == px);
        // Nothing changed: nothing sent. One band changed: that one.
        assert!(bands.update(&m, &pic, |_| false).is_empty());
        let mut px2 = px.clone();
        px2[(w * 30 + 5) as usize] = [1, 2, 3];
        let pic2 = Picture {
            px: &px2,
            w,
            h,
            area,
            coarse: false,
        };
        let pieces = bands.update(&m, &pic2, |_| false);
        assert_eq!(pieces.len(), 1);
        // Pixel row 30 is in cell row 3, band 1, screen row 2 + 2. Its new
        // image has the band's other id, and the old one is deleted after
        // it has arrived.
        assert!(pieces[0].starts_with(b"\x1b[5;4H"));
        assert_eq!(kitty::decode(&pieces[0])[0].0, kitty_id(1, false));
        assert!(pieces[0].ends_with(&kitty::delete(kitty_id(1, true))));
        // Text over row 3 (band 0): its image is deleted, then sent again
        // when the text is gone.
        let pieces = bands.update(&m, &pic2, |r| r == 3);
        assert_eq!(pieces, vec![kitty_delete(&m, 0)]);
        assert_eq!(bands.update(&m, &pic2, |_| false).len(), 1);
        // A popup over rows 5-8 (bands 1-3): deleted at once, without a
        // picture; deleted again with the next one when pieces were still
        // queued (one of them may show a band again).
        let over = |r: u16| (5..=8).contains(&r);
        let deletes: Vec<_> = (1..4).map(|b| kitty_delete(&m, b)).collect();
        assert_eq!(bands.uncover(&m, true, over), deletes);
        assert!(bands.uncover(&m, true, over).is_empty());
        assert_eq!(bands.update(&m, &pic2, over), deletes);
        assert!(bands.update(&m, &pic2, over).is_empty());
        // Sixel and iTerm2 images are erased by the text itself.
        let mut sixel = Bands::default();
        sixel.update(&mode(Protocol::Sixel), &pic2, |_| false);
        assert!(sixel
            .uncover(&mode(Protocol::Sixel), false, over)
            .is_empty());
    }

    /// Through tmux's passthrough a band moves the outer terminal's cursor
    /// itself, to the band's cell plus the pane's place, and puts it back.
    #[test]
    fn bands_through_tmux_are_placed_in_the_outer_terminal() {
        for protocol in [Protocol::Sixel, Protocol::Kitty, Protocol::Iterm2] {
            let m = PixelMode {
                passthrough: true,
                pane: Some((10, 5)),
                ..mode(protocol)
            };
            let (w, h) = (32, 16);
            let px = picture(w, h, 2);
            let pic = Picture {
                px: &px,
                w,
                h,
                area: Rect::new(3, 2, 8, 2),
                coarse: false,
            };
            let pieces = Bands::default().update(&m, &pic, |_| false);
            assert_eq!(pieces.len(), 1, "{protocol:?}");
            // Row 5 + 2 + 1, column 10 + 3 + 1; escapes doubled inside.
            assert!(
                pieces[0].starts_with(b"\x1bPtmux;\x1b\x1b7\x1b\x1b[8;14H"),
                "{protocol:?}: {}",
                String::from_utf8_lossy(&pieces[0][..40])
            );
            assert!(pieces[0].ends_with(b"\x1b\x1b8\x1b\\"), "{protocol:?}");
            // Without the pane's place: the cursor move goes to tmux.
            let m = PixelMode { pane: None, ..m };
            let pieces = Bands::default().update(&m, &pic, |_| false);
            assert!(
                pieces[0].starts_with(b"\x1b[3;4H\x1bPtmux;"),
                "{protocol:?}"
            );
        }
    }

    #[test]
    fn sixel_bands_are_the_cells_pixels_within_the_palette() {
        let m = mode(Protocol::Sixel);
        let area = Rect::new(0, 0, 10, 4);
        // Rendered at half the cell size: scaled up for the terminal.
        let (w, h) = (20, 16);
        let px = picture(w, h, 2);
        let pic = Picture {
            px: &px,
            w,
            h,
            area,
            coarse: false,
        };
        let pieces = Bands::default().update(&m, &pic, |_| false);
        assert_eq!(pieces.len(), 2);
        for (b, p) in pieces.iter().enumerate() {
            let (sw, sh, got) = sixel::decode(p).unwrap();
            assert_eq!((sw, sh), (40, 16));
            for (i, g) in got.iter().enumerate() {
                let (x, y) = (i % sw, i / sw + b * 16);
                let want = px[(y / 2) * w as usize + x / 2];
                let g = g.unwrap();
                assert!(
                    (0..3).all(|c| g[c].abs_diff(want[c]) <= 24),
                    "{g:?} {want:?}"
                );
            }
        }
    }

    #[test]
    fn a_coarse_picture_is_replaced_band_by_band_and_its_holes_found() {
        // kitty: the sharp picture after the coarse one deletes nothing at
        // once (no band goes blank); each band's new image replaces the old.
        let m = mode(Protocol::Kitty);
        let area = Rect::new(0, 0, 20, 7);
        let sharp = picture(80, 56, 1);
        let (small, w, h) = super::super::downscale(&sharp, 80, 56, 4);
        let coarse = Picture {
            px: &small,
            w,
            h,
            area,
            coarse: true,
        };
        let mut bands = Bands::default();
        // Text over row 6 (band 3) then: that band is a hole once it goes.
        assert_eq!(bands.update(&m, &coarse, |r| r == 6).len(), 3);
        assert!(!bands.holes(|r| r == 6) && bands.holes(|_| false));
        // The same coarse picture again: only the hole is sent.
        let pieces = bands.update(&m, &coarse, |_| false);
        assert_eq!(pieces.len(), 1);
        assert!(pieces[0].starts_with(b"\x1b[7;1H"), "band 3 at row 6");
        assert!(!bands.holes(|_| false));
        let pic = Picture {
            px: &sharp,
            w: 80,
            h: 56,
            area,
            coarse: false,
        };
        let (now, plan) = bands.plan(&m, &pic, |_| false);
        assert!(now.is_empty(), "nothing deleted before the new images");
        let pieces = bands.accept(plan.encode(), |_| false).0;
        assert_eq!(pieces.len(), 4);
        for p in &pieces {
            assert_eq!(kitty::decode(p)[0].1, 80, "sharp");
            assert_eq!(p.windows(5).filter(|w| w == b"a=d,d").count(), 1);
        }
        // Sixel: each coarse pixel is one colour over its block of the
        // terminal's pixels (4x8 cells, a 20x14 picture over 80x56).
        let m = mode(Protocol::Sixel);
        let pieces = Bands::default().update(&m, &coarse, |_| false);
        for p in &pieces {
            let (sw, sh, got) = sixel::decode(p).unwrap();
            let at = |x: usize, y: usize| got[y * sw + x].unwrap();
            for y in 0..sh {
                for x in 0..sw {
                    assert_eq!(at(x, y), at(x / 4 * 4, y / 4 * 4), "({x}, {y})");
                }
            }
        }
    }
}
