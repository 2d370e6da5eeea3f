//! The inspector pane: the selected pixel, its ray tree (replayed when the
//! pixel or the view changes), the open folds, the cursor line and scroll.

use std::collections::HashSet;

use crate::inspect::{inspect_pixel, lines, PixelTree, TreeLine};
use crate::render::post::Displayed;
use crate::render::Tracer;

/// The selected pixel and the sample replayed for its ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Selected {
    pub x: u32,
    pub y: u32,
    pub sample: u32,
}

#[derive(Default)]
pub struct Inspector {
    /// Arrows move the pixel cursor instead of the camera.
    pub select_mode: bool,
    pub selected: Option<Selected>,
    /// The tree of `selected` for a view generation.
    tree: Option<((Selected, u64), PixelTree)>,
    /// Open folds.
    expanded: HashSet<usize>,
    /// The tree's lines as shown, folds applied.
    lines: Vec<TreeLine>,
    /// The cursor line and the first visible line.
    pub cursor: usize,
    pub top: usize,
    /// Rows and columns of the pane: long lines wrap.
    pub height: usize,
    pub width: usize,
}

impl Inspector {
    /// Selects pixel `(x, y)` of a `size` view (clamped into it).
    pub fn select(&mut self, x: u32, y: u32, sample: u32, (w, h): (u32, u32)) {
        if w == 0 || h == 0 {
            return;
        }
        self.selected = Some(Selected {
            x: x.min(w - 1),
            y: y.min(h - 1),
            sample,
        });
        self.cursor = 0;
        self.top = 0;
        self.expanded.clear();
    }

    /// Keeps the selection on the same point of the image when the view
    /// changes size from `old` to `new`.
    pub fn rescale(&mut self, old: (u32, u32), new: (u32, u32)) {
        if let Some(s) = &mut self.selected {
            if old.0 > 0 && old.1 > 0 && new.0 > 0 && new.1 > 0 {
                let scale = |v: u32, from: u32, to: u32| {
                    (((v as f64 + 0.5) * to as f64 / from as f64) as u32).min(to - 1)
                };
                s.x = scale(s.x, old.0, new.0);
                s.y = scale(s.y, old.1, new.1);
            }
        }
    }

    pub fn tree(&self) -> Option<&PixelTree> {
        self.tree.as_ref().map(|t| &t.1)
    }

    pub fn lines(&self) -> &[TreeLine] {
        &self.lines
    }

    /// Replays the selected pixel's tree when the selection or the view
    /// (`generation`) changed, takes the pixel's values before and after
    /// bloom from the shown image (`film` of `spp` samples), and keeps the
    /// cursor inside the lines and on screen.
    pub fn refresh(&mut self, tracer: &Tracer, generation: u64, film: Option<(&Displayed, u32)>) {
        match self.selected {
            None => {
                self.tree = None;
                self.lines.clear();
            }
            Some(s) => {
                let key = (s, generation);
                if self.tree.as_ref().map(|t| t.0) != Some(key) {
                    self.tree = Some((key, inspect_pixel(tracer, s.x, s.y, s.sample)));
                }
                if let (Some((_, tree)), Some((shown, spp))) = (&mut self.tree, film) {
                    tree.set_pixel(shown, spp);
                }
                self.relayout();
            }
        }
    }

    /// Lines again after a fold changed, and the cursor kept visible.
    fn relayout(&mut self) {
        let expanded = &self.expanded;
        self.lines = match &self.tree {
            Some((_, t)) => lines(t, &|id| expanded.contains(&id)),
            None => Vec::new(),
        };
        self.cursor = self.cursor.min(self.lines.len().saturating_sub(1));
        let height = self.height.max(1);
        if self.cursor < self.top {
            self.top = self.cursor;
        }
        // Down until the cursor line's last row is on screen.
        let rows = |i: usize| wrap(&self.lines[i], self.width).len();
        while self.top < self.cursor && (self.top..=self.cursor).map(rows).sum::<usize>() > height {
            self.top += 1;
        }
    }

    /// The ray of the line at the debug cursor, or of the nearest line
    /// above it that is a ray's (none above the first ray).
    pub fn cursor_ray(&self) -> Option<usize> {
        let end = (self.cursor + 1).min(self.lines.len());
        self.lines[..end].iter().rev().find_map(|l| l.ray)
    }

    pub fn move_cursor(&mut self, n: i64) {
        let last = self.lines.len().saturating_sub(1) as i64;
        self.cursor = (self.cursor as i64 + n).clamp(0, last) as usize;
        self.relayout();
    }

    /// Toggles the first fold at or below the cursor; false when there is none.
    pub fn fold(&mut self) -> bool {
        let found = self
            .lines
            .iter()
            .enumerate()
            .skip(self.cursor)
            .find_map(|(i, l)| l.fold.map(|(id, _)| (i, id)));
        let Some((i, id)) = found else {
            return false;
        };
        if !self.expanded.remove(&id) {
            self.expanded.insert(id);
        }
        self.cursor = i;
        self.relayout();
        true
    }
}

/// `line` indented by its depth and wrapped at spaces to `width` columns,
/// continuation rows indented further (a word longer than a row is cut
/// where the row ends). Width 0 leaves the line whole.
pub fn wrap(line: &TreeLine, width: usize) -> Vec<String> {
    let indent = "  ".repeat(line.depth);
    let whole = format!("{indent}{}", line.text);
    if width == 0 || whole.chars().count() <= width {
        return vec![whole];
    }
    let more = format!("{indent}    ");
    let mut rows = Vec::new();
    let mut row = indent.clone();
    let mut fresh = true;
    for word in line.text.split(' ') {
        let room = width.saturating_sub(row.chars().count());
        let need = word.chars().count() + usize::from(!fresh);
        if need > room && !fresh {
            rows.push(std::mem::replace(&mut row, more.clone()));
            fresh = true;
        }
        if !fresh {
            row.push(' ');
        }
        let mut rest: Vec<char> = word.chars().collect();
        loop {
            let room = width.saturating_sub(row.chars().count()).max(1);
            if rest.len() <= room {
                row.extend(rest);
                break;
            }
            row.extend(rest.drain(..room));
            rows.push(std::mem::replace(&mut row, more.clone()));
        }
        fresh = false;
    }
    rows.push(row);
    rows
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inspect::LineKind;

    #[test]
    fn long_lines_wrap_at_spaces_with_nothing_lost() {
        let line = TreeLine {
            depth: 2,
            kind: LineKind::Occluded,
            text: "occluded by tall_box triangle 29: point (0.1, 0.2, 0.3) shadow ray \
                   o=(0.0000000001234567890123, 1, 2)"
                .into(),
            fold: None,
            ray: None,
        };
        let rows = wrap(&line, 24);
        assert!(rows.len() > 3, "{rows:?}");
        assert!(rows.iter().all(|r| r.chars().count() <= 24), "{rows:?}");
        assert!(rows[0].starts_with("    occluded by"), "{rows:?}");
        assert!(rows[1..].iter().all(|r| r.starts_with("        ")));
        let words: Vec<&str> = line.text.split(' ').collect();
        let back: String = rows.iter().map(|r| r.trim()).collect::<Vec<_>>().join(" ");
        // Every character survives, in order (cut words lose only the cut).
        assert_eq!(back.replace(' ', ""), words.concat());
        assert_eq!(wrap(&line, 0).len(), 1);
        assert_eq!(wrap(&line, 500), vec![format!("    {}", line.text)]);
    }
}
