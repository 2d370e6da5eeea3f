//! The environment light from the command line (`--env`, `--env-strength`,
//! `--env-rotate`) and from scene files (`[environment] map`): a camera
//! looking at the sky sees the map where its convention puts it, turned
//! and scaled as asked; what cannot be light is refused, naming the file
//! or value, with no output written.

use crate::files::{rayterm, Dir};
use glam::Vec3;

/// A 16x8 map whose colour depends on the way it looks: grey along -X (the
/// edges), green along -Z (a quarter of the width), red along +X (the
/// centre), blue along +Z (three quarters).
fn compass() -> Vec<Vec3> {
    (0..8)
        .flat_map(|_| 0..16)
        .map(|x| match x {
            2..=5 => Vec3::new(0.0, 0.5, 0.0),
            6..=9 => Vec3::new(0.5, 0.0, 0.0),
            10..=13 => Vec3::new(0.0, 0.0, 0.5),
            _ => Vec3::splat(0.25),
        })
        .collect()
}

/// `px` (16 wide) as a Radiance HDR file, through the image crate.
fn hdr(px: &[Vec3]) -> Vec<u8> {
    let rgb: Vec<image::Rgb<f32>> = px.iter().map(|c| image::Rgb(c.to_array())).collect();
    let mut bytes = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut bytes)
        .encode(&rgb, 16, px.len() / 16)
        .unwrap();
    bytes
}

/// A scene of one triangle behind a camera at the origin that looks along
/// -Z with a narrow view: it sees only the sky. `env` is its
/// `[environment]` table's body, if any.
fn looking_at_the_sky(d: &Dir, at: &str, env: Option<&str>) -> String {
    let mesh = std::path::Path::new(at).with_file_name("tri.obj");
    let mesh = mesh.to_str().unwrap();
    d.write(mesh, "v -1 -1 5\nv 1 -1 5\nv 0 1 5\nf 1 2 3\n");
    let table = env.map_or(String::new(), |e| format!("[environment]\n{e}\n"));
    d.write(
        at,
        format!(
            "[camera]\neye = [0, 0, 0]\ntarget = [0, 0, -1]\nfov = 20\n\n[[mesh]]\n\
             file = \"tri.obj\"\n\n{table}"
        ),
    )
}

/// Renders `args` in `d` to `out.exr` and gives its pixels, which must all
/// be the same.
fn sky_colour(d: &Dir, args: &[&str]) -> Vec3 {
    let mut all = vec!["render"];
    all.extend(args);
    all.extend(["--size", "16x16", "--spp", "2", "-o", "out.exr"]);
    let r = rayterm(&d.0, &all);
    assert!(r.ok(), "{args:?}: {}", r.stderr);
    let img = rayterm::raster::read_linear(&d.path("out.exr")).unwrap();
    std::fs::remove_file(d.path("out.exr")).unwrap();
    let first = img.pixels()[0];
    assert!(img.pixels().iter().all(|&p| p == first), "{args:?}");
    first
}

#[test]
fn render_env_shows_the_map_where_its_convention_puts_it() {
    let d = Dir::new("envlight-cli");
    d.write("sky.hdr", hdr(&compass()));
    let exr = rayterm::raster::openexr::encode(16, 8, &compass()).unwrap();
    d.write("sky.exr", exr);
    let scene = looking_at_the_sky(&d, "s.toml", None);
    let green = Vec3::new(0.0, 0.5, 0.0);
    // Along -Z, a quarter of the width from the left.
    assert_eq!(sky_colour(&d, &[&scene, "--env", "sky.hdr"]), green);
    assert_eq!(sky_colour(&d, &[&scene, "--env", "sky.exr"]), green);
    // Turned 90 degrees, what was along +X (the centre) is along -Z.
    let turned = sky_colour(&d, &[&scene, "--env", "sky.hdr", "--env-rotate", "90"]);
    assert!(
        (turned - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-6,
        "{turned}"
    );
    let doubled = sky_colour(&d, &[&scene, "--env", "sky.hdr", "--env-strength", "2"]);
    assert_eq!(doubled, 2.0 * green);
    // A colour or a grey level, for any scene.
    let c = Vec3::new(0.2, 0.3, 0.5);
    assert_eq!(sky_colour(&d, &[&scene, "--env", "0.2,0.3,0.5"]), c);
    assert_eq!(sky_colour(&d, &[&scene, "--env", "0.5"]), Vec3::splat(0.5));
    // The environment feature off, the sky is black.
    let off = sky_colour(&d, &[&scene, "--env", "0.5", "--no", "environment"]);
    assert_eq!(off, Vec3::ZERO);
    // A built-in scene takes it too, and the map is an input no output
    // may replace.
    let r = rayterm(
        &d.0,
        &["render", "cornell", "--env", "sky.hdr", "-o", "sky.hdr"],
    );
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert_eq!(std::fs::read(d.path("sky.hdr")).unwrap(), hdr(&compass()));
    // The inspector names the map and where it looked.
    let r = rayterm(
        &d.0,
        &[
            "inspect", &scene, "--env", "sky.hdr", "--size", "16x16", "--pixel", "8,8",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    assert!(
        r.stdout.contains("miss: environment face latlong uv (0.25"),
        "{}",
        r.stdout
    );
    // Every command that opens a scene takes it.
    for command in ["tui", "inspect", "converge"] {
        let r = rayterm(&d.0, &[command, "--help"]);
        assert!(r.stdout.contains("--env-rotate <DEGREES>"), "{command}");
    }
}

#[test]
fn a_scene_file_names_its_map_beside_it() {
    let d = Dir::new("envlight-toml");
    d.write("scenes/maps/sky.hdr", hdr(&compass()));
    let env = "map = \"maps/sky.hdr\"\nstrength = 2.0\nrotate = 90.0";
    let scene = looking_at_the_sky(&d, "scenes/s.toml", Some(env));
    let red = sky_colour(&d, &[&scene]);
    assert!((red - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6, "{red}");
    // From elsewhere, the map is still the one beside the scene.
    let r = rayterm(
        &d.path("scenes/maps"),
        &["render", "../s.toml", "--size", "4x4", "-o", "o.png"],
    );
    assert!(r.ok(), "{}", r.stderr);
    // --env replaces it.
    assert_eq!(sky_colour(&d, &[&scene, "--env", "0.5"]), Vec3::splat(0.5));
}

#[test]
fn what_cannot_be_light_is_refused_naming_it() {
    let d = Dir::new("envlight-refused");
    let whole = hdr(&compass());
    d.write("cut.hdr", &whole[..whole.len() - 40]);
    d.write("junk.hdr", "not an image at all");
    let scene = looking_at_the_sky(&d, "s.toml", None);
    for (args, says) in [
        (
            &["--env", "missing.hdr"][..],
            &["--env missing.hdr", "not found"][..],
        ),
        (&["--env", "junk.hdr"], &["junk.hdr", "not an image"]),
        (
            &["--env", "cut.hdr"],
            &["--env cut.hdr: cut.hdr: ", "truncated"],
        ),
        (
            &["--env", "0.5", "--env-strength", "-1"],
            &["--env-strength -1", "0 or more"],
        ),
        (
            &["--env", "0.5", "--env-strength", "nan"],
            &["--env-strength NaN"],
        ),
        (&["--env", "-0.5"], &["--env -0.5", "0 or more"]),
        (&["--env", "0.1,nan,0.2"], &["--env 0.1,nan,0.2"]),
    ] {
        let mut all = vec!["render", scene.as_str(), "-o", "out.png"];
        all.extend(args);
        let r = rayterm(&d.0, &all);
        assert_eq!(r.code, Some(1), "{args:?}: {}", r.stderr);
        for s in says {
            assert!(
                r.stderr.contains(s),
                "{args:?}: '{s}' missing in {}",
                r.stderr
            );
        }
        assert!(!d.path("out.png").exists(), "{args:?}");
    }
    d.write("sky.hdr", &whole);
    for (env, says) in [
        (
            "map = \"none.hdr\"",
            &["t.toml:10:7: environment map none.hdr", "not found"][..],
        ),
        (
            "map = \"junk.hdr\"",
            &["environment map junk.hdr", "not an image"],
        ),
        (
            "map = \"sky.hdr\"\ncolor = [1, 1, 1]",
            &["t.toml:10:7", "give it without color"],
        ),
        (
            "map = \"sky.hdr\"\nsky = true",
            &["give it without color, sky or faces"],
        ),
        (
            "map = \"sky.hdr\"\nstrength = -1",
            &["t.toml:11:12: environment strength must be 0 or more, not -1"],
        ),
        (
            "map = \"sky.hdr\"\nstrength = nan",
            &["t.toml:11:12", "not a finite number"],
        ),
        (
            "color = [1, 1, 1]\nrotate = 90",
            &["t.toml:11:10", "apply to a map"],
        ),
    ] {
        let scene = looking_at_the_sky(&d, "t.toml", Some(env));
        let r = rayterm(&d.0, &["render", &scene, "-o", "out.png"]);
        assert_eq!(r.code, Some(1), "{env}: {}", r.stderr);
        for s in says {
            assert!(r.stderr.contains(s), "{env}: '{s}' missing in {}", r.stderr);
        }
        assert!(!d.path("out.png").exists(), "{env}");
    }
}
