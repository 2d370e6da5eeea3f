//! Pass time and terminal bytes of the TUI, as `rayterm bench` reports them:
//! `cargo run --release --example tui_pass -- SCENE [COLS ROWS [PASSES]]`.

use anyhow::{Context, Result};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args
        .first()
        .context("usage: tui_pass SCENE [COLS ROWS [PASSES]]")?;
    let num = |i: usize, default: u32| -> Result<u32> {
        args.get(i).map_or(Ok(default), |s| {
            s.parse().with_context(|| format!("bad number '{s}'"))
        })
    };
    let stats = rayterm::tui::bench::measure_pass(
        scene,
        num(1, 160)? as u16,
        num(2, 48)? as u16,
        num(3, 50)?,
    )?;
    println!("{}", serde_json::to_string_pretty(&stats)?);
    Ok(())
}
