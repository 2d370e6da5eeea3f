//! One piece of an OBJ file, read on its own: a big file is cut into
//! pieces of whole statements, read in parallel, and stitched in order
//! ([`super::ObjFile::parse`]). A piece knows the vertices, UVs and normals
//! defined before it (counted first, [`census`]), so every index resolves
//! as in a reading from the top; what depends on the statements before it
//! in other ways (the current object and material, the triangle count) is
//! recorded and settled when the pieces are stitched.

use std::borrow::Cow;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

use anyhow::{anyhow, Result};
use glam::{DVec3, Vec2};

use super::{Face, Faces, NONE};
use crate::memory;
use crate::scene::load::numbers::{self, Absurd};
use crate::words::quoted;

/// Pieces are cut after about this many bytes.
pub(crate) const PIECE: usize = 4 << 20;

/// Triangles a piece counts before adding them to the shared count.
const FLUSH: u64 = 1 << 16;

/// Statements ignored by design, silently (lines and points are counted,
/// to say why a file of nothing else has no triangles).
const SILENT: &[&str] = &["s"];

/// `text` cut into pieces of about `size` bytes, each ending after a line
/// that ends a statement (not blank, not continued by `\`).
pub(crate) fn cut(text: &str, size: usize) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = text;
    'pieces: while rest.len() > size {
        let bytes = rest.as_bytes();
        let mut from = size;
        while let Some(i) = bytes[from..].iter().position(|&b| b == b'\n') {
            let end = from + i;
            let start = bytes[..end]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |j| j + 1);
            let line = rest[start..end].trim_end();
            if !line.is_empty() && !line.ends_with('\\') {
                out.push(&rest[..end + 1]);
                rest = &rest[end + 1..];
                continue 'pieces;
            }
            from = end + 1;
        }
        break;
    }
    out.push(rest);
    out
}

/// The lines of `text`, as `str::lines` cuts them, with one search for
/// line ends over the whole text rather than one per line.
fn lines(text: &str) -> impl Iterator<Item = &str> + '_ {
    let mut ends = memchr::memchr_iter(b'\n', text.as_bytes());
    let mut start = 0;
    std::iter::from_fn(move || match ends.next() {
        Some(end) => {
            let line = &text[start..end];
            start = end + 1;
            Some(line.strip_suffix('\r').unwrap_or(line))
        }
        None if start < text.len() => {
            let line = &text[start..];
            start = text.len();
            Some(line)
        }
        None => None,
    })
}

/// How a piece's text can be read: pure ASCII text without vertical tabs
/// (the one ASCII space `split_ascii_whitespace` does not split at) is
/// cut into words by bytes; text without `\` has no continued lines.
#[derive(Clone, Copy)]
struct Plain {
    ascii: bool,
    continued: bool,
}

impl Plain {
    fn of(text: &str) -> Plain {
        Plain {
            ascii: text.is_ascii() && !text.contains('\x0b'),
            continued: text.contains('\\'),
        }
    }

    /// `s` without leading and trailing whitespace.
    fn trim(self, s: &str) -> &str {
        match self.ascii {
            true => s.trim_ascii(),
            false => s.trim(),
        }
    }

    /// The words of `s`, as `str::split_whitespace` finds them.
    fn words(self, s: &str) -> Words<'_> {
        match self.ascii {
            true => Words::Ascii(s.split_ascii_whitespace()),
            false => Words::Any(s.split_whitespace()),
        }
    }
}

enum Words<'a> {
    Ascii(std::str::SplitAsciiWhitespace<'a>),
    Any(std::str::SplitWhitespace<'a>),
}

impl<'a> Iterator for Words<'a> {
    type Item = &'a str;
    #[inline]
    fn next(&mut self) -> Option<&'a str> {
        match self {
            Words::Ascii(w) => w.next(),
            Words::Any(w) => w.next(),
        }
    }
}

/// Lines of `text` with `\` continuations joined, numbered from 1 by
/// their first line.
fn logical_lines(text: &str, plain: Plain) -> impl Iterator<Item = (usize, Cow<'_, str>)> + '_ {
    let mut lines = lines(text).enumerate();
    std::iter::from_fn(move || {
        let (i, first) = lines.next()?;
        if !plain.continued || !first.trim_end().ends_with('\\') {
            return Some((i + 1, Cow::Borrowed(first)));
        }
        let mut line = first.to_string();
        while line.trim_end().ends_with('\\') {
            let cut = line.trim_end().len() - 1;
            line.truncate(cut);
            match lines.next() {
                Some((_, next)) => {
                    line.push(' ');
                    line.push_str(next);
                }
                None => break,
            }
        }
        Some((i + 1, Cow::Owned(line)))
    })
}

/// A statement's keyword and arguments; `None` for a blank line or a
/// comment.
fn statement(line: &str, plain: Plain) -> Option<(&str, &str)> {
    let line = plain.trim(line);
    if line.is_empty() || line.starts_with('#') {
        return None;
    }
    let key = match plain.ascii {
        true => line.bytes().position(|b| b.is_ascii_whitespace()),
        false => line.find(char::is_whitespace),
    };
    Some(match key {
        Some(k) => (&line[..k], plain.trim(&line[k..])),
        None => (line, ""),
    })
}

/// The lines of a piece, and its `v`, `vt` and `vn` statements.
pub(crate) fn census(text: &str) -> (usize, [usize; 3]) {
    let lines = memchr::memchr_iter(b'\n', text.as_bytes()).count();
    let mut counts = [0; 3];
    let plain = Plain::of(text);
    for (_, line) in logical_lines(text, plain) {
        match statement(&line, plain) {
            Some(("v", _)) => counts[0] += 1,
            Some(("vt", _)) => counts[1] += 1,
            Some(("vn", _)) => counts[2] += 1,
            _ => {}
        }
    }
    (lines, counts)
}

/// Where a piece's vertices, UVs and normals go: its part of the file's.
pub(crate) struct Out<'a> {
    pub(crate) positions: &'a mut [DVec3],
    pub(crate) position_lines: &'a mut [u32],
    pub(crate) uvs: &'a mut [Vec2],
    pub(crate) normals: &'a mut [DVec3],
}

/// A statement that changes the group, after the piece's first `.0` faces.
pub(crate) enum Switch {
    /// `o` or `g`, with its name.
    Object(String),
    /// `usemtl`, with its name and line.
    Material(String, usize),
}

/// Statements of kinds rayterm does not read: the first [`Ignored::KINDS`]
/// keywords, each with its first line and count, and the rest counted
/// together, so that a file of a million made-up keywords, or of one
/// keyword a gigabyte long, costs no more than its lines.
#[derive(Default)]
pub(crate) struct Ignored {
    /// The keyword's first [`Ignored::LONGEST`] characters, whether it had
    /// more, its first line and its count.
    kinds: Vec<(String, bool, usize, usize)>,
    /// The first line and count of the statements past those kinds.
    others: Option<(usize, usize)>,
}

impl Ignored {
    const KINDS: usize = 16;
    const LONGEST: usize = 32;

    pub(crate) fn add(&mut self, keyword: &str, line: usize, count: usize) {
        match keyword.char_indices().nth(Self::LONGEST) {
            Some((cut, _)) => self.add_kind(&keyword[..cut], true, line, count),
            None => self.add_kind(keyword, false, line, count),
        }
    }

    fn add_kind(&mut self, word: &str, long: bool, line: usize, count: usize) {
        if let Some(e) = self.kinds.iter_mut().find(|k| k.0 == word && k.1 == long) {
            e.3 += count;
        } else if self.kinds.len() < Self::KINDS {
            self.kinds.push((word.to_string(), long, line, count));
        } else {
            let o = self.others.get_or_insert((line, 0));
            o.1 += count;
        }
    }

    /// Adds those of a later piece of the file.
    pub(crate) fn extend(&mut self, later: Ignored) {
        for (word, long, line, count) in later.kinds {
            self.add_kind(&word, long, line, count);
        }
        if let Some((line, count)) = later.others {
            self.others.get_or_insert((line, 0)).1 += count;
        }
    }

    /// `vp (line 1 and 1 more), curv (line 3)`, or `None` when nothing
    /// was ignored.
    pub(crate) fn list(&self) -> Option<String> {
        let lines = |line: usize, count: usize| match count {
            1 => format!("line {line}"),
            c => format!("line {line} and {} more", c - 1),
        };
        let mut list: Vec<String> = self
            .kinds
            .iter()
            .map(|(w, long, line, count)| {
                let w = crate::words::printable(w) + if *long { "…" } else { "" };
                format!("{w} ({})", lines(*line, *count))
            })
            .collect();
        if let Some((line, count)) = self.others {
            list.push(format!(
                "{} of other kinds ({})",
                crate::words::count(count as u64, "statement", "statements"),
                lines(line, count)
            ));
        }
        (!list.is_empty()).then(|| list.join(", "))
    }
}

/// Lines of one kind that a warning counts: the first and how many.
#[derive(Default)]
pub(crate) struct Tally {
    pub(crate) first: Option<usize>,
    pub(crate) count: usize,
}

impl Tally {
    fn add(&mut self, line: usize) {
        self.first.get_or_insert(line);
        self.count += 1;
    }

    /// Both counts, `self` first (from earlier in the file).
    pub(crate) fn then(self, later: Tally) -> Tally {
        Tally {
            first: self.first.or(later.first),
            count: self.count + later.count,
        }
    }
}

/// Vertices holding a number 32-bit floats cannot hold (`inf`, `nan`,
/// `1e39`): the first one's line and why, and how many.
#[derive(Default)]
pub(crate) struct Unusable {
    pub(crate) first: Option<(usize, String)>,
    pub(crate) count: usize,
}

impl Unusable {
    fn add(&mut self, line: usize, why: &str) {
        self.first.get_or_insert_with(|| (line, why.to_string()));
        self.count += 1;
    }

    /// Both counts, `self` first (from earlier in the file).
    pub(crate) fn then(self, later: Unusable) -> Unusable {
        Unusable {
            first: self.first.or(later.first),
            count: self.count + later.count,
        }
    }
}

/// One piece as read, up to its first error.
#[derive(Default)]
pub(crate) struct Piece {
    pub(crate) faces: Faces,
    /// The colours of the vertices that have one (`v x y z r g b`), by
    /// their number in the file, as written.
    pub(crate) colors: Vec<(u32, [f32; 3])>,
    /// Vertices whose colour is not a finite number: read without one.
    pub(crate) bad_colors: Tally,
    /// Faces of fewer than three vertices: skipped.
    pub(crate) short_faces: Tally,
    /// Lines and points (`l`, `p`): not drawn.
    pub(crate) lines: Tally,
    /// Vertices that cannot be placed: NaN, the faces using them skipped.
    pub(crate) unusable: Unusable,
    pub(crate) switches: Vec<(usize, Switch)>,
    pub(crate) libraries: Vec<(String, usize)>,
    /// Warnings with their lines.
    pub(crate) warnings: Vec<(usize, String)>,
    pub(crate) absurd: Absurd,
    pub(crate) ignored: Ignored,
    /// The first error, where reading stopped.
    pub(crate) error: Option<anyhow::Error>,
    /// Reading stopped because the triangles of this piece, or of all the
    /// pieces read so far, would not fit in memory.
    pub(crate) full: bool,
}

/// What the pieces read together share: the memory for triangles and the
/// triangles read so far.
pub(crate) struct Shared {
    pub(crate) available: u64,
    pub(crate) triangles: AtomicU64,
}

/// Why reading a piece stopped early.
enum Stop {
    Error(anyhow::Error),
    Full,
}

impl From<anyhow::Error> for Stop {
    fn from(e: anyhow::Error) -> Self {
        Stop::Error(e)
    }
}

/// A piece being read.
struct Reader<'a> {
    path: &'a Path,
    out: Out<'a>,
    /// Vertices, UVs and normals defined so far in the file.
    counts: [usize; 3],
    /// And in this piece.
    here: [usize; 3],
    piece: Piece,
    plain: Plain,
    budget: &'a Shared,
    triangles: u64,
    pending: u64,
}

/// Reads the piece `text`, which starts after line `line` and after the
/// `counts` vertices, UVs and normals defined before it.
pub(crate) fn read(
    path: &Path,
    text: &str,
    line: usize,
    counts: [usize; 3],
    out: Out,
    budget: &Shared,
) -> Piece {
    let mut r = Reader {
        path,
        out,
        counts,
        here: [0; 3],
        piece: Piece::default(),
        plain: Plain::of(text),
        budget,
        triangles: 0,
        pending: 0,
    };
    for (i, text) in logical_lines(text, r.plain) {
        match r.statement(line + i, &text) {
            Ok(()) => {}
            Err(Stop::Error(e)) => {
                r.piece.error = Some(e);
                break;
            }
            Err(Stop::Full) => {
                r.piece.full = true;
                break;
            }
        }
    }
    r.piece
}

/// The numbers of a `v`, `vt` or `vn` statement (up to a trailing
/// comment), without allocating: the first seven, and how many there were.
struct Numbers {
    values: [f64; 7],
    total: usize,
    /// The first number that is not finite or beyond f32 (read as NaN),
    /// and why: an error unless it is a vertex colour's.
    unusable: Option<(usize, String)>,
}

impl Numbers {
    /// The numbers, where every one is usable.
    fn usable(self) -> Result<Numbers, String> {
        match self.unusable {
            Some((_, why)) => Err(why),
            None => Ok(self),
        }
    }
}

impl std::ops::Deref for Numbers {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.values[..self.total.min(7)]
    }
}

fn numbers(words: Words, line: usize, absurd: &mut Absurd) -> Result<Numbers, String> {
    let mut n = Numbers {
        values: [0.0; 7],
        total: 0,
        unusable: None,
    };
    for w in words.take_while(|w| !w.starts_with('#')) {
        let x = match numbers::parse(w) {
            Ok(x) => x,
            // A number, but not one f32 holds (`nan`, `inf`, `1e39`).
            Err(why) if w.parse::<f64>().is_ok() => {
                n.unusable.get_or_insert((n.total, why));
                f64::NAN
            }
            Err(_) if numbers::spelled_not_finite(w) => {
                let why = format!("'{}' is not a finite number", quoted(w));
                n.unusable.get_or_insert((n.total, why));
                f64::NAN
            }
            Err(why) => return Err(why),
        };
        absurd.check(line, x, || w.to_string());
        if let Some(slot) = n.values.get_mut(n.total) {
            *slot = x;
        }
        n.total += 1;
    }
    Ok(n)
}

/// One index of a face corner, resolved against the `count` defined so far.
fn index(word: &str, count: usize, what: &str) -> Result<u32, String> {
    let k: i64 = word
        .parse()
        .map_err(|_| format!("'{}' is not a valid {what} index", quoted(word)))?;
    let i = match k {
        0 => return Err(format!("{what} index 0 (indices start at 1)")),
        k if k > 0 => k - 1,
        k => count as i64 + k,
    };
    if i < 0 {
        return Err(format!(
            "relative {what} index {k} reaches before the first {what} \
             (only {count} defined so far)"
        ));
    }
    u32::try_from(i)
        .ok()
        .filter(|&i| i != NONE)
        .ok_or_else(|| format!("{what} index {k} is out of range ({count} defined so far)"))
}

/// One face corner, `v`, `v/vt`, `v//vn` or `v/vt/vn`, against the
/// vertices, UVs and normals defined so far.
fn corner(word: &str, counts: [usize; 3]) -> Result<[u32; 3], String> {
    // A one-character set: searched for character by character, which in
    // words this short beats the search `split('/')` starts each time.
    let mut parts = word.split(['/']);
    let v = parts.next().unwrap_or("");
    let vt = parts.next().unwrap_or("");
    let vn = parts.next().unwrap_or("");
    if parts.next().is_some() || v.is_empty() {
        return Err(format!(
            "'{}' is not a face vertex (v, v/vt, v//vn or v/vt/vn)",
            quoted(word)
        ));
    }
    let optional = |w: &str, count, what| match w {
        "" => Ok(NONE),
        w => index(w, count, what),
    };
    Ok([
        index(v, counts[0], "vertex")?,
        optional(vt, counts[1], "texture coordinate")?,
        optional(vn, counts[2], "normal")?,
    ])
}

impl Reader<'_> {
    fn statement(&mut self, n: usize, line: &str) -> Result<(), Stop> {
        let path = self.path;
        let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
        let plain = self.plain;
        let Some((key, rest)) = statement(line, plain) else {
            return Ok(());
        };
        let absurd = &mut self.piece.absurd;
        match key {
            "v" => {
                let v = numbers(plain.words(rest), n, absurd).map_err(at)?;
                let mut unusable = false;
                let v = match v.unusable {
                    // A colour that is not a number: read without it, as
                    // Blender reads it.
                    Some((k, _)) if k >= 3 && matches!(v.total, 6 | 7) => {
                        self.piece.bad_colors.add(n);
                        Numbers {
                            unusable: None,
                            ..v
                        }
                    }
                    // A coordinate (or w): the vertex cannot be placed, and
                    // the faces using it are skipped, as other readers
                    // leave what such faces would draw.
                    Some((_, ref why)) if matches!(v.total, 3 | 4 | 6 | 7) => {
                        self.piece.unusable.add(n, why);
                        unusable = true;
                        v
                    }
                    _ => v.usable().map_err(at)?,
                };
                let p = match *v {
                    // A fourth number is a rational curve's weight, which
                    // polygons ignore, as other OBJ readers do; six are a
                    // position and an RGB colour, seven RGBA (alpha
                    // unused).
                    [x, y, z] | [x, y, z, _] => DVec3::new(x, y, z),
                    [x, y, z, r, g, b] | [x, y, z, r, g, b, _] => {
                        let rgb = [r, g, b];
                        if rgb.iter().all(|c| !c.is_nan()) {
                            let i = self.counts[0] as u32;
                            self.piece.colors.push((i, rgb.map(|c| c as f32)));
                        }
                        DVec3::new(x, y, z)
                    }
                    _ => {
                        return Err(at(format!(
                            "a vertex takes 3 coordinates (x y z), optionally with w or an \
                             RGB colour; found {} numbers",
                            v.total
                        ))
                        .into())
                    }
                };
                self.out.positions[self.here[0]] = if unusable { DVec3::NAN } else { p };
                self.out.position_lines[self.here[0]] = n as u32;
                self.here[0] += 1;
                self.counts[0] += 1;
            }
            "vt" => {
                let v = numbers(plain.words(rest), n, absurd)
                    .and_then(Numbers::usable)
                    .map_err(at)?;
                let uv = match *v {
                    [u] => Vec2::new(u as f32, 0.0),
                    [u, v] | [u, v, _] => Vec2::new(u as f32, v as f32),
                    _ => {
                        return Err(at(format!(
                            "a texture coordinate takes 1 to 3 numbers (u [v [w]]), found {}",
                            v.total
                        ))
                        .into())
                    }
                };
                self.out.uvs[self.here[1]] = uv;
                self.here[1] += 1;
                self.counts[1] += 1;
            }
            "vn" => {
                let v = numbers(plain.words(rest), n, absurd)
                    .and_then(Numbers::usable)
                    .map_err(at)?;
                match *v {
                    [x, y, z] => self.out.normals[self.here[2]] = DVec3::new(x, y, z),
                    _ => {
                        return Err(at(format!(
                            "a normal takes 3 numbers (x y z), found {}",
                            v.total
                        ))
                        .into())
                    }
                }
                self.here[2] += 1;
                self.counts[2] += 1;
            }
            "f" => self.face(n, rest)?,
            "o" | "g" => {
                let at = self.piece.faces.faces.len();
                self.piece
                    .switches
                    .push((at, Switch::Object(rest.to_string())));
            }
            // Without a name, the material `newmtl` without one defines
            // (or none), as in other readers.
            "usemtl" => {
                let at = self.piece.faces.faces.len();
                self.piece
                    .switches
                    .push((at, Switch::Material(rest.to_string(), n)));
            }
            "mtllib" => {
                if rest.is_empty() {
                    self.piece.warnings.push((
                        n,
                        format!(
                            "{}:{n}: mtllib without a file name: ignored",
                            path.display()
                        ),
                    ));
                } else {
                    self.piece.libraries.push((rest.to_string(), n));
                }
            }
            "l" | "p" => self.piece.lines.add(n),
            k if SILENT.contains(&k) => {}
            other => self.piece.ignored.add(other, n, 1),
        }
        Ok(())
    }

    /// A face; stops when the triangles read so far would not fit in
    /// memory (the stitching says where, as a reading from the top would).
    fn face(&mut self, n: usize, rest: &str) -> Result<(), Stop> {
        let path = self.path;
        let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
        let Faces { corners, faces } = &mut self.piece.faces;
        let start = corners.len();
        for word in self.plain.words(rest).take_while(|w| !w.starts_with('#')) {
            corners.push(corner(word, self.counts).map_err(at)?);
        }
        let len = corners.len() - start;
        if len < 3 {
            corners.truncate(start);
            self.piece.short_faces.add(n);
            return Ok(());
        }
        faces.push(Face {
            line: n as u32,
            start: start as u32,
            len: len as u32,
        });
        let t = len as u64 - 2;
        self.triangles += t;
        self.pending += t;
        let available = self.budget.available;
        let fits = |t: u64| t.saturating_mul(memory::BYTES_PER_TRIANGLE) <= available;
        if !fits(self.triangles) {
            return Err(Stop::Full);
        }
        if self.pending >= FLUSH {
            let all = self
                .budget
                .triangles
                .fetch_add(self.pending, Ordering::Relaxed)
                + self.pending;
            self.pending = 0;
            if !fits(all) {
                return Err(Stop::Full);
            }
        }
        Ok(())
    }
}
