//! TOML scene files. Unknown keys, wrong types and non-finite numbers are
//! errors that name the file, line and column.

use std::path::Path;

use anyhow::{anyhow, bail, Context, Result};
use glam::{Affine3A, EulerRot, Quat, Vec3};
use serde::Deserialize;

use super::obj::{self, MeshData, Parts, Placement};
use super::source::{resolve, Disk, Source};
use super::texture::FACE_NAMES;
use super::{
    bezier, BloomSettings, Builder, Camera, CubeMap, Environment, Light, Material, Scene, Settings,
};

/// A number that must be finite; the error carries the value's position.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "f64")]
struct Num(f32);

impl TryFrom<f64> for Num {
    type Error = String;
    fn try_from(x: f64) -> Result<Self, String> {
        if x.is_finite() && (x as f32).is_finite() {
            Ok(Num(x as f32))
        } else {
            Err(format!("{x} is not a finite number"))
        }
    }
}

type V3 = [Num; 3];

fn v3(v: V3) -> Vec3 {
    Vec3::new(v[0].0, v[1].0, v[2].0)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    description: Option<String>,
    camera: Option<CameraSpec>,
    #[serde(default, rename = "mesh")]
    meshes: Vec<toml::Spanned<MeshSpec>>,
    #[serde(default, rename = "light")]
    lights: Vec<toml::Spanned<LightSpec>>,
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
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = CameraSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("\"auto\" or a table with eye, target, up and fov")
            }
            fn visit_str<E: serde::de::Error>(self, s: &str) -> Result<CameraSpec, E> {
                match s {
                    "auto" => Ok(CameraSpec::Auto),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(s), &self)),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, m: A) -> Result<CameraSpec, A::Error> {
                CameraTable::deserialize(serde::de::value::MapAccessDeserializer::new(m))
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
    /// Vertical field of view, degrees.
    fov: Option<Num>,
}

/// `scale = 2.0` or `scale = [1, 2, 1]`.
enum ScaleSpec {
    Uniform(Num),
    Axes(V3),
}

impl<'de> Deserialize<'de> for ScaleSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = ScaleSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of three numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<ScaleSpec, E> {
                Num::try_from(x).map(ScaleSpec::Uniform).map_err(E::custom)
            }
            fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<ScaleSpec, E> {
                self.visit_f64(x as f64)
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, s: A) -> Result<ScaleSpec, A::Error> {
                V3::deserialize(serde::de::value::SeqAccessDeserializer::new(s))
                    .map(ScaleSpec::Axes)
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
    scale: Option<ScaleSpec>,
    /// Segments per patch edge for Bézier patch (`.bpt`) files.
    segments: Option<u32>,
    material: Option<MaterialSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialSpec {
    name: Option<String>,
    kd: Option<V3>,
    ks: Option<V3>,
    ns: Option<Num>,
    d: Option<Num>,
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
    color: Option<V3>,
    a: Option<V3>,
    b: Option<V3>,
    color_a: Option<V3>,
    color_b: Option<V3>,
    corner: Option<V3>,
    edge1: Option<V3>,
    edge2: Option<V3>,
    /// At corner, corner+edge1, corner+edge1+edge2, corner+edge2.
    colors: Option<[V3; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EnvSpec {
    color: Option<V3>,
    sky: Option<bool>,
    faces: Option<FacesSpec>,
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
    size: Option<[u32; 2]>,
    spp: Option<u32>,
    max_depth: Option<u32>,
    builder: Option<Builder>,
    ambient: Option<V3>,
    light_samples: Option<u32>,
    glossy_samples: Option<u32>,
    bloom: Option<BloomSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BloomSpec {
    threshold: Option<Num>,
    sigma: Option<Num>,
    radius: Option<u32>,
    strength: Option<Num>,
}

/// Things a caller can change about a scene file as it loads.
#[derive(Clone, Copy, Debug, Default)]
pub struct Overrides {
    /// Segments per patch edge for every Bézier mesh (`teapot:N`).
    pub segments: Option<u32>,
}

/// 1-based line and column of byte offset `at` in `text`.
fn line_col(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

fn parse(path: &Path, text: &str) -> Result<SceneFile> {
    toml::from_str(text).map_err(|e| {
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(span) => {
                let (l, c) = line_col(text, span.start);
                anyhow!("{}:{l}:{c}: {msg}", path.display())
            }
            None => anyhow!("{}: {msg}", path.display()),
        }
    })
}

pub fn load_path(path: &Path) -> Result<Scene> {
    load_with(&Disk, path, Overrides::default())
}

/// Largest segment count accepted for Bézier meshes (32 patches x 2 x 1024² ≈ 67M triangles).
const MAX_SEGMENTS: u32 = 1024;

pub fn load_with(src: &dyn Source, path: &Path, ov: Overrides) -> Result<Scene> {
    let bytes = src
        .read(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let text =
        String::from_utf8(bytes).map_err(|_| anyhow!("{}: not UTF-8 text", path.display()))?;
    let f = parse(path, &text)?;
    let mut parts = Parts::default();
    let at = |span: std::ops::Range<usize>| {
        let (line, col) = line_col(&text, span.start);
        format!("{}:{line}:{col}", path.display())
    };
    for spanned in &f.meshes {
        let m = spanned.get_ref();
        let first_vertex = parts.geometry.positions.len();
        let mesh_path = resolve(path, &m.file);
        let mut xf = Affine3A::IDENTITY;
        if let Some(s) = &m.scale {
            let s = match s {
                ScaleSpec::Uniform(s) => Vec3::splat(s.0),
                ScaleSpec::Axes(a) => v3(*a),
            };
            if s.cmpeq(Vec3::ZERO).any() {
                bail!(
                    "{}: mesh {}: scale must not be zero",
                    path.display(),
                    m.file
                );
            }
            xf = Affine3A::from_scale(s);
        }
        if let Some(r) = m.rotate {
            let r = v3(r);
            let q = Quat::from_euler(
                EulerRot::ZYX,
                r.z.to_radians(),
                r.y.to_radians(),
                r.x.to_radians(),
            );
            xf = Affine3A::from_quat(q) * xf;
        }
        if let Some(t) = m.translate {
            xf = Affine3A::from_translation(v3(t)) * xf;
        }
        let place = Placement { transform: xf };
        let material = m
            .material
            .as_ref()
            .map(|ms| material_from(&mut parts, src, path, ms));
        let is_bpt = mesh_path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bpt"));
        if is_bpt {
            let segments = ov
                .segments
                .or(m.segments)
                .unwrap_or(8)
                .clamp(1, MAX_SEGMENTS);
            let bytes = src.read(&mesh_path).with_context(|| {
                format!(
                    "{}: cannot read mesh {}",
                    path.display(),
                    mesh_path.display()
                )
            })?;
            let patches = bezier::parse_bpt(&String::from_utf8_lossy(&bytes))
                .map_err(|e| anyhow!("{}:{}: {}", mesh_path.display(), e.line, e.message))?;
            let pm = bezier::tessellate(&patches, segments);
            let mat = match material {
                Some(mat) => parts.add_material(mat),
                None => parts.add_material(Material::default()),
            };
            let name = mesh_path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            parts.add_mesh(
                MeshData {
                    name,
                    positions: &pm.positions,
                    normals: Some(&pm.normals),
                    uvs: Some(&pm.uvs),
                    indices: &pm.indices,
                    material: mat,
                },
                &place,
            );
        } else {
            obj::load_into(&mut parts, src, &mesh_path, &place, material.as_ref())
                .with_context(|| format!("{}: mesh {}", path.display(), m.file))?;
        }
        let reach = parts.geometry.positions[first_vertex..]
            .iter()
            .fold(0.0f32, |r, p| r.max(p.abs().max_element()));
        if reach > obj::ABSURD {
            parts.warnings.push(format!(
                "{}: mesh {}: coordinates reach {reach:e} once placed; beyond {:e} shading \
                 and shadows lose all precision",
                at(spanned.span()),
                m.file,
                obj::ABSURD
            ));
        }
    }
    if parts.geometry.indices.is_empty() {
        bail!("{}: the scene has no triangles", path.display());
    }
    let bounds = parts.geometry.bounds();
    let camera = match f.camera {
        None | Some(CameraSpec::Auto) => Camera::auto(&bounds),
        Some(CameraSpec::Explicit(c)) => {
            let cam = Camera {
                eye: v3(c.eye),
                target: v3(c.target),
                up: c.up.map(v3).unwrap_or(Vec3::Y),
                vfov: c.fov.map_or(45.0, |f| f.0),
            };
            let fwd = cam.target - cam.eye;
            if fwd.length_squared() == 0.0 || fwd.cross(cam.up).length_squared() == 0.0 {
                bail!(
                    "{}: camera: eye, target and up must not be collinear",
                    path.display()
                );
            }
            if !(1.0..179.0).contains(&cam.vfov) {
                bail!(
                    "{}: camera: fov must be between 1 and 179 degrees",
                    path.display()
                );
            }
            if cam.eye.abs().max(cam.target.abs()).max_element() > obj::ABSURD {
                parts.warnings.push(format!(
                    "{}: camera beyond {:e}: its rays lose all precision",
                    path.display(),
                    obj::ABSURD
                ));
            }
            cam
        }
    };
    let lights = f
        .lights
        .iter()
        .map(|l| {
            let light = light_from(l.get_ref()).map_err(|e| anyhow!("{}: {e}", at(l.span())))?;
            let reach = match &light {
                Light::Point { position, .. } => position.abs().max_element(),
                Light::Segment { a, b, .. } => a.abs().max(b.abs()).max_element(),
                Light::Parallelogram {
                    corner,
                    edge1,
                    edge2,
                    ..
                } => (corner.abs() + edge1.abs() + edge2.abs()).max_element(),
            };
            if reach > obj::ABSURD {
                parts.warnings.push(format!(
                    "{}: light at {reach:e}: beyond {:e} shading loses all precision",
                    at(l.span()),
                    obj::ABSURD
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
    let environment = environment_from(src, path, f.environment)?;
    let settings = settings_from(path, f.render)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    Ok(Scene {
        name: f.name.unwrap_or(stem),
        description: f.description.unwrap_or_default(),
        geometry: parts.geometry,
        meshes: parts.meshes,
        materials: parts.materials,
        textures: parts.textures,
        lights,
        camera,
        environment,
        settings,
        warnings: parts.warnings,
    })
}

fn material_from(parts: &mut Parts, src: &dyn Source, path: &Path, m: &MaterialSpec) -> Material {
    let d = Material::default();
    Material {
        name: m.name.clone().unwrap_or_else(|| "inline".into()),
        kd: m.kd.map(v3).unwrap_or(d.kd),
        ks: m.ks.map(v3).unwrap_or(d.ks),
        ns: m.ns.map_or(d.ns, |n| n.0.max(0.0)),
        dissolve: m.d.map_or(1.0, |x| x.0.clamp(0.0, 1.0)),
        texture: m
            .texture
            .as_ref()
            .and_then(|t| parts.texture(src, &resolve(path, t), path)),
    }
}

fn light_from(l: &LightSpec) -> Result<Light, String> {
    let need = |v: Option<V3>, name: &str| {
        v.map(v3)
            .ok_or_else(|| format!("this light needs `{name}`"))
    };
    let given = |names: &[(&str, bool)]| -> Result<(), String> {
        match names.iter().find(|(_, set)| *set) {
            Some((n, _)) => Err(format!("`{n}` does not apply to this type of light")),
            None => Ok(()),
        }
    };
    Ok(match l.kind {
        LightType::Point => {
            given(&[
                ("a", l.a.is_some()),
                ("b", l.b.is_some()),
                ("corner", l.corner.is_some()),
                ("colors", l.colors.is_some()),
            ])?;
            Light::Point {
                position: need(l.position, "position")?,
                color: need(l.color, "color")?,
            }
        }
        LightType::Segment => {
            given(&[
                ("position", l.position.is_some()),
                ("corner", l.corner.is_some()),
                ("colors", l.colors.is_some()),
            ])?;
            Light::Segment {
                a: need(l.a, "a")?,
                b: need(l.b, "b")?,
                color_a: need(l.color_a.or(l.color), "color_a")?,
                color_b: need(l.color_b.or(l.color), "color_b")?,
            }
        }
        LightType::Parallelogram => {
            given(&[
                ("position", l.position.is_some()),
                ("a", l.a.is_some()),
                ("b", l.b.is_some()),
            ])?;
            let colors = match (l.colors, l.color) {
                (Some(c), _) => c.map(v3),
                (None, Some(c)) => [v3(c); 4],
                (None, None) => {
                    return Err("this light needs `colors` (four corners) or `color`".into())
                }
            };
            Light::Parallelogram {
                corner: need(l.corner, "corner")?,
                edge1: need(l.edge1, "edge1")?,
                edge2: need(l.edge2, "edge2")?,
                colors,
            }
        }
    })
}

/// The generated sky cube map that ships inside the binary.
pub fn sky() -> Result<CubeMap> {
    let src = super::builtin::files();
    load_cube(&src, Path::new("data/sky/x"), |face| format!("{face}.png"))
}

fn load_cube(src: &dyn Source, base: &Path, name: impl Fn(&str) -> String) -> Result<CubeMap> {
    let mut faces = Vec::with_capacity(6);
    for face in FACE_NAMES {
        let p = resolve(base, &name(face));
        let bytes = src
            .read(&p)
            .with_context(|| format!("environment face {face}: cannot read {}", p.display()))?;
        faces.push(
            super::Texture::decode(&p.display().to_string(), &bytes)
                .with_context(|| format!("environment face {face}: {}", p.display()))?,
        );
    }
    let faces: [super::Texture; 6] = faces
        .try_into()
        .map_err(|_| anyhow!("six faces expected"))?;
    Ok(CubeMap { faces })
}

fn environment_from(src: &dyn Source, path: &Path, e: Option<EnvSpec>) -> Result<Environment> {
    let Some(e) = e else {
        return Ok(Environment::Color(Vec3::ZERO));
    };
    let given = e.color.is_some() as u8 + e.sky.unwrap_or(false) as u8 + e.faces.is_some() as u8;
    if given > 1 {
        bail!(
            "{}: environment: give one of color, sky = true or faces",
            path.display()
        );
    }
    if let Some(f) = e.faces {
        let names = [f.posx, f.negx, f.posy, f.negy, f.posz, f.negz];
        let cube = load_cube(src, path, |face| {
            let i = FACE_NAMES.iter().position(|n| *n == face).unwrap_or(0);
            names[i].clone()
        })
        .with_context(|| format!("{}: environment", path.display()))?;
        return Ok(Environment::CubeMap(Box::new(cube)));
    }
    if e.sky == Some(true) {
        return Ok(Environment::CubeMap(Box::new(sky()?)));
    }
    Ok(Environment::Color(e.color.map(v3).unwrap_or(Vec3::ZERO)))
}

fn settings_from(path: &Path, r: Option<RenderSpec>) -> Result<Settings> {
    let mut s = Settings::default();
    let Some(r) = r else { return Ok(s) };
    if let Some([w, h]) = r.size {
        if w == 0 || h == 0 || w > 16384 || h > 16384 {
            bail!(
                "{}: render.size must be between 1x1 and 16384x16384",
                path.display()
            );
        }
        (s.width, s.height) = (w, h);
    }
    s.spp = r.spp.unwrap_or(s.spp).max(1);
    s.max_depth = r.max_depth.unwrap_or(s.max_depth).min(64);
    s.builder = r.builder.unwrap_or(s.builder);
    s.ambient = r.ambient.map(v3).unwrap_or(s.ambient);
    s.light_samples = r.light_samples.unwrap_or(s.light_samples).clamp(1, 4096);
    s.glossy_samples = r.glossy_samples.unwrap_or(s.glossy_samples).clamp(1, 256);
    if let Some(b) = r.bloom {
        let d = BloomSettings::default();
        s.bloom = BloomSettings {
            threshold: b.threshold.map_or(d.threshold, |x| x.0),
            sigma: b.sigma.map_or(d.sigma, |x| x.0.max(0.1)),
            radius: b.radius.unwrap_or(d.radius).min(256),
            strength: b.strength.map_or(d.strength, |x| x.0),
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
        let src = crate::scene::source::Memory::default()
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
            parse(Path::new("a"), "camera = \"auto\"\n").unwrap().camera,
            Some(CameraSpec::Auto)
        ));
        let f = parse(
            Path::new("a"),
            "[camera]\neye = [0, 1, 2]\ntarget = [0, 0, 0]\nfov = 30\n",
        )
        .unwrap();
        assert!(matches!(f.camera, Some(CameraSpec::Explicit(_))));
        assert!(parse(Path::new("a"), "camera = \"manual\"\n").is_err());
    }
}
