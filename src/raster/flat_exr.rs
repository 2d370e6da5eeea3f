//! OpenEXR images of 4-byte channels (u32 or f32) stored uncompressed, one
//! scanline per chunk, with text attributes: the layout partial films use.
//! Written and read here rather than through the `exr` crate because a
//! merge reads gigabytes of them: the whole file goes into one buffer the
//! caller reuses, and samples are read where they lie, with no per-channel
//! copies. Only this layout is read; any other OpenEXR file is refused.

use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

/// A channel's sample type, as OpenEXR numbers them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SampleType {
    U32 = 0,
    F32 = 2,
}

/// What an image holds besides its samples.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct ExrHeader {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// In the order the file stores them: sorted by name, byte by byte.
    pub(crate) channels: Vec<(String, SampleType)>,
    /// The text attributes, each with where its value lies in the file.
    pub(crate) attributes: Vec<(String, String, Range<usize>)>,
}

impl ExrHeader {
    /// Bytes of one scanline's samples.
    pub(crate) fn row_bytes(&self) -> usize {
        4 * self.width as usize * self.channels.len()
    }

    pub(crate) fn attribute(&self, name: &str) -> Option<&str> {
        self.attributes
            .iter()
            .find(|(k, _, _)| k == name)
            .map(|(_, v, _)| v.as_str())
    }
}

const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
/// Version 2, single-part scanline, names of at most 31 bytes.
const VERSION: [u8; 4] = [2, 0, 0, 0];
const MAX_NAME: usize = 31;

/// The image `l` describes (its attributes' ranges ignored), each scanline's
/// samples appended by `row(y, out)`: channel after channel in `l`'s order,
/// `width` little-endian samples each. Text is stored as Latin-1, other
/// characters as `?`.
pub(crate) fn encode(l: &ExrHeader, mut row: impl FnMut(u32, &mut Vec<u8>)) -> Result<Vec<u8>> {
    let names = l.channels.iter().map(|(n, _)| n);
    if !names.clone().zip(names.skip(1)).all(|(a, b)| a < b) {
        bail!("channels must be sorted by name, each once");
    }
    if l.width == 0 || l.height == 0 || l.width > i32::MAX as u32 || l.height > i32::MAX as u32 {
        bail!("a {}x{} image cannot be stored", l.width, l.height);
    }
    let row_bytes = l.row_bytes();
    let mut out = Vec::new();
    out.extend(MAGIC);
    out.extend(VERSION);
    let attr = |out: &mut Vec<u8>, name: &str, kind: &str, value: &[u8]| -> Result<()> {
        if name.is_empty() || name.len() > MAX_NAME {
            bail!("attribute name {name:?} is not 1 to {MAX_NAME} bytes");
        }
        for s in [name, kind] {
            out.extend(s.as_bytes());
            out.push(0);
        }
        out.extend((value.len() as i32).to_le_bytes());
        out.extend(value);
        Ok(())
    };
    let mut chlist = Vec::new();
    for (name, kind) in &l.channels {
        if name.is_empty() || name.len() > MAX_NAME || name.contains('\0') {
            bail!("channel name {name:?} is not 1 to {MAX_NAME} bytes");
        }
        chlist.extend(name.as_bytes());
        chlist.push(0);
        chlist.extend((*kind as i32).to_le_bytes());
        chlist.extend([0; 4]);
        chlist.extend(1i32.to_le_bytes());
        chlist.extend(1i32.to_le_bytes());
    }
    chlist.push(0);
    let window: Vec<u8> = [0, 0, l.width as i32 - 1, l.height as i32 - 1]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    attr(&mut out, "channels", "chlist", &chlist)?;
    attr(&mut out, "compression", "compression", &[0])?;
    attr(&mut out, "dataWindow", "box2i", &window)?;
    attr(&mut out, "displayWindow", "box2i", &window)?;
    attr(&mut out, "lineOrder", "lineOrder", &[0])?;
    attr(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes())?;
    attr(&mut out, "screenWindowCenter", "v2f", &[0; 8])?;
    attr(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes())?;
    for (name, value, _) in &l.attributes {
        let latin1: Vec<u8> = value
            .chars()
            .map(|c| if (c as u32) < 256 { c as u8 } else { b'?' })
            .collect();
        attr(&mut out, name, "string", &latin1)?;
    }
    out.push(0);
    let table = out.len();
    let chunk = 8 + row_bytes;
    out.reserve(8 * l.height as usize + chunk * l.height as usize);
    for y in 0..l.height as usize {
        out.extend(((table + 8 * l.height as usize + y * chunk) as u64).to_le_bytes());
    }
    for y in 0..l.height {
        out.extend((y as i32).to_le_bytes());
        out.extend((row_bytes as i32).to_le_bytes());
        let at = out.len();
        row(y, &mut out);
        if out.len() - at != row_bytes {
            bail!("scanline {y} has {} bytes, not {row_bytes}", out.len() - at);
        }
    }
    Ok(out)
}

/// A file's prefix longer than any header and offset table this layout
/// has (16384 scanlines).
const HEADER_LIMIT: u64 = 1 << 20;

/// An image open for reading its scanlines a band at a time: the header
/// and offset table checked, the file of the size they promise, each
/// scanline's chunk where the writer puts it (one after another, in
/// order), so that a band is one read.
pub(crate) struct Scanlines {
    pub(crate) layout: ExrHeader,
    path: PathBuf,
    /// The header and offset table, as the file stores them.
    pub(crate) head: Vec<u8>,
}

impl Scanlines {
    /// Opens the image at `path`; `admit` sees its size and channel count
    /// before anything else is read and may refuse them. Every error names
    /// the file.
    pub(crate) fn open(
        path: &Path,
        admit: &dyn Fn(u32, u32, usize) -> Result<()>,
    ) -> Result<Scanlines> {
        let mut file = super::open(path)?;
        let mut head = Vec::new();
        (&mut file)
            .take(HEADER_LIMIT)
            .read_to_end(&mut head)
            .with_context(|| format!("{}: cannot be read", path.display()))?;
        let (layout, end) = header(&head).map_err(|e| unfit(path, e))?;
        admit(layout.width, layout.height, layout.channels.len())?;
        let h = layout.height as u64;
        let chunk = 8 + layout.row_bytes() as u64;
        let size = end as u64 + 8 * h + h * chunk;
        let actual = file.metadata()?.len();
        if actual != size {
            bail!(
                "{}: {actual} bytes where its header promises {size}: the file is cut short or has been added to",
                path.display()
            );
        }
        head.truncate(end + 8 * h as usize);
        for y in 0..h {
            let at = le_u64(&head, end + 8 * y as usize).map_err(|e| unfit(path, e))?;
            if at != end as u64 + 8 * h + y * chunk {
                bail!(
                    "{}: the offset table does not list the scanlines one after another",
                    path.display()
                );
            }
        }
        Ok(Scanlines {
            layout,
            path: path.to_path_buf(),
            head,
        })
    }

    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// Bytes of one scanline's chunk: its line number and size, then its
    /// samples.
    pub(crate) fn chunk(&self) -> usize {
        8 + self.layout.row_bytes()
    }

    /// Reads the chunks of scanlines `rows` into `buf`, one after another,
    /// checking that each says it is the scanline it should be.
    pub(crate) fn read(&self, rows: Range<u32>, buf: &mut Vec<u8>) -> Result<()> {
        use std::os::unix::fs::FileExt;
        let chunk = self.chunk();
        buf.resize(rows.len() * chunk, 0);
        let at = self.head.len() as u64 + rows.start as u64 * chunk as u64;
        super::open(&self.path)?
            .read_exact_at(buf, at)
            .with_context(|| {
                format!(
                    "{}: cannot be read (changed while being read?)",
                    self.path.display()
                )
            })?;
        for (y, c) in rows.zip(buf.chunks_exact(chunk)) {
            if le_u32(c, 0)? != y || le_u32(c, 4)? as usize != chunk - 8 {
                bail!(
                    "{}: the chunk of scanline {y} says otherwise",
                    self.path.display()
                );
            }
        }
        Ok(())
    }
}

fn unfit(path: &Path, e: anyhow::Error) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: not an uncompressed scanline OpenEXR image of 32-bit channels ({e})",
        path.display()
    )
}

fn le_u32(b: &[u8], at: usize) -> Result<u32> {
    match b.get(at..at.saturating_add(4)) {
        Some(s) => Ok(u32::from_le_bytes(s.try_into().unwrap())),
        None => bail!("cut short at byte {at}"),
    }
}

fn le_u64(b: &[u8], at: usize) -> Result<u64> {
    match b.get(at..at.saturating_add(8)) {
        Some(s) => Ok(u64::from_le_bytes(s.try_into().unwrap())),
        None => bail!("cut short at byte {at}"),
    }
}

/// The layout a header gives, and where the header ends.
pub(crate) fn header(b: &[u8]) -> Result<(ExrHeader, usize)> {
    if b.get(0..4) != Some(&MAGIC[..]) {
        bail!("no OpenEXR magic number");
    }
    if b.get(4..8) != Some(&VERSION[..]) {
        bail!("not a single-part scanline image of version 2");
    }
    let mut at = 8;
    let text = |at: &mut usize| -> Result<String> {
        let rest = b.get(*at..).unwrap_or_default();
        let len = rest
            .iter()
            .take(MAX_NAME + 1)
            .position(|&c| c == 0)
            .ok_or_else(|| {
                anyhow::anyhow!("a name at byte {at} is not ended within {MAX_NAME} bytes")
            })?;
        *at += len + 1;
        Ok(latin1(&rest[..len]))
    };
    let mut l = ExrHeader::default();
    let (mut window, mut compression, mut channels) = (None, None, None);
    loop {
        let name = text(&mut at)?;
        if name.is_empty() {
            break;
        }
        let kind = text(&mut at)?;
        let size = le_u32(b, at)? as usize;
        let value = at + 4..(at + 4).saturating_add(size);
        let v = b
            .get(value.clone())
            .ok_or_else(|| anyhow::anyhow!("attribute {name} runs past the end"))?;
        at = value.end;
        match (name.as_str(), kind.as_str()) {
            ("channels", "chlist") => channels = Some(chlist(v)?),
            ("compression", "compression") => compression = v.first().copied(),
            ("dataWindow", "box2i") if v.len() == 16 => {
                let i =
                    |k: usize| i32::from_le_bytes(v[4 * k..4 * k + 4].try_into().unwrap()) as i64;
                window = Some((i(0), i(1), i(2), i(3)));
            }
            (_, "string") => l.attributes.push((name, latin1(v), value)),
            _ => {}
        }
    }
    if compression != Some(0) {
        bail!("compressed, or no compression attribute");
    }
    let Some((x0, y0, x1, y1)) = window else {
        bail!("no data window");
    };
    let (w, h) = (x1 - x0 + 1, y1 - y0 + 1);
    if (x0, y0) != (0, 0)
        || !(1..=i32::MAX as i64).contains(&w)
        || !(1..=i32::MAX as i64).contains(&h)
    {
        bail!("a data window from ({x0}, {y0}) to ({x1}, {y1})");
    }
    (l.width, l.height) = (w as u32, h as u32);
    l.channels = channels.ok_or_else(|| anyhow::anyhow!("no channel list"))?;
    Ok((l, at))
}

/// Latin-1 text as read, control characters made printable: names and
/// values of a damaged file reach messages, and none rayterm writes holds
/// one.
fn latin1(b: &[u8]) -> String {
    crate::words::printable(&b.iter().map(|&c| c as char).collect::<String>())
}

/// A channel list: sorted, 32-bit, unsubsampled.
fn chlist(v: &[u8]) -> Result<Vec<(String, SampleType)>> {
    let mut out: Vec<(String, SampleType)> = Vec::new();
    let (mut at, mut last): (usize, &[u8]) = (0, &[]);
    loop {
        let rest = v.get(at..).unwrap_or_default();
        let len = rest
            .iter()
            .position(|&c| c == 0)
            .ok_or_else(|| anyhow::anyhow!("the channel list is not ended"))?;
        if len == 0 {
            return Ok(out);
        }
        let name = latin1(&rest[..len]);
        let field = |k: usize| le_u32(v, at + len + 1 + 4 * k);
        let kind = match field(0)? {
            0 => SampleType::U32,
            2 => SampleType::F32,
            _ => bail!("channel {name} is not 32-bit"),
        };
        if (field(2)?, field(3)?) != (1, 1) {
            bail!("channel {name} is subsampled");
        }
        // Byte by byte, as the file stores them.
        if !out.is_empty() && last >= &rest[..len] {
            bail!("channel {name} is out of order or given twice");
        }
        last = &rest[..len];
        out.push((name, kind));
        at += len + 1 + 16;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn layout() -> ExrHeader {
        ExrHeader {
            width: 3,
            height: 2,
            channels: vec![("B".into(), SampleType::F32), ("n".into(), SampleType::U32)],
            attributes: vec![("a.note".into(), "caf\u{e9} \u{263a}".into(), 0..0)],
        }
    }

    fn image() -> Vec<u8> {
        encode(&layout(), |y, out| {
            for x in 0..3 {
                out.extend((x as f32 + 10.0 * y as f32).to_le_bytes());
            }
            for x in 0..3u32 {
                out.extend((100 * y + x).to_le_bytes());
            }
        })
        .unwrap()
    }

    #[test]
    fn the_exr_crate_reads_what_is_written() {
        use exr::prelude::*;
        let img = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_buffered(std::io::Cursor::new(image()))
            .unwrap();
        let l = &img.layer_data;
        assert_eq!((l.size.0, l.size.1), (3, 2));
        let ch = &l.channel_data.list;
        assert_eq!(ch[0].name.to_string(), "B");
        match &ch[0].sample_data {
            FlatSamples::F32(v) => assert_eq!(v, &[0.0, 1.0, 2.0, 10.0, 11.0, 12.0]),
            other => panic!("{other:?}"),
        }
        match &ch[1].sample_data {
            FlatSamples::U32(v) => assert_eq!(v, &[0, 1, 2, 100, 101, 102]),
            other => panic!("{other:?}"),
        }
        let note = &l.attributes.other[&Text::from("a.note")];
        assert!(format!("{note:?}").contains("caf"), "{note:?}");
    }

    /// One test's folder of files, removed when the test ends, passed or
    /// failed.
    struct Folder(PathBuf);

    impl Folder {
        fn new(test: &str) -> Self {
            let d = std::env::temp_dir()
                .join(format!("rayterm-flat-exr-{test}-{}", std::process::id()));
            std::fs::create_dir_all(&d).unwrap();
            Folder(d)
        }

        fn file(&self, name: &str, bytes: &[u8]) -> PathBuf {
            let p = self.0.join(name);
            std::fs::write(&p, bytes).unwrap();
            p
        }
    }

    impl Drop for Folder {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn any(_: u32, _: u32, _: usize) -> Result<()> {
        Ok(())
    }

    #[test]
    fn a_round_trip_gives_the_layout_and_samples() {
        let bytes = image();
        let f = Folder::new("round");
        let img = Scanlines::open(&f.file("round.exr", &bytes), &any).unwrap();
        let l = &img.layout;
        assert_eq!(l.channels, layout().channels);
        assert_eq!((l.width, l.height), (3, 2));
        assert_eq!(l.attribute("a.note"), Some("caf\u{e9} ?"));
        assert_eq!(&bytes[l.attributes[0].2.clone()], b"caf\xe9 ?");
        let mut buf = Vec::new();
        img.read(1..2, &mut buf).unwrap();
        assert_eq!(buf.len(), img.chunk());
        let n = |x: usize| u32::from_le_bytes(buf[8 + 12 + 4 * x..][..4].try_into().unwrap());
        assert_eq!([n(0), n(1), n(2)], [100, 101, 102]);
        assert_eq!(img.head, bytes[..img.head.len()]);
        assert_eq!(img.head.len() + 2 * img.chunk(), bytes.len());
    }

    #[test]
    fn damaged_headers_and_tables_are_refused_not_trusted() {
        let bytes = image();
        let f = Folder::new("damaged");
        let (_, end) = header(&bytes).unwrap();
        // Every cut of the header fails cleanly, as does every cut file.
        for cut in 0..end {
            assert!(header(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        for cut in [0, 4, end, end + 8, bytes.len() - 1] {
            let p = f.file("cut.exr", &bytes[..cut]);
            let err = Scanlines::open(&p, &any).err().unwrap().to_string();
            assert!(err.contains("cut.exr"), "{err}");
        }
        let refuses = |b: &[u8], rows: Range<u32>| {
            let p = f.file("bad.exr", b);
            let err = match Scanlines::open(&p, &any) {
                Err(e) => e,
                Ok(img) => img.read(rows, &mut Vec::new()).err().unwrap(),
            };
            assert!(err.to_string().contains("bad.exr"), "{err}");
        };
        // A chunk offset pointing anywhere else.
        for to in [0u64, 1, end as u64, bytes.len() as u64 - 4, u64::MAX] {
            let mut b = bytes.clone();
            b[end..end + 8].copy_from_slice(&to.to_le_bytes());
            refuses(&b, 0..2);
        }
        // Two chunks claiming one scanline.
        let mut b = bytes.clone();
        let second = u64::from_le_bytes(b[end + 8..end + 16].try_into().unwrap()) as usize;
        b[second..second + 4].copy_from_slice(&0i32.to_le_bytes());
        refuses(&b, 0..2);
        // A file another program would read, but not of this layout.
        refuses(&[&bytes[..], &[0]].concat(), 0..2);
        let e = Scanlines::open(&f.file("small.exr", &bytes), &|w, _, _| {
            anyhow::ensure!(w < 3, "too wide");
            Ok(())
        });
        assert!(e.is_err());
    }
}
