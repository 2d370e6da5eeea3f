//! Partial films: a film over a range of sample indices, stored as
//! OpenEXR (the mean as R, G, B for any viewer; the exact colour sums, the
//! sample count and the error statistics as u32 channels, f64s and i128s
//! split into words) with attributes saying which scene, size, seed,
//! rayterm version and samples it holds. The parts of a split render
//! (`render --part K/N`, `--samples A..B`) and checkpoints are partial
//! films; [`merge`] turns parts back into the film one render would have
//! made: the same mean to the bit (colours are summed exactly), the error
//! statistics merged by Chan et al. in range order.

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use super::film::{Film, Piece, PixelStats, FIXED_MAX, FIXED_ONE};
use super::Session;
use crate::geometry::sampling::PIXEL_STRATA;
use crate::raster::openexr::{self, Channels, Samples};
use crate::scene::BloomSettings;

/// The most samples per pixel any render takes, and the end of every range.
pub const MAX_SPP: u32 = 1 << 20;

const KIND: &str = "rayterm partial film 1";

/// The widest and tallest film rayterm renders.
const MAX_SIDE: u32 = 16384;

/// What a partial film says about where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct Meta {
    pub scene: String,
    /// [`super::content::scene_hash`] of the scene and plan.
    pub hash: u64,
    pub seed: u64,
    pub version: String,
    /// The samples per pixel the whole render is to have, when known
    /// (`--part K/N` of it, or a checkpoint of a render to a set spp).
    pub total: Option<u32>,
    /// Bloom's settings when the plan runs it: what `merge` post-processes
    /// with.
    pub bloom: Option<BloomSettings>,
    /// Nothing in the scene is sampled: one sample is the exact image.
    pub exact: bool,
    pub triangles: u64,
    /// Rays traced and seconds spent rendering the samples held.
    pub rays: u64,
    pub seconds: f64,
}

impl Meta {
    /// What a session renders, before any sample.
    pub fn of(s: &Session, total: Option<u32>) -> Meta {
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
        }
    }
}

/// A uniform film over the sample indices `film.start..film.start + film.spp`.
#[derive(Clone, Debug)]
pub struct Part {
    pub film: Film,
    pub meta: Meta,
}

impl Part {
    pub fn range(&self) -> Range<u32> {
        self.film.start..self.film.start + self.film.spp
    }

    /// What its header says.
    pub fn header(&self) -> Header {
        Header {
            meta: self.meta.clone(),
            range: self.range(),
            size: (self.film.width, self.film.height),
        }
    }

    /// The partial film as OpenEXR bytes.
    pub fn encode(&self) -> Result<Vec<u8>> {
        encode(&self.film, &self.meta)
    }

    /// Reads a partial film, refusing anything that is not one rayterm
    /// wrote whole: every error names the file.
    pub fn read(path: &Path) -> Result<Part> {
        let c = openexr::read_channels(path, &admit(path))?;
        decode(c).with_context(|| format!("{}: not a usable partial film", path.display()))
    }
}

/// What a partial film's header says: enough to check and order the parts
/// of a merge before any pixel is read.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    pub meta: Meta,
    pub range: Range<u32>,
    pub size: (u32, u32),
}

impl Header {
    /// Reads a partial film's header, naming the file in every error.
    pub fn read(path: &Path) -> Result<Header> {
        let (w, h, attributes) = openexr::read_header(path, &admit(path))?;
        header_of(w, h, &attributes)
            .with_context(|| format!("{}: not a usable partial film", path.display()))
    }

    /// Refuses a part that another film cannot be merged with or continue:
    /// another rayterm version, scene, size or seed, named by `this` and
    /// `that`.
    pub fn check_same(&self, other: &Meta, size: (u32, u32), this: &str, that: &str) -> Result<()> {
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

/// Refuses, from its header, a film no rayterm render writes or this
/// machine cannot hold.
fn admit(path: &Path) -> impl Fn(u32, u32, usize) -> Result<()> + '_ {
    move |w, h, channels| {
        if w > MAX_SIDE || h > MAX_SIDE || channels > 64 {
            bail!(
                "{}: {w}x{h} pixels of {channels} channels is no partial film rayterm writes",
                path.display()
            );
        }
        // The decoded channels, the film and the image made from it.
        let per_pixel = 4 * channels as u64 + Film::BYTES_PER_PIXEL;
        crate::memory::check(
            &format!("{}: a {w}x{h} partial film", path.display()),
            w as u64 * h as u64 * per_pixel,
            None,
        )
    }
}

/// `film` and `meta` as a partial film's OpenEXR bytes.
pub fn encode(f: &Film, meta: &Meta) -> Result<Vec<u8>> {
    if f.adaptive.is_some() {
        bail!("an adaptive film cannot be stored as a partial film");
    }
    let px = &f.pixels;
    let mut ch: HashMap<String, Samples> = HashMap::new();
    let mean = |c: usize| Samples::F32(px.iter().map(|p| p.mean[c] as f32).collect());
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        ch.insert(name.into(), mean(c));
    }
    let mut u32s = |name: String, get: &dyn Fn(&PixelStats) -> u32| {
        ch.insert(name, Samples::U32(px.iter().map(get).collect()));
    };
    for (name, get) in WORDS {
        u32s(name.to_string(), &get);
    }
    for (name, get) in F64S {
        u32s(format!("{name}.lo"), &|p| get(p).to_bits() as u32);
        u32s(format!("{name}.hi"), &|p| (get(p).to_bits() >> 32) as u32);
    }
    for (c, cname) in ["R", "G", "B"].into_iter().enumerate() {
        for w in 0..4 {
            u32s(format!("sum.{cname}.{w}"), &|p| {
                (p.sum[c] >> (32 * w)) as u32
            });
        }
    }
    let m = meta;
    let r = f.start..f.start + f.spp;
    let mut attributes: HashMap<String, String> = [
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
    ]
    .into_iter()
    .map(|(k, v)| (format!("rayterm.{k}"), v))
    .collect();
    if let Some(t) = m.total {
        attributes.insert("rayterm.total".into(), t.to_string());
    }
    let mut c = Channels {
        width: f.width,
        height: f.height,
        channels: ch,
        attributes,
    };
    let sum = format!("{:08x}", checksum(&c));
    c.attributes.insert(CHECKSUM.into(), sum);
    openexr::encode_channels(&c)
}

/// The attribute holding [`checksum`].
const CHECKSUM: &str = "rayterm.checksum";

/// CRC-32 of every channel's samples and every other attribute, as the
/// file stores them, in name order. OpenEXR keeps no checksum of its own,
/// and a damaged word of a sum is often a plausible one: without this, a
/// flipped bit would merge into a wrong image.
fn checksum(c: &Channels) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&c.width.to_le_bytes());
    h.update(&c.height.to_le_bytes());
    let mut names: Vec<&String> = c.channels.keys().collect();
    names.sort();
    let mut buf = Vec::new();
    for name in names {
        h.update(name.as_bytes());
        h.update(&[0]);
        buf.clear();
        match &c.channels[name] {
            Samples::F32(v) => buf.extend(v.iter().flat_map(|x| x.to_bits().to_le_bytes())),
            Samples::U32(v) => buf.extend(v.iter().flat_map(|x| x.to_le_bytes())),
        }
        h.update(&buf);
    }
    let mut attrs: Vec<(&String, &String)> = c
        .attributes
        .iter()
        .filter(|(k, _)| *k != CHECKSUM)
        .collect();
    attrs.sort();
    for (k, v) in attrs {
        for s in [k, v] {
            h.update(openexr::stored_text(s).as_bytes());
            h.update(&[0]);
        }
    }
    h.finalize()
}

/// The one-word fields of a pixel.
type Word = (&'static str, fn(&PixelStats) -> u32);
const WORDS: [Word; 7] = [
    ("n", |p| p.n),
    ("blocks", |p| p.blocks),
    ("open", |p| p.open),
    ("head.block", |p| p.head.block),
    ("head.n", |p| p.head.n),
    ("tail.block", |p| p.tail.block),
    ("tail.n", |p| p.tail.n),
];

/// The f64 fields of a pixel, stored as two words.
type Double = (&'static str, fn(&PixelStats) -> f64);
const F64S: [Double; 8] = [
    ("m2", |p| p.m2),
    ("block_mean", |p| p.block_mean),
    ("block_m2", |p| p.block_m2),
    ("checker", |p| p.checker),
    ("head.sum", |p| p.head.sum),
    ("head.diff", |p| p.head.diff),
    ("tail.sum", |p| p.tail.sum),
    ("tail.diff", |p| p.tail.diff),
];

/// Refuses attributes that are not a partial film's.
fn check_kind(a: &HashMap<String, String>) -> Result<()> {
    if a.get("rayterm.film").map(String::as_str) != Some(KIND) {
        bail!("no rayterm.film attribute saying \"{KIND}\"");
    }
    if !a.contains_key(CHECKSUM) {
        bail!("no {CHECKSUM} attribute");
    }
    Ok(())
}

/// The header of a `w` x `h` partial film with attributes `a`.
fn header_of(w: u32, h: u32, attrs: &HashMap<String, String>) -> Result<Header> {
    check_kind(attrs)?;
    if w == 0 || h == 0 {
        bail!("the film has no pixels ({w}x{h})");
    }
    let attr = |k: &str| -> Result<&String> {
        attrs
            .get(&format!("rayterm.{k}"))
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
    let bloom = match attr("bloom")?.as_str() {
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
    let meta = Meta {
        scene: attr("scene")?.clone(),
        hash: u64::from_str_radix(attr("hash")?, 16)
            .map_err(|_| anyhow::anyhow!("rayterm.hash is not hexadecimal"))?,
        seed: num("seed", attr("seed")?)?,
        version: attr("version")?.clone(),
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
    };
    Ok(Header {
        meta,
        range: start..end,
        size: (w, h),
    })
}

fn decode(mut c: Channels) -> Result<Part> {
    check_kind(&c.attributes)?;
    let stored = &c.attributes[CHECKSUM];
    if u32::from_str_radix(stored, 16).ok() != Some(checksum(&c)) {
        bail!("its data do not match their checksum: the file is damaged");
    }
    let Header {
        meta,
        range: Range { start, end },
        ..
    } = header_of(c.width, c.height, &c.attributes)?;
    let (w, h) = (c.width, c.height);
    let count = w as usize * h as usize;
    let mut word = |name: &str| -> Result<Vec<u32>> {
        match c.channels.remove(name) {
            Some(Samples::U32(v)) if v.len() == count => Ok(v),
            Some(_) => bail!("channel {name} is not {count} u32 samples"),
            None => bail!("no channel {name}"),
        }
    };
    type Put = fn(&mut PixelStats, u32);
    let words: [(&str, Put); 7] = [
        ("n", |p, v| p.n = v),
        ("blocks", |p, v| p.blocks = v),
        ("open", |p, v| p.open = v),
        ("head.block", |p, v| p.head.block = v),
        ("head.n", |p, v| p.head.n = v),
        ("tail.block", |p, v| p.tail.block = v),
        ("tail.n", |p, v| p.tail.n = v),
    ];
    type Field = fn(&mut PixelStats) -> &mut f64;
    let doubles: [(&str, Field); 8] = [
        ("m2", |p| &mut p.m2),
        ("block_mean", |p| &mut p.block_mean),
        ("block_m2", |p| &mut p.block_m2),
        ("checker", |p| &mut p.checker),
        ("head.sum", |p| &mut p.head.sum),
        ("head.diff", |p| &mut p.head.diff),
        ("tail.sum", |p| &mut p.tail.sum),
        ("tail.diff", |p| &mut p.tail.diff),
    ];
    // The columns in the order the pixels are built from: the words, each
    // f64's low and high word, each colour sum's four words from the low.
    let mut names: Vec<String> = words.iter().map(|(n, _)| n.to_string()).collect();
    for (name, _) in &doubles {
        names.extend([format!("{name}.lo"), format!("{name}.hi")]);
    }
    for cname in ["R", "G", "B"] {
        names.extend((0..4).map(|wd| format!("sum.{cname}.{wd}")));
    }
    let columns = names
        .iter()
        .map(|n| word(n))
        .collect::<Result<Vec<Vec<u32>>>>()?;
    // One pass over the pixels, each written once: reading the columns
    // side by side streams them, where a pass per column would not.
    let (first_double, first_sum) = (words.len(), words.len() + 2 * doubles.len());
    let pixels: Vec<PixelStats> = (0..count)
        .map(|i| {
            let at = |k: usize| columns[k][i];
            let mut p = PixelStats::default();
            for (k, (_, put)) in words.iter().enumerate() {
                put(&mut p, at(k));
            }
            for (k, (_, field)) in doubles.iter().enumerate() {
                let j = first_double + 2 * k;
                *field(&mut p) = f64::from_bits(at(j) as u64 | (at(j + 1) as u64) << 32);
            }
            for (c, sum) in p.sum.iter_mut().enumerate() {
                let j = first_sum + 4 * c;
                let bits = (0..4).fold(0u128, |s, wd| s | (at(j + wd) as u128) << (32 * wd));
                *sum = bits as i128;
            }
            p
        })
        .collect();
    drop(columns);
    let mut pixels = pixels;
    let spp = end - start;
    let mut bad = 0u64;
    for (i, p) in pixels.iter_mut().enumerate() {
        check_pixel(p, spp, start, end)
            .with_context(|| format!("pixel ({}, {})", i % w as usize, i / w as usize))?;
        p.mean = p.mean_of_sum();
        bad += (spp - p.n) as u64;
    }
    let mut film = Film::new(0, 0);
    (film.width, film.height, film.pixels) = (w, h, pixels);
    (film.start, film.spp, film.bad_count) = (start, spp, bad);
    Ok(Part { film, meta })
}

/// Refuses statistics no render of `spp` samples from `start` leaves.
fn check_pixel(p: &PixelStats, spp: u32, start: u32, end: u32) -> Result<()> {
    let most = p.n as i128 * (FIXED_MAX as f64 * FIXED_ONE) as i128;
    let finite = [p.m2, p.block_mean, p.block_m2, p.checker]
        .iter()
        .chain(&[p.head.sum, p.head.diff, p.tail.sum, p.tail.diff])
        .all(|x| x.is_finite());
    let blocks = (start / PIXEL_STRATA)..end.div_ceil(PIXEL_STRATA);
    let piece = |q: &Piece| q.n == 0 || (q.n < PIXEL_STRATA && blocks.contains(&q.block));
    let ok = p.n <= spp
        && p.sum.iter().all(|s| s.abs() <= most)
        && finite
        && p.m2 >= 0.0
        && p.block_m2 >= 0.0
        && p.checker >= 0.0
        && p.blocks as u64 * PIXEL_STRATA as u64 <= p.n as u64
        && p.open <= p.n.saturating_mul(PIXEL_STRATA)
        && piece(&p.head)
        && piece(&p.tail);
    if !ok {
        bail!("statistics no render of samples {start}..{end} leaves");
    }
    Ok(())
}

/// The parts of one render, checked from their headers and put in range
/// order, with the render's total and the ranges no part holds.
pub struct Plan {
    pub parts: Vec<(PathBuf, Header)>,
    pub total: u32,
    pub missing: Vec<Range<u32>>,
}

/// Reads the headers of `paths` and checks that they come from one render
/// and do not overlap. Missing ranges are returned; the caller decides
/// whether they may be.
pub fn plan(paths: &[PathBuf]) -> Result<Plan> {
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
    Ok(Plan {
        parts,
        total,
        missing,
    })
}

/// Reads the planned parts in range order and merges them, holding one
/// part at a time beside the sum so far.
pub fn merge(plan: &Plan, cancel: &dyn Fn() -> bool) -> Result<Part> {
    let mut merged: Option<Part> = None;
    for (path, header) in &plan.parts {
        if cancel() {
            return Err(crate::interrupt::Interrupted.into());
        }
        let part = Part::read(path)?;
        if part.header() != *header {
            bail!("{}: changed while being merged", path.display());
        }
        match &mut merged {
            None => merged = Some(part),
            Some(m) => {
                m.film.merge(&part.film);
                m.meta.rays += part.meta.rays;
                m.meta.seconds += part.meta.seconds;
            }
        }
    }
    let mut merged = merged.ok_or_else(|| anyhow::anyhow!("no parts to merge"))?;
    merged.meta.total = Some(plan.total);
    Ok(merged)
}

/// `0..16 and 48..64`.
pub fn ranges_text(r: &[Range<u32>]) -> String {
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
