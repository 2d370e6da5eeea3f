//! The one drawing kit: pixels, rectangles, thick and dashed lines, and
//! text in an 8x8 bitmap font, clipped to a box. Generic over the pixel, so
//! the converge plot draws sRGB bytes, the debug views linear colours and
//! overlays transparent layers (`Option<Vec3>`) with the same code.

/// On and off lengths of a dash pattern, in pixels along the line.
pub(crate) type Dash = Option<(u32, u32)>;

/// Width and height of a glyph of [`Canvas::text`] at scale 1.
pub(crate) const GLYPH: i32 = 8;

#[derive(Clone, Debug, PartialEq)]
pub struct Canvas<P> {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Row-major, from the top; `width * height` of them.
    pub(crate) pixels: Vec<P>,
    /// Pixels outside this box are not drawn: (x0, y0, x1, y1), inclusive.
    pub(crate) clip: (i32, i32, i32, i32),
}

impl<P: Copy> Canvas<P> {
    /// Row-major, from the top.
    pub fn pixels(&self) -> &[P] {
        &self.pixels
    }

    /// A canvas filled with `background`.
    pub(crate) fn new(width: u32, height: u32, background: P) -> Self {
        Self::from_pixels(
            width,
            height,
            vec![background; width as usize * height as usize],
        )
    }

    /// A canvas over existing pixels (`width * height` of them).
    pub(crate) fn from_pixels(width: u32, height: u32, pixels: Vec<P>) -> Self {
        debug_assert_eq!(pixels.len(), width as usize * height as usize);
        Self {
            width,
            height,
            pixels,
            clip: (0, 0, width as i32 - 1, height as i32 - 1),
        }
    }

    /// Clips further drawing to the whole canvas again.
    pub(crate) fn unclip(&mut self) {
        self.clip = (0, 0, self.width as i32 - 1, self.height as i32 - 1);
    }

    pub(crate) fn put(&mut self, x: i32, y: i32, c: P) {
        let (x0, y0, x1, y1) = self.clip;
        let inside = (x0..=x1).contains(&x) && (y0..=y1).contains(&y);
        if inside && x < self.width as i32 && y < self.height as i32 && x >= 0 && y >= 0 {
            self.pixels[y as usize * self.width as usize + x as usize] = c;
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Option<P> {
        (x < self.width && y < self.height)
            .then(|| self.pixels[y as usize * self.width as usize + x as usize])
    }

    /// The filled rectangle with corners `(x0, y0)` and `(x1, y1)`, inclusive.
    pub(crate) fn rect(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, c: P) {
        for y in y0.max(self.clip.1)..=y1.min(self.clip.3) {
            for x in x0.max(self.clip.0)..=x1.min(self.clip.2) {
                self.put(x, y, c);
            }
        }
    }

    /// A line `width` pixels thick from `a` to `b`, stepping along its major
    /// axis with rounding, optionally dashed.
    pub(crate) fn line(&mut self, a: (f64, f64), b: (f64, f64), c: P, width: i32, dash: Dash) {
        if ![a.0, a.1, b.0, b.1].iter().all(|v| v.is_finite()) {
            return;
        }
        let steps = (b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil().max(1.0);
        // Longer lines than the canvas could hold are clipped elsewhere.
        let steps = steps.min(1e6) as u32;
        for i in 0..=steps {
            if let Some((on, off)) = dash {
                if i % (on + off) >= on {
                    continue;
                }
            }
            let t = i as f64 / steps as f64;
            let x = (a.0 + (b.0 - a.0) * t).round() as i32;
            let y = (a.1 + (b.1 - a.1) * t).round() as i32;
            let lo = -(width - 1) / 2;
            self.rect(x + lo, y + lo, x + lo + width - 1, y + lo + width - 1, c);
        }
    }

    /// Text with its top-left corner at `(x, y)`, each font pixel `scale`
    /// pixels wide; characters outside ASCII draw as blanks.
    pub(crate) fn text(&mut self, x: i32, y: i32, s: &str, c: P, scale: i32) {
        for (i, ch) in s.chars().enumerate() {
            let glyph = if ch.is_ascii() {
                font8x8::legacy::BASIC_LEGACY[ch as usize]
            } else {
                [0; 8]
            };
            let gx = x + i as i32 * GLYPH * scale;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..GLYPH {
                    if bits >> col & 1 == 1 {
                        let (px, py) = (gx + col * scale, y + row as i32 * scale);
                        self.rect(px, py, px + scale - 1, py + scale - 1, c);
                    }
                }
            }
        }
    }
}

/// Pixels `s` takes across in [`Canvas::text`] at `scale`.
pub(crate) fn text_width(s: &str, scale: i32) -> i32 {
    s.chars().count() as i32 * GLYPH * scale
}

impl<P: Copy> Canvas<Option<P>> {
    /// Paints the drawn pixels of this layer over `under` (same size).
    pub(crate) fn over(&self, under: &mut [P]) {
        for (u, p) in under.iter_mut().zip(&self.pixels) {
            if let Some(p) = p {
                *u = *p;
            }
        }
    }

    /// Whether anything was drawn.
    pub fn is_blank(&self) -> bool {
        self.pixels.iter().all(Option::is_none)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipped_drawing_stays_inside() {
        let mut c = Canvas::new(10, 10, 0u8);
        c.clip = (2, 2, 7, 7);
        c.rect(-5, -5, 20, 20, 1);
        assert_eq!(c.pixels.iter().filter(|&&p| p == 1).count(), 36);
        c.unclip();
        c.put(0, 0, 2);
        c.put(-1, 3, 2);
        c.put(10, 3, 2);
        assert_eq!(c.get(0, 0), Some(2));
        assert_eq!(c.pixels.iter().filter(|&&p| p == 2).count(), 1);
    }

    #[test]
    fn dashed_lines_leave_gaps() {
        let mut solid = Canvas::new(40, 1, false);
        solid.line((0.0, 0.0), (39.0, 0.0), true, 1, None);
        let mut dashed = Canvas::new(40, 1, false);
        dashed.line((0.0, 0.0), (39.0, 0.0), true, 1, Some((2, 2)));
        let count = |c: &Canvas<bool>| c.pixels.iter().filter(|p| **p).count();
        assert_eq!((count(&solid), count(&dashed)), (40, 20));
    }

    #[test]
    fn text_draws_glyphs_and_layers_paint_over() {
        let mut layer = Canvas::new(24, 8, None);
        layer.text(0, 0, "1", Some(7u8), 1);
        assert!(!layer.is_blank());
        assert_eq!(text_width("12", 2), 32);
        let mut under = vec![0u8; 24 * 8];
        layer.over(&mut under);
        assert!(under.contains(&7) && under.contains(&0));
    }
}
