//! Mesh files of every format: which loader reads a file (by its
//! extension), and a bare mesh file as a scene with the auto camera and
//! light (or the file's own, where the format has them: glTF).

use std::path::Path;

use anyhow::{bail, Result};
use glam::{DAffine3, Vec3};

use super::gltf::{self, FileCamera, FileLight};
use super::obj;
use super::parts::{Parts, Placed};
use super::source::{FileKind, Source};
use super::up::Up;
use crate::scene::light::Cone;
use crate::scene::rebase::Rebase;
use crate::scene::{Camera, EnvLight, Environment, Light, Material, Scene, Settings};

/// The key light of a glTF file without lights, in Phong units (π times
/// this in lux), and the radiance of its sky: a white matte surface
/// facing both shows about 1.
const DEFAULT_KEY: Vec3 = Vec3::splat(0.6);
const DEFAULT_SKY: Vec3 = Vec3::splat(0.4);

/// The mesh formats, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    Obj,
    Ply,
    Stl,
    Gltf,
}

/// The extensions a bare mesh file may have, as messages list them.
pub(crate) const EXTENSIONS: &str = ".obj, .ply, .stl, .gltf or .glb";

impl MeshFormat {
    /// What a file of this format holds, as messages name it.
    pub(crate) fn kind(self) -> FileKind {
        match self {
            MeshFormat::Obj => FileKind::Obj,
            MeshFormat::Ply => FileKind::Ply,
            MeshFormat::Stl => FileKind::Stl,
            MeshFormat::Gltf => FileKind::Gltf,
        }
    }

    /// The up axis of a file of this format unless told otherwise: Z for
    /// STL (3D printing and CAD are Z-up), Y for the others (glTF's
    /// specification says so; OBJ and PLY writers mostly are).
    pub(crate) fn up(self) -> Up {
        match self {
            MeshFormat::Stl => Up::Z,
            _ => Up::Y,
        }
    }

    /// The format of `path` by its extension (any case).
    pub(crate) fn of(path: &Path) -> Option<MeshFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply,
            "stl" => MeshFormat::Stl,
            "gltf" | "glb" => MeshFormat::Gltf,
            _ => return None,
        })
    }
}

/// Reads a mesh file in `format`: materials and textures go into `parts`,
/// the meshes come back placed by `xf` in f64. `material` replaces the
/// file's materials when given.
pub fn load_placed(
    format: MeshFormat,
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<Vec<Placed>> {
    let placed = read_placed(format, parts, src, path, xf, material)?;
    for m in &placed {
        parts
            .budget
            .take(m.positions.len() as u64, m.indices.len() as u64);
    }
    Ok(placed)
}

fn read_placed(
    format: MeshFormat,
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<Vec<Placed>> {
    match format {
        MeshFormat::Obj => obj::load_placed(parts, src, path, xf, material),
        MeshFormat::Gltf => {
            let g = gltf::load(parts, src, path, xf, material)?;
            if !g.cameras.is_empty() || !g.lights.is_empty() {
                parts.warnings.push(format!(
                    "{}: its camera and lights are used when it is opened on its own, \
                     not as a mesh of a scene file",
                    path.display()
                ));
            }
            Ok(g.meshes)
        }
        MeshFormat::Stl => {
            let bytes = src.read(path, FileKind::Stl)?;
            let id = parts.add_material(material.cloned().unwrap_or_default());
            let room = parts.budget.room();
            super::stl::parse(path, &bytes, xf, id, &mut parts.warnings, room)
        }
        MeshFormat::Ply => {
            let bytes = src.read(path, FileKind::Ply)?;
            let room = parts.budget.room();
            let ply = super::ply::parse(path, &bytes, &mut parts.warnings, room)?;
            drop(bytes);
            let material = match material {
                Some(m) => m.clone(),
                None => {
                    let texture = ply.texture.as_ref().and_then(|(file, line)| {
                        let from = format!("{}:{line}", path.display());
                        parts.texture(src, path, file, &from)
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

/// A bare mesh file: its own camera (the first, or the one named by
/// `camera`) and lights where it has them (glTF), else the shared
/// workload's auto camera and point light (none where `env_given`: the
/// environment light the caller puts in lights it); moved next to the
/// origin (and scaled) in f64 when far or huge ([`Rebase`](crate::scene::rebase::Rebase)).
pub(crate) fn load_bare_from(
    src: &dyn Source,
    path: &Path,
    format: MeshFormat,
    camera: Option<&str>,
    up: Option<Up>,
    env_given: bool,
) -> Result<Scene> {
    let mut parts = Parts::default();
    let xf = up.unwrap_or(format.up()).to_y();
    let (meshes, camera, file_lights) = match format {
        MeshFormat::Gltf => {
            let g = gltf::load(&mut parts, src, path, &xf, None)?;
            let camera = match camera {
                Some(name) => Some(pick_camera(path, g.cameras, name)?),
                None => g.cameras.into_iter().next(),
            };
            (g.meshes, camera, g.lights)
        }
        _ => {
            if let Some(name) = camera {
                bail!(
                    "--camera {name}: {} has no cameras (only glTF files name theirs)",
                    path.display()
                );
            }
            (
                load_placed(format, &mut parts, src, path, &xf, None)?,
                None,
                Vec::new(),
            )
        }
    };
    let (min, max) = super::parts::bounds(&meshes);
    let (frame, moved) = Rebase::fit(min, max);
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
    let (centre, radius) = ((min + max) * 0.5, (max - min).length() * 0.5);
    let camera = match camera {
        Some(c) => {
            // The target, about which the view orbits: as far ahead as
            // the scene's centre.
            let ahead = c.forward.normalize();
            let d = (centre - c.eye).dot(ahead);
            let d = if d > 0.0 { d } else { radius.max(1e-9) };
            Camera {
                eye: frame.point(c.eye),
                target: frame.point(c.eye + ahead * d),
                up: c.up.normalize().as_vec3(),
                projection: c.projection.scaled(frame.scale as f32),
            }
        }
        None => Camera::auto(&b),
    };
    // The frame's scale (a power of two, for scenes past f32's comfort)
    // scales distances: intensities make up for it.
    let s = frame.scale as f32;
    let mut lights: Vec<Light> = file_lights
        .iter()
        .map(|l| match *l {
            FileLight::Point {
                position,
                intensity,
                range,
                cone,
            } => Light::Photometric {
                position: frame.point(position),
                intensity: intensity * (s * s),
                range: range.map(|r| (r * frame.scale) as f32),
                cone: cone.map(|c| Cone {
                    axis: c.axis.as_vec3(),
                    cos_inner: c.cos_inner,
                    cos_outer: c.cos_outer,
                }),
            },
            FileLight::Directional {
                direction,
                illuminance,
            } => Light::Directional {
                direction: direction.as_vec3(),
                illuminance,
            },
        })
        .collect();
    // A file's own lights light it as authored. A file without lights
    // gets a key light and, so that every face shows, ambient light (a
    // Phong file) or a grey sky (a glTF file, whose metals show only
    // what they reflect).
    let unlit = lights.is_empty() && !env_given;
    let sky = unlit && format == MeshFormat::Gltf;
    let mut environment = Environment::Color(Vec3::ZERO);
    let mut ambient = Vec3::ZERO;
    if unlit {
        let (key, fill) = match sky {
            true => (DEFAULT_KEY, Vec3::ZERO),
            false => (Vec3::ONE, Vec3::splat(0.1)),
        };
        lights.push(Light::Point {
            position: Camera::auto_light(&b),
            color: key,
        });
        ambient = fill;
    }
    if sky {
        environment = Environment::Light(Box::new(EnvLight::constant(DEFAULT_SKY)));
    }
    let name = path.display().to_string();
    Ok(Scene {
        description: format!("mesh {name}"),
        lights,
        environment,
        settings: Settings {
            ambient,
            ..Settings::default()
        },
        ..parts.into_scene(name, camera)
    })
}

/// The camera of `cameras` that `name` names (its node's name or its own),
/// or the `name`-th (from 1); else an error listing what there is.
fn pick_camera(path: &Path, cameras: Vec<FileCamera>, name: &str) -> Result<FileCamera> {
    let by_number = name.parse::<usize>().ok().filter(|&i| i >= 1);
    let found = cameras
        .iter()
        .position(|c| c.names.iter().any(|n| n == name))
        .or(by_number.map(|i| i - 1).filter(|&i| i < cameras.len()));
    match found {
        Some(i) => Ok(cameras.into_iter().nth(i).expect("an index of cameras")),
        None if cameras.is_empty() => bail!(
            "--camera {name}: {} has no perspective camera",
            path.display()
        ),
        None => {
            let listed: Vec<String> = cameras
                .iter()
                .enumerate()
                .map(|(i, c)| match c.names.as_slice() {
                    [] => format!("{}", i + 1),
                    names => format!("{} ({})", names.join(" / "), i + 1),
                })
                .collect();
            bail!(
                "--camera {name}: {} has no such camera; its cameras are {}",
                path.display(),
                listed.join(", ")
            )
        }
    }
}
