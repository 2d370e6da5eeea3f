//! Loaders: a scene spec (a built-in name, a `.toml` scene file or a bare
//! mesh file: OBJ, PLY, STL, glTF) read into the scene model, [`open`]
//! the one way in. Files are read in f64 and placed in f64 before the
//! model's f32 ([`crate::scene::rebase::Rebase`]).

pub mod bezier;
pub mod builtin;
mod envmap;
mod file;
mod gltf;
pub mod mesh;
mod mtl;
mod numbers;
pub mod obj;
mod parts;
mod ply;
mod polygon;
pub mod source;
mod stl;
mod tangents;
pub(crate) mod up;

use std::path::Path;

use anyhow::{bail, Context, Result};

pub(crate) use envmap::EnvRequest;
use source::{Disk, InputFile, Source};

use crate::scene::{Environment, Scene};

/// How a scene is opened: what the command line chose, and where its
/// files are read.
#[derive(Clone, Default)]
pub struct Opening<'a> {
    /// The camera to look through, where the file names its cameras
    /// (glTF).
    pub camera: Option<String>,
    /// Whether glTF files may name files outside their folder.
    pub allow_outside: bool,
    /// A bare mesh file's up axis, where not its format's
    /// ([`mesh::MeshFormat::up`]).
    pub up: Option<up::Up>,
    /// An environment light in place of the scene's environment, whatever
    /// the scene.
    pub env: Option<EnvRequest>,
    /// Where the spec's file and the files it names are read: the disk
    /// when `None` (files held in memory for tests and the stability
    /// battery's probes).
    pub source: Option<&'a dyn Source>,
}

/// A scene as opened, its warnings in [`Scene::warnings`].
#[derive(Debug)]
pub struct Opened {
    pub scene: Scene,
    /// The files read from disk, for `rayterm inputs` and partial films.
    pub(crate) inputs: Vec<InputFile>,
}

/// Opens `spec`: a built-in name (`cornell`, `teapot:32`, ...), a `.toml`
/// scene file or a bare mesh file ([`mesh::MeshFormat`]), as `how` says;
/// far-away and huge scenes are moved and scaled in f64 as they load
/// ([`crate::scene::rebase::Rebase`]).
pub fn open(spec: &str, how: &Opening) -> Result<Opened> {
    let mut opened = open_any(spec, how)?;
    let scene = &mut opened.scene;
    scene.warnings = fold_repeats(std::mem::take(&mut scene.warnings));
    Ok(opened)
}

/// Each warning once, in the order first given, with how many more came
/// alike (the same but for the line they name): a file that repeats a
/// fault (ten thousand `mtllib` lines naming a missing file) says so in
/// one line.
fn fold_repeats(warnings: Vec<String>) -> Vec<String> {
    let mut seen: std::collections::HashMap<String, usize> = Default::default();
    let mut order: Vec<(String, usize)> = Vec::new();
    for w in warnings {
        match seen.entry(without_line(&w)) {
            std::collections::hash_map::Entry::Occupied(e) => order[*e.get()].1 += 1,
            std::collections::hash_map::Entry::Vacant(e) => {
                e.insert(order.len());
                order.push((w, 0));
            }
        }
    }
    order
        .into_iter()
        .map(|(w, more)| match more {
            0 => w,
            n => format!("{w} (and {n} more like it)"),
        })
        .collect()
}

/// `w` with the first `:LINE:` it holds (a place, `file:LINE: ...`) made
/// `:#:`.
fn without_line(w: &str) -> String {
    let b = w.as_bytes();
    let mut i = 0;
    while let Some(at) = w[i..].find(':').map(|k| i + k) {
        let digits = b[at + 1..]
            .iter()
            .take_while(|c| c.is_ascii_digit())
            .count();
        if digits > 0 && b.get(at + 1 + digits) == Some(&b':') {
            return format!("{}:#{}", &w[..at], &w[at + 1 + digits..]);
        }
        i = at + 1;
    }
    w.to_string()
}

/// The scene `spec` names, opened as `how` says, with the files read.
fn open_any(spec: &str, how: &Opening) -> Result<Opened> {
    let Some(env) = &how.env else {
        return open_named(spec, how);
    };
    // The command line's own mistakes before a long load.
    let disk = Disk::new(how.allow_outside);
    let mut warnings = Vec::new();
    let light = env.light(how.source.unwrap_or(&disk), &mut warnings)?;
    let mut opened = open_named(spec, how)?;
    opened.scene.environment = Environment::Light(Box::new(light));
    opened.scene.warnings.extend(warnings);
    opened.inputs.extend(disk.files());
    Ok(opened)
}

/// [`open_any`] but for the environment light asked for.
fn open_named(spec: &str, how: &Opening) -> Result<Opened> {
    let camera = how.camera.as_deref();
    if let Some(scene) = builtin::load(spec)? {
        if let Some(name) = camera {
            bail!("--camera {name}: the built-in scene {spec} has one camera, no named ones");
        }
        if let Some(up) = how.up {
            bail!("--up {up}: applies to mesh files; {spec} is a built-in scene");
        }
        return Ok(Opened {
            scene,
            inputs: Vec::new(),
        });
    }
    let path = Path::new(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let disk = Disk::new(how.allow_outside);
    let src = how.source.unwrap_or(&disk);
    match ext.as_deref() {
        Some("toml") if camera.is_some() => bail!(
            "--camera {}: {spec} is a scene file: its [camera] is the one used",
            camera.unwrap_or_default()
        ),
        Some("toml") if how.up.is_some() => bail!(
            "--up {}: {spec} is a scene file: give each [[mesh]] its own `up`",
            how.up.unwrap_or(up::Up::Y)
        ),
        Some("toml") => file::load_with(src, path, file::Overrides::default()),
        _ if mesh::MeshFormat::of(path).is_some() => {
            let format = mesh::MeshFormat::of(path).unwrap_or(mesh::MeshFormat::Obj);
            mesh::load_bare_from(src, path, format, camera, how.up, how.env.is_some())
        }
        _ if !path.exists() => {
            bail!("unknown scene '{spec}': not a built-in (see `rayterm scenes`) and no such file")
        }
        _ => match std::fs::metadata(path) {
            Ok(m) if !m.is_file() => bail!(
                "{spec}: not a regular file ({}); a scene is a built-in name, a .toml scene \
                 file or a {} mesh",
                source::file_type_name(&m),
                mesh::EXTENSIONS
            ),
            _ => {
                bail!(
                    "{spec}: a scene must be a built-in name, a .toml scene file or a {} mesh",
                    mesh::EXTENSIONS
                )
            }
        },
    }
    .map(|mut scene| {
        // Summaries print it; a mesh's name is its file's, from the command line.
        scene.name = crate::words::quoted(&scene.name);
        Opened {
            scene,
            inputs: disk.files(),
        }
    })
    .with_context(|| format!("loading scene '{spec}'"))
}
