//! `rayterm stability`: the numerical stability battery as a table.

use std::process::ExitCode;

use anyhow::Result;

use super::args::StabilityArgs;
use super::progress::ReportBar;
use crate::report::stability::{run_and_print, Options};

pub(crate) fn run(a: StabilityArgs) -> Result<ExitCode> {
    let (width, height) = a.size;
    let o = Options {
        width,
        height,
        ..Options::default()
    };
    Ok(if run_and_print(&a.scene, &o, a.json, &ReportBar::new())? {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
