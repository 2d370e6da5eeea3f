//! Writes the teapot tessellated at N segments per patch edge (64 N²
//! triangles, the meshes of `rayterm bench scaling`) as a Wavefront OBJ,
//! for engines that read only files: `cargo run --release --example
//! teapot_obj -- 128 > teapot128.obj` (1.05M triangles).

use std::io::{BufWriter, Write};

fn main() -> anyhow::Result<()> {
    let n: u32 = std::env::args().nth(1).map_or(Ok(64), |s| s.parse())?;
    let g = rayterm::report::scaling::teapot(n)?;
    let mut out = BufWriter::new(std::io::stdout().lock());
    // `{}` prints the shortest decimal that reads back as the same float.
    for p in g.positions() {
        writeln!(out, "v {} {} {}", p.x, p.y, p.z)?;
    }
    for t in g.indices() {
        writeln!(out, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
    }
    out.flush()?;
    Ok(())
}
