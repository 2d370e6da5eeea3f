//! TOML scene files. Unknown keys, wrong types, arrays of the wrong length,
//! out-of-range settings and non-finite numbers are errors that name the
//! file, line and column; doubtful values (negative colours, absurd
//! coordinates) are warnings that name them too.
//!
//! Coordinates stay in f64 until the whole scene is placed: meshes, camera
//! and lights then go through one [`Rebase`](crate::scene::rebase::Rebase) (moved next to the origin when
//! far, scaled down when huge) and are rounded to f32 last.

use std::marker::PhantomData;
use std::ops::{Range, RangeInclusive};
use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use glam::{DAffine3, DQuat, DVec3, EulerRot, Vec3};
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use serde::Deserialize;
use toml::Spanned;

use crate::memory;

use super::bezier;
use super::mesh;
use super::numbers::{self, ABSURD};
use super::obj::{Parts, Placed};
use super::parts::bounds;
use super::source::{resolve, FileKind, Source};
use super::up::Up;
use crate::scene::rebase::Rebase;
use crate::scene::show::{show, show3};
use crate::scene::texture::{Encoding, FACE_NAMES};
use crate::scene::{
    BloomSettings, Builder, Camera, CubeMap, EnvLight, Environment, Light, Material, Projection,
    Scene, Settings,
};
use crate::words::{clip_quotes, printable, quoted};

/// A number that must be finite (also as f32); kept in f64 until the
/// scene is placed. The error carries the value's position.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "f64")]
struct Num(f64);

impl TryFrom<f64> for Num {
    type Error = String;
    fn try_from(x: f64) -> Result<Self, String> {
        match numbers::unusable(x) {
            Some(why) => Err(format!("{} {why}", show(x))),
            None => Ok(Num(x)),
        }
    }
}

impl Num {
    fn f32(self) -> f32 {
        self.0 as f32
    }
}

/// An array of exactly `N` values (serde's own arrays ignore extra ones).
#[derive(Clone, Copy, Debug)]
struct Exact<T, const N: usize>([T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T, const N: usize>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for V<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                write!(f, "an array of {N} values")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut items = Vec::with_capacity(N);
                while items.len() < N {
                    match seq.next_element::<T>()? {
                        Some(x) => items.push(x),
                        None => return Err(de::Error::invalid_length(items.len(), &self)),
                    }
                }
                let mut extra = 0;
                while seq.next_element::<IgnoredAny>()?.is_some() {
                    extra += 1;
                }
                if extra > 0 {
                    return Err(de::Error::invalid_length(N + extra, &self));
                }
                items
                    .try_into()
                    .map(Exact)
                    .map_err(|_| de::Error::invalid_length(0, &self))
            }
        }
        d.deserialize_seq(V(PhantomData))
    }
}

type V3 = Exact<Num, 3>;
/// A colour, with its position for warnings.
type Rgb = Spanned<V3>;

fn v3(v: V3) -> DVec3 {
    DVec3::new(v.0[0].0, v.0[1].0, v.0[2].0)
}

fn rgb(v: &Rgb) -> Vec3 {
    v3(*v.get_ref()).as_vec3()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    description: Option<String>,
    camera: Option<Spanned<CameraSpec>>,
    #[serde(default, rename = "mesh")]
    meshes: Vec<Spanned<MeshSpec>>,
    #[serde(default, rename = "light")]
    lights: Vec<Spanned<LightSpec>>,
    environment: Option<EnvSpec>,
    render: Option<RenderSpec>,
}

/// `camera = "auto"` or a table. Hand-written rather than `untagged` so
/// errors inside the table keep their line and column.
enum CameraSpec {
    Auto,
    Explicit(CameraTable),
}

impl<'de> Deserialize<'de> for CameraSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = CameraSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("\"auto\" or a table with eye, target, up and fov")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<CameraSpec, E> {
                match s {
                    "auto" => Ok(CameraSpec::Auto),
                    _ => Err(E::invalid_value(de::Unexpected::Str(s), &self)),
                }
            }
            fn visit_map<A: de::MapAccess<'de>>(self, m: A) -> Result<CameraSpec, A::Error> {
                CameraTable::deserialize(de::value::MapAccessDeserializer::new(m))
                    .map(CameraSpec::Explicit)
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    eye: V3,
    target: V3,
    up: Option<V3>,
    projection: Option<Spanned<ProjectionType>>,
    /// Vertical field of view, degrees (perspective).
    fov: Option<Spanned<Num>>,
    /// The view's height in scene units (orthographic).
    height: Option<Spanned<Num>>,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
enum ProjectionType {
    Perspective,
    Orthographic,
}

/// `scale = 2.0` or `scale = [1, 2, 1]`.
enum ScaleSpec {
    Uniform(Num),
    Axes(V3),
}

impl<'de> Deserialize<'de> for ScaleSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ScaleSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of three numbers")
            }
            fn visit_f64<E: de::Error>(self, x: f64) -> Result<ScaleSpec, E> {
                Num::try_from(x).map(ScaleSpec::Uniform).map_err(E::custom)
            }
            fn visit_i64<E: de::Error>(self, x: i64) -> Result<ScaleSpec, E> {
                self.visit_f64(x as f64)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, s: A) -> Result<ScaleSpec, A::Error> {
                V3::deserialize(de::value::SeqAccessDeserializer::new(s)).map(ScaleSpec::Axes)
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSpec {
    file: String,
    translate: Option<V3>,
    /// Degrees about X, then Y, then Z.
    rotate: Option<V3>,
    scale: Option<Spanned<ScaleSpec>>,
    /// Segments per patch edge for Bézier patch (`.bpt`) files.
    segments: Option<Spanned<u32>>,
    /// The file's up axis, where not its format's.
    up: Option<Spanned<String>>,
    material: Option<MaterialSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    name: Option<String>,
    kd: Option<Rgb>,
    ks: Option<Rgb>,
    ns: Option<Spanned<Num>>,
    d: Option<Spanned<Num>>,
    texture: Option<String>,
}

#[derive(Deserialize, Clone, Copy, PartialEq)]
#[serde(rename_all = "lowercase")]
enum LightType {
    Point,
    Segment,
    Parallelogram,
}

/// One `[[light]]`. Flat rather than an internally tagged enum, which would
/// lose the positions of errors inside it; which fields a type needs is
/// checked after parsing and reported at the table's line.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightSpec {
    #[serde(rename = "type")]
    kind: LightType,
    position: Option<V3>,
    color: Option<Rgb>,
    a: Option<V3>,
    b: Option<V3>,
    color_a: Option<Rgb>,
    color_b: Option<Rgb>,
    corner: Option<V3>,
    edge1: Option<V3>,
    edge2: Option<V3>,
    /// At corner, corner+edge1, corner+edge1+edge2, corner+edge2.
    colors: Option<Spanned<Exact<V3, 4>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvSpec {
    color: Option<Rgb>,
    sky: Option<bool>,
    faces: Option<FacesSpec>,
    /// An equirectangular map: an environment light.
    map: Option<Spanned<String>>,
    /// The map's radiance multiplied by this.
    strength: Option<Spanned<Num>>,
    /// Degrees the map turns about +Y.
    rotate: Option<Spanned<Num>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FacesSpec {
    posx: String,
    negx: String,
    posy: String,
    negy: String,
    posz: String,
    negz: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderSpec {
    size: Option<Spanned<Exact<u32, 2>>>,
    spp: Option<Spanned<u32>>,
    max_depth: Option<Spanned<u32>>,
    integrator: Option<crate::scene::Integrator>,
    builder: Option<Builder>,
    ambient: Option<Rgb>,
    light_samples: Option<Spanned<u32>>,
    glossy_samples: Option<Spanned<u32>>,
    bloom: Option<BloomSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BloomSpec {
    threshold: Option<Num>,
    sigma: Option<Spanned<Num>>,
    radius: Option<Spanned<u32>>,
    strength: Option<Num>,
}

/// Things a caller can change about a scene file as it loads.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Overrides {
    /// Segments per patch edge for every Bézier mesh (`teapot:N`).
    pub(crate) segments: Option<u32>,
}

/// Byte offsets where the lines of `text` start.
fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

/// 1-based line and column of byte offset `at` in `text`, given its
/// [`line_starts`] (a binary search: scenes with many meshes stay linear).
fn line_col(text: &str, starts: &[usize], at: usize) -> (usize, usize) {
    let at = at.min(text.len());
    let line = starts.partition_point(|&s| s <= at).max(1);
    let col = text
        .get(starts[line - 1]..at)
        .map_or(0, |l| l.chars().count())
        + 1;
    (line, col)
}

fn parse(path: &Path, text: &str) -> Result<SceneFile> {
    toml::from_str(text).map_err(|e| {
        // The parser quotes keys and values whole: a ten-megabyte key would
        // be echoed.
        let msg = clip_quotes(e.message().trim());
        match e.span() {
            Some(span) => {
                let (l, c) = line_col(text, &line_starts(text), span.start);
                anyhow!("{}:{l}:{c}: {msg}", path.display())
            }
            None => anyhow!("{}: {msg}", path.display()),
        }
    })
}

/// Largest segment count accepted for Bézier meshes.
const MAX_SEGMENTS: u32 = bezier::MAX_SEGMENTS;

/// Positions in a scene file, for messages: `file:line:col`.
struct Locator<'a> {
    path: &'a Path,
    text: &'a str,
    starts: Vec<usize>,
}

impl Locator<'_> {
    fn at(&self, span: Range<usize>) -> String {
        let (line, col) = line_col(self.text, &self.starts, span.start);
        format!("{}:{line}:{col}", self.path.display())
    }

    /// `value` within `range`, or an error at the value.
    fn range(&self, v: &Spanned<u32>, range: RangeInclusive<u32>, what: &str) -> Result<u32> {
        let x = *v.get_ref();
        if !range.contains(&x) {
            let (lo, hi) = range.into_inner();
            bail!(
                "{}: {what} must be from {lo} to {hi}, not {x}",
                self.at(v.span())
            );
        }
        Ok(x)
    }

    /// Warns on a colour with a negative or absurd component.
    fn colour(&self, c: &Rgb, what: &str, warnings: &mut Vec<String>) -> Vec3 {
        let v = rgb(c);
        let [x, y, z] = v.to_array().map(|c| show(c as f64));
        let shown = format!("{what} [{x}, {y}, {z}]");
        warnings.extend(self.odd_colours(c.span(), &shown, &[v]));
        v
    }

    /// A warning for colours `v`, `shown` at `span`, of which one has a
    /// negative component or one beyond [`ABSURD`] (the same bound as an
    /// MTL's colours: such a light's shading overflows to infinity, and its
    /// samples are dropped).
    fn odd_colours(&self, span: Range<usize>, shown: &str, v: &[Vec3]) -> Option<String> {
        let (kind, why) = if v.iter().any(|c| c.min_element() < 0.0) {
            (
                "negative",
                "light and reflectance cannot be negative".to_string(),
            )
        } else if v.iter().any(|c| c.abs().max_element() as f64 > ABSURD) {
            (
                "absurd",
                format!("beyond {ABSURD:e} shading can overflow to infinity"),
            )
        } else {
            return None;
        };
        Some(format!("{}: {kind} {shown}: {why}", self.at(span)))
    }
}

/// The placement of a `[[mesh]]`: its up axis turned to +Y (`up`, or its
/// format's; a `.bpt` is Y-up unless told), then scale, rotate, translate.
fn placement(m: &MeshSpec, loc: &Locator, format: Option<mesh::MeshFormat>) -> Result<DAffine3> {
    let up = match &m.up {
        Some(u) => u
            .get_ref()
            .parse::<Up>()
            .map_err(|e| anyhow!("{}: up: {e}", loc.at(u.span())))?,
        None => format.map_or(Up::Y, mesh::MeshFormat::up),
    };
    let mut xf = up.to_y();
    if let Some(s) = &m.scale {
        let v = match s.get_ref() {
            ScaleSpec::Uniform(s) => DVec3::splat(s.0),
            ScaleSpec::Axes(a) => v3(*a),
        };
        if v.cmpeq(DVec3::ZERO).any() {
            bail!("{}: scale must not be zero", loc.at(s.span()));
        }
        xf = DAffine3::from_scale(v) * xf;
    }
    if let Some(r) = m.rotate {
        let r = v3(r);
        let q = DQuat::from_euler(
            EulerRot::ZYX,
            r.z.to_radians(),
            r.y.to_radians(),
            r.x.to_radians(),
        );
        xf = DAffine3::from_quat(q) * xf;
    }
    if let Some(t) = m.translate {
        xf = DAffine3::from_translation(v3(t)) * xf;
    }
    Ok(xf)
}

/// A `.bpt` mesh tessellated and placed, after checking the memory it needs.
fn patches(
    src: &dyn Source,
    mesh_path: &Path,
    segments: u32,
    xf: &DAffine3,
    material: u32,
    room: u64,
) -> Result<Placed> {
    let text = src.read_text(mesh_path, FileKind::Patches)?;
    let patches = bezier::parse_bpt(&text)
        .map_err(|e| anyhow!("{}:{}: {}", mesh_path.display(), e.line, e.message))?;
    let n = segments as u64;
    let triangles = patches.len() as u64 * 2 * n * n;
    let vertices = patches.len() as u64 * (n + 1) * (n + 1);
    let what = format!(
        "{}: {} patches at {segments} segments per edge make {triangles} triangles, which",
        mesh_path.display(),
        patches.len()
    );
    if vertices > u32::MAX as u64 {
        bail!("{what} is more than 32-bit indices address ({vertices} vertices); lower segments");
    }
    let needed = memory::mesh_bytes(vertices, triangles);
    if needed > room {
        bail!(
            "{what} would need {} of memory; {} is available; lower segments",
            memory::bytes(needed),
            memory::bytes(room)
        );
    }
    let pm = bezier::tessellate(&patches, segments);
    let nxf = xf.matrix3.inverse().transpose();
    let mut positions = Vec::with_capacity(pm.positions.len());
    for p in &pm.positions {
        let q = xf.transform_point3(p.as_dvec3());
        if let Some(why) = q.to_array().into_iter().find_map(numbers::unusable) {
            bail!(
                "{}: once placed, the surface reaches {}, which {why}",
                mesh_path.display(),
                show3(q)
            );
        }
        positions.push(q);
    }
    Ok(Placed {
        name: mesh_path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        positions,
        normals: Some(
            pm.normals
                .iter()
                .map(|n| (nxf * n.as_dvec3()).normalize_or_zero().as_vec3())
                .collect(),
        ),
        uvs: Some(pm.uvs),
        uvs1: None,
        tangents: None,
        colors: None,
        indices: pm.indices,
        material,
    })
}

/// Every string of the file with control characters replaced (TOML
/// escapes can hold them), so no name or path echoed to a terminal can
/// carry an escape sequence.
fn sanitize(f: &mut SceneFile) {
    let clean = |s: &mut String| *s = printable(s);
    f.name.iter_mut().for_each(clean);
    f.description.iter_mut().for_each(clean);
    for m in &mut f.meshes {
        let m = m.get_mut();
        clean(&mut m.file);
        if let Some(mat) = &mut m.material {
            mat.name.iter_mut().for_each(clean);
            mat.texture.iter_mut().for_each(clean);
        }
    }
    if let Some(map) = f.environment.as_mut().and_then(|e| e.map.as_mut()) {
        clean(map.get_mut());
    }
    if let Some(faces) = f.environment.as_mut().and_then(|e| e.faces.as_mut()) {
        for s in [
            &mut faces.posx,
            &mut faces.negx,
            &mut faces.posy,
            &mut faces.negy,
            &mut faces.posz,
            &mut faces.negz,
        ] {
            clean(s);
        }
    }
}

/// A file name written in the scene: an error naming `what` when empty.
fn named<'a>(written: &'a str, what: &str) -> Result<&'a str> {
    if written.trim().is_empty() {
        bail!("{what}: the file name is empty");
    }
    Ok(written)
}

pub(crate) fn load_with(src: &dyn Source, path: &Path, ov: Overrides) -> Result<Scene> {
    let text = src.read_text(path, FileKind::Scene)?;
    let mut f = parse(path, &text)?;
    sanitize(&mut f);
    let loc = Locator {
        path,
        text: &text,
        starts: line_starts(&text),
    };
    let mut parts = Parts::default();
    let mut placed: Vec<Placed> = Vec::new();
    for spanned in &f.meshes {
        let m = spanned.get_ref();
        let here = loc.at(spanned.span());
        let mesh_path = resolve(path, named(&m.file, &format!("{here}: mesh"))?);
        let is_bpt = mesh_path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bpt"));
        // An unknown extension is read as OBJ, as it always was.
        let format =
            (!is_bpt).then(|| mesh::MeshFormat::of(&mesh_path).unwrap_or(mesh::MeshFormat::Obj));
        let xf = placement(m, &loc, format)?;
        let material = m
            .material
            .as_ref()
            .map(|ms| material_from(&mut parts, src, &loc, ms));
        let first = placed.len();
        let outside = src.outside(path, &mesh_path);
        if let Some(o) = &outside {
            parts.warnings.push(o.warning(&here, "mesh", &m.file));
        }
        let before = parts.warnings.len();
        let shown = quoted(&m.file);
        let (loaded, kind) = if is_bpt {
            let segments = match (ov.segments, &m.segments) {
                (Some(n), _) => n,
                (None, Some(s)) => loc.range(s, 1..=MAX_SEGMENTS, "segments")?,
                (None, None) => 8,
            };
            let mat = parts.add_material(material.unwrap_or_default());
            let room = parts.budget.room();
            let p = patches(src, &mesh_path, segments, &xf, mat, room);
            if let Ok(p) = &p {
                parts
                    .budget
                    .take(p.positions.len() as u64, p.indices.len() as u64);
            }
            (p.map(|p| vec![p]), FileKind::Patches)
        } else {
            if let Some(s) = &m.segments {
                parts.warnings.push(format!(
                    "{}: segments applies to .bpt meshes only: ignored",
                    loc.at(s.span())
                ));
            }
            let format = format.unwrap_or(mesh::MeshFormat::Obj);
            let p = mesh::load_placed(format, &mut parts, src, &mesh_path, &xf, material.as_ref());
            (p, format.kind())
        };
        let loaded = match &outside {
            Some(o) => o.quiet(kind, loaded, &mut parts.warnings, before),
            None => loaded,
        };
        placed.extend(loaded.with_context(|| format!("{here}: mesh {shown}"))?);
        let reach = placed[first..]
            .iter()
            .flat_map(|p| &p.positions)
            .fold(0.0f64, |r, p| r.max(p.abs().max_element()));
        if reach > ABSURD {
            parts.warnings.push(format!(
                "{here}: mesh {shown}: coordinates reach {} once placed; beyond {ABSURD:e} \
                 they are almost certainly a mistake",
                show(reach),
            ));
        }
    }
    let (min, max) = bounds(&placed);
    let (frame, moved) = Rebase::fit(min, max);
    parts.warnings.extend(
        moved
            .into_iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
    for m in placed {
        parts.add_placed(m, &frame);
    }
    if parts.geometry.indices.is_empty() {
        bail!(
            "{}: the scene has no triangles{}",
            path.display(),
            parts.why_empty()
        );
    }
    let bounds = parts.geometry.bounds();
    let camera = match &f.camera {
        None => Camera::auto(&bounds),
        Some(c) => match c.get_ref() {
            CameraSpec::Auto => Camera::auto(&bounds),
            CameraSpec::Explicit(t) => camera_from(t, &frame, &loc, c.span(), &mut parts)?,
        },
    };
    let lights = f
        .lights
        .iter()
        .map(|l| {
            let here = loc.at(l.span());
            let light = light_from(l.get_ref(), &frame, &loc, &mut parts.warnings)
                .map_err(|e| anyhow!("{here}: {e}"))?;
            let reach = match &light {
                Light::Point { position, .. } | Light::Photometric { position, .. } => {
                    position.abs().max_element()
                }
                Light::Directional { .. } => 0.0,
                Light::Segment { a, b, .. } => a.abs().max(b.abs()).max_element(),
                Light::Parallelogram {
                    corner,
                    edge1,
                    edge2,
                    ..
                } => (corner.abs() + edge1.abs() + edge2.abs()).max_element(),
            };
            if reach as f64 > ABSURD {
                parts.warnings.push(format!(
                    "{here}: light at {reach:e}: beyond {ABSURD:e} shading loses all precision"
                ));
            }
            Ok(light)
        })
        .collect::<Result<Vec<_>>>()?;
    if lights.is_empty() {
        parts.warnings.push(format!(
            "{}: no lights; only ambient light and the environment show",
            path.display()
        ));
    }
    let environment = environment_from(src, &loc, f.environment, &mut parts.warnings)?;
    let settings = settings_from(&loc, f.render, &mut parts.warnings)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(Scene {
        description: f.description.unwrap_or_default(),
        lights,
        environment,
        settings,
        ..parts.into_scene(f.name.unwrap_or(stem), camera)
    })
}

fn camera_from(
    c: &CameraTable,
    frame: &Rebase,
    loc: &Locator,
    table: Range<usize>,
    parts: &mut Parts,
) -> Result<Camera> {
    let here = loc.at(table);
    let (eye, target) = (v3(c.eye), v3(c.target));
    let up = c.up.map_or(DVec3::Y, v3);
    let fwd = target - eye;
    if fwd.length_squared() == 0.0 || fwd.cross(up).length_squared() == 0.0 {
        bail!("{here}: camera: eye, target and up must not be collinear");
    }
    let projection = projection_from(c, frame, loc, &here)?;
    let cam = Camera {
        eye: frame.point(eye),
        target: frame.point(target),
        up: up.as_vec3(),
        projection,
    };
    if cam.eye == cam.target {
        bail!("{here}: camera: eye and target are too close to tell apart in f32");
    }
    if cam.eye.abs().max(cam.target.abs()).max_element() as f64 > ABSURD {
        parts.warnings.push(format!(
            "{here}: camera beyond {ABSURD:e}: its rays lose all precision"
        ));
    }
    Ok(cam)
}

/// A camera table's projection: perspective with `fov` (default), or
/// orthographic with `height`; the other's field is an error.
fn projection_from(
    c: &CameraTable,
    frame: &Rebase,
    loc: &Locator,
    here: &str,
) -> Result<Projection> {
    let ortho = c
        .projection
        .as_ref()
        .is_some_and(|p| *p.get_ref() == ProjectionType::Orthographic);
    let at = |n: &Spanned<Num>| loc.at(n.span());
    if ortho {
        if let Some(f) = &c.fov {
            bail!(
                "{}: camera: fov is for perspective cameras; an orthographic one takes height",
                at(f)
            );
        }
        let Some(h) = &c.height else {
            bail!(
                "{here}: camera: an orthographic camera needs height (the view's height in \
                 scene units)"
            );
        };
        // Placed with the scene, which may be scaled for f32.
        let half_height = (h.get_ref().0 * 0.5 * frame.scale) as f32;
        if !(half_height > 0.0 && half_height.is_finite()) {
            bail!("{}: camera: height must be more than 0", at(h));
        }
        return Ok(Projection::Orthographic { half_height });
    }
    if let Some(h) = &c.height {
        bail!(
            "{}: camera: height is for orthographic cameras (projection = \"orthographic\"); \
             a perspective one takes fov",
            at(h)
        );
    }
    let vfov = c.fov.as_ref().map_or(45.0, |f| f.get_ref().f32());
    if !(1.0..179.0).contains(&vfov) {
        let at = c.fov.as_ref().map_or(here.to_string(), at);
        bail!("{at}: camera: fov must be between 1 and 179 degrees");
    }
    Ok(Projection::perspective(vfov))
}

fn material_from(parts: &mut Parts, src: &dyn Source, loc: &Locator, m: &MaterialSpec) -> Material {
    let d = Material::default();
    let w = &mut parts.warnings;
    let kd = m.kd.as_ref().map_or(d.kd, |c| loc.colour(c, "kd", w));
    let ks = m.ks.as_ref().map_or(d.ks, |c| loc.colour(c, "ks", w));
    let ns = m.ns.as_ref().map_or(d.ns, |n| {
        let x = n.get_ref().f32();
        if x < 0.0 {
            w.push(format!("{}: negative ns {x}: using 0", loc.at(n.span())));
        }
        x.max(0.0)
    });
    let dissolve = m.d.as_ref().map_or(d.dissolve, |n| {
        let x = n.get_ref().f32();
        if !(0.0..=1.0).contains(&x) {
            w.push(format!(
                "{}: d {x} is outside 0..1: clamped",
                loc.at(n.span())
            ));
        }
        x.clamp(0.0, 1.0)
    });
    let from = loc.path.display().to_string();
    let texture = match m.texture.as_deref() {
        Some(t) if t.trim().is_empty() => {
            parts.warnings.push(format!(
                "{from}: material texture: the file name is empty; using the material colour"
            ));
            None
        }
        Some(t) => parts.texture(src, loc.path, t, &from),
        None => None,
    };
    Material {
        name: m.name.clone().unwrap_or_else(|| "inline".into()),
        kd,
        ks,
        ns,
        dissolve,
        texture,
        pbr: None,
        alpha: None,
        unlit: false,
    }
}

fn light_from(
    l: &LightSpec,
    frame: &Rebase,
    loc: &Locator,
    warnings: &mut Vec<String>,
) -> Result<Light, String> {
    let need = |v: Option<V3>, name: &str| {
        v.map(v3)
            .ok_or_else(|| format!("this light needs `{name}`"))
    };
    let point = |v: Option<V3>, name: &str| need(v, name).map(|p| frame.point(p));
    let vector = |v: Option<V3>, name: &str| need(v, name).map(|p| frame.vector(p));
    let mut colour = |c: Option<&Rgb>, name: &str| {
        c.map(|c| loc.colour(c, name, warnings))
            .ok_or_else(|| format!("this light needs `{name}`"))
    };
    let given = |names: &[(&str, bool)]| -> Result<(), String> {
        match names.iter().find(|(_, set)| *set) {
            Some((n, _)) => Err(format!("`{n}` does not apply to this type of light")),
            None => Ok(()),
        }
    };
    let mut odd = None;
    let light = match l.kind {
        LightType::Point => {
            given(&[
                ("a", l.a.is_some()),
                ("b", l.b.is_some()),
                ("corner", l.corner.is_some()),
                ("colors", l.colors.is_some()),
            ])?;
            Light::Point {
                position: point(l.position, "position")?,
                color: colour(l.color.as_ref(), "color")?,
            }
        }
        LightType::Segment => {
            given(&[
                ("position", l.position.is_some()),
                ("corner", l.corner.is_some()),
                ("colors", l.colors.is_some()),
            ])?;
            Light::Segment {
                a: point(l.a, "a")?,
                b: point(l.b, "b")?,
                color_a: colour(l.color_a.as_ref().or(l.color.as_ref()), "color_a")?,
                color_b: colour(l.color_b.as_ref().or(l.color.as_ref()), "color_b")?,
            }
        }
        LightType::Parallelogram => {
            given(&[
                ("position", l.position.is_some()),
                ("a", l.a.is_some()),
                ("b", l.b.is_some()),
            ])?;
            let colors = match (&l.colors, &l.color) {
                (Some(c), _) => {
                    let v = c.get_ref().0.map(|c| v3(c).as_vec3());
                    odd = loc.odd_colours(c.span(), "colors", &v);
                    v
                }
                (None, Some(c)) => [colour(Some(c), "color")?; 4],
                (None, None) => {
                    return Err("this light needs `colors` (four corners) or `color`".into())
                }
            };
            Light::Parallelogram {
                corner: point(l.corner, "corner")?,
                edge1: vector(l.edge1, "edge1")?,
                edge2: vector(l.edge2, "edge2")?,
                colors,
            }
        }
    };
    warnings.extend(odd);
    Ok(light)
}

/// The generated sky cube map that ships inside the binary.
pub(crate) fn sky() -> Result<CubeMap> {
    let src = super::builtin::files();
    load_cube(
        &src,
        Path::new("data/sky/x"),
        |face| format!("{face}.png"),
        &mut Vec::new(),
    )
}

/// The six faces `name` gives, beside `base`; those outside its folder are
/// warned about in `warnings` and read at arm's length.
fn load_cube(
    src: &dyn Source,
    base: &Path,
    name: impl Fn(&str) -> String,
    warnings: &mut Vec<String>,
) -> Result<CubeMap> {
    let mut faces = Vec::with_capacity(6);
    for face in FACE_NAMES {
        let written = name(face);
        let what = format!("environment face {face}");
        let p = resolve(base, named(&written, &what)?);
        let outside = src.outside(base, &p);
        if let Some(o) = &outside {
            warnings.push(o.warning(&base.display().to_string(), &what, &written));
        }
        let read = src
            .read(&p, FileKind::Image)
            .map_err(anyhow::Error::from)
            .and_then(|bytes| {
                crate::scene::Texture::decode(&crate::words::path(&p), &bytes, Encoding::Srgb)
                    .map_err(|e| {
                        anyhow!(
                            "{}: {}",
                            crate::words::path(&p),
                            clip_quotes(&format!("{e:#}"))
                        )
                    })
            });
        let read = match &outside {
            Some(o) => o.quiet(FileKind::Image, read, warnings, usize::MAX),
            None => read,
        };
        faces.push(read.with_context(|| what.clone())?);
    }
    let faces: [crate::scene::Texture; 6] = faces
        .try_into()
        .map_err(|_| anyhow!("six faces expected"))?;
    Ok(CubeMap { faces })
}

fn environment_from(
    src: &dyn Source,
    loc: &Locator,
    e: Option<EnvSpec>,
    warnings: &mut Vec<String>,
) -> Result<Environment> {
    let path = loc.path;
    let Some(e) = e else {
        return Ok(Environment::Color(Vec3::ZERO));
    };
    let given = e.color.is_some() as u8 + e.sky.unwrap_or(false) as u8 + e.faces.is_some() as u8;
    if let Some(map) = &e.map {
        if given > 0 {
            bail!(
                "{}: environment: map is the whole environment: give it without color, sky or \
                 faces",
                loc.at(map.span())
            );
        }
        let strength = match &e.strength {
            Some(s) if s.get_ref().0 < 0.0 => bail!(
                "{}: environment strength must be 0 or more, not {}",
                loc.at(s.span()),
                show(s.get_ref().0)
            ),
            Some(s) => s.get_ref().f32(),
            None => 1.0,
        };
        let rotate = e.rotate.as_ref().map_or(0.0, |r| r.get_ref().f32());
        let light = map_from(src, loc, map, warnings)?;
        return Ok(Environment::Light(Box::new(
            light.scaled(strength).rotated(rotate),
        )));
    }
    if let Some(n) = e.strength.as_ref().or(e.rotate.as_ref()) {
        bail!(
            "{}: environment: strength and rotate apply to a map",
            loc.at(n.span())
        );
    }
    if given > 1 {
        bail!(
            "{}: environment: give one of color, sky = true, faces or map",
            path.display()
        );
    }
    if given == 0 && e.sky.is_none() {
        warnings.push(format!(
            "{}: environment: none of color, sky = true, faces or map given; the background \
             stays black",
            path.display()
        ));
    }
    if let Some(f) = e.faces {
        let names = [f.posx, f.negx, f.posy, f.negy, f.posz, f.negz];
        let name = |face: &str| {
            let i = FACE_NAMES.iter().position(|n| *n == face).unwrap_or(0);
            names[i].clone()
        };
        let cube = load_cube(src, path, name, warnings)
            .with_context(|| format!("{}: environment", path.display()))?;
        // Faces of unequal sizes or not square are read as they are, but
        // were hardly meant: their edges will not meet texel for texel.
        let sizes: Vec<String> = cube
            .faces
            .iter()
            .zip(FACE_NAMES)
            .map(|(t, face)| format!("{face} {}x{}", t.width, t.height))
            .collect();
        let first = (cube.faces[0].width, cube.faces[0].height);
        if cube
            .faces
            .iter()
            .any(|t| (t.width, t.height) != first || t.width != t.height)
        {
            warnings.push(format!(
                "{}: environment faces are not squares of one size ({}): their edges will show",
                path.display(),
                sizes.join(", ")
            ));
        }
        return Ok(Environment::CubeMap(Box::new(cube)));
    }
    if e.sky == Some(true) {
        return Ok(Environment::CubeMap(Box::new(sky()?)));
    }
    Ok(Environment::Color(e.color.map_or(Vec3::ZERO, |c| {
        loc.colour(&c, "environment color", warnings)
    })))
}

/// The environment light of `[environment] map`, beside the scene file;
/// one outside its folder is warned about and read at arm's length.
fn map_from(
    src: &dyn Source,
    loc: &Locator,
    map: &Spanned<String>,
    warnings: &mut Vec<String>,
) -> Result<EnvLight> {
    let here = loc.at(map.span());
    let written = map.get_ref();
    let p = resolve(
        loc.path,
        named(written, &format!("{here}: environment map"))?,
    );
    let outside = src.outside(loc.path, &p);
    if let Some(o) = &outside {
        warnings.push(o.warning(&here, "environment map", written));
    }
    let before = warnings.len();
    let read = super::envmap::read(src, &p, warnings);
    let read = match &outside {
        Some(o) => o.quiet(FileKind::Image, read, warnings, before),
        None => read,
    };
    read.with_context(|| format!("{here}: environment map {}", quoted(written)))
}

/// Render settings, range-checked as the command line checks its options.
fn settings_from(
    loc: &Locator,
    r: Option<RenderSpec>,
    warnings: &mut Vec<String>,
) -> Result<Settings> {
    let mut s = Settings::default();
    let Some(r) = r else { return Ok(s) };
    if let Some(size) = &r.size {
        let [w, h] = size.get_ref().0;
        if w == 0 || h == 0 || w > 16384 || h > 16384 {
            bail!(
                "{}: render.size must be between 1x1 and 16384x16384, not {w}x{h}",
                loc.at(size.span())
            );
        }
        (s.width, s.height) = (w, h);
    }
    if let Some(v) = &r.spp {
        s.spp = loc.range(v, 1..=crate::scene::MAX_SPP, "render.spp")?;
    }
    if let Some(v) = &r.max_depth {
        s.max_depth = loc.range(v, 0..=crate::scene::MAX_DEPTH, "render.max_depth")?;
    }
    s.builder = r.builder.unwrap_or(s.builder);
    s.integrator = r.integrator.or(s.integrator);
    if let Some(c) = &r.ambient {
        s.ambient = loc.colour(c, "ambient", warnings);
    }
    if let Some(v) = &r.light_samples {
        s.light_samples = loc.range(v, 1..=4096, "render.light_samples")?;
    }
    if let Some(v) = &r.glossy_samples {
        s.glossy_samples = loc.range(v, 1..=256, "render.glossy_samples")?;
    }
    if let Some(b) = r.bloom {
        let d = BloomSettings::default();
        let sigma = match &b.sigma {
            Some(x) if x.get_ref().0 < 0.1 => {
                bail!("{}: bloom.sigma must be at least 0.1", loc.at(x.span()))
            }
            Some(x) => x.get_ref().f32(),
            None => d.sigma,
        };
        s.bloom = BloomSettings {
            threshold: b.threshold.map_or(d.threshold, Num::f32),
            sigma,
            radius: match &b.radius {
                Some(v) => loc.range(v, 0..=256, "bloom.radius")?,
                None => d.radius,
            },
            strength: b.strength.map_or(d.strength, Num::f32),
        };
    }
    Ok(s)
}
#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        format!(
            "{:#}",
            parse(Path::new("s.toml"), text).err().expect("should fail")
        )
    }

    #[test]
    fn unknown_key_names_line_and_column() {
        let e = err("[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\nfox = 30\n");
        assert!(e.starts_with("s.toml:4:1:"), "{e}");
        assert!(e.contains("fox"), "{e}");
    }

    #[test]
    fn wrong_type_and_nan_name_the_value() {
        let e = err("[[light]]\ntype = \"point\"\nposition = [0, 1, 0]\ncolor = \"white\"\n");
        assert!(e.starts_with("s.toml:4:"), "{e}");
        let e = err("[[light]]\ntype = \"point\"\nposition = [0, nan, 0]\ncolor = [1, 1, 1]\n");
        assert!(e.starts_with("s.toml:3:"), "{e}");
        assert!(e.contains("finite"), "{e}");
        let e = err("[[light]]\ntype = \"spot\"\n");
        assert!(e.starts_with("s.toml:"), "{e}");
    }

    fn load_text(text: &str) -> Result<Scene> {
        let src = crate::scene::load::source::Memory::default()
            .with("s.toml", text)
            .with("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        load_with(&src, Path::new("s.toml"), Overrides::default())
    }

    #[test]
    fn absurd_placements_warn_with_their_line() {
        let light = "[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\ncolor = [1, 1, 1]\n";
        let s = load_text(&format!(
            "[[mesh]]\nfile = \"m.obj\"\nscale = 1e30\n{light}"
        ))
        .unwrap();
        assert!(
            s.warnings
                .iter()
                .any(|w| w.starts_with("s.toml:1:1: mesh m.obj")),
            "{:?}",
            s.warnings
        );
        let s = load_text(&format!(
            "[[mesh]]\nfile = \"m.obj\"\n{}",
            light.replace("[0, 2, 0]", "[0, 2e30, 0]")
        ))
        .unwrap();
        assert!(
            s.warnings
                .iter()
                .any(|w| w.starts_with("s.toml:3:1: light")),
            "{:?}",
            s.warnings
        );
        let s = load_text(&format!(
            "[[mesh]]\nfile = \"m.obj\"\nscale = 1e10\n{light}"
        ))
        .unwrap();
        assert!(s.warnings.is_empty(), "{:?}", s.warnings);
        // Beyond f32: an error at the value.
        let e = load_text("[[mesh]]\nfile = \"m.obj\"\ntranslate = [0, 1e39, 0]\n").unwrap_err();
        assert!(format!("{e:#}").starts_with("s.toml:3:"), "{e:#}");
    }

    #[test]
    fn camera_auto_or_table() {
        assert!(matches!(
            parse(Path::new("a"), "camera = \"auto\"\n")
                .unwrap()
                .camera
                .map(Spanned::into_inner),
            Some(CameraSpec::Auto)
        ));
        let f = parse(
            Path::new("a"),
            "[camera]\neye = [0, 1, 2]\ntarget = [0, 0, 0]\nfov = 30\n",
        )
        .unwrap();
        assert!(matches!(
            f.camera.map(Spanned::into_inner),
            Some(CameraSpec::Explicit(_))
        ));
        assert!(parse(Path::new("a"), "camera = \"manual\"\n").is_err());
    }

    const MESH: &str = "[[mesh]]\nfile = \"m.obj\"\n";

    fn load_err(text: &str) -> String {
        format!("{:#}", load_text(text).expect_err("should fail"))
    }

    /// A field of view out of range is reported at its own line, not at
    /// the camera table's.
    #[test]
    fn a_bad_fov_is_reported_where_it_is() {
        let e = load_err(&format!(
            "{MESH}[camera]\neye = [0, 1, 2]\ntarget = [0, 0, 0]\n\nfov = 0\n"
        ));
        assert!(
            e.starts_with("s.toml:7:7: camera: fov must be between 1 and 179"),
            "{e}"
        );
    }

    #[test]
    fn fixed_size_arrays_are_strict() {
        let light = "[[light]]\ntype = \"point\"\ncolor = [1, 1, 1]\n";
        for (extra, at) in [
            (format!("{light}position = [0, 1, 2, 3]\n"), "s.toml:6:12"),
            (format!("{light}position = [0, 1]\n"), "s.toml:6:12"),
            ("[render]\nsize = [64, 48, 7]\n".into(), "s.toml:4:8"),
            (
                "[[light]]\ntype = \"parallelogram\"\ncorner = [0, 1, 0]\nedge1 = [1, 0, 0]\n\
                 edge2 = [0, 0, 1]\ncolors = [[1, 1, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1]]\n"
                    .into(),
                "s.toml:8:10",
            ),
        ] {
            let e = load_err(&format!("{MESH}{extra}"));
            assert!(e.starts_with(at) && e.contains("invalid length"), "{extra:?}: {e}");
        }
    }

    #[test]
    fn settings_out_of_range_are_errors_at_the_value() {
        for (render, at) in [
            (
                "spp = 0",
                "s.toml:4:7: render.spp must be from 1 to 1048576",
            ),
            (
                "spp = 1048577",
                "s.toml:4:7: render.spp must be from 1 to 1048576",
            ),
            (
                "max_depth = 65",
                "s.toml:4:13: render.max_depth must be from 0 to 64",
            ),
            (
                "light_samples = 0",
                "s.toml:4:17: render.light_samples must be from 1 to 4096",
            ),
            ("glossy_samples = 257", "s.toml:4:18: render.glossy_samples"),
            ("size = [0, 48]", "s.toml:4:8: render.size must be between"),
            ("bloom = { radius = 1000 }", "s.toml:4:20: bloom.radius"),
            ("bloom = { sigma = 0 }", "s.toml:4:19: bloom.sigma"),
            (
                "integrator = \"bidirectional\"",
                "s.toml:4:14: unknown variant",
            ),
        ] {
            let e = load_err(&format!("{MESH}[render]\n{render}\n"));
            assert!(e.starts_with(at), "{render}: {e}");
        }
        let e = load_err("[[mesh]]\nfile = \"p.bpt\"\nsegments = 0\n");
        assert!(
            e.starts_with("s.toml:3:12: segments must be from 1 to 1024"),
            "{e}"
        );
    }

    #[test]
    fn doubtful_values_warn_at_their_position() {
        let s = load_text(
            "[[mesh]]\nfile = \"m.obj\"\nsegments = 4\nmaterial = { kd = [-1, 0, 0], ns = -2, d = 2 }\n\
             [[light]]\ntype = \"point\"\nposition = [0, 1, 0]\ncolor = [1, -1, 1]\n\
             [render]\nambient = [-0.1, 0, 0]\n[environment]\ncolor = [0, 0, -1]\n",
        )
        .unwrap();
        let all = s.warnings.join("\n");
        for part in [
            "s.toml:3:12: segments applies to .bpt meshes only",
            "s.toml:4:19: negative kd [-1, 0, 0]",
            "s.toml:4:36: negative ns -2: using 0",
            "s.toml:4:44: d 2 is outside 0..1",
            "s.toml:8:9: negative color [1, -1, 1]",
            "s.toml:10:11: negative ambient",
            "s.toml:12:9: negative environment color",
        ] {
            assert!(all.contains(part), "missing '{part}' in\n{all}");
        }
        assert_eq!(s.materials[0].ns, 0.0);
        assert_eq!(s.materials[0].dissolve, 1.0);
    }

    #[test]
    fn far_scenes_are_moved_in_f64_with_camera_and_lights() {
        let off = 3.0e7;
        let s = load_text(&format!(
            "[camera]\neye = [{e}, 0.25, 4]\ntarget = [{t}, 0.25, 0]\n{MESH}\
             translate = [{off}, 0, 0]\n[[light]]\ntype = \"point\"\nposition = [{l}, 2, 1]\n\
             color = [1, 1, 1]\n",
            e = off + 0.25,
            t = off + 0.25,
            l = off + 0.125,
        ))
        .unwrap();
        // Every coordinate exact, though f32 at 3e7 is 2 apart.
        assert_eq!(
            s.geometry.positions,
            [
                Vec3::new(-0.5, 0.0, 0.0),
                Vec3::new(0.5, 0.0, 0.0),
                Vec3::new(-0.5, 1.0, 0.0)
            ]
        );
        assert_eq!(s.camera.eye, Vec3::new(-0.25, 0.25, 4.0));
        assert!(matches!(s.lights[0], Light::Point { position, .. }
            if position == Vec3::new(-0.375, 2.0, 1.0)));
        assert!(
            s.warnings
                .iter()
                .any(|w| w.starts_with("s.toml: the scene lies around")),
            "{:?}",
            s.warnings
        );
    }

    #[test]
    fn placements_beyond_f32_are_errors_naming_both_files() {
        let e = load_err(&format!("{MESH}scale = 3e38\ntranslate = [3e38, 0, 0]\n"));
        assert!(
            e.starts_with(
                "s.toml:1:1: mesh m.obj: m.obj:2: vertex (1, 0, 0) lands at (6e38, 0, 0)"
            ),
            "{e}"
        );
        // Within f32, a huge scene is scaled down and says so.
        let s = load_text(&format!("{MESH}scale = 3e38\n")).unwrap();
        assert!(s.geometry.bounds().extent().max_element() < 2.0);
        assert!(
            s.warnings.iter().any(|w| w.contains("scaled by 2^-")),
            "{:?}",
            s.warnings
        );
    }
}
