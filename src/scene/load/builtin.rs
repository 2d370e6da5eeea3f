//! Built-in scenes. Their TOML, OBJ, MTL and image files live in `data/` and
//! are compiled into the binary, so `rayterm render cornell` works from any
//! directory; they load through the same code as user scene files.

use std::path::Path;

use anyhow::{bail, Context, Result};

use super::file::{load_with, Overrides};
use super::source::Embedded;
use crate::scene::Scene;

macro_rules! embed {
    ($($p:literal),* $(,)?) => {
        &[$((concat!("data/", $p), include_bytes!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/", $p)) as &[u8])),*]
    };
}

static FILES: &[(&str, &[u8])] = embed![
    "cornell.toml",
    "cornell-area.toml",
    "cube-textured.toml",
    "mirrors.toml",
    "teapot.toml",
    "env.toml",
    "meshes/cornell.obj",
    "meshes/cornell.mtl",
    "meshes/cube.obj",
    "meshes/cube.mtl",
    "meshes/plane.obj",
    "meshes/sphere.obj",
    "meshes/sphere_mirror.obj",
    "meshes/sphere_red.obj",
    "meshes/sphere_blue.obj",
    "meshes/sphere_gold.obj",
    "meshes/floor_mirror.obj",
    "meshes/mirrors.mtl",
    "teapot.bpt",
    "meshes/checker.png",
    "sky/posx.png",
    "sky/negx.png",
    "sky/posy.png",
    "sky/negy.png",
    "sky/posz.png",
    "sky/negz.png",
];

pub(crate) fn files() -> Embedded {
    Embedded(FILES)
}

/// Name and one-line description of every built-in scene.
pub const SCENES: &[(&str, &str)] = &[
    (
        "cornell",
        "Cornell box, short box and tall mirror box, point light",
    ),
    (
        "cornell-area",
        "Cornell box under a four-colour parallelogram light",
    ),
    ("cube-textured", "a textured cube on a plane"),
    (
        "mirrors",
        "mirror, glossy and coloured spheres on a mirror floor",
    ),
    (
        "teapot",
        "Utah teapot from Newell's patches; teapot:N for N segments per patch edge",
    ),
    ("env", "chrome teapot and spheres under a sky cube map"),
];

/// Loads a built-in scene; `Ok(None)` when `spec` names none.
pub(crate) fn load(spec: &str) -> Result<Option<Scene>> {
    let (name, arg) = match spec.split_once(':') {
        Some((n, a)) => (n, Some(a)),
        None => (spec, None),
    };
    let Some((name, description)) = SCENES.iter().find(|(n, _)| *n == name) else {
        return Ok(None);
    };
    let mut ov = Overrides::default();
    if let Some(a) = arg {
        if *name != "teapot" {
            bail!("scene '{name}' takes no ':N' parameter (only teapot:N does)");
        }
        let n: u32 = a
            .parse()
            .ok()
            .filter(|n| (1..=1024).contains(n))
            .with_context(|| format!("teapot:{a}: N must be a whole number from 1 to 1024"))?;
        ov.segments = Some(n);
    }
    let path = format!("data/{name}.toml");
    let mut scene = load_with(&files(), Path::new(&path), ov)?;
    scene.name = spec.to_string();
    if scene.description.is_empty() {
        scene.description = description.to_string();
    }
    Ok(Some(scene))
}
