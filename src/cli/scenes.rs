//! `rayterm scenes`: the built-in scenes with their sizes.

use std::process::ExitCode;

use anyhow::Result;

use crate::scene::load::{self, builtin::SCENES};

pub(crate) fn run() -> Result<ExitCode> {
    crate::outln!(
        "{:<14} {:>9} {:>7}  description",
        "name",
        "triangles",
        "lights"
    )?;
    for (name, description) in SCENES {
        let s = load::open(name, &Default::default())?.scene;
        crate::outln!(
            "{:<14} {:>9} {:>7}  {description}",
            name,
            s.geometry.triangle_count(),
            s.lights.len()
        )?;
    }
    crate::outln!(
        "\nAlso: teapot:N (N segments per patch edge, 1..1024), any .toml scene file or mesh file (.obj, .ply, .stl, .gltf, .glb)."
    )?;
    Ok(ExitCode::SUCCESS)
}
