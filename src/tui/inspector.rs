//! The inspector pane: the selected pixel, its ray tree (replayed when the
//! pixel or the view changes), the open folds, the cursor line and scroll.

use std::collections::HashSet;
use std::time::{Duration, Instant};

use crate::inspect::{inspect_pixel, lines, LineKind, PixelTree, TreeLine};
use crate::interrupt::Cancel;
use crate::render::post::Displayed;
use crate::render::Tracer;

/// The selected pixel and the sample replayed for its ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Selected {
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) sample: u32,
}

/// The longest the pane replays a sample for, on the interface's thread:
/// most trees take microseconds, but a sample can hold hundreds of glossy
/// paths with thousands of light samples at each hit.
const TREE_WAIT: Duration = Duration::from_millis(300);

#[derive(Default)]
pub(crate) struct Inspector {
    /// Arrows move the pixel cursor instead of the camera.
    pub(crate) select_mode: bool,
    pub(crate) selected: Option<Selected>,
    /// The tree of `selected` for a view generation; `None` where its
    /// sample takes longer than [`TREE_WAIT`] to replay.
    tree: Option<((Selected, u64), Option<PixelTree>)>,
    /// Open folds.
    expanded: HashSet<usize>,
    /// The tree's lines as shown, folds applied.
    lines: Vec<TreeLine>,
    /// The cursor line and the first visible line.
    pub(crate) cursor: usize,
    pub(crate) top: usize,
    /// Rows and columns of the pane: long lines wrap.
    pub(crate) height: usize,
    pub(crate) width: usize,
}

impl Inspector {
    /// Selects pixel `(x, y)` of a `size` view (clamped into it).
    pub(crate) fn select(&mut self, x: u32, y: u32, sample: u32, (w, h): (u32, u32)) {
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
    pub(crate) fn rescale(&mut self, old: (u32, u32), new: (u32, u32)) {
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

    #[cfg(test)]
    pub(crate) fn tree(&self) -> Option<&PixelTree> {
        self.tree.as_ref().and_then(|t| t.1.as_ref())
    }

    pub(crate) fn lines(&self) -> &[TreeLine] {
        &self.lines
    }

    /// Replays the selected pixel's tree when the selection or the view
    /// (`generation`) changed, takes the pixel's values before and after
    /// bloom from the shown image (`film` of `spp` samples), and keeps the
    /// cursor inside the lines and on screen.
    pub(crate) fn refresh(
        &mut self,
        tracer: &Tracer,
        generation: u64,
        film: Option<(&Displayed, u32)>,
    ) {
        match self.selected {
            None => {
                self.tree = None;
                self.lines.clear();
            }
            Some(s) => {
                let key = (s, generation);
                if self.tree.as_ref().map(|t| t.0) != Some(key) {
                    let start = Instant::now();
                    let late = || start.elapsed() > TREE_WAIT;
                    let t = Tracer {
                        cancel: Cancel::When(&late),
                        ..tracer.clone()
                    };
                    let tree = inspect_pixel(&t, s.x, s.y, s.sample);
                    self.tree = Some((key, (!late()).then_some(tree)));
                }
                if let (Some((_, Some(tree))), Some((shown, spp))) = (&mut self.tree, film) {
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
            Some((_, Some(t))) => lines(t, &|id| expanded.contains(&id)),
            Some(((s, _), None)) => vec![TreeLine {
                depth: 0,
                kind: LineKind::Result,
                text: format!(
                    "the ray tree of pixel ({}, {}) takes over {} ms to replay, so it is \
                     not shown here (`rayterm inspect` prints any tree)",
                    s.x,
                    s.y,
                    TREE_WAIT.as_millis()
                ),
                fold: None,
                ray: None,
            }],
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
    pub(crate) fn cursor_ray(&self) -> Option<usize> {
        let end = (self.cursor + 1).min(self.lines.len());
        self.lines[..end].iter().rev().find_map(|l| l.ray)
    }

    pub(crate) fn move_cursor(&mut self, n: i64) {
        let last = self.lines.len().saturating_sub(1) as i64;
        self.cursor = (self.cursor as i64 + n).clamp(0, last) as usize;
        self.relayout();
    }

    /// Toggles the first fold at or below the cursor; false when there is none.
    pub(crate) fn fold(&mut self) -> bool {
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
pub(crate) fn wrap(line: &TreeLine, width: usize) -> Vec<String> {
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

    /// A sample of 256 glossy paths of 64 hits with 4096 light samples at
    /// each is not replayed on the interface's thread for long: the pane
    /// says so within about `TREE_WAIT`.
    #[test]
    fn a_tree_too_slow_to_replay_is_left_out() {
        use crate::render::{SceneRequest, Session};
        let d = std::env::temp_dir().join(format!("rayterm-inspector-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        std::fs::write(
            d.join("planes.obj"),
            "v -1e3 0 -1e3\nv 1e3 0 -1e3\nv 1e3 0 1e3\nv -1e3 0 1e3\n\
             v -1e3 1 -1e3\nv 1e3 1 -1e3\nv 1e3 1 1e3\nv -1e3 1 1e3\n\
             f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n",
        )
        .unwrap();
        std::fs::write(
            d.join("s.toml"),
            "[camera]\neye = [0.0, 0.5, 0.0]\ntarget = [1.0, 0.2, 0.0]\nfov = 40.0\n\
             [[mesh]]\nfile = \"planes.obj\"\n\
             material = { name = \"g\", kd = [0.1, 0.1, 0.1], ks = [0.9, 0.9, 0.9], ns = 10.0 }\n\
             [[light]]\ntype = \"parallelogram\"\ncorner = [-0.5, 0.9, -0.5]\n\
             edge1 = [1.0, 0.0, 0.0]\nedge2 = [0.0, 0.0, 1.0]\n\
             colors = [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]\n\
             [render]\nmax_depth = 64\nglossy_samples = 256\nlight_samples = 4096\n",
        )
        .unwrap();
        let req = SceneRequest {
            size: Some((4, 4)),
            ..SceneRequest::new(d.join("s.toml").to_str().unwrap())
        };
        let (session, _) = Session::open(&req).unwrap();
        let mut inspector = Inspector::default();
        inspector.select(2, 2, 0, (4, 4));
        let start = Instant::now();
        inspector.refresh(&session.tracer(), 0, None);
        assert!(start.elapsed() < TREE_WAIT * 10, "{:?}", start.elapsed());
        assert!(inspector.tree().is_none());
        assert!(
            inspector.lines()[0].text.contains("takes over 300 ms"),
            "{:?}",
            inspector.lines()
        );
        std::fs::remove_dir_all(d).unwrap();
    }

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
