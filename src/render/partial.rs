//! Partial films: a film over a range of sample indices, stored as
//! uncompressed OpenEXR (the mean as R, G, B for any viewer; each word of
//! the exact colour sums, the sample count and the error statistics as a
//! u32 channel, or as one number in `rayterm.constants` where every pixel
//! has the same) with attributes saying which scene, size, seed, rayterm
//! version and samples it holds, and a CRC-32 of the whole file. The parts
//! of a split render (`render --part K/N`, `--samples A..B`) and
//! checkpoints are partial films; [`merge`] turns parts back into the film
//! one render would have made: the same mean to the bit (colours are
//! summed exactly), the error statistics merged by Chan et al. in range
//! order.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Result};

use glam::Vec3;

use super::film::{BlockPart, Film, PixelStats, Report, FIXED_MAX, FIXED_ONE};
use super::Session;
use crate::geometry::sampling::PIXEL_STRATA;
use crate::interrupt::Cancel;
use crate::raster::flat_exr::{self, ExrHeader, SampleType, Scanlines};
use crate::scene::load::source::InputFile;
use crate::scene::BloomSettings;
use crate::words::quoted;

pub(crate) use crate::scene::MAX_SPP;

const KIND: &str = "rayterm partial film 2";

/// The widest and tallest film rayterm renders.
const MAX_SIDE: u32 = 16384;

/// What a partial film says about where it came from.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Meta {
    pub(crate) scene: String,
    /// [`super::content::scene_hash`] of the scene and plan.
    pub(crate) hash: u64,
    pub(crate) seed: u64,
    pub(crate) version: String,
    /// The samples per pixel the whole render is to have, when known
    /// (`--part K/N` of it, or a checkpoint of a render to a set spp).
    pub(crate) total: Option<u32>,
    /// Bloom's settings when the plan runs it: what `merge` post-processes
    /// with.
    pub(crate) bloom: Option<BloomSettings>,
    /// Nothing in the scene is sampled: one sample is the exact image.
    pub(crate) exact: bool,
    pub(crate) triangles: u64,
    /// Rays traced and seconds spent rendering the samples held.
    pub(crate) rays: u64,
    pub(crate) seconds: f64,
    /// Which of `render --part K/N` it is, where it is one.
    pub(crate) part: Option<(u32, u32)>,
    /// The options of `render` every part of the render shares (the scene,
    /// its size, spp, seed and features), as words: what renders a missing
    /// part, and what `merge --check` opens the scene with.
    pub(crate) command: Vec<String>,
    /// The files the scene was read from, with their CRC-32s, where
    /// recorded (not for a list too long for the header).
    pub(crate) inputs: Option<Vec<InputFile>>,
}

impl Meta {
    /// What a session renders, before any sample.
    pub(crate) fn of(s: &Session, total: Option<u32>) -> Meta {
        Meta {
            scene: s.scene.name.clone(),
            hash: super::content::scene_hash(&s.scene, &s.plan),
            seed: s.seed,
            version: env!("CARGO_PKG_VERSION").to_string(),
            total,
            bloom: s.plan.bloom.then_some(s.scene.settings.bloom),
            exact: s.plan.deterministic,
            triangles: s.scene.geometry.triangle_count() as u64,
            rays: 0,
            seconds: 0.0,
            part: None,
            command: Vec::new(),
            inputs: Some(s.inputs.clone()),
        }
    }
}

/// A uniform film over the sample indices `film.start..film.start + film.spp`.
#[derive(Clone, Debug)]
pub(crate) struct Part {
    pub(crate) film: Film,
    pub(crate) meta: Meta,
}

impl Part {
    pub(crate) fn range(&self) -> Range<u32> {
        self.film.start..self.film.start + self.film.spp
    }

    /// What its header says.
    pub(crate) fn header(&self) -> Header {
        Header {
            meta: self.meta.clone(),
            range: self.range(),
            size: (self.film.width, self.film.height),
        }
    }

    /// Reads a partial film, refusing anything that is not one rayterm
    /// wrote whole: every error names the file.
    pub(crate) fn read(path: &Path) -> Result<Part> {
        let source = Source::open(path)?;
        let header = source.header.clone();
        let mut sources = [source];
        let mut pixels = Vec::new();
        let bad = gather(&mut sources, Cancel::Never, |band| {
            pixels.extend_from_slice(band)
        })?;
        let [source] = sources;
        source.finish()?;
        Ok(Part::of(header, pixels, bad))
    }

    /// The part a header and its pixels make.
    fn of(header: Header, pixels: Vec<PixelStats>, bad: u64) -> Part {
        let Header { meta, range, size } = header;
        let mut film = Film::of_stats(size.0, size.1, pixels);
        (film.start, film.spp, film.bad_count) = (range.start, range.len() as u32, bad);
        Part { film, meta }
    }
}

/// What a partial film's header says: enough to check and order the parts
/// of a merge before any pixel is read.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub(crate) meta: Meta,
    pub range: Range<u32>,
    pub(crate) size: (u32, u32),
}

impl Header {
    /// Reads a partial film's header, naming the file in every error.
    pub fn read(path: &Path) -> Result<Header> {
        let image = scanlines(path)?;
        header_of(&image.layout).map_err(|e| unusable(&image, e))
    }

    /// Refuses a part that another film cannot be merged with or continue:
    /// another rayterm version, scene, size or seed, named by `this` and
    /// `that`.
    pub(crate) fn check_same(
        &self,
        other: &Meta,
        size: (u32, u32),
        this: &str,
        that: &str,
    ) -> Result<()> {
        let m = &self.meta;
        let differ = |field: &str, a: String, b: String| -> Result<()> {
            bail!("{this} and {that} differ in {field}: {a} against {b}")
        };
        if m.version != other.version {
            differ("rayterm version", m.version.clone(), other.version.clone())?;
        }
        let own = self.size;
        if own != size {
            differ(
                "size",
                format!("{}x{}", own.0, own.1),
                format!("{}x{}", size.0, size.1),
            )?;
        }
        if m.seed != other.seed {
            differ("seed", m.seed.to_string(), other.seed.to_string())?;
        }
        if m.hash != other.hash {
            differ(
                "scene (content hash)",
                format!("{} {:016x}", m.scene, m.hash),
                format!("{} {:016x}", other.scene, other.hash),
            )?;
        }
        Ok(())
    }
}

/// Why [`admit`] refused a film: its own words, which name the file.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct NotAdmitted(String);

/// Refuses, from its header, a film no rayterm render writes or this
/// machine cannot hold.
fn admit(path: &Path) -> impl Fn(u32, u32, usize) -> Result<()> + '_ {
    move |w, h, channels| {
        if w > MAX_SIDE || h > MAX_SIDE || channels > 64 {
            return Err(NotAdmitted(format!(
                "{}: {w}x{h} pixels of {channels} channels is no partial film rayterm writes",
                path.display()
            ))
            .into());
        }
        // The decoded channels, the film and the image made from it.
        let per_pixel = 4 * channels as u64 + Film::BYTES_PER_PIXEL;
        crate::memory::check(
            &format!("{}: a {w}x{h} partial film", path.display()),
            w as u64 * h as u64 * per_pixel,
            None,
        )
        .map_err(|e| NotAdmitted(format!("{e:#}")).into())
    }
}

/// A pixel's statistics as words, named by [`FIELDS`].
type Words = [u32; FIELDS.len()];

/// The channel (or constant) names of a pixel's words: the counts, each
/// f64's low and high word, each colour sum's four words from the low.
const FIELDS: [&str; 35] = [
    "n",
    "blocks",
    "open",
    "head.block",
    "head.n",
    "tail.block",
    "tail.n",
    "m2.lo",
    "m2.hi",
    "block_mean.lo",
    "block_mean.hi",
    "block_m2.lo",
    "block_m2.hi",
    "checker.lo",
    "checker.hi",
    "head.sum.lo",
    "head.sum.hi",
    "head.diff.lo",
    "head.diff.hi",
    "tail.sum.lo",
    "tail.sum.hi",
    "tail.diff.lo",
    "tail.diff.hi",
    "sum.R.0",
    "sum.R.1",
    "sum.R.2",
    "sum.R.3",
    "sum.G.0",
    "sum.G.1",
    "sum.G.2",
    "sum.G.3",
    "sum.B.0",
    "sum.B.1",
    "sum.B.2",
    "sum.B.3",
];

/// Where the f64s and the sums start among a pixel's words.
const DOUBLES: usize = 7;
const SUMS: usize = 23;

fn words(p: &PixelStats) -> Words {
    let mut w = [0; FIELDS.len()];
    w[..DOUBLES].copy_from_slice(&[
        p.n,
        p.blocks,
        p.open,
        p.head.block,
        p.head.n,
        p.tail.block,
        p.tail.n,
    ]);
    let doubles = [
        p.m2,
        p.block_mean,
        p.block_m2,
        p.checker,
        p.head.sum,
        p.head.diff,
        p.tail.sum,
        p.tail.diff,
    ];
    for (k, x) in doubles.into_iter().enumerate() {
        let b = x.to_bits();
        w[DOUBLES + 2 * k..][..2].copy_from_slice(&[b as u32, (b >> 32) as u32]);
    }
    for (c, s) in p.sum.into_iter().enumerate() {
        for k in 0..4 {
            w[SUMS + 4 * c + k] = (s >> (32 * k)) as u32;
        }
    }
    w
}

/// The pixel [`words`] gave `w`, its mean left to compute.
fn from_words(w: &Words) -> PixelStats {
    let double = |k: usize| {
        let j = DOUBLES + 2 * k;
        f64::from_bits(w[j] as u64 | (w[j + 1] as u64) << 32)
    };
    let sum = |c: usize| {
        let half = |k: usize| w[SUMS + 4 * c + k] as u64 | (w[SUMS + 4 * c + k + 1] as u64) << 32;
        ((half(2) as u128) << 64 | half(0) as u128) as i128
    };
    PixelStats {
        sum: [sum(0), sum(1), sum(2)],
        n: w[0],
        blocks: w[1],
        open: w[2],
        head: BlockPart {
            block: w[3],
            n: w[4],
            sum: double(4),
            diff: double(5),
        },
        tail: BlockPart {
            block: w[5],
            n: w[6],
            sum: double(6),
            diff: double(7),
        },
        m2: double(0),
        block_mean: double(1),
        block_m2: double(2),
        checker: double(3),
        // Partial films keep no quarters.
        quarters: f32::NAN,
        ..PixelStats::default()
    }
}

/// A channel of a partial film: the mean for viewers, or a word.
#[derive(Clone, Copy)]
enum Column {
    Mean(usize),
    Word(usize),
}

/// The attribute holding the whole file's CRC-32, written as eight hex
/// digits over these zeros. OpenEXR keeps no checksum of its own, and a
/// damaged word of a sum is often a plausible one: without it, a flipped
/// bit would merge into a wrong image.
const CHECKSUM: &str = "rayterm.checksum";
const UNSEALED: &str = "00000000";

/// `film` and `meta` as a partial film's OpenEXR bytes.
pub(crate) fn encode(f: &Film, meta: &Meta) -> Result<Vec<u8>> {
    if f.adaptive.is_some() {
        bail!("an adaptive film cannot be stored as a partial film");
    }
    let Some(first) = f.pixels().first().map(words) else {
        bail!("a film with no pixels cannot be stored");
    };
    // Words every pixel shares are stored once, as attributes: most of a
    // uniform film's counts, and the empty pieces of aligned ranges.
    let mut varies = [false; FIELDS.len()];
    for p in f.pixels() {
        for (v, (a, b)) in varies.iter_mut().zip(words(p).iter().zip(&first)) {
            *v |= a != b;
        }
    }
    let mut columns: Vec<(&str, Column)> = vec![
        ("R", Column::Mean(0)),
        ("G", Column::Mean(1)),
        ("B", Column::Mean(2)),
    ];
    columns.extend(
        (0..FIELDS.len())
            .filter(|&k| varies[k])
            .map(|k| (FIELDS[k], Column::Word(k))),
    );
    columns.sort_by_key(|(name, _)| *name);
    let constants: Vec<String> = (0..FIELDS.len())
        .filter(|&k| !varies[k])
        .map(|k| format!("{}={}", FIELDS[k], first[k]))
        .collect();
    let m = meta;
    let r = f.start..f.start + f.spp;
    let mut attributes: Vec<(String, String)> = [
        ("film", KIND.to_string()),
        ("version", m.version.clone()),
        ("scene", m.scene.clone()),
        ("hash", format!("{:016x}", m.hash)),
        ("seed", m.seed.to_string()),
        ("samples", format!("{}..{}", r.start, r.end)),
        ("exact", m.exact.to_string()),
        ("triangles", m.triangles.to_string()),
        ("rays", m.rays.to_string()),
        ("seconds", m.seconds.to_string()),
        (
            "bloom",
            match m.bloom {
                None => "off".into(),
                Some(b) => format!("{} {} {} {}", b.threshold, b.sigma, b.radius, b.strength),
            },
        ),
        ("constants", constants.join(" ")),
        ("checksum", UNSEALED.into()),
    ]
    .into_iter()
    .map(|(k, v)| (format!("rayterm.{k}"), v))
    .collect();
    if let Some(t) = m.total {
        attributes.push(("rayterm.total".into(), t.to_string()));
    }
    if let Some((k, n)) = m.part {
        attributes.push(("rayterm.part".into(), format!("{k}/{n}")));
    }
    if !m.command.is_empty() {
        attributes.push(("rayterm.command".into(), ascii_json(&m.command)));
    }
    let inputs = m.inputs.as_ref().map(|list| {
        let pairs: Vec<(String, String)> = list
            .iter()
            .map(|i| (format!("{:08x}", i.crc), i.path.display().to_string()))
            .collect();
        ascii_json(&pairs)
    });
    // A list longer than a header holds is left out: `merge --check` then
    // names no file.
    if let Some(list) = inputs.filter(|l| l.len() <= INPUTS_LIMIT) {
        attributes.push(("rayterm.inputs".into(), list));
    }
    attributes.sort();
    let layout = ExrHeader {
        width: f.width,
        height: f.height,
        channels: columns
            .iter()
            .map(|&(name, c)| {
                let kind = match c {
                    Column::Mean(_) => SampleType::F32,
                    Column::Word(_) => SampleType::U32,
                };
                (name.to_string(), kind)
            })
            .collect(),
        attributes: attributes.into_iter().map(|(k, v)| (k, v, 0..0)).collect(),
    };
    let w = f.width as usize;
    let mut row_words = vec![[0; FIELDS.len()]; w];
    let mut bytes = flat_exr::encode(&layout, |y, out| {
        let px = &f.pixels()[y as usize * w..][..w];
        for (r, p) in row_words.iter_mut().zip(px) {
            *r = words(p);
        }
        for &(_, c) in &columns {
            match c {
                Column::Mean(c) => {
                    out.extend(px.iter().flat_map(|p| (p.mean[c] as f32).to_le_bytes()))
                }
                Column::Word(k) => out.extend(row_words.iter().flat_map(|r| r[k].to_le_bytes())),
            }
        }
    })?;
    let (written, _) = flat_exr::header(&bytes)?;
    let at = sealed_at(&written)?;
    let crc = format!("{:08x}", crc32fast::hash(&bytes));
    bytes[at].copy_from_slice(crc.as_bytes());
    Ok(bytes)
}

/// The longest list of inputs a header records, in bytes (a header is
/// read up to 1 MiB).
const INPUTS_LIMIT: usize = 256 << 10;

/// `value` as JSON in ASCII: attributes are Latin-1, and a path may hold
/// any character.
fn ascii_json(value: &impl serde::Serialize) -> String {
    let json = serde_json::to_string(value).unwrap_or_default();
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        match c.is_ascii() {
            true => out.push(c),
            false => {
                for u in c.encode_utf16(&mut [0; 2]) {
                    out += &format!("\\u{u:04x}");
                }
            }
        }
    }
    out
}

/// Where the checksum's eight digits lie in a file of layout `l`.
fn sealed_at(l: &ExrHeader) -> Result<Range<usize>> {
    match l.attributes.iter().find(|(k, _, _)| k == CHECKSUM) {
        Some((_, _, at)) if at.len() == UNSEALED.len() => Ok(at.clone()),
        _ => bail!("no {CHECKSUM} attribute of eight hex digits"),
    }
}

/// The header of a partial film of layout `l`.
fn header_of(l: &ExrHeader) -> Result<Header> {
    let attrs: HashMap<&str, &str> = l
        .attributes
        .iter()
        .map(|(k, v, _)| (k.as_str(), v.as_str()))
        .collect();
    if attrs.get("rayterm.film") != Some(&KIND) {
        bail!("no rayterm.film attribute saying \"{KIND}\"");
    }
    let (w, h) = (l.width, l.height);
    let attr = |k: &str| -> Result<&str> {
        attrs
            .get(format!("rayterm.{k}").as_str())
            .copied()
            .ok_or_else(|| anyhow::anyhow!("no rayterm.{k} attribute"))
    };
    fn num<T: std::str::FromStr>(k: &str, v: &str) -> Result<T> {
        v.parse()
            .map_err(|_| anyhow::anyhow!("rayterm.{k} is not a number: {v:?}"))
    }
    let samples = attr("samples")?;
    let (a, b) = samples
        .split_once("..")
        .ok_or_else(|| anyhow::anyhow!("rayterm.samples is not A..B: {samples:?}"))?;
    let (start, end): (u32, u32) = (num("samples", a)?, num("samples", b)?);
    if start >= end || end > MAX_SPP {
        bail!("rayterm.samples {start}..{end} is not a range within 0..{MAX_SPP}");
    }
    let total = match attrs.get("rayterm.total") {
        None => None,
        Some(t) => Some(num::<u32>("total", t)?).filter(|&t| t >= end && t <= MAX_SPP),
    };
    if attrs.contains_key("rayterm.total") && total.is_none() {
        bail!("rayterm.total is not a sample count from the range's end to {MAX_SPP}");
    }
    let bloom = match attr("bloom")? {
        "off" => None,
        b => {
            let v: Vec<&str> = b.split(' ').collect();
            let [t, s, r, st] = v.as_slice() else {
                bail!("rayterm.bloom is not four numbers: {b:?}");
            };
            let bloom = BloomSettings {
                threshold: num("bloom", t)?,
                sigma: num("bloom", s)?,
                radius: num("bloom", r)?,
                strength: num("bloom", st)?,
            };
            let finite = [bloom.threshold, bloom.sigma, bloom.strength]
                .iter()
                .all(|x| x.is_finite());
            if !finite || bloom.sigma <= 0.0 || bloom.radius > 1024 {
                bail!("rayterm.bloom has settings no scene has: {b:?}");
            }
            Some(bloom)
        }
    };
    let seconds: f64 = num("seconds", attr("seconds")?)?;
    let part = match attrs.get("rayterm.part") {
        None => None,
        Some(p) => {
            let kn = p
                .split_once('/')
                .and_then(|(k, n)| Some((k.parse::<u32>().ok()?, n.parse::<u32>().ok()?)))
                .filter(|&(k, n)| (1..=n).contains(&k));
            Some(kn.ok_or_else(|| anyhow::anyhow!("rayterm.part is not K/N: {p:?}"))?)
        }
    };
    let json = |k: &str| attrs.get(format!("rayterm.{k}").as_str()).copied();
    let command: Vec<String> = match json("command") {
        None => Vec::new(),
        Some(c) => serde_json::from_str(c)
            .map_err(|_| anyhow::anyhow!("rayterm.command is not a list of words"))?,
    };
    let inputs = match json("inputs") {
        None => None,
        Some(list) => {
            let pairs: Vec<(String, String)> = serde_json::from_str(list)
                .map_err(|_| anyhow::anyhow!("rayterm.inputs is not a list of files"))?;
            let inputs = pairs
                .into_iter()
                .map(|(crc, path)| {
                    let crc = u32::from_str_radix(&crc, 16).map_err(|_| {
                        anyhow::anyhow!("rayterm.inputs gives {} as a CRC-32", quoted(&crc))
                    })?;
                    Ok(InputFile {
                        path: path.into(),
                        crc,
                    })
                })
                .collect::<Result<Vec<_>>>()?;
            Some(inputs)
        }
    };
    let meta = Meta {
        scene: attr("scene")?.to_string(),
        hash: u64::from_str_radix(attr("hash")?, 16)
            .map_err(|_| anyhow::anyhow!("rayterm.hash is not hexadecimal"))?,
        seed: num("seed", attr("seed")?)?,
        version: attr("version")?.to_string(),
        total,
        bloom,
        exact: num("exact", attr("exact")?)?,
        triangles: num("triangles", attr("triangles")?)?,
        rays: num("rays", attr("rays")?)?,
        seconds: if seconds.is_finite() && seconds >= 0.0 {
            seconds
        } else {
            bail!("rayterm.seconds is not a duration")
        },
        part,
        command,
        inputs,
    };
    Ok(Header {
        meta,
        range: start..end,
        size: (w, h),
    })
}

/// A partial film being read: its header, where each of a pixel's words
/// comes from, and the checksum of what has been read so far.
struct Source {
    image: Scanlines,
    header: Header,
    /// The other words: which, and their channel's byte offset in a chunk.
    columns: Vec<(usize, usize)>,
    stored: Option<u32>,
    crc: crc32fast::Hasher,
    /// The words every pixel shares, the others left zero.
    shared: Words,
}

/// A film's header, where its checksum lies, its columns and its shared
/// words.
type Said = (Header, Range<usize>, Vec<(usize, usize)>, Words);

/// The scanlines of the partial film at `path`; a file that holds none at
/// all (a finished image, say) is named as no partial film.
fn scanlines(path: &Path) -> Result<Scanlines> {
    Scanlines::open(path, &admit(path)).map_err(|e| {
        match path.is_file() && !e.is::<NotAdmitted>() {
            true => e.context(format!(
                "{}: not a partial film (one that render --part, --samples or --checkpoint writes)",
                path.display()
            )),
            false => e,
        }
    })
}

impl Source {
    /// Opens the partial film at `path`, checking its header and that it
    /// says where every word of a pixel is. Errors name the file.
    fn open(path: &Path) -> Result<Source> {
        let image = scanlines(path)?;
        match Source::read_layout(&image.layout) {
            Ok(read) => Ok(Source::of(image, read)),
            Err(e) => Err(unusable(&image, e)),
        }
    }

    /// What the layout `l` of a film says, checked before any checksum is
    /// (see [`unusable`]).
    fn read_layout(l: &ExrHeader) -> Result<Said> {
        let header = header_of(l)?;
        let at = sealed_at(l)?;
        let field = |name: &str| FIELDS.iter().position(|f| *f == name);
        let mut shared = [0; FIELDS.len()];
        let mut given = [false; FIELDS.len()];
        let mut give = |name: &str| -> Result<usize> {
            match field(name) {
                Some(k) if !given[k] => {
                    given[k] = true;
                    Ok(k)
                }
                Some(_) => bail!("{} is given twice", quoted(name)),
                None => bail!("{} is no word of a pixel", quoted(name)),
            }
        };
        let row = 4 * l.width as usize;
        let mut columns = Vec::new();
        for (c, (name, kind)) in l.channels.iter().enumerate() {
            match (name.as_str(), kind) {
                ("R" | "G" | "B", SampleType::F32) => {}
                (_, SampleType::U32) => columns.push((give(name)?, 8 + c * row)),
                _ => bail!(
                    "channel {} is not of the type a partial film stores",
                    quoted(name)
                ),
            }
        }
        let constants = l.attribute("rayterm.constants").unwrap_or_default();
        for c in constants.split(' ').filter(|c| !c.is_empty()) {
            let (name, v) = c.split_once('=').ok_or_else(|| {
                anyhow::anyhow!("rayterm.constants has '{}', not NAME=VALUE", quoted(c))
            })?;
            shared[give(name)?] = v.parse().map_err(|_| {
                anyhow::anyhow!(
                    "rayterm.constants gives {} as '{}'",
                    quoted(name),
                    quoted(v)
                )
            })?;
        }
        if let Some(k) = given.iter().position(|g| !g) {
            bail!("no channel or constant holds {}", FIELDS[k]);
        }
        Ok((header, at, columns, shared))
    }

    fn of(mut image: Scanlines, read: Said) -> Source {
        let (header, at, columns, shared) = read;
        let (stored, crc) = seal(&mut image.head, at);
        Source {
            image,
            header,
            columns,
            stored,
            crc,
            shared,
        }
    }

    /// Reads scanlines `rows` into `buf` and merges each pixel, checked,
    /// into `pixels` (those rows of the film); returns the samples dropped
    /// as not finite.
    fn merge_into(
        &mut self,
        rows: Range<u32>,
        buf: &mut Vec<u8>,
        pixels: &mut [PixelStats],
    ) -> Result<u64> {
        self.image.read(rows.clone(), buf)?;
        self.crc.update(buf);
        let Range { start, end } = self.header.range;
        let spp = end - start;
        let w = self.header.size.0 as usize;
        let mut bad = 0u64;
        let mut columns = Vec::with_capacity(self.columns.len());
        for ((y, chunk), px) in rows
            .zip(buf.chunks_exact(self.image.chunk()))
            .zip(pixels.chunks_exact_mut(w))
        {
            columns.clear();
            columns.extend(
                self.columns
                    .iter()
                    .map(|&(k, at)| (k, &chunk[at..at + 4 * w])),
            );
            // The shared words, and each channel's word of this pixel over
            // them: every channel is read in order, a word a pixel.
            let mut words = self.shared;
            for (x, p) in px.iter_mut().enumerate() {
                for (k, column) in &columns {
                    let b = &column[4 * x..4 * x + 4];
                    words[*k] = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                }
                let q = from_words(&words);
                if !plausible(&q, spp, start, end) {
                    bail!(
                        "{}: pixel ({x}, {y}) holds statistics no render of samples {start}..{end} leaves",
                        self.image.path().display()
                    );
                }
                bad += (spp - q.n) as u64;
                p.merge_stats(&q);
            }
        }
        Ok(bad)
    }

    /// Refuses the film if what was read does not match its checksum.
    fn finish(self) -> Result<()> {
        if self.stored != Some(self.crc.finalize()) {
            return Err(damaged(self.image.path()));
        }
        Ok(())
    }
}

/// The checksum `head` stores at `at`, and the checksum of `head` with it
/// zeroed again, as it was computed.
fn seal(head: &mut [u8], at: Range<usize>) -> (Option<u32>, crc32fast::Hasher) {
    let stored = u32::from_str_radix(&String::from_utf8_lossy(&head[at.clone()]), 16).ok();
    head[at].copy_from_slice(UNSEALED.as_bytes());
    let mut crc = crc32fast::Hasher::new();
    crc.update(head);
    (stored, crc)
}

fn damaged(path: &Path) -> anyhow::Error {
    anyhow::anyhow!(
        "{}: its data do not match their checksum: the file is damaged",
        crate::words::path(path)
    )
}

/// The error for a film whose header makes no sense: that it is damaged
/// where its checksum says so (a flipped bit in a name is damage, not
/// another kind of film), or else `e`.
fn unusable(image: &Scanlines, e: anyhow::Error) -> anyhow::Error {
    if let Ok(at) = sealed_at(&image.layout) {
        let (stored, mut crc) = seal(&mut image.head.clone(), at);
        let rows = (BAND_BYTES / image.chunk()).max(1) as u32;
        let mut buf = Vec::new();
        for y in (0..image.layout.height).step_by(rows as usize) {
            let band = y..(y + rows).min(image.layout.height);
            if image.read(band, &mut buf).is_err() {
                return damaged(image.path());
            }
            crc.update(&buf);
        }
        if stored != Some(crc.finalize()) {
            return damaged(image.path());
        }
    }
    e.context(format!(
        "{}: not a usable partial film",
        crate::words::path(image.path())
    ))
}

/// Merges the partial films `sources`, of one size and in range order, a
/// band of scanlines at a time in one buffer (the band's pixels stay in
/// cache while every part adds to them), and hands each band's merged
/// pixels, top to bottom, to `done`; returns the samples dropped as not
/// finite.
fn gather(
    sources: &mut [Source],
    cancel: Cancel,
    mut done: impl FnMut(&[PixelStats]),
) -> Result<u64> {
    let Some(first) = sources.first() else {
        bail!("no parts to merge");
    };
    let (w, h) = (first.header.size.0 as usize, first.header.size.1);
    let band = (BAND_BYTES / (w * std::mem::size_of::<PixelStats>())).clamp(1, h as usize) as u32;
    let mut pixels = vec![PixelStats::default(); band as usize * w];
    let mut buf = Vec::new();
    let mut bad = 0;
    for y in (0..h).step_by(band as usize) {
        cancel.check()?;
        let rows = y..(y + band).min(h);
        let px = &mut pixels[..rows.len() * w];
        px.fill(PixelStats::default());
        for s in sources.iter_mut() {
            bad += s.merge_into(rows.clone(), &mut buf, px)?;
        }
        for p in px.iter_mut() {
            p.mean = p.mean_of_sum();
        }
        done(px);
    }
    Ok(bad)
}

/// The film pixels a band holds: what stays in a core's cache.
const BAND_BYTES: usize = 4 << 20;

/// Whether a render of `spp` samples from `start` can leave `p`.
fn plausible(p: &PixelStats, spp: u32, start: u32, end: u32) -> bool {
    let most = p.n as i128 * (FIXED_MAX as f64 * FIXED_ONE) as i128;
    let finite = [p.m2, p.block_mean, p.block_m2, p.checker]
        .iter()
        .chain(&[p.head.sum, p.head.diff, p.tail.sum, p.tail.diff])
        .all(|x| x.is_finite());
    let blocks = (start / PIXEL_STRATA)..end.div_ceil(PIXEL_STRATA);
    // No more samples than the range holds of the piece's block, so that
    // pieces joined across parts never exceed a block.
    let held = |b: u32| {
        let lo = b * PIXEL_STRATA;
        (lo + PIXEL_STRATA).min(end).saturating_sub(lo.max(start))
    };
    let piece = |q: &BlockPart| {
        q.n == 0 || (q.n < PIXEL_STRATA && blocks.contains(&q.block) && q.n <= held(q.block))
    };
    p.n <= spp
        && p.sum.iter().all(|s| s.unsigned_abs() <= most as u128)
        && finite
        && p.m2 >= 0.0
        && p.block_m2 >= 0.0
        && p.checker >= 0.0
        && p.blocks as u64 * PIXEL_STRATA as u64 <= p.n as u64
        && p.open <= p.n.saturating_mul(PIXEL_STRATA)
        && piece(&p.head)
        && piece(&p.tail)
}

/// The parts of one render, checked from their headers and put in range
/// order, with the render's total and the ranges no part holds.
pub(crate) struct MergePlan {
    pub(crate) parts: Vec<(PathBuf, Header)>,
    pub(crate) total: u32,
    pub(crate) missing: Vec<Range<u32>>,
}

/// Reads the headers of `paths` and checks that they come from one render
/// and do not overlap. Missing ranges are returned; the caller decides
/// whether they may be.
pub(crate) fn plan(paths: &[PathBuf]) -> Result<MergePlan> {
    let mut parts = Vec::with_capacity(paths.len());
    for p in paths {
        parts.push((p.clone(), Header::read(p)?));
    }
    let Some((first_path, first)) = parts.first() else {
        bail!("no parts to merge");
    };
    let name = |p: &Path| p.display().to_string();
    for (p, part) in &parts[1..] {
        part.check_same(&first.meta, first.size, &name(p), &name(first_path))?;
    }
    let mut total = None::<(u32, PathBuf)>;
    for (p, part) in &parts {
        match (part.meta.total, &total) {
            (Some(t), Some((u, q))) if t != *u => bail!(
                "{} is a part of {t} samples, {} of {u}: they are not one render",
                name(p),
                name(q)
            ),
            (Some(t), _) => total = Some((t, p.clone())),
            _ => {}
        }
    }
    parts.sort_by_key(|(_, part)| part.range.start);
    for pair in parts.windows(2) {
        let ((p, a), (q, b)) = (&pair[0], &pair[1]);
        let same = |x: &Path| std::fs::canonicalize(x).ok();
        if same(p).is_some() && same(p) == same(q) {
            bail!("{} is given twice", name(p));
        }
        if a.range.end > b.range.start {
            bail!(
                "{} (samples {:?}) and {} (samples {:?}) overlap",
                name(p),
                a.range,
                name(q),
                b.range
            );
        }
    }
    let end = parts.last().map_or(0, |(_, p)| p.range.end);
    let total = total.map_or(end, |t| t.0);
    let mut missing = Vec::new();
    let mut at = 0;
    for (_, part) in &parts {
        if part.range.start > at {
            missing.push(at..part.range.start);
        }
        at = part.range.end;
    }
    if total > at {
        missing.push(at..total);
    }
    Ok(MergePlan {
        parts,
        total,
        missing,
    })
}

/// A merged render: what its image file and closing line need. A merge
/// measures them band by band and never holds the merged statistics whole
/// (176 bytes a pixel, against 12 for the image).
pub(crate) struct Merged {
    pub(crate) meta: Meta,
    pub(crate) size: (u32, u32),
    /// The linear mean image, row-major.
    pub(crate) image: Vec<Vec3>,
    pub(crate) report: Report,
}

/// Opens the planned parts, checking that none changed since planned.
fn open_planned(plan: &MergePlan) -> Result<Vec<Source>> {
    let mut sources = Vec::with_capacity(plan.parts.len());
    for (path, header) in &plan.parts {
        let s = Source::open(path)?;
        if s.header != *header {
            bail!("{}: changed while being merged", path.display());
        }
        sources.push(s);
    }
    Ok(sources)
}

/// What the merged parts say of their render: the first's meta with the
/// rays and seconds of them all, and no part number.
fn merged_meta(sources: &[Source]) -> Result<Meta> {
    let mut meta = sources[0].header.meta.clone();
    meta.rays = sources
        .iter()
        .try_fold(0u64, |n, s| n.checked_add(s.header.meta.rays))
        .ok_or_else(|| {
            anyhow::anyhow!("the parts' rayterm.rays add up to more than 2^64: one is damaged")
        })?;
    meta.seconds = sources.iter().map(|s| s.header.meta.seconds).sum();
    meta.part = None;
    Ok(meta)
}

/// Reads the planned parts and merges them in range order.
pub(crate) fn merge(plan: &MergePlan, cancel: Cancel) -> Result<Merged> {
    let mut sources = open_planned(plan)?;
    let size = sources[0].header.size;
    let mut image = Vec::with_capacity(size.0 as usize * size.1 as usize);
    // The film's estimate, summed in its order: the same figure to the bit.
    let mut rel_mse = Some(0.0);
    let bad = gather(&mut sources, cancel, |band| {
        image.extend(band.iter().map(|p| p.mean.as_vec3()));
        for p in band {
            rel_mse = rel_mse.zip(p.rel_variance()).map(|(s, v)| s + v);
        }
    })?;
    let mut meta = merged_meta(&sources)?;
    meta.total = Some(plan.total);
    let range = sources[0].header.range.start..sources[sources.len() - 1].header.range.end;
    let spp = sources.iter().map(|s| s.header.range.len() as u32).sum();
    for s in sources {
        s.finish()?;
    }
    let pixels = image.len().max(1) as f64;
    let report = Report {
        spp: (spp, spp as f64, spp),
        adaptive: false,
        samples: range.start..range.start + spp,
        relative_error: rel_mse
            .filter(|_| !image.is_empty())
            .map(|s| (s / pixels).sqrt()),
        bad_count: bad,
    };
    Ok(Merged {
        meta,
        size,
        image,
        report,
    })
}

/// Merges the planned parts into one partial film, which merges again
/// with the parts still to come (a staged merge): their samples must
/// follow one another, since a partial film holds one range.
pub(crate) fn merge_part(plan: &MergePlan, cancel: Cancel) -> Result<Part> {
    let (start, end) = match (plan.parts.first(), plan.parts.last()) {
        (Some((_, a)), Some((_, b))) => (a.range.start, b.range.end),
        _ => bail!("no parts to merge"),
    };
    if let Some(gap) = plan
        .missing
        .iter()
        .find(|m| m.start >= start && m.end <= end)
    {
        bail!(
            "samples {}..{} are missing between the parts, and a partial film holds one range \
             of samples: merge these parts once those samples are rendered",
            gap.start,
            gap.end
        );
    }
    let mut sources = open_planned(plan)?;
    let size = sources[0].header.size;
    let count = size.0 as u64 * size.1 as u64;
    crate::memory::check(
        &format!("a merged {}x{} partial film", size.0, size.1),
        count * Film::BYTES_PER_PIXEL,
        None,
    )?;
    let mut pixels = Vec::with_capacity(count as usize);
    let bad = gather(&mut sources, cancel, |band| pixels.extend_from_slice(band))?;
    let mut meta = merged_meta(&sources)?;
    meta.total = sources.iter().find_map(|s| s.header.meta.total);
    for s in sources {
        s.finish()?;
    }
    let header = Header {
        meta,
        range: start..end,
        size,
    };
    Ok(Part::of(header, pixels, bad))
}

impl MergePlan {
    /// The parts of `render --part K/N` the missing samples make, where
    /// they are whole parts: N, and each missing K.
    pub(crate) fn missing_parts(&self) -> Option<(u32, Vec<u32>)> {
        let n = self
            .parts
            .iter()
            .find_map(|(_, h)| h.meta.part.map(|p| p.1))?;
        let at = |i: u32| (i as u64 * self.total as u64 / n as u64) as u32;
        let mut ks = Vec::new();
        for m in &self.missing {
            let within: Vec<u32> = (1..=n)
                .filter(|&k| at(k - 1) < at(k) && at(k - 1) >= m.start && at(k) <= m.end)
                .collect();
            let held: u32 = within.iter().map(|&k| at(k) - at(k - 1)).sum();
            if held != m.end - m.start {
                return None;
            }
            ks.extend(within);
        }
        Some((n, ks))
    }
}

/// `0..16 and 48..64`.
pub(crate) fn ranges_text(r: &[Range<u32>]) -> String {
    let each: Vec<String> = r
        .iter()
        .map(|r| format!("{}..{}", r.start, r.end))
        .collect();
    match each.as_slice() {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Statistics that no render of the range leaves, though each field is
    /// in its own bounds, are refused: a sum of `i128::MIN` (whose `abs`
    /// wraps) and a block piece of more samples than the range holds of
    /// that block (two such pieces joined would exceed a block).
    #[test]
    fn forged_statistics_are_not_plausible() {
        let honest = PixelStats {
            n: 4,
            head: BlockPart {
                block: 0,
                n: 4,
                ..BlockPart::default()
            },
            ..PixelStats::default()
        };
        assert!(plausible(&honest, 4, 12, 16));
        let low = PixelStats {
            sum: [i128::MIN, 0, 0],
            ..honest
        };
        assert!(!plausible(&low, 4, 12, 16));
        let wide = PixelStats {
            n: 4,
            head: BlockPart {
                n: 12,
                ..honest.head
            },
            ..honest
        };
        assert!(!plausible(&wide, 4, 12, 16));
        // The same piece is fine where the range holds 12 of the block.
        assert!(plausible(&PixelStats { n: 12, ..wide }, 12, 4, 16));
    }

    #[test]
    fn every_field_of_a_pixel_survives_its_words() {
        let mut r = crate::geometry::sampling::Rng::for_sample(1, 2, 3);
        for _ in 0..1000 {
            let w: Vec<u32> = (0..FIELDS.len()).map(|_| r.next_u32()).collect();
            let w: Words = w.try_into().unwrap();
            let p = from_words(&w);
            assert_eq!(words(&p), w);
            // The names say what the words hold.
            let at = |name: &str| w[FIELDS.iter().position(|f| *f == name).unwrap()];
            assert_eq!(at("n"), p.n);
            assert_eq!(at("tail.block"), p.tail.block);
            assert_eq!(at("sum.G.2"), (p.sum[1] >> 64) as u32);
            assert_eq!(at("sum.B.0"), p.sum[2] as u32);
            assert_eq!(at("checker.lo"), p.checker.to_bits() as u32);
            assert_eq!(at("head.diff.hi"), (p.head.diff.to_bits() >> 32) as u32);
        }
    }
}
