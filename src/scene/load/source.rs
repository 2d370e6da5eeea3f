//! Where scene files come from: the file system, or the files compiled into
//! the binary for the built-in scenes. Both go through the same loaders.
//!
//! Every read from disk goes through [`read_file`]: only regular files are
//! read (a FIFO would block forever, `/dev/zero` never ends), and each kind
//! of file has a size limit ([`FileKind::limit`]), so no file makes a loader
//! hang or exhaust memory. [`text`] turns the bytes of a text file into a
//! string the parsers share: BOM stripped, UTF-8 checked with the line of
//! the first bad byte, CR and CRLF line endings turned into LF.

use std::fmt;
use std::fs::{File, Metadata};
use std::io::{ErrorKind, Read};
use std::path::{Component, Path, PathBuf};

use anyhow::{anyhow, Result};

/// What a file holds: sets its size limit and names it in messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A TOML scene file.
    Scene,
    /// A Wavefront OBJ mesh.
    Obj,
    /// A Wavefront MTL material library.
    Mtl,
    /// A PLY mesh.
    Ply,
    /// An STL mesh.
    Stl,
    /// A glTF file (`.gltf` JSON, which may embed its buffers, or `.glb`).
    Gltf,
    /// A glTF buffer (`.bin`).
    Buffer,
    /// Bézier patches (`.bpt`).
    Patches,
    /// An image: a texture or a cube-map face (and image references).
    Image,
}

const MIB: u64 = 1 << 20;

impl FileKind {
    /// Largest file of this kind that is read, in bytes.
    ///
    /// Scene files, material libraries and patch files are small by nature;
    /// an OBJ may hold tens of millions of triangles (1 GiB of text is about
    /// 20 million), and so may binary meshes (2 GiB is 40 million triangles
    /// of binary STL, 100 million of binary PLY); an encoded image is bounded here and its decoded size
    /// by the texture budget ([`crate::scene::texture::TEXTURE_BUDGET`]).
    pub(crate) const fn limit(self) -> u64 {
        match self {
            FileKind::Scene => 16 * MIB,
            FileKind::Obj => 1024 * MIB,
            FileKind::Mtl => 16 * MIB,
            FileKind::Ply | FileKind::Stl | FileKind::Gltf | FileKind::Buffer => 2048 * MIB,
            FileKind::Patches => 64 * MIB,
            FileKind::Image => 256 * MIB,
        }
    }

    /// The kind in words with its article: `an OBJ mesh`.
    pub(crate) fn a_noun(self) -> String {
        let an = matches!(self, FileKind::Obj | FileKind::Stl | FileKind::Image);
        format!("{} {}", if an { "an" } else { "a" }, self.noun())
    }

    /// The kind in words, as messages name it.
    pub(crate) const fn noun(self) -> &'static str {
        match self {
            FileKind::Scene => "scene file",
            FileKind::Obj => "OBJ mesh",
            FileKind::Mtl => "material library",
            FileKind::Ply => "PLY mesh",
            FileKind::Stl => "STL mesh",
            FileKind::Gltf => "glTF file",
            FileKind::Buffer => "glTF buffer",
            FileKind::Patches => "patch file",
            FileKind::Image => "image",
        }
    }
}

/// Why a file could not be read.
#[derive(Debug)]
pub(crate) enum Cause {
    NotFound,
    /// Not a regular file: what it is instead ("a FIFO", "a directory", ...).
    NotRegular(String),
    TooLarge {
        size: u64,
        limit: u64,
    },
    PermissionDenied,
    Other(std::io::Error),
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Cause::NotFound => f.write_str("not found"),
            Cause::NotRegular(what) => write!(f, "not a regular file ({what})"),
            Cause::TooLarge { size, limit } => write!(
                f,
                "too large ({size} bytes, limit {limit} = {})",
                crate::memory::bytes(*limit)
            ),
            Cause::PermissionDenied => f.write_str("permission denied"),
            Cause::Other(e) => write!(f, "{e}"),
        }
    }
}

/// A file that could not be read: which, what it was meant to hold, and why.
#[derive(Debug)]
pub struct ReadError {
    pub(crate) path: PathBuf,
    pub(crate) kind: FileKind,
    pub(crate) cause: Cause,
}

impl ReadError {
    pub(crate) fn new(path: &Path, kind: FileKind, cause: Cause) -> Self {
        Self {
            path: path.to_path_buf(),
            kind,
            cause,
        }
    }

    pub(crate) fn is_not_found(&self) -> bool {
        matches!(self.cause, Cause::NotFound)
    }
}

impl fmt::Display for ReadError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(
            f,
            "cannot read {} {}: {}",
            self.kind.noun(),
            crate::words::path(&self.path),
            self.cause
        )
    }
}

impl std::error::Error for ReadError {}

impl From<std::io::Error> for Cause {
    fn from(e: std::io::Error) -> Self {
        match e.kind() {
            // No file can have such a path: a file for a directory, or a
            // name longer than the system allows.
            ErrorKind::NotFound | ErrorKind::NotADirectory | ErrorKind::InvalidFilename => {
                Cause::NotFound
            }
            ErrorKind::PermissionDenied => Cause::PermissionDenied,
            _ => Cause::Other(e),
        }
    }
}

/// What a non-regular file is, in words.
pub(crate) fn file_type_name(meta: &Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a file"
}

/// Refuses anything but a regular file within `limit` bytes.
fn check_meta(path: &Path, meta: &Metadata, limit: u64) -> Result<(), Cause> {
    if !meta.is_file() {
        let what = file_type_name(meta);
        let linked = std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink());
        return Err(Cause::NotRegular(if linked {
            format!("a symbolic link to {what}")
        } else {
            what.to_string()
        }));
    }
    if meta.len() > limit {
        return Err(Cause::TooLarge {
            size: meta.len(),
            limit,
        });
    }
    Ok(())
}

fn open_nonblocking(path: &Path) -> std::io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    // A FIFO swapped in after the check must not block the open.
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    options.open(path)
}

/// Reads a regular file of at most `kind.limit()` bytes.
///
/// The path is checked before it is opened (a FIFO is never opened), and the
/// opened file again (it may have been replaced in between); the read itself
/// stops one byte past the limit, so a file growing meanwhile cannot make it
/// unbounded either.
pub(crate) fn read_file(path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError> {
    read_limited(path, kind.limit()).map_err(|cause| ReadError::new(path, kind, cause))
}

fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, Cause> {
    check_meta(path, &std::fs::metadata(path)?, limit)?;
    let file = open_nonblocking(path)?;
    let meta = file.metadata()?;
    check_meta(path, &meta, limit)?;
    // No more than the size it was opened with: a file of the kernel's
    // (`/proc/self/environ`) says it is empty and then reads as anything,
    // and a file growing as it is read is not one to trust either.
    let size = meta.len();
    let mut bytes = Vec::with_capacity(size as usize);
    file.take(size + 1).read_to_end(&mut bytes)?;
    if bytes.len() as u64 > size {
        return Err(Cause::NotRegular(
            "it holds more than its size says: a file of the kernel's, or one being written".into(),
        ));
    }
    Ok(bytes)
}

/// A control character other than tab and newline: never shown as is (an
/// escape sequence in a name would reach the terminal).
fn unprintable(c: char) -> bool {
    c.is_control() && c != '\n' && c != '\t'
}

/// Whether a byte of UTF-8 text may be a carriage return or another
/// [`unprintable`] character, or begin one (U+0080 to U+009F start with
/// 0xC2): a quick test over the bytes before the exact one over characters.
#[inline(always)]
fn suspect(b: u8) -> bool {
    (b < 0x20 && b != b'\n' && b != b'\t') || b == 0x7f || b == 0xc2
}

/// Where UTF-8 stops being valid in `body` (at byte `at`): its line,
/// column and byte, as messages name them.
fn invalid_utf8(path: &Path, body: &[u8], at: usize) -> String {
    let before = &body[..at];
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    let column = before.len()
        - before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1)
        + 1;
    format!(
        "{}:{line}: not valid UTF-8 (byte 0x{:02x} at column {column})",
        path.display(),
        body[at]
    )
}

/// The text of a file: a UTF-8 byte-order mark removed, CRLF and lone CR
/// line endings turned into LF (so files from any system read alike),
/// other control characters than tab turned into U+FFFD (names and
/// messages echo the file), and invalid UTF-8 reported with its line.
pub fn text(path: &Path, mut bytes: Vec<u8>) -> Result<String> {
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    // Checked in place: a big mesh is read without a copy.
    let s = String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        anyhow!(
            "{}; save the file as UTF-8",
            invalid_utf8(path, e.as_bytes(), at)
        )
    })?;
    Ok(clean(s))
}

/// [`text`], with invalid UTF-8 read as U+FFFD and said in one warning
/// naming the first line where it is: for OBJ and MTL files, which tools
/// write in Latin-1 and other code pages as often as in UTF-8, and which
/// other readers take byte by byte. Text with a UTF-16 byte-order mark is
/// decoded as such ([`utf16`]).
pub(crate) fn text_lossy(path: &Path, mut bytes: Vec<u8>, warnings: &mut Vec<String>) -> String {
    if let Some(s) = utf16(path, &bytes, warnings) {
        return clean(s);
    }
    if bytes.starts_with(b"\xEF\xBB\xBF") {
        bytes.drain(..3);
    }
    let s = String::from_utf8(bytes).unwrap_or_else(|e| {
        let at = e.utf8_error().valid_up_to();
        warnings.push(format!(
            "{}: read as U+FFFD, as are the file's other invalid bytes (is it Latin-1?)",
            invalid_utf8(path, e.as_bytes(), at)
        ));
        String::from_utf8_lossy(e.as_bytes()).into_owned()
    });
    clean(s)
}

/// Text that starts with a UTF-16 byte-order mark, little- or
/// big-endian, decoded (Windows tools save text so), with a warning that
/// says so; `None` for other text. A lone surrogate reads as U+FFFD, and
/// an odd last byte is left out; the warning counts both.
fn utf16(path: &Path, bytes: &[u8], warnings: &mut Vec<String>) -> Option<String> {
    let (big, order) = match bytes.get(..2)? {
        [0xFF, 0xFE] => (false, "little-endian"),
        [0xFE, 0xFF] => (true, "big-endian"),
        _ => return None,
    };
    let units = bytes[2..].chunks_exact(2).map(|u| match big {
        true => u16::from_be_bytes([u[0], u[1]]),
        false => u16::from_le_bytes([u[0], u[1]]),
    });
    let mut lone = 0u64;
    let text = char::decode_utf16(units)
        .map(|c| {
            c.unwrap_or_else(|_| {
                lone += 1;
                char::REPLACEMENT_CHARACTER
            })
        })
        .collect();
    let mut faults = Vec::new();
    if lone > 0 {
        faults.push(format!(
            "{} read as U+FFFD",
            crate::words::count(lone, "lone surrogate", "lone surrogates")
        ));
    }
    if bytes.len() % 2 == 1 {
        faults.push("its odd last byte left out".to_string());
    }
    let faults: String = faults.iter().map(|f| format!("; {f}")).collect();
    warnings.push(format!(
        "{}: UTF-16 text ({order}, as its byte-order mark says): decoded{faults}",
        path.display()
    ));
    Some(text)
}

/// Line endings made LF and control characters other than tab U+FFFD
/// ([`text`]).
fn clean(s: String) -> String {
    if !s
        .as_bytes()
        .chunks(64)
        .any(|c| c.iter().fold(false, |a, &b| a | suspect(b)))
    {
        return s;
    }
    let mut s = if s.contains('\r') {
        s.replace("\r\n", "\n").replace('\r', "\n")
    } else {
        s
    };
    if s.contains(unprintable) {
        s = crate::words::printable_but(&s, "\n\t");
    }
    s
}

pub trait Source: Sync {
    fn read(&self, path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError>;

    /// The file as text (see [`text`]).
    fn read_text(&self, path: &Path, kind: FileKind) -> Result<String> {
        text(path, self.read(path, kind)?)
    }

    /// `target`, named inside `base`, when it lies outside `base`'s folder
    /// ([`Outside`]); never for files without folders to leave (embedded,
    /// in memory).
    fn outside(&self, _base: &Path, _target: &Path) -> Option<Outside> {
        None
    }

    /// Whether a glTF file may name files outside its folder (it may not
    /// unless asked: its URIs are relative references).
    fn outside_allowed(&self) -> bool {
        false
    }
}

/// A file named inside another that lies outside that file's folder (by
/// `..`, an absolute path or a symbolic link). It is read all the same,
/// with a warning naming where it resolves, but at arm's length: no
/// message quotes what it holds, since a scene could name `/etc/passwd`
/// or `/proc/self/environ` to have a message show it.
#[derive(Clone, Debug)]
pub struct Outside {
    pub(crate) path: PathBuf,
    /// Where it resolves, symbolic links followed.
    pub(crate) resolved: PathBuf,
    /// The folder it lies outside of.
    pub(crate) folder: PathBuf,
}

impl Outside {
    /// `{from}: {what} {written} lies outside the folder of ...`.
    pub(crate) fn warning(&self, from: &str, what: &str, written: &str) -> String {
        format!(
            "{from}: {what} {} lies outside {} (it resolves to {}); no message quotes what it holds",
            crate::words::quoted(written),
            crate::words::path(&self.folder),
            crate::words::path(&self.resolved)
        )
    }

    /// What reading the file as `kind` gave, said without quoting it: the
    /// warnings pushed onto `warnings` since `before` become one, and an
    /// error names the file (and line) and not what went wrong in it,
    /// unless it is the file's own [`ReadError`] (not found, too large).
    pub(crate) fn quiet<T>(
        &self,
        kind: FileKind,
        result: Result<T>,
        warnings: &mut Vec<String>,
        before: usize,
    ) -> Result<T> {
        let shown = crate::words::path(&self.path);
        let hidden = warnings.len().saturating_sub(before);
        if hidden > 0 {
            warnings.truncate(before);
            warnings.push(format!(
                "{shown}: {} about it not shown, as it lies outside {}",
                crate::words::count(hidden as u64, "warning", "warnings"),
                crate::words::path(&self.folder)
            ));
        }
        result.map_err(|e| {
            let own = e
                .chain()
                .filter_map(|c| c.downcast_ref::<ReadError>())
                .any(|r| r.path == self.path);
            if own {
                return e;
            }
            // The line an error names is no part of the file's text.
            let (text, path) = (format!("{e:#}"), self.path.display().to_string());
            let line: String = text
                .find(&path)
                .map(|at| &text[at + path.len()..])
                .and_then(|rest| rest.strip_prefix(':'))
                .map(|rest| rest.chars().take_while(char::is_ascii_digit).collect())
                .filter(|digits: &String| !digits.is_empty())
                .map_or(String::new(), |d| format!(":{d}"));
            anyhow!(
                "{shown}{line}: not read as {}; why is not shown, as the reason may quote \
                 the file, which lies outside {}",
                kind.a_noun(),
                crate::words::path(&self.folder)
            )
        })
    }
}

/// `target`, named inside `base`, when outside `base`'s folder, both with
/// symbolic links followed (a path that does not exist yet, lexically).
fn outside_of(base: &Path, target: &Path) -> Option<Outside> {
    let real = |p: &Path| {
        std::fs::canonicalize(p)
            .or_else(|_| std::path::absolute(p).map(|a| normalize(&a)))
            .ok()
    };
    let folder = real(
        base.parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new(".")),
    )?;
    let resolved = real(target)?;
    (!resolved.starts_with(&folder)).then(|| Outside {
        path: target.to_path_buf(),
        resolved,
        folder,
    })
}

/// A file a scene was read from, and the CRC-32 of what was read: what
/// `rayterm inputs` lists, and what partial films record so that `merge
/// --check` can say which file differs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct InputFile {
    pub(crate) path: PathBuf,
    pub(crate) crc: u32,
}

/// The file system, through [`read_file`], remembering the files it read
/// (so that no output can overwrite one of them) with their checksums.
#[derive(Default)]
pub(crate) struct Disk {
    read: std::sync::Mutex<Vec<InputFile>>,
    /// Whether glTF files may name files outside their folder.
    allow_outside: bool,
}

impl Disk {
    /// Files on disk; `allow_outside` lets glTF files name files outside
    /// their folder (`--allow-outside`).
    pub(crate) fn new(allow_outside: bool) -> Self {
        Disk {
            allow_outside,
            ..Disk::default()
        }
    }

    /// The files read so far, each once, in the order first read.
    pub(crate) fn files(self) -> Vec<InputFile> {
        let mut read = self.read.into_inner().unwrap_or_else(|e| e.into_inner());
        let mut seen = std::collections::HashSet::new();
        read.retain(|i| seen.insert(i.path.clone()));
        read
    }
}

impl Source for Disk {
    fn read(&self, path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError> {
        let bytes = read_file(path, kind)?;
        // A pass over bytes just read, at memory speed: far less than
        // parsing them.
        let crc = crc32fast::hash(&bytes);
        if let Ok(mut r) = self.read.lock() {
            r.push(InputFile {
                path: path.to_path_buf(),
                crc,
            });
        }
        Ok(bytes)
    }

    fn outside(&self, base: &Path, target: &Path) -> Option<Outside> {
        outside_of(base, target)
    }

    fn outside_allowed(&self) -> bool {
        self.allow_outside
    }
}

/// Files embedded in the binary, keyed by their path under `data/`.
pub(crate) struct Embedded(pub &'static [(&'static str, &'static [u8])]);

impl Source for Embedded {
    fn read(&self, path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError> {
        let key = normalize(path);
        self.0
            .iter()
            .find(|(name, _)| Path::new(name) == key)
            .map(|(_, bytes)| bytes.to_vec())
            .ok_or_else(|| ReadError::new(path, kind, Cause::NotFound))
    }
}

/// Removes `.` and resolves `name/..` lexically, keeping the `..` that lead
/// out of the starting folder: `a/../../b` is `../b`. Only for paths with
/// no symbolic links in them (embedded and in-memory files).
pub(crate) fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.components().next_back() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                // `/..` is `/`.
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(".."),
            },
            c => out.push(c),
        }
    }
    out
}

/// Resolves a path written inside the file at `base`: relative to that
/// file's folder (never to the current directory), with Windows
/// backslashes accepted. `..` is left for the file system to resolve, as
/// a shell would, so leading ones are kept and symbolic links followed.
pub(crate) fn resolve(base: &Path, written: &str) -> PathBuf {
    let cleaned = written.trim().trim_matches('"').replace('\\', "/");
    let p = Path::new(&cleaned);
    let joined = if p.is_absolute() {
        p.to_path_buf()
    } else {
        base.parent().unwrap_or(Path::new("")).join(p)
    };
    let path: PathBuf = joined
        .components()
        .filter(|c| *c != Component::CurDir)
        .collect();
    // `.` beside a file in the working directory is that directory, not "".
    if path.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        path
    }
}

/// Files held in memory, keyed by path: scenes built or mutated in code (the
/// stability battery, tests, fuzzing) load through the ordinary loaders.
#[derive(Clone, Debug, Default)]
pub struct Memory(pub Vec<(PathBuf, Vec<u8>)>);

impl Memory {
    pub fn with(mut self, path: &str, bytes: impl Into<Vec<u8>>) -> Self {
        self.0.push((normalize(Path::new(path)), bytes.into()));
        self
    }
}

impl Source for Memory {
    fn read(&self, path: &Path, kind: FileKind) -> Result<Vec<u8>, ReadError> {
        let key = normalize(path);
        self.0
            .iter()
            .find(|(p, _)| *p == key)
            .map(|(_, b)| b.clone())
            .ok_or_else(|| ReadError::new(path, kind, Cause::NotFound))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalize_keeps_leading_parents() {
        let n = |p: &str| normalize(Path::new(p));
        assert_eq!(n("a/./b/../c"), PathBuf::from("a/c"));
        assert_eq!(n("../x"), PathBuf::from("../x"));
        assert_eq!(n("./../x"), PathBuf::from("../x"));
        assert_eq!(n("a/../../x"), PathBuf::from("../x"));
        assert_eq!(n("../../x/../y"), PathBuf::from("../../y"));
        assert_eq!(n("/../x"), PathBuf::from("/x"));
        assert_eq!(
            n("data/scenes/../meshes/a.obj"),
            PathBuf::from("data/meshes/a.obj")
        );
    }

    #[test]
    fn resolve_is_relative_to_the_file() {
        let r = |b: &str, w: &str| resolve(Path::new(b), w);
        assert_eq!(r("m.obj", "."), PathBuf::from("."));
        assert_eq!(
            r("env.toml", "../teapot.bpt"),
            PathBuf::from("../teapot.bpt")
        );
        assert_eq!(
            r("./cornell.toml", "../meshes/cornell.obj"),
            PathBuf::from("../meshes/cornell.obj")
        );
        assert_eq!(
            r("../amb.toml", "../plane.obj"),
            PathBuf::from("../../plane.obj")
        );
        assert_eq!(r("s/a.toml", "m\\b c.obj"), PathBuf::from("s/m/b c.obj"));
        assert_eq!(r("s/a.toml", "/abs/x.obj"), PathBuf::from("/abs/x.obj"));
    }

    #[test]
    fn text_strips_bom_and_unifies_line_endings() {
        let p = Path::new("f");
        assert_eq!(
            text(p, b"\xEF\xBB\xBFv 1\r\nv 2\rv 3\n".to_vec()).unwrap(),
            "v 1\nv 2\nv 3\n"
        );
        assert_eq!(
            text(p, b"o \x1b[2J\tx\x00\n".to_vec()).unwrap(),
            "o \u{fffd}[2J\tx\u{fffd}\n"
        );
        let e = text(p, b"ok\nok\nbad \xff here\n".to_vec()).unwrap_err();
        assert_eq!(
            e.to_string(),
            "f:3: not valid UTF-8 (byte 0xff at column 5); save the file as UTF-8"
        );
        // Read lossily, the same text with U+FFFD, and one warning.
        let mut w = Vec::new();
        let t = text_lossy(p, b"\xEF\xBB\xBFok\r\nd\xe9j\xe0\n\xff\n".to_vec(), &mut w);
        assert_eq!(t, "ok\nd\u{fffd}j\u{fffd}\n\u{fffd}\n");
        assert_eq!(
            w,
            [
                "f:2: not valid UTF-8 (byte 0xe9 at column 2): read as U+FFFD, as are the \
              file's other invalid bytes (is it Latin-1?)"
            ]
        );
        w.clear();
        assert_eq!(text_lossy(p, b"v 1\r\n".to_vec(), &mut w), "v 1\n");
        assert!(w.is_empty());
    }

    #[test]
    fn utf16_text_is_decoded_with_a_warning() {
        let p = Path::new("f");
        let text = "v 1 é\r\nf 1\n";
        let le: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain(text.encode_utf16().flat_map(u16::to_le_bytes))
            .collect();
        let be: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain(text.encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        for (bytes, order) in [(le, "little-endian"), (be, "big-endian")] {
            let mut w = Vec::new();
            assert_eq!(text_lossy(p, bytes, &mut w), "v 1 é\nf 1\n");
            assert_eq!(
                w,
                [format!(
                    "f: UTF-16 text ({order}, as its byte-order mark says): decoded"
                )]
            );
        }
        // A lone surrogate, an odd last byte, nothing but the mark.
        let mut w = Vec::new();
        let t = text_lossy(p, vec![0xFF, 0xFE, b'a', 0, 0x00, 0xD8, b'b', 0, 7], &mut w);
        assert_eq!(t, "a\u{fffd}b");
        assert_eq!(
            w,
            [
                "f: UTF-16 text (little-endian, as its byte-order mark says): decoded; 1 lone \
              surrogate read as U+FFFD; its odd last byte left out"
            ]
        );
        w.clear();
        assert_eq!(text_lossy(p, vec![0xFE, 0xFF], &mut w), "");
        assert_eq!(w.len(), 1);
    }
}
