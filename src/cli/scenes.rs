//! `rayterm scenes`: the built-in scenes with their sizes.

use std::process::ExitCode;

use anyhow::Result;

use crate::scene::{builtin::SCENES, load};

pub fn run() -> Result<ExitCode> {
    crate::outln!(
        "{:<14} {:>9} {:>7}  description",
        "name",
        "triangles",
        "lights"
    )?;
    for (name, description) in SCENES {
        let s = load(name)?;
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
