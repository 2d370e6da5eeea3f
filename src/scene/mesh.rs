//! Mesh files of every format: which loader reads a file (by its
//! extension), and a bare mesh file as a scene with the auto camera and
//! light (or the file's own, where the format has them).

use std::path::Path;

use anyhow::{bail, Result};
use glam::{DAffine3, Vec3};

use super::frame::Frame;
use super::obj;
use super::parts::{Parts, Placed};
use super::source::{resolve, Kind, Source};
use super::{Camera, Environment, Light, Material, Scene, Settings};

/// The mesh formats, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Obj,
    Ply,
    Stl,
}

/// The extensions a bare mesh file may have, as messages list them.
pub const EXTENSIONS: &str = ".obj, .ply or .stl";

impl Format {
    /// The format of `path` by its extension (any case).
    pub fn of(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => Format::Obj,
            "ply" => Format::Ply,
            "stl" => Format::Stl,
            _ => return None,
        })
    }
}

/// Reads a mesh file in `format`: materials and textures go into `parts`,
/// the meshes come back placed by `xf` in f64. `material` replaces the
/// file's materials when given.
pub fn load_placed(
    format: Format,
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<Vec<Placed>> {
    match format {
        Format::Obj => obj::load_placed(parts, src, path, xf, material),
        Format::Stl => {
            let bytes = src.read(path, Kind::Stl)?;
            let id = parts.add_material(material.cloned().unwrap_or_default());
            super::stl::parse(path, &bytes, xf, id, &mut parts.warnings)
        }
        Format::Ply => {
            let bytes = src.read(path, Kind::Ply)?;
            let ply = super::ply::parse(path, &bytes, &mut parts.warnings)?;
            drop(bytes);
            let material = match material {
                Some(m) => m.clone(),
                None => {
                    let texture = ply.texture.as_ref().and_then(|(file, line)| {
                        let from = format!("{}:{line}", path.display());
                        parts.texture(src, &resolve(path, file), &from)
                    });
                    Material {
                        name: "ply".into(),
                        // Vertex colours are the diffuse colour as they are.
                        kd: if ply.colors.is_some() || texture.is_some() {
                            Vec3::ONE
                        } else {
                            Material::default().kd
                        },
                        texture,
                        ..Material::default()
                    }
                }
            };
            let id = parts.add_material(material);
            Ok(vec![ply.placed(path, xf, id)?])
        }
    }
}

/// A bare mesh file: the shared workload's auto camera and point light;
/// moved next to the origin (and scaled) in f64 when far or huge
/// ([`Frame`]).
pub fn load_bare_from(src: &dyn Source, path: &Path, format: Format) -> Result<Scene> {
    let mut parts = Parts::default();
    let meshes = load_placed(format, &mut parts, src, path, &DAffine3::IDENTITY, None)?;
    let (min, max) = super::parts::bounds(&meshes);
    let (frame, moved) = Frame::fit(min, max);
    parts.warnings.extend(
        moved
            .into_iter()
            .map(|w| format!("{}: {w}", path.display())),
    );
    for m in meshes {
        parts.add_placed(m, &frame);
    }
    if parts.geometry.indices.is_empty() {
        bail!("{}: no triangles{}", path.display(), parts.why_empty());
    }
    let b = parts.geometry.bounds();
    let name = path.display().to_string();
    Ok(Scene {
        description: format!("mesh {name}"),
        name,
        camera: Camera::auto(&b),
        lights: vec![Light::Point {
            position: Camera::auto_light(&b),
            color: Vec3::ONE,
        }],
        environment: Environment::Color(Vec3::ZERO),
        settings: Settings {
            ambient: Vec3::splat(0.1),
            ..Settings::default()
        },
        geometry: parts.geometry,
        meshes: parts.meshes,
        materials: parts.materials,
        textures: parts.textures,
        warnings: parts.warnings,
    })
}
