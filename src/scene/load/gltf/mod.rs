//! glTF 2.0 (`.gltf` with external or embedded buffers, and `.glb`),
//! through the `gltf` crate for the document (parsed and validated); its
//! buffers and images are read through the scene's [`Source`], with the
//! same limits as every other file.
//!
//! Read: the default scene (or the first) through its node hierarchy, each
//! node's transform applied in f64; triangle primitives (strips and fans
//! turned into triangles) with positions, normals, `TEXCOORD_0`,
//! `TEXCOORD_1` (kept where a texture reads it), `COLOR_0` and, for normal
//! maps, `TANGENT` (MikkTSpace's where the file has none, see
//! [`super::tangents`]), quantized or not, sparse or not, compressed with
//! meshoptimizer or not (see [`accessor`]); metallic-roughness materials
//! (see [`metallic_roughness`]) with their base colour, metallic-roughness,
//! normal, occlusion and emissive textures, each on the UV set it names
//! and with its own `KHR_texture_transform` (see [`texcoord`]), the
//! samplers' wrap modes (WebP images through `EXT_texture_webp`),
//! `KHR_materials_emissive_strength`, `_unlit`, `_ior`, `_specular` and
//! `_pbrSpecularGlossiness` (converted, see [`specular`]);
//! `EXT_mesh_gpu_instancing`; perspective and orthographic cameras (the
//! first, or the one `--camera` names); `KHR_lights_punctual` lights in
//! their units (candela and lux). What cannot be mapped is listed once in
//! the warnings.

mod accessor;
mod check;
mod extensions;
mod instancing;
mod lenient;
mod meshopt;
mod primitive;
mod specgloss;
mod specular;
mod texcoord;
mod uri;

use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use ::gltf::camera::Projection as CameraKind;
use ::gltf::khr_lights_punctual::Kind as LightKind;
use ::gltf::material::AlphaMode;
use ::gltf::texture::WrappingMode;
use anyhow::{anyhow, bail, Context, Result};
use glam::{DAffine3, DMat4, DVec3, Vec3};

use super::parts::{mesh_fits, Parts, Placed};
use super::source::{FileKind, Outside, Source};
use crate::scene::texture::{Encoding, Texture, Wrap};
use crate::scene::{Alpha, Material, Pbr, Projection};
use check::{check_lights, check_transform, check_trees, check_values, Broken};
use primitive::{Decoded, Key};
use texcoord::Transform;
use uri::inline_uri;

const TEXTURE_TRANSFORM: &str = "KHR_texture_transform";

/// A camera of the file, placed in f64.
#[derive(Clone, Debug)]
pub(crate) struct FileCamera {
    /// The names `--camera` knows it by: its node's and its own.
    pub(crate) names: Vec<String>,
    pub(crate) eye: DVec3,
    pub(crate) forward: DVec3,
    pub(crate) up: DVec3,
    /// Its projection; an orthographic one's extent in the file's units
    /// (scaled by its node), which the scene's frame scales in turn.
    pub(crate) projection: Projection,
}

/// A light of the file, placed in f64, in its units.
#[derive(Clone, Copy, Debug)]
pub(crate) enum FileLight {
    /// A point light, or a spot light with its cone.
    Point {
        position: DVec3,
        /// Candela per channel.
        intensity: Vec3,
        range: Option<f64>,
        cone: Option<FileCone>,
    },
    /// Light travelling along `direction`.
    Directional {
        direction: DVec3,
        /// Lux per channel.
        illuminance: Vec3,
    },
}

/// A spot light's cone: its axis and the cosines of its inner and outer
/// angles.
#[derive(Clone, Copy, Debug)]
pub(crate) struct FileCone {
    pub(crate) axis: DVec3,
    pub(crate) cos_inner: f32,
    pub(crate) cos_outer: f32,
}

/// What a glTF file holds, placed.
pub(crate) struct GltfScene {
    pub(crate) meshes: Vec<Placed>,
    /// The usable cameras, in the order the scene's nodes
    /// are visited.
    pub(crate) cameras: Vec<FileCamera>,
    pub(crate) lights: Vec<FileLight>,
}

/// Things of the file rayterm cannot show, each listed once with where it
/// was first found and in how many places (a place noted twice, as a
/// material whose five textures read a missing set, counts once).
#[derive(Default)]
struct Unmapped(Vec<(String, String, std::collections::HashSet<String>)>);

impl Unmapped {
    fn note(&mut self, what: &str, place: impl FnOnce() -> String) {
        let place = place();
        match self.0.iter_mut().find(|(w, _, _)| w == what) {
            Some(e) => {
                e.2.insert(place);
            }
            None => self
                .0
                .push((what.to_string(), place.clone(), [place].into())),
        }
    }

    fn warning(&self, path: &Path) -> Option<String> {
        if self.0.is_empty() {
            return None;
        }
        let list: Vec<String> = self
            .0
            .iter()
            .map(|(w, first, places)| match places.len() {
                1 => format!("{w} ({first})"),
                n => format!("{w} ({first} and {} more)", n - 1),
            })
            .collect();
        Some(format!(
            "{}: not shown, rayterm has no equivalent: {}",
            path.display(),
            list.join(", ")
        ))
    }
}

/// An object's name in the file, or its index when it has none (messages
/// put the kind before either: `mesh Body`, `mesh 3`).
fn named(name: Option<&str>, index: usize) -> String {
    match name {
        Some(n) if !n.trim().is_empty() => crate::words::quoted(n),
        _ => index.to_string(),
    }
}

/// The material of glTF metallic-roughness factors, shaded by
/// [`crate::render::brdf`]: the base colour as kd, and the alpha of
/// `BLEND` (and of `MASK`, 0 or 1 by its cutoff) as dissolve. The reader
/// adds the textures.
pub(crate) fn metallic_roughness(
    base: [f32; 4],
    metallic: f32,
    roughness: f32,
    alpha: AlphaMode,
    cutoff: f32,
) -> Material {
    Material {
        name: String::new(),
        kd: Vec3::new(base[0], base[1], base[2]).clamp(Vec3::ZERO, Vec3::ONE),
        ks: Vec3::ZERO,
        ns: 0.0,
        dissolve: 1.0,
        alpha: {
            let factor = if base[3].is_finite() {
                base[3].clamp(0.0, 1.0)
            } else {
                1.0
            };
            match alpha {
                AlphaMode::Opaque => None,
                AlphaMode::Blend => Some(Alpha {
                    cutoff: None,
                    factor,
                    texture: None,
                }),
                AlphaMode::Mask => Some(Alpha {
                    cutoff: Some(if cutoff.is_finite() { cutoff } else { 0.5 }),
                    factor,
                    texture: None,
                }),
            }
        },
        texture: None,
        unlit: false,
        pbr: Some(Pbr {
            metallic: metallic.clamp(0.0, 1.0),
            roughness: roughness.clamp(0.0, 1.0),
            ..Pbr::default()
        }),
    }
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::Clamp,
        WrappingMode::MirroredRepeat => Wrap::Mirror,
    }
}

struct Reader<'a> {
    path: &'a Path,
    doc: &'a ::gltf::Document,
    src: &'a dyn Source,
    buffers: Vec<Vec<u8>>,
    /// Where each buffer's bytes come from, for messages that quote them.
    origins: Vec<String>,
    /// The buffers outside the glTF's folder, read as allowed: messages
    /// quote nothing they hold.
    foreign: Vec<Option<Outside>>,
    unmapped: Unmapped,
    /// Decoded images by index and encoding (`None` when they could not
    /// be).
    images: HashMap<(usize, Encoding), Option<Texture>>,
    /// Materials made so far: glTF index to rayterm id.
    materials: HashMap<Option<usize>, u32>,
    /// Cameras and images the crate cannot read, until used.
    broken: Broken,
    /// Primitives decoded, until the last primitive sharing their
    /// accessors takes them, and how many are still to come.
    decoded: HashMap<Key, Decoded>,
    uses: HashMap<Key, usize>,
    /// `EXT_meshopt_compression` views by index, and those decoded so far.
    compressed: HashMap<usize, Result<meshopt::Compressed, String>>,
    unpacked: HashMap<usize, Vec<u8>>,
    /// Accessors not aligned to their components, by index, with why:
    /// noted by the checks, which take the reader as it is.
    misaligned: RefCell<BTreeMap<usize, String>>,
}

impl Reader<'_> {
    fn at(&self) -> String {
        self.path.display().to_string()
    }

    /// An image's texture, decoded once; an error for one the crate cannot
    /// read ([`Broken`]), named with the material that uses it (`user`).
    fn image(
        &mut self,
        parts: &mut Parts,
        image: ::gltf::Image,
        user: &str,
        encoding: Encoding,
    ) -> Result<Option<Texture>> {
        let index = image.index();
        if let Some(t) = self.images.get(&(index, encoding)) {
            return Ok(t.clone());
        }
        let name = named(image.name(), index);
        let from = format!("{}: image {name}", self.at());
        if let Some(why) = self.broken.images.get(&index) {
            bail!("{from} (of {user}): {why}");
        }
        let decoded = match image.source() {
            ::gltf::image::Source::View { view, .. } => {
                let bytes = self
                    .buffers
                    .get(view.buffer().index())
                    .and_then(|b| b.get(view.offset()..view.offset().checked_add(view.length())?));
                match (bytes, self.foreign.get(view.buffer().index())) {
                    (Some(b), Some(Some(o))) => Texture::decode(&from, b, encoding).map_err(|_| {
                        format!(
                            "not read as an image; why is not shown, as the reason may quote \
                             its buffer, which lies outside {}",
                            crate::words::path(&o.folder)
                        )
                    }),
                    (Some(b), _) => Texture::decode(&from, b, encoding)
                        .map_err(|e| crate::words::clip_quotes(&format!("{e:#}"))),
                    (None, _) => Err("its buffer view lies outside the buffer".into()),
                }
            }
            ::gltf::image::Source::Uri { uri, .. } => match inline_uri(uri) {
                Some(Ok(b)) => Texture::decode(&from, &b, encoding)
                    .map_err(|e| crate::words::clip_quotes(&format!("{e:#}"))),
                Some(Err(e)) => Err(e),
                None => {
                    // Read, decoded and warned about as every texture is.
                    let (p, o) = match uri::file(self.src, self.path, uri) {
                        Ok(found) => found,
                        Err(e) => bail!("{from} (of {user}): {e}"),
                    };
                    let id = parts.texture_at(self.src, &p, o, uri, &from, encoding);
                    let t = id.map(|i| parts.textures[i as usize].clone());
                    self.images.insert((index, encoding), t.clone());
                    return Ok(t);
                }
            },
        };
        let t = match decoded {
            Ok(t) => Some(t),
            Err(e) => {
                parts
                    .warnings
                    .push(format!("{from}: {e}; using the material colour"));
                None
            }
        };
        self.images.insert((index, encoding), t.clone());
        Ok(t)
    }

    /// The texture of a material's texture slot, tinted by `tint`.
    fn texture(
        &mut self,
        parts: &mut Parts,
        info: Option<::gltf::texture::Info>,
        user: &str,
        encoding: Encoding,
        tint: Vec3,
    ) -> Result<Option<u32>> {
        let Some(info) = info else {
            return Ok(None);
        };
        let transform = info.texture_transform().map(|t| Ok(Transform::of_info(&t)));
        self.texture_of(
            parts,
            info.texture(),
            info.tex_coord(),
            transform,
            user,
            encoding,
            tint,
        )
    }

    /// A texture decoded as `encoding`, with its sampler's wrapping and
    /// `tint`, reading the coordinates its `texCoord` and
    /// `KHR_texture_transform` say; `None` (noted) where it cannot be
    /// shown.
    #[allow(clippy::too_many_arguments)]
    fn texture_of(
        &mut self,
        parts: &mut Parts,
        texture: ::gltf::Texture,
        tex_coord: u32,
        transform: Option<Result<Transform, String>>,
        user: &str,
        encoding: Encoding,
        tint: Vec3,
    ) -> Result<Option<u32>> {
        let transform = match transform {
            Some(Err(why)) => {
                parts.warnings.push(format!(
                    "{}: {user}: a texture's KHR_texture_transform cannot be read ({why}): \
                     the texture is drawn without it",
                    self.at()
                ));
                None
            }
            Some(Ok(t)) => Some(t),
            None => None,
        };
        let uv = match texcoord::uv_map(tex_coord, transform.as_ref()) {
            Ok(uv) => uv,
            Err(what) => {
                self.unmapped.note(&what, || user.to_string());
                return Ok(None);
            }
        };
        let sampler = texture.sampler();
        let image = match texture.source() {
            Some(image) => self.image(parts, image, user, encoding)?,
            None => {
                let t = named(texture.name(), texture.index());
                let what = extensions::sourceless(&texture);
                self.unmapped
                    .note(&what, || format!("texture {t} of {user}"));
                None
            }
        };
        Ok(image.map(|mut t| {
            // Every material of the image shares its texels.
            t.tint = tint;
            t.wrap = [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())];
            t.uv = uv;
            parts.add_texture(t)
        }))
    }

    /// The rayterm material of a primitive's material, made once.
    fn material(&mut self, parts: &mut Parts, m: ::gltf::Material) -> Result<u32> {
        let key = m.index();
        if let Some(&id) = self.materials.get(&key) {
            return Ok(id);
        }
        let Some(index) = key else {
            // No material: the specification's default, a rough metal.
            let mut m = metallic_roughness([1.0; 4], 1.0, 1.0, AlphaMode::Opaque, 0.5);
            m.name = "default".into();
            let id = parts.add_material(m);
            self.materials.insert(key, id);
            return Ok(id);
        };
        let name = named(m.name(), index);
        let here = format!("material {name}");
        let pbr = m.pbr_metallic_roughness();
        // A specular-glossiness material, converted, in place of its
        // metallic-roughness fallback.
        let spec_gloss = self.ext_object(parts, &m, specular::SPEC_GLOSS, &here);
        let converted = spec_gloss.map(|v| self.spec_gloss_factors(parts, v, &here));
        let (base, metallic, roughness) = match &converted {
            Some(c) => (c.base, c.metallic, c.roughness),
            None => (
                pbr.base_color_factor(),
                pbr.metallic_factor(),
                pbr.roughness_factor(),
            ),
        };
        let mut mat = metallic_roughness(
            base,
            metallic,
            roughness,
            m.alpha_mode(),
            m.alpha_cutoff().unwrap_or(0.5),
        );
        mat.name = match m.name() {
            Some(n) if !n.trim().is_empty() => name.clone(),
            _ => format!("material {name}"),
        };
        let mut p = mat.pbr.take().expect("a metallic-roughness material");
        // Each texture multiplies its factor: the base colour's, the
        // emissive colour's; metallic and roughness scale at lookup.
        let base_tint = mat.kd;
        match (spec_gloss, &converted) {
            // The diffuse texture tinted by the converted base colour
            // (exact where the conversion finds no metal).
            (Some(v), Some(c)) => {
                let diffuse = v.get("diffuseTexture");
                mat.texture =
                    self.json_texture(parts, diffuse, &here, Encoding::Srgb, base_tint)?;
                p.metallic_roughness = self.spec_gloss_texture(parts, v, c, &here)?;
                if p.metallic_roughness.is_some() {
                    (p.metallic, p.roughness) = (1.0, 1.0);
                }
            }
            _ => {
                mat.texture = self.texture(
                    parts,
                    pbr.base_color_texture(),
                    &here,
                    Encoding::Srgb,
                    base_tint,
                )?;
                p.metallic_roughness = self.texture(
                    parts,
                    pbr.metallic_roughness_texture(),
                    &here,
                    Encoding::Linear,
                    Vec3::ONE,
                )?;
            }
        }
        if let Some(n) = m.normal_texture() {
            let scale = n.scale();
            let id = self.texture_of(
                parts,
                n.texture(),
                n.tex_coord(),
                n.extension_value(TEXTURE_TRANSFORM).map(Transform::of_json),
                &here,
                Encoding::Linear,
                Vec3::ONE,
            )?;
            p.normal = id.map(|id| (id, if scale.is_finite() { scale } else { 1.0 }));
        }
        if let Some(o) = m.occlusion_texture() {
            let strength = o.strength();
            let id = self.texture_of(
                parts,
                o.texture(),
                o.tex_coord(),
                o.extension_value(TEXTURE_TRANSFORM).map(Transform::of_json),
                &here,
                Encoding::Linear,
                Vec3::ONE,
            )?;
            p.occlusion = id.map(|id| {
                (
                    id,
                    if strength.is_finite() {
                        strength.clamp(0.0, 1.0)
                    } else {
                        1.0
                    },
                )
            });
        }
        let strength = m.emissive_strength().unwrap_or(1.0);
        if !(strength >= 0.0 && strength.is_finite()) {
            parts.warnings.push(format!(
                "{}: {here}: emissiveStrength {strength} is not a finite number of at least 0; \
                 the material emits nothing",
                self.at()
            ));
        }
        let strength = if strength.is_finite() {
            strength.max(0.0)
        } else {
            0.0
        };
        p.emissive = (Vec3::from_array(m.emissive_factor()) * strength).max(Vec3::ZERO);
        if !p.emissive.is_finite() {
            p.emissive = Vec3::ZERO;
        }
        if p.emissive != Vec3::ZERO {
            p.emissive_texture = self.texture(
                parts,
                m.emissive_texture(),
                &here,
                Encoding::Srgb,
                p.emissive,
            )?;
        }
        mat.unlit = m
            .extensions()
            .is_some_and(|e| e.contains_key("KHR_materials_unlit"));
        let ior = m
            .extensions()
            .and_then(|e| e.get("KHR_materials_ior"))
            .map(|i| i.get("ior").map_or(Some(1.5), serde_json::Value::as_f64));
        match ior {
            None => {}
            // 0 is the extension's way to say "reflects everything".
            Some(Some(0.0)) => p.dielectric_f0 = 1.0,
            Some(Some(i)) if (1.0..1e6).contains(&i) => {
                p.dielectric_f0 = (((i - 1.0) / (i + 1.0)).powi(2)) as f32
            }
            Some(i) => parts.warnings.push(format!(
                "{}: {here}: KHR_materials_ior's ior {} is not 0 or a number of at least 1; \
                 0.04 is used (ior 1.5)",
                self.at(),
                i.map_or("(not a number)".to_string(), |i| i.to_string())
            )),
        }
        self.specular(parts, &m, &mut p, &here)?;
        if let Some(a) = &mut mat.alpha {
            a.texture = match spec_gloss {
                Some(v) => {
                    let diffuse = v.get("diffuseTexture");
                    self.json_texture(parts, diffuse, &here, Encoding::Alpha, Vec3::ONE)?
                }
                None => self.texture(
                    parts,
                    pbr.base_color_texture(),
                    &here,
                    Encoding::Alpha,
                    Vec3::ONE,
                )?,
            };
        }
        // A surface there everywhere needs no test.
        mat.alpha = mat.alpha.filter(|a| {
            a.texture.is_some() || a.factor < 1.0 && a.cutoff.is_none_or(|c| a.factor < c)
        });
        mat.pbr = Some(p);
        let id = parts.add_material(mat);
        self.materials.insert(key, id);
        Ok(id)
    }
}

/// The length a .glb's header declares (at least its 12 header bytes).
fn glb_length(body: &[u8]) -> Option<usize> {
    let n = u32::from_le_bytes(body.strip_prefix(b"glTF")?.get(4..8)?.try_into().ok()?);
    Some((n as usize).max(12))
}

/// Whether a file the glTF 2.0 reader refused is a glTF 1.0 one: a binary
/// file of container version 1, or JSON whose `asset.version` is 1.x
/// (glTF 1.0 keeps its meshes and nodes in objects, not arrays, so the
/// reader's own message would be about a type).
fn version_1(body: &[u8]) -> bool {
    if let Some(v) = body.strip_prefix(b"glTF").and_then(|b| b.get(..4)) {
        return v == 1u32.to_le_bytes();
    }
    serde_json::from_slice::<serde_json::Value>(body).is_ok_and(|j| {
        let v = j.pointer("/asset/version");
        // A number (`"version": 1`, as collada2gltf wrote it), or no
        // version where 2.0's arrays are 1.0's objects.
        v.and_then(|v| v.as_str())
            .is_some_and(|v| v == "1" || v.starts_with("1."))
            || v.and_then(|v| v.as_f64()).is_some_and(|v| v < 2.0)
            || ["meshes", "nodes", "accessors"]
                .iter()
                .any(|k| j.get(k).is_some_and(|v| v.is_object()))
    })
}

/// Reads a glTF file: materials and textures go into `parts`; meshes,
/// the cameras and the lights come back placed by `xf`
/// in f64. `material` replaces the file's materials when given.
pub(crate) fn load(
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<GltfScene> {
    let bytes = src.read(path, FileKind::Gltf)?;
    let invalid = |e: &dyn std::fmt::Display| {
        let e = crate::words::clip_quotes(&e.to_string());
        anyhow!("{}: not a valid glTF file: {e}", path.display())
    };
    // A .gltf is JSON text, read with or without a byte-order mark as every
    // text file is (a .glb starts with its magic number).
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&bytes);
    // Bytes after a .glb's declared length are not the file's (glTF
    // allows readers to ignore them): said, and left out.
    let body = match glb_length(body).filter(|&n| n < body.len()) {
        Some(n) => {
            parts.warnings.push(format!(
                "{}: {} after the end its header declares ({n} bytes): ignored",
                path.display(),
                crate::words::count((body.len() - n) as u64, "byte", "bytes")
            ));
            &body[..n]
        }
        None => body,
    };
    let body_is_glb = body.starts_with(b"glTF");
    let file = ::gltf::Gltf::from_slice_without_validation(body)
        .or_else(|e| lenient::reread(body).unwrap_or(Err(e)))
        .map_err(|e| match version_1(body) {
            true => anyhow!(
                "{}: glTF 1.0 is not supported (rayterm reads glTF 2.0; \
                 glTF-Pipeline or Blender convert a 1.0 file)",
                path.display()
            ),
            false => invalid(&e),
        })?;
    drop(bytes);
    let mut json = file.document.into_json();
    // glTF 1.0 is another format, which the 2.0 schema misreads.
    let version = &json.asset.version;
    // Written by hand or by a careless tool: read as 2.0, as other readers
    // read it.
    if version.trim().is_empty() {
        parts.warnings.push(format!(
            "{}: its asset.version is empty: read as glTF 2.0",
            path.display()
        ));
    } else if version.split('.').next() != Some("2") {
        bail!(
            "{}: glTF version {}: only glTF 2.x is read",
            path.display(),
            crate::words::quoted(version)
        );
    }
    // The crate's validation indexes the POSITION accessor before
    // checking it: checked here first.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = prim
                .attributes
                .get(&::gltf::json::validation::Checked::Valid(
                    ::gltf::json::mesh::Semantic::Positions,
                ))
                .map(|i| i.value());
            if let Some(i) = position.filter(|&i| i >= json.accessors.len()) {
                bail!(invalid(&format!(
                    "meshes[{m}].primitives[{p}].attributes.POSITION: accessor {i} does not exist \
                     ({} accessors)",
                    json.accessors.len()
                )));
            }
        }
    }
    let drawn_without = extensions::check(path, &mut json, &mut parts.warnings)?;
    extensions::prefer_webp(path, &mut json)?;
    let undefined = extensions::undefined_attributes(&mut json);
    // rayterm shows a file at rest: its animations are counted, not read,
    // so nothing in them (targets of other extensions) can refuse it.
    let animations = std::mem::take(&mut json.animations).len();
    let broken = Broken::of(&json);
    let doc = lenient::document(json).map_err(|e| invalid(&e))?;
    let mut blob = file.blob;
    let is_glb = body_is_glb;
    let used: std::collections::HashSet<usize> = doc.views().map(|v| v.buffer().index()).collect();
    let (mut buffers, mut origins, mut foreign) = (Vec::new(), Vec::new(), Vec::new());
    for b in doc.buffers() {
        let name = named(b.name(), b.index());
        if meshopt::fallback(&b) {
            buffers.push(Vec::new());
            origins.push(String::new());
            foreign.push(None);
            continue;
        }
        let mut outside = None;
        // The binary chunk is padded to 4 bytes past the buffer's length.
        let mut read = || -> Result<(Vec<u8>, usize, String)> {
            Ok(match b.source() {
                ::gltf::buffer::Source::Bin => (
                    blob.take().ok_or_else(|| match is_glb && b.index() == 0 {
                        true => anyhow!(
                            "{}: buffer {name} is the binary chunk of a .glb, and the file has none",
                            path.display()
                        ),
                        false => anyhow!(
                            "{}: buffer {name} has no uri (only a .glb's first buffer, its \
                             binary chunk, goes without one)",
                            path.display()
                        ),
                    })?,
                    3,
                    String::new(),
                ),
                ::gltf::buffer::Source::Uri(uri) => match inline_uri(uri) {
                    Some(d) => (
                        d.map_err(|e| anyhow!("{}: buffer {name}: {e}", path.display()))?,
                        0,
                        String::new(),
                    ),
                    None => {
                        let (p, o) = uri::file(src, path, uri)
                            .map_err(|e| anyhow!("{}: buffer {name}: {e}", path.display()))?;
                        let data = src
                            .read(&p, FileKind::Buffer)
                            .with_context(|| format!("{}: buffer {name}", path.display()))?;
                        outside = o;
                        (data, 0, crate::words::path(&p))
                    }
                },
            })
        };
        // A buffer no view reads is no part of the picture: one that cannot
        // be read is said, not a reason to refuse the file.
        let (mut data, padding, origin) = match read() {
            Ok(read) => read,
            Err(e) if !used.contains(&b.index()) => {
                parts
                    .warnings
                    .push(format!("{e:#}; no view reads it: left out"));
                buffers.push(Vec::new());
                origins.push(String::new());
                foreign.push(None);
                continue;
            }
            Err(e) => return Err(e),
        };
        if data.len() < b.length() {
            bail!(
                "{}: buffer {name} holds {} bytes, the file declares {} (truncated?)",
                path.display(),
                data.len(),
                b.length()
            );
        }
        // byteLength is the buffer's length: bytes past it are no part of it.
        if data.len() > b.length() + padding {
            parts.warnings.push(format!(
                "{}: buffer {name} holds {} bytes, the file declares {}: the first {} are read",
                path.display(),
                data.len(),
                b.length(),
                b.length()
            ));
        }
        data.truncate(b.length());
        buffers.push(data);
        origins.push(origin);
        foreign.push(outside);
    }
    let mut r = Reader {
        path,
        doc: &doc,
        src,
        buffers,
        origins,
        foreign,
        unmapped: Unmapped::default(),
        images: HashMap::new(),
        materials: HashMap::new(),
        broken,
        decoded: HashMap::new(),
        uses: HashMap::new(),
        compressed: meshopt::views(&doc),
        unpacked: HashMap::new(),
        misaligned: RefCell::default(),
    };
    for ext in doc.extensions_used() {
        if !extensions::reads(ext) && !drawn_without.iter().any(|d| d == ext) {
            r.unmapped
                .note(&crate::words::quoted(ext), || "extensionsUsed".into());
        }
    }
    if let Some((first, count)) = undefined {
        for _ in 0..count {
            r.unmapped
                .note("vertex attributes whose names glTF does not define", || {
                    first.clone()
                });
        }
    }
    if animations > 0 {
        r.unmapped.note("animations", || "shown at rest".into());
    }
    if doc.skins().next().is_some() {
        r.unmapped.note("skins", || "shown at rest".into());
    }
    let override_id = material.map(|m| parts.add_material(m.clone()));
    let scene = doc.default_scene().or_else(|| doc.scenes().next());
    let mut out = GltfScene {
        meshes: Vec::new(),
        cameras: Vec::new(),
        lights: Vec::new(),
    };
    // An empty scene is valid (Blender writes one beside the scene it
    // exports); one that leaves the file's meshes unplaced is said.
    let meshes = doc.meshes().len();
    let roots: Vec<::gltf::Node> = match &scene {
        Some(s) => {
            if meshes > 0 && s.nodes().len() == 0 {
                parts.warnings.push(format!(
                    "{}: its scene {} has no nodes, so nothing is placed, though the file has {}",
                    path.display(),
                    named(s.name(), s.index()),
                    crate::words::count(meshes as u64, "mesh", "meshes")
                ));
            }
            s.nodes().collect()
        }
        // A file without scenes is a library to glTF; its nodes that are
        // no other's child are placed, as Blender's importer places them,
        // and said.
        None => {
            let children: std::collections::HashSet<usize> = doc
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()).collect::<Vec<_>>())
                .collect();
            let roots: Vec<_> = doc
                .nodes()
                .filter(|n| !children.contains(&n.index()))
                .collect();
            if meshes > 0 {
                parts.warnings.push(format!(
                    "{}: it has no scenes; its {} placed as a scene's would be",
                    path.display(),
                    crate::words::count(roots.len() as u64, "root node is", "root nodes are")
                ));
            }
            roots
        }
    };
    // Depth first, with each node's world transform in f64: each node
    // once, as the hierarchy is a forest. Each instance of a mesh is a copy
    // of it, counted before anything is read.
    check_trees(path, &doc, &roots)?;
    let (vertices, triangles, uses) = r.instanced(&roots)?;
    r.uses = uses;
    mesh_fits(vertices, triangles, parts.budget.room())
        .map_err(|e| anyhow!("{}: its meshes, each instance counted: {e}", path.display()))?;
    check_values(path, &doc, &r.broken)?;
    check_lights(path, &doc, &mut parts.warnings)?;
    let mut stack: Vec<(::gltf::Node, DAffine3)> = roots.into_iter().map(|n| (n, *xf)).collect();
    stack.reverse();
    while let Some((node, parent)) = stack.pop() {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * DAffine3::from_mat4(local);
        let node_name = named(node.name(), node.index());
        check_transform(path, &node, &node_name, world)?;
        if let ::gltf::scene::Transform::Matrix { matrix: m } = node.transform() {
            // Its last row: what an affine placement drops.
            if [m[0][3], m[1][3], m[2][3], m[3][3]] != [0.0, 0.0, 0.0, 1.0] {
                r.unmapped.note(
                    "projective node matrices (their last row is not 0 0 0 1: read as their \
                     affine part)",
                    || format!("node {node_name}"),
                );
            }
        }
        if let Some(mesh) = node.mesh() {
            let mesh_name = named(mesh.name(), mesh.index());
            if node.weights().is_some() || mesh.weights().is_some() {
                r.unmapped
                    .note("morph targets", || format!("mesh {mesh_name}"));
            }
            let drawn = mesh.primitives().any(|p| primitive::drawn(p.mode()));
            let placements = match drawn {
                true => r.placements(&node, &node_name, world)?,
                false => vec![(world, node_name.clone())],
            };
            for (xf, name) in &placements {
                for p in mesh.primitives() {
                    out.meshes
                        .extend(r.primitive(parts, p, &mesh_name, name, xf, override_id)?);
                }
            }
        }
        if let Some(cam) = node.camera() {
            if let Some(why) = r.broken.cameras.get(&cam.index()) {
                bail!(
                    "{}: node {node_name}: camera {}: {why}",
                    path.display(),
                    named(cam.name(), cam.index())
                );
            }
            let names = [node.name(), cam.name()]
                .into_iter()
                .flatten()
                .map(str::to_string)
                .collect();
            let up = world.transform_vector3(DVec3::Y);
            let projection = match cam.projection() {
                CameraKind::Perspective(p) => Projection::perspective(p.yfov().to_degrees()),
                // ymag is the half height in the camera's own space: the
                // node's scale on the way scales it. The width follows the
                // image's aspect, as a perspective camera's does (xmag, like
                // aspectRatio, is not read).
                CameraKind::Orthographic(o) => Projection::Orthographic {
                    half_height: (o.ymag().abs() as f64 * up.length()) as f32,
                },
            };
            let c = FileCamera {
                names,
                eye: world.transform_point3(DVec3::ZERO),
                forward: world.transform_vector3(DVec3::NEG_Z),
                up,
                projection,
            };
            let usable = c.eye.is_finite()
                && c.forward.cross(c.up).length_squared() > 0.0
                && c.forward.cross(c.up).is_finite()
                && match c.projection {
                    Projection::Orthographic { half_height: h } => h > 0.0 && h.is_finite(),
                    Projection::Perspective { .. } => true,
                };
            match usable {
                true => out.cameras.push(c),
                false => r
                    .unmapped
                    .note("cameras scaled to nothing (or past 32-bit floats)", || {
                        format!("node {node_name}")
                    }),
            }
        }
        if let Some(light) = node.light() {
            // Lights keep their units whatever the node's scale (the
            // extension's rule); only where they are and point moves.
            let value =
                Vec3::from_array(light.color()).max(Vec3::ZERO) * light.intensity().max(0.0);
            let position = world.transform_point3(DVec3::ZERO);
            let direction = world.transform_vector3(DVec3::NEG_Z);
            let aimed = direction.length_squared() > 0.0 && direction.is_finite();
            let range = light
                .range()
                .filter(|r| *r > 0.0 && r.is_finite())
                .map(f64::from);
            match light.kind() {
                LightKind::Point => out.lights.push(FileLight::Point {
                    position,
                    intensity: value,
                    range,
                    cone: None,
                }),
                LightKind::Spot {
                    inner_cone_angle,
                    outer_cone_angle,
                } if aimed => {
                    let outer = outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2);
                    let inner = inner_cone_angle.clamp(0.0, outer);
                    out.lights.push(FileLight::Point {
                        position,
                        intensity: value,
                        range,
                        cone: Some(FileCone {
                            axis: direction.normalize(),
                            cos_inner: inner.cos(),
                            cos_outer: outer.cos(),
                        }),
                    })
                }
                LightKind::Directional if aimed => out.lights.push(FileLight::Directional {
                    direction: direction.normalize(),
                    illuminance: value,
                }),
                // A zero scale on the way leaves it no direction.
                _ => r.unmapped.note(
                    "spot and directional lights scaled to nothing (their direction is zero)",
                    || format!("node {node_name}"),
                ),
            }
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
    }
    parts.warnings.extend(r.misaligned_warning());
    parts.warnings.extend(r.unmapped.warning(path));
    parts.warnings.extend(r.broken.unused(path, doc.as_json()));
    Ok(out)
}
