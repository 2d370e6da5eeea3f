//! Where an image goes, checked before any rendering: a format rayterm
//! writes, a directory that exists and takes files, never a directory or
//! one of the inputs. Regular files are replaced atomically; a character
//! device or a FIFO with a reader (`/dev/null`, `/dev/stdout`) is written in
//! place; anything else is refused, so no device is ever replaced.

use std::fs::{self, OpenOptions};
use std::io::Write;
use std::os::unix::fs::{FileTypeExt, MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use glam::Vec3;

use super::temporary;
use crate::interrupt::{Cancel, Interrupted};

/// The image formats `rayterm render -o` writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB after bloom.
    Png,
    /// The linear film before bloom, 8-bit mantissas.
    Hdr,
    /// The linear film before bloom, 32-bit float: exact.
    Exr,
    /// A table of numbers.
    Csv,
    /// An animation in 256 colours.
    Gif,
    /// An animation in 24-bit colour.
    Apng,
}

impl ImageFormat {
    /// What a render writes.
    pub(crate) const RENDERS: &'static [ImageFormat] =
        &[ImageFormat::Png, ImageFormat::Exr, ImageFormat::Hdr];

    /// What a turntable writes (a `.png` is an APNG, as browsers read it).
    pub(crate) const ANIMATIONS: &'static [ImageFormat] =
        &[ImageFormat::Gif, ImageFormat::Apng, ImageFormat::Png];

    fn describe(self) -> &'static str {
        match self {
            ImageFormat::Png => ".png (the picture)",
            ImageFormat::Hdr => ".hdr (the linear film, 8-bit mantissas)",
            ImageFormat::Exr => ".exr (the linear film, 32-bit float)",
            ImageFormat::Csv => ".csv (the table)",
            ImageFormat::Gif => ".gif (an animation, 256 colours)",
            ImageFormat::Apng => ".apng (an animation, 24-bit colour)",
        }
    }

    pub(crate) fn of(path: &Path) -> Option<ImageFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFormat::Png),
            "hdr" => Some(ImageFormat::Hdr),
            "exr" => Some(ImageFormat::Exr),
            "csv" => Some(ImageFormat::Csv),
            "gif" => Some(ImageFormat::Gif),
            "apng" => Some(ImageFormat::Apng),
            _ => None,
        }
    }

    /// A linear image encoded in this format; PNG is not linear.
    pub fn encode_linear(self, width: u32, height: u32, img: &[Vec3]) -> Result<Vec<u8>> {
        match self {
            ImageFormat::Hdr => super::hdr::encode(width, height, img),
            ImageFormat::Exr => super::openexr::encode(width, height, img),
            ImageFormat::Png | ImageFormat::Csv | ImageFormat::Gif | ImageFormat::Apng => {
                bail!("{} is not a linear image format", self.describe())
            }
        }
    }
}

#[derive(Debug)]
pub struct Output {
    pub(crate) path: PathBuf,
    pub(crate) format: ImageFormat,
    /// A device or FIFO is opened when checked and kept open: a FIFO's
    /// reader would see the end of its input if it were closed.
    device: Option<fs::File>,
}

impl Output {
    /// Checks `path` as an output in one of the `accepted` formats (by its
    /// extension; a device or FIFO without one gets the first) of a command
    /// whose inputs are `inputs`.
    pub(crate) fn check(
        path: &Path,
        inputs: &[PathBuf],
        accepted: &[ImageFormat],
    ) -> Result<Output> {
        let shown = path.display();
        let mut device = None;
        // `x.png/` names a directory whatever is there: the file's name
        // would read as `x.png`, and only the write would fail.
        if path.as_os_str().as_encoded_bytes().ends_with(b"/") {
            bail!("{shown} ends in /, which names a directory; name a file");
        }
        // `/dev/stdout` and its kin name a descriptor of this process,
        // whatever it is open on: written where it stands.
        if let Some(fd) = descriptor(path) {
            device = Some(duplicate(path, fd)?);
        }
        match fs::metadata(path) {
            _ if device.is_some() => {}
            Ok(m) => {
                let t = m.file_type();
                if t.is_dir() {
                    bail!("{shown} is a directory; name a file inside it");
                } else if t.is_file() {
                    // Replaced atomically, as a new file is written.
                } else if t.is_char_device() || t.is_fifo() {
                    // Opening without blocking fails on a FIFO nobody
                    // reads, where writing would wait forever.
                    let f = OpenOptions::new()
                        .write(true)
                        .custom_flags(libc::O_NONBLOCK)
                        .open(path)
                        .map_err(|e| match t.is_fifo() {
                            true => anyhow::anyhow!("{shown} is a FIFO that no process is reading"),
                            false => anyhow::anyhow!("cannot open {shown}: {}", reason(&e)),
                        })?;
                    blocking(&f);
                    device = Some(f);
                } else {
                    bail!("{shown} is not a regular file (a block device or socket); refusing to write to it");
                }
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => bail!("{shown}: {}", reason(&e)),
        }
        // A device or pipe gets a PNG unless its name says otherwise.
        let format = match (ImageFormat::of(path), device.is_some()) {
            (Some(f), _) if accepted.contains(&f) => f,
            (None, true) => accepted[0],
            _ => bail!(
                "{shown}: unknown format; this writes {}",
                accepted
                    .iter()
                    // A .png among animations is one too.
                    .map(
                        |&f| match f == ImageFormat::Png && accepted.contains(&ImageFormat::Gif) {
                            true => ".png (an APNG)",
                            false => f.describe(),
                        }
                    )
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        if device.is_none() {
            check_directory(path)?;
        }
        let out = Output {
            path: path.to_path_buf(),
            format,
            device,
        };
        out.check_not_input(inputs)?;
        Ok(out)
    }

    /// Refuses an output that is one of `inputs` (the same file under any
    /// name).
    pub(crate) fn check_not_input(&self, inputs: &[PathBuf]) -> Result<()> {
        let Ok(m) = fs::metadata(&self.path) else {
            return Ok(());
        };
        for input in inputs {
            if let Ok(i) = fs::metadata(input) {
                if (i.dev(), i.ino()) == (m.dev(), m.ino()) {
                    bail!(
                        "{} is an input of this render ({}); choose another output",
                        self.path.display(),
                        input.display()
                    );
                }
            }
        }
        Ok(())
    }
}

impl Output {
    /// Writes `bytes`: atomically through a temporary file beside a regular
    /// target (removed on any failure), or in place into a device or FIFO.
    pub(crate) fn write(&self, bytes: &[u8]) -> Result<()> {
        self.write_result(bytes, Cancel::Never)
    }

    /// Whether the output is written in place (a device, a FIFO, a
    /// descriptor), not replaced.
    pub(crate) fn in_place(&self) -> bool {
        self.device.is_some()
    }

    /// Whether the image goes where standard output goes (`-o
    /// /dev/stdout`): what a command would print there then goes to
    /// standard error, so as not to follow the image into its stream.
    pub(crate) fn is_stdout(&self) -> bool {
        use std::os::fd::AsFd;
        let Some(f) = &self.device else {
            return false;
        };
        let Ok(out) = std::io::stdout().as_fd().try_clone_to_owned() else {
            return false;
        };
        match (f.metadata(), fs::File::from(out).metadata()) {
            (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
            _ => false,
        }
    }

    /// [`Output::write`] for a command's result: a `cancel` set while a
    /// regular file is written leaves it as it was, and the error is
    /// [`Interrupted`]. A device or FIFO is written all the same: what it
    /// took cannot be taken back.
    pub(crate) fn write_result(&self, bytes: &[u8], cancel: Cancel) -> Result<()> {
        let path = &self.path;
        if let Some(mut f) = self.device.as_ref() {
            return f
                .write_all(bytes)
                .and_then(|()| f.flush())
                .map_err(|e| anyhow::anyhow!("cannot write {}: {}", path.display(), reason(&e)));
        }
        temporary::remove_stale(path);
        let (tmp, mut f) = temporary::create(path)
            .map_err(|e| anyhow::anyhow!("cannot write {}: {}", path.display(), reason(&e)))?;
        crate::interrupt::writing(Some(&tmp));
        let written = (|| -> std::io::Result<bool> {
            f.write_all(bytes)?;
            // A file replaced keeps its permissions.
            if let Some(m) = fs::symlink_metadata(path).ok().filter(|m| m.is_file()) {
                f.set_permissions(m.permissions())?;
            }
            f.sync_all()?;
            if cancel.is_set() {
                return Ok(false);
            }
            fs::rename(&tmp, path).map(|()| true)
        })();
        if !matches!(written, Ok(true)) {
            let _ = fs::remove_file(&tmp);
        }
        crate::interrupt::writing(None);
        match written {
            Ok(true) => Ok(()),
            Ok(false) => Err(Interrupted.into()),
            Err(e) => {
                bail!("cannot write {}: {}", path.display(), reason(&e))
            }
        }
    }
}

/// The descriptor `path` names, through `/proc/self/fd` (`/dev/stdout`,
/// `/dev/fd/2`, `/proc/self/fd/1`): a file there is the one this process
/// has open, which a regular file standard output is redirected to must
/// not be replaced by (nor `/dev/stdout` itself, the link, by a file).
fn descriptor(path: &Path) -> Option<i32> {
    let fds = PathBuf::from(format!("/proc/{}/fd", std::process::id()));
    let mut p = path.to_path_buf();
    // A few links at most: /dev/stdout -> /proc/self/fd/1.
    for _ in 0..8 {
        let parent = temporary::folder(&p);
        if fs::canonicalize(parent).ok().as_deref() == Some(fds.as_path()) {
            return p.file_name()?.to_str()?.parse().ok();
        }
        let target = fs::read_link(&p).ok()?;
        p = parent.join(target);
    }
    None
}

/// A descriptor of this process, duplicated to write an image to: refused
/// when not open for writing.
fn duplicate(path: &Path, fd: i32) -> Result<fs::File> {
    use std::os::fd::BorrowedFd;
    // SAFETY: fcntl only asks about the descriptor, open or not.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 {
        bail!("{}: descriptor {fd} is not open", path.display());
    }
    if flags & libc::O_ACCMODE == libc::O_RDONLY {
        bail!(
            "{}: descriptor {fd} is open for reading only",
            path.display()
        );
    }
    // SAFETY: the descriptor is open (fcntl said so) and only borrowed to
    // be duplicated.
    unsafe { BorrowedFd::borrow_raw(fd) }
        .try_clone_to_owned()
        .map(fs::File::from)
        .map_err(|e| anyhow::anyhow!("cannot open {}: {}", path.display(), reason(&e)))
}

/// Clears `O_NONBLOCK` again, so writes wait for a slow reader.
fn blocking(f: &fs::File) {
    use std::os::fd::AsRawFd;
    let fd = f.as_raw_fd();
    // SAFETY: fcntl on a descriptor this file owns; only the flag changes.
    unsafe {
        let flags = libc::fcntl(fd, libc::F_GETFL);
        if flags >= 0 {
            libc::fcntl(fd, libc::F_SETFL, flags & !libc::O_NONBLOCK);
        }
    }
}

/// The directory `path` goes in exists and takes new files: probed with
/// the temporary file a write makes, created and removed at once, which
/// also catches read-only file systems (root bypasses permission bits, not
/// those) and names too long for them.
fn check_directory(path: &Path) -> Result<()> {
    let dir = temporary::folder(path);
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => bail!("{}: {} is not a directory", path.display(), dir.display()),
        Err(_) => bail!(
            "{}: directory {} does not exist",
            path.display(),
            dir.display()
        ),
    }
    match temporary::create(path) {
        Ok((probe, _)) => {
            let _ = fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => bail!(
            "{}: cannot create files in {}: {}",
            path.display(),
            dir.display(),
            reason(&e)
        ),
    }
}

/// `stem-NNN.png` for the first number not taken yet, in `dir`.
pub(crate) fn fresh_name(dir: &Path, stem: &str) -> PathBuf {
    (1..)
        .map(|n| dir.join(format!("{stem}-{n:03}.png")))
        // Not `exists`, which follows links: a dangling link's name is
        // taken too, and writing there would replace the link.
        .find(|p| p.symlink_metadata().is_err())
        .expect("an unused file name exists")
}

/// An I/O error in words, without the OS error number.
pub(crate) fn reason(e: &std::io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_lowercase(),
        None => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("rayterm-out-{name}-{}", std::process::id()));
        fs::create_dir_all(&d).unwrap();
        d
    }

    /// A signal that arrives while the file is written leaves the old one
    /// and no temporary file.
    #[test]
    fn a_write_stopped_at_the_end_leaves_the_old_file() {
        let d = dir("stopped");
        let target = d.join("x.png");
        fs::write(&target, b"old").unwrap();
        let out = Output::check(&target, &[], &[ImageFormat::Png]).unwrap();
        let e = out
            .write_result(b"new", Cancel::When(&|| true))
            .unwrap_err();
        assert!(e.is::<Interrupted>(), "{e}");
        let names: Vec<_> = fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["x.png"]);
        assert_eq!(fs::read(&target).unwrap(), b"old");
        out.write(b"new").unwrap();
        assert_eq!(fs::read(&target).unwrap(), b"new");
        fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn fresh_names_pass_over_every_kind_of_entry() {
        let d = dir("fresh");
        fs::write(d.join("x-001.png"), b"").unwrap();
        std::os::unix::fs::symlink(d.join("gone.png"), d.join("x-002.png")).unwrap();
        fs::create_dir(d.join("x-003.png")).unwrap();
        assert_eq!(fresh_name(&d, "x"), d.join("x-004.png"));
        fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn formats_by_extension() {
        let d = dir("fmt");
        assert_eq!(
            Output::check(&d.join("a.PNG"), &[], ImageFormat::RENDERS)
                .unwrap()
                .format,
            ImageFormat::Png
        );
        assert_eq!(
            Output::check(&d.join("a.hdr"), &[], ImageFormat::RENDERS)
                .unwrap()
                .format,
            ImageFormat::Hdr
        );
        for bad in ["a.jpg", "noext", "a.png.tmp"] {
            let e = Output::check(&d.join(bad), &[], ImageFormat::RENDERS)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("unknown format") && e.contains(".png") && e.contains(".exr"),
                "{e}"
            );
        }
        fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn directories_inputs_and_missing_folders_are_refused() {
        let d = dir("dirs");
        let e = Output::check(&d, &[], ImageFormat::RENDERS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a directory"), "{e}");
        let sub = d.join("x.png");
        fs::create_dir(&sub).unwrap();
        let e = Output::check(&sub, &[], ImageFormat::RENDERS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a directory"), "{e}");
        let e = Output::check(&d.join("nope/x.png"), &[], ImageFormat::RENDERS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not exist"), "{e}");
        let scene = d.join("scene.png");
        fs::write(&scene, b"input").unwrap();
        let e = Output::check(&scene, std::slice::from_ref(&scene), ImageFormat::RENDERS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is an input"), "{e}");
        fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn devices_are_written_in_place() {
        let null = Output::check(Path::new("/dev/null"), &[], ImageFormat::RENDERS).unwrap();
        assert_eq!(
            (null.device.is_some(), null.format),
            (true, ImageFormat::Png)
        );
        let d = dir("dev");
        let link = d.join("null.hdr");
        std::os::unix::fs::symlink("/dev/null", &link).unwrap();
        let out = Output::check(&link, &[], ImageFormat::RENDERS).unwrap();
        assert_eq!((out.device.is_some(), out.format), (true, ImageFormat::Hdr));
        fs::remove_dir_all(d).unwrap();
    }

    #[test]
    fn a_fifo_without_a_reader_is_refused() {
        let d = dir("fifo");
        let fifo = d.join("f.png");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if !made.is_ok_and(|s| s.success()) {
            eprintln!("skipping: mkfifo is not available");
            return;
        }
        let e = Output::check(&fifo, &[], ImageFormat::RENDERS)
            .unwrap_err()
            .to_string();
        assert!(e.contains("FIFO that no process is reading"), "{e}");
        assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
        fs::remove_dir_all(d).unwrap();
    }
}
