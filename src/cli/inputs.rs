//! `rayterm inputs SCENE`: the files the scene reads, one a line, as the
//! scene is opened for a render (the files the loaders read, no list of
//! its own).

use std::process::ExitCode;

use anyhow::Result;

use super::args::InputsArgs;
use crate::render::Session;

pub(crate) fn run(a: InputsArgs) -> Result<ExitCode> {
    let (scene, inputs) = Session::load(&a.scene.request())?;
    for w in &scene.warnings {
        super::say("warning", w);
    }
    // `a/../b` written out, as every message writes paths (the same file
    // on any path without symbolic links on it).
    for i in &inputs {
        crate::outln!("{}", crate::words::tidy(&i.path).display())?;
    }
    Ok(ExitCode::SUCCESS)
}
