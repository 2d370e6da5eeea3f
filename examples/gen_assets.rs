//! Regenerates rayterm's procedural assets under `data/`:
//!
//! * `data/meshes/checker.png`: a 256x256 test texture;
//! * `data/sky/{posx,negx,posy,negy,posz,negz}.png`: a 128x128-per-face sky
//!   cube map (OpenGL face convention, see [`face_direction`]);
//! * `data/meshes/*.obj` and `*.mtl`: sphere, plane, cube, Cornell box and the
//!   materials of the mirrors and teapot scenes.
//!
//! ```text
//! cargo run --release --example gen_assets            # writes into data/
//! cargo run --release --example gen_assets -- DIR     # writes into DIR/
//! ```
//!
//! Everything is computed from this file alone (integer hashing for noise,
//! fixed `{:.6}` float formatting), so re-running it reproduces the files.
//! (`data/teapot.bpt` is hand-written data, not generated here.)

use std::error::Error;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use image::{Rgb, RgbImage};

type Result<T> = std::result::Result<T, Box<dyn Error>>;

fn main() -> Result<()> {
    let out = std::env::args_os()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("data"));
    for dir in ["sky", "meshes"] {
        fs::create_dir_all(out.join(dir))?;
    }

    let checker = out.join("meshes/checker.png");
    checker_texture().save(&checker)?;
    println!("wrote {}", checker.display());

    for face in CubeFace::ALL {
        let path = out.join(format!("sky/{}.png", face.name()));
        sky_face(face, SKY_FACE_SIZE).save(&path)?;
        println!("wrote {}", path.display());
    }

    let meshes = out.join("meshes");
    let sphere = Mesh::uv_sphere(32, 24);
    let plane = Mesh::plane();
    let files = [
        (
            "sphere.obj",
            sphere.to_obj("UV sphere, radius 1, centred at the origin", None),
        ),
        (
            "plane.obj",
            plane.to_obj("2x2 quad at y = 0 facing +Y", None),
        ),
        (
            "cube.obj",
            Mesh::cube().to_obj("cube [-1, 1]^3", Some(("cube.mtl", "checker"))),
        ),
        ("cube.mtl", CUBE_MTL.to_string()),
        ("cornell.obj", cornell_box()),
        ("cornell.mtl", CORNELL_MTL.to_string()),
        ("mirrors.mtl", MIRRORS_MTL.to_string()),
        (
            "sphere_mirror.obj",
            sphere.to_obj("mirror sphere", Some(("mirrors.mtl", "mirror"))),
        ),
        (
            "sphere_red.obj",
            sphere.to_obj("red sphere", Some(("mirrors.mtl", "red_glossy"))),
        ),
        (
            "sphere_blue.obj",
            sphere.to_obj("blue sphere", Some(("mirrors.mtl", "blue"))),
        ),
        (
            "sphere_gold.obj",
            sphere.to_obj("gold sphere", Some(("mirrors.mtl", "gold"))),
        ),
        (
            "floor_mirror.obj",
            plane.to_obj("mirror floor", Some(("mirrors.mtl", "floor_mirror"))),
        ),
    ];
    for (name, text) in files {
        let path = meshes.join(name);
        fs::write(&path, text)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Shared helpers
// ---------------------------------------------------------------------------

/// Fixed-precision float text; never prints a negative zero.
fn num(x: f64) -> String {
    let text = format!("{x:.6}");
    if text == "-0.000000" {
        "0.000000".to_string()
    } else {
        text
    }
}

/// A 32-bit integer hash (lowbias32 by Chris Wellons), for repeatable noise.
fn hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb_352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846c_a68b);
    x ^ (x >> 16)
}

/// Hash of a lattice point to [0, 1).
fn lattice(x: i32, y: i32, seed: u32) -> f64 {
    let h = hash((x as u32) ^ hash((y as u32) ^ hash(seed)));
    f64::from(h >> 8) / f64::from(1u32 << 24)
}

/// Smooth value noise in [0, 1).
fn value_noise(p: DVec2, seed: u32) -> f64 {
    let cell = p.floor();
    let f = p - cell;
    let (x, y) = (cell.x as i32, cell.y as i32);
    let s = f * f * (DVec2::splat(3.0) - 2.0 * f);
    let top = lerp(lattice(x, y, seed), lattice(x + 1, y, seed), s.x);
    let bottom = lerp(lattice(x, y + 1, seed), lattice(x + 1, y + 1, seed), s.x);
    lerp(top, bottom, s.y)
}

/// Fractal sum of value noise, roughly in [0, 1).
fn fbm(mut p: DVec2, octaves: u32, seed: u32) -> f64 {
    let (mut sum, mut amplitude, mut total) = (0.0, 0.5, 0.0);
    for octave in 0..octaves {
        sum += amplitude * value_noise(p, seed.wrapping_add(octave));
        total += amplitude;
        amplitude *= 0.5;
        // Rotate a little between octaves to hide the lattice.
        p = DVec2::new(1.6 * p.x - 1.2 * p.y, 1.2 * p.x + 1.6 * p.y);
    }
    sum / total
}

fn lerp(a: f64, b: f64, t: f64) -> f64 {
    a + (b - a) * t
}

fn smoothstep(edge0: f64, edge1: f64, x: f64) -> f64 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Linear [0, 1] colour to an 8-bit sRGB pixel.
fn srgb8(c: DVec3) -> Rgb<u8> {
    let encode = |x: f64| {
        let x = x.clamp(0.0, 1.0);
        let v = if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (v * 255.0).round() as u8
    };
    Rgb([encode(c.x), encode(c.y), encode(c.z)])
}

// ---------------------------------------------------------------------------
// Checker texture
// ---------------------------------------------------------------------------

/// 5x7 bitmap of the letter "F" (rows top to bottom, bit 4 = leftmost).
const GLYPH_F: [u8; 7] = [
    0b11111, 0b10000, 0b10000, 0b11110, 0b10000, 0b10000, 0b10000,
];

/// 256x256, row 0 at the top of the image. An 8x8 checker of cream and slate
/// blue cells (32 px), each cell laid with faint 16x8 px bricks and noise, a
/// 4 px dark frame, a red "F" near the top-left corner and a yellow glow in
/// the bottom-right corner: any flip, rotation or transposition of the
/// texture coordinates is visible.
fn checker_texture() -> RgbImage {
    const SIZE: u32 = 256;
    const CELL: u32 = 32;
    const BORDER: u32 = 4;
    const GLYPH_SCALE: u32 = 6;
    const GLYPH_AT: (u32, u32) = (12, 10);
    let cream = DVec3::new(0.78, 0.70, 0.52);
    let slate = DVec3::new(0.045, 0.095, 0.20);
    let red = DVec3::new(0.75, 0.03, 0.02);
    let yellow = DVec3::new(1.0, 0.68, 0.05);
    let frame = DVec3::new(0.012, 0.012, 0.015);

    RgbImage::from_fn(SIZE, SIZE, |x, y| {
        if x < BORDER || y < BORDER || x >= SIZE - BORDER || y >= SIZE - BORDER {
            return srgb8(frame);
        }
        let dark_cell = (x / CELL + y / CELL) % 2 == 1;
        let mut colour = if dark_cell { slate } else { cream };

        // Bricks: 8 px courses, 16 px bricks, every other course offset by 8.
        let course = y / 8;
        let bx = x + if course % 2 == 1 { 8 } else { 0 };
        if y % 8 == 7 || bx % 16 == 15 {
            colour *= 0.82;
        }
        let brick = hash(course * 977 + bx / 16);
        colour *= 0.94 + 0.08 * f64::from(brick & 0xff) / 255.0;
        let grain = value_noise(DVec2::new(f64::from(x), f64::from(y)) / 3.0, 7);
        colour *= 0.93 + 0.14 * grain;

        // Yellow glow in the bottom-right corner.
        let corner = DVec2::new(f64::from(SIZE - x), f64::from(SIZE - y)).length();
        colour = colour.lerp(
            yellow,
            (1.0 - corner / 72.0).clamp(0.0, 1.0).powf(1.5) * 0.85,
        );

        // The letter F.
        let (gx, gy) = (x.wrapping_sub(GLYPH_AT.0), y.wrapping_sub(GLYPH_AT.1));
        if gx < 5 * GLYPH_SCALE && gy < 7 * GLYPH_SCALE {
            let row = GLYPH_F[(gy / GLYPH_SCALE) as usize];
            if row & (0b10000 >> (gx / GLYPH_SCALE)) != 0 {
                colour = red;
            }
        }
        srgb8(colour)
    })
}

// ---------------------------------------------------------------------------
// Sky cube map
// ---------------------------------------------------------------------------

const SKY_FACE_SIZE: u32 = 128;

/// The cube-map faces, in the OpenGL order and convention.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CubeFace {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl CubeFace {
    const ALL: [CubeFace; 6] = [
        CubeFace::PosX,
        CubeFace::NegX,
        CubeFace::PosY,
        CubeFace::NegY,
        CubeFace::PosZ,
        CubeFace::NegZ,
    ];

    fn name(self) -> &'static str {
        match self {
            CubeFace::PosX => "posx",
            CubeFace::NegX => "negx",
            CubeFace::PosY => "posy",
            CubeFace::NegY => "negy",
            CubeFace::PosZ => "posz",
            CubeFace::NegZ => "negz",
        }
    }
}

/// Direction -> (face, u, v): the OpenGL cube-map lookup (GL spec, "Cube Map
/// Texture Selection"). The face is the axis of largest magnitude (ties go
/// X before Y before Z), then with `ma = |major component|`:
///
/// ```text
/// face  sc    tc    ma
/// posx  -z    -y    x
/// negx  +z    -y    x
/// posy  +x    +z    y
/// negy  +x    -z    y
/// posz  +x    -y    z
/// negz  -x    -y    z
/// u = (sc / ma + 1) / 2,  v = (tc / ma + 1) / 2
/// ```
///
/// `u` runs left to right across the PNG, `v` top to bottom (`v = 0` is the
/// first row of the file), so pixel `(column, row) = (u * 128, v * 128)`.
/// With this, every face image is upright for the side faces (+Y at the top
/// of posx/negx/posz/negz), the top of posy borders negz and the top of negy
/// borders posz.
fn face_uv(d: DVec3) -> (CubeFace, f64, f64) {
    let a = d.abs();
    let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            (CubeFace::PosX, -d.z, -d.y, a.x)
        } else {
            (CubeFace::NegX, d.z, -d.y, a.x)
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            (CubeFace::PosY, d.x, d.z, a.y)
        } else {
            (CubeFace::NegY, d.x, -d.z, a.y)
        }
    } else if d.z >= 0.0 {
        (CubeFace::PosZ, d.x, -d.y, a.z)
    } else {
        (CubeFace::NegZ, -d.x, -d.y, a.z)
    };
    (face, 0.5 * (sc / ma + 1.0), 0.5 * (tc / ma + 1.0))
}

/// The inverse of [`face_uv`]: the (unnormalised) direction through `(u, v)`
/// of `face`.
fn face_direction(face: CubeFace, u: f64, v: f64) -> DVec3 {
    let (sc, tc) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    match face {
        CubeFace::PosX => DVec3::new(1.0, -tc, -sc),
        CubeFace::NegX => DVec3::new(-1.0, -tc, sc),
        CubeFace::PosY => DVec3::new(sc, 1.0, tc),
        CubeFace::NegY => DVec3::new(sc, -1.0, -tc),
        CubeFace::PosZ => DVec3::new(sc, -tc, 1.0),
        CubeFace::NegZ => DVec3::new(-sc, -tc, -1.0),
    }
}

/// Unit vector toward the sun: elevation 35 degrees, azimuth 30 degrees from
/// +X toward -Z, i.e. about (0.7094, 0.5736, -0.4096). It lies in the posx face.
fn sun_direction() -> DVec3 {
    let (elevation, azimuth) = (35.0f64.to_radians(), 30.0f64.to_radians());
    DVec3::new(
        elevation.cos() * azimuth.cos(),
        elevation.sin(),
        -elevation.cos() * azimuth.sin(),
    )
}

/// Linear radiance-ish colour (clamped to [0, 1] later) of the sky in the
/// unit direction `d`.
fn sky_colour(d: DVec3) -> DVec3 {
    let horizon = DVec3::new(0.60, 0.74, 0.90);
    let zenith = DVec3::new(0.07, 0.22, 0.62);
    let haze = DVec3::new(0.46, 0.46, 0.45);
    let ground_near = DVec3::new(0.26, 0.21, 0.15);
    let ground_far = DVec3::new(0.10, 0.08, 0.06);
    let sun = sun_direction();
    let cos_sun = d.dot(sun).clamp(-1.0, 1.0);
    let angle = cos_sun.acos();

    // Sky above, ground below, blended over a narrow band at the horizon.
    let up = d.y.max(0.0);
    let mut sky = horizon.lerp(zenith, up.powf(0.5));
    // Warm glow around the sun (broad + tight), a little stronger low down.
    let glow = 0.55 * (-angle / 0.06).exp() + 0.22 * (-angle / 0.45).exp();
    sky += DVec3::new(1.0, 0.72, 0.42) * glow;

    // Cheap clouds: fractal noise on a plane above the viewer, thinning
    // toward the horizon (where the projection would stretch them).
    if d.y > 0.0 {
        let p = DVec2::new(d.x, d.z) / (d.y + 0.08) * 1.1;
        let density = fbm(p + DVec2::new(3.7, -1.3), 5, 11);
        let cover = smoothstep(0.52, 0.72, density) * smoothstep(0.02, 0.22, d.y);
        let lit = 0.80 + 0.20 * (0.5 + 0.5 * cos_sun);
        let shade = smoothstep(0.55, 0.85, density);
        let cloud = DVec3::new(1.0, 0.97, 0.93) * lit * (1.0 - 0.25 * shade)
            + DVec3::new(1.0, 0.8, 0.55) * (0.6 * (-angle / 0.25).exp());
        sky = sky.lerp(cloud, cover * 0.9);
    }

    // Sun disc: 1.5 degrees radius with a soft 0.3 degree edge.
    let radius = 1.5f64.to_radians();
    let edge = 0.3f64.to_radians();
    let disc = 1.0 - smoothstep(radius - edge, radius, angle);
    sky = sky.lerp(DVec3::new(1.0, 0.96, 0.86) * 1.5, disc);

    let down = (-d.y).max(0.0);
    let ground = haze
        .lerp(ground_near, smoothstep(0.0, 0.06, down))
        .lerp(ground_far, smoothstep(0.05, 1.0, down).powf(0.7));
    // Slight texture on the ground so that it does not look like a void.
    let ground = if d.y < 0.0 {
        let p = DVec2::new(d.x, d.z) / (-d.y + 0.05) * 3.0;
        ground * (0.88 + 0.24 * fbm(p, 4, 23))
    } else {
        ground
    };
    ground.lerp(sky, smoothstep(-0.012, 0.012, d.y))
}

fn sky_face(face: CubeFace, size: u32) -> RgbImage {
    RgbImage::from_fn(size, size, |column, row| {
        let u = (f64::from(column) + 0.5) / f64::from(size);
        let v = (f64::from(row) + 0.5) / f64::from(size);
        let d = face_direction(face, u, v).normalize();
        // The lookup documented in `face_uv` must land back on this texel.
        let (f, u2, v2) = face_uv(d);
        assert!(f == face && (u2 - u).abs() < 1e-9 && (v2 - v).abs() < 1e-9);
        srgb8(sky_colour(d))
    })
}

// ---------------------------------------------------------------------------
// Meshes
// ---------------------------------------------------------------------------

/// One triangle corner: 0-based indices into positions, uvs and normals.
#[derive(Clone, Copy)]
struct Corner {
    position: usize,
    uv: usize,
    normal: usize,
}

/// A mesh with separate position / uv / normal index streams, as in OBJ.
struct Mesh {
    positions: Vec<DVec3>,
    uvs: Vec<DVec2>,
    normals: Vec<DVec3>,
    triangles: Vec<[Corner; 3]>,
}

impl Mesh {
    /// Radius-1 UV sphere around the origin: `slices` around the Y axis,
    /// `stacks` from pole to pole. One position per pole and one per ring
    /// point (the u = 0 / u = 1 seam reuses the same position index), so the
    /// surface is closed; only the texture coordinates are split at the seam
    /// and at the poles.
    ///
    /// u = 0 (and 1) is the meridian through -Z, u = 0.5 faces +Z, u grows
    /// toward +X as seen from +Z; v = 0 at the south pole (-Y), 1 at the north
    /// pole (+Y). Vertex normals equal positions.
    fn uv_sphere(slices: usize, stacks: usize) -> Mesh {
        let point = |ring: usize, slice: usize| {
            let theta = PI * ring as f64 / stacks as f64;
            let phi = 2.0 * PI * slice as f64 / slices as f64;
            DVec3::new(
                -theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            )
        };
        let mut positions = vec![DVec3::Y];
        for ring in 1..stacks {
            for slice in 0..slices {
                positions.push(point(ring, slice));
            }
        }
        positions.push(DVec3::NEG_Y);
        let south = positions.len() - 1;
        let ring_position = |ring: usize, slice: usize| 1 + (ring - 1) * slices + slice % slices;

        let mut uvs = Vec::new();
        for ring in 1..stacks {
            for slice in 0..=slices {
                uvs.push(DVec2::new(
                    slice as f64 / slices as f64,
                    1.0 - ring as f64 / stacks as f64,
                ));
            }
        }
        let ring_uv = |ring: usize, slice: usize| (ring - 1) * (slices + 1) + slice;
        let north_uv = uvs.len();
        uvs.extend((0..slices).map(|s| DVec2::new((s as f64 + 0.5) / slices as f64, 1.0)));
        let south_uv = uvs.len();
        uvs.extend((0..slices).map(|s| DVec2::new((s as f64 + 0.5) / slices as f64, 0.0)));

        let on_ring = |ring: usize, slice: usize| Corner {
            position: ring_position(ring, slice),
            uv: ring_uv(ring, slice),
            normal: ring_position(ring, slice),
        };
        let mut triangles = Vec::new();
        for slice in 0..slices {
            let north = Corner {
                position: 0,
                uv: north_uv + slice,
                normal: 0,
            };
            triangles.push([on_ring(1, slice), on_ring(1, slice + 1), north]);
            for ring in 1..stacks - 1 {
                let (upper_left, upper_right) = (on_ring(ring, slice), on_ring(ring, slice + 1));
                let (lower_left, lower_right) =
                    (on_ring(ring + 1, slice), on_ring(ring + 1, slice + 1));
                triangles.push([lower_left, lower_right, upper_right]);
                triangles.push([lower_left, upper_right, upper_left]);
            }
            let south_pole = Corner {
                position: south,
                uv: south_uv + slice,
                normal: south,
            };
            triangles.push([
                south_pole,
                on_ring(stacks - 1, slice + 1),
                on_ring(stacks - 1, slice),
            ]);
        }
        let normals = positions.clone();
        let mesh = Mesh {
            positions,
            uvs,
            normals,
            triangles,
        };
        mesh.check_outward(DVec3::ZERO);
        mesh.check_closed();
        mesh
    }

    /// The 2x2 quad [-1, 1] x {0} x [-1, 1], normal +Y; u along +X, v along -Z
    /// (so the texture reads upright seen from above with -Z up the screen).
    fn plane() -> Mesh {
        let positions = vec![
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, -1.0),
            DVec3::new(-1.0, 0.0, -1.0),
        ];
        let uvs = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let corner = |i: usize| Corner {
            position: i,
            uv: i,
            normal: 0,
        };
        let mesh = Mesh {
            positions,
            uvs,
            normals: vec![DVec3::Y],
            triangles: vec![
                [corner(0), corner(1), corner(2)],
                [corner(0), corner(2), corner(3)],
            ],
        };
        mesh.check_outward(DVec3::new(0.0, -1.0, 0.0));
        mesh
    }

    /// The cube [-1, 1]^3: 8 positions, 6 face normals, the 4 corners of the
    /// unit uv square; 12 triangles. Each face shows the whole texture once,
    /// upright and unmirrored seen from outside (sides: +Y up; top: -Z up;
    /// bottom: +Z up).
    fn cube() -> Mesh {
        // (normal, u direction, v direction) with u x v = normal.
        let faces = [
            (DVec3::X, DVec3::NEG_Z, DVec3::Y),
            (DVec3::NEG_X, DVec3::Z, DVec3::Y),
            (DVec3::Y, DVec3::X, DVec3::NEG_Z),
            (DVec3::NEG_Y, DVec3::X, DVec3::Z),
            (DVec3::Z, DVec3::X, DVec3::Y),
            (DVec3::NEG_Z, DVec3::NEG_X, DVec3::Y),
        ];
        let positions: Vec<DVec3> = (0..8)
            .map(|i| {
                let sign = |bit: i32| if i & bit != 0 { 1.0 } else { -1.0 };
                DVec3::new(sign(1), sign(2), sign(4))
            })
            .collect();
        let index_of = |p: DVec3| {
            usize::from(p.x > 0.0) | usize::from(p.y > 0.0) << 1 | usize::from(p.z > 0.0) << 2
        };
        let uvs = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let mut triangles = Vec::new();
        for (face, &(n, u, v)) in faces.iter().enumerate() {
            assert_eq!(u.cross(v), n);
            let corners: Vec<Corner> = [-u - v, u - v, u + v, -u + v]
                .iter()
                .enumerate()
                .map(|(k, &offset)| Corner {
                    position: index_of(n + offset),
                    uv: k,
                    normal: face,
                })
                .collect();
            triangles.push([corners[0], corners[1], corners[2]]);
            triangles.push([corners[0], corners[2], corners[3]]);
        }
        let mesh = Mesh {
            positions,
            uvs,
            normals: faces.iter().map(|f| f.0).collect(),
            triangles,
        };
        mesh.check_outward(DVec3::ZERO);
        mesh.check_closed();
        mesh
    }

    /// Asserts every triangle is counter-clockwise seen from outside: its
    /// geometric normal agrees with its vertex normals and points away from
    /// `inside`.
    fn check_outward(&self, inside: DVec3) {
        for t in &self.triangles {
            let [a, b, c] = t.map(|k| self.positions[k.position]);
            let n = (b - a).cross(c - a);
            assert!(n.length() > 1e-9, "degenerate triangle");
            assert!(n.dot((a + b + c) / 3.0 - inside) > 0.0, "inward triangle");
            for k in t {
                assert!(n.dot(self.normals[k.normal]) > 0.0, "normal disagrees");
            }
        }
    }

    /// Asserts every edge is shared by exactly two triangles in opposite
    /// directions (closed, consistently wound, no cracks).
    fn check_closed(&self) {
        let mut edges = std::collections::HashMap::<(usize, usize), i32>::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k].position, t[(k + 1) % 3].position);
                *edges.entry((a, b)).or_default() += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            assert_eq!(count, 1, "edge {a}-{b} used twice in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "open edge {a}-{b}");
        }
    }

    fn to_obj(&self, title: &str, material: Option<(&str, &str)>) -> String {
        let mut out = String::new();
        let _ = writeln!(out, "# rayterm: {title}");
        let _ = writeln!(
            out,
            "# {} vertices, {} triangles; generated by `cargo run --release --example gen_assets`",
            self.positions.len(),
            self.triangles.len()
        );
        if let Some((library, _)) = material {
            let _ = writeln!(out, "mtllib {library}");
        }
        for p in &self.positions {
            let _ = writeln!(out, "v {} {} {}", num(p.x), num(p.y), num(p.z));
        }
        for uv in &self.uvs {
            let _ = writeln!(out, "vt {} {}", num(uv.x), num(uv.y));
        }
        for n in &self.normals {
            let _ = writeln!(out, "vn {} {} {}", num(n.x), num(n.y), num(n.z));
        }
        if let Some((_, name)) = material {
            let _ = writeln!(out, "usemtl {name}");
        }
        for t in &self.triangles {
            let corner = |c: &Corner| format!("{}/{}/{}", c.position + 1, c.uv + 1, c.normal + 1);
            let _ = writeln!(
                out,
                "f {} {} {}",
                corner(&t[0]),
                corner(&t[1]),
                corner(&t[2])
            );
        }
        out
    }
}

// ---------------------------------------------------------------------------
// Cornell box
// ---------------------------------------------------------------------------

/// The Cornell box, 32 triangles, in the box (-1, 0, -1)..(1, 2, 1) open
/// toward +Z. Classic Cornell measurements (mm) map as
/// `x = (278 - x_c) / 278`, `y = y_c / 274.4`, `z = 1 - z_c / 279.6`; the two
/// blocks are rebuilt as exact rotated boxes of the classic size and place.
fn cornell_box() -> String {
    struct Object {
        name: &'static str,
        material: &'static str,
        triangles: Vec<[DVec3; 3]>,
    }
    /// Two triangles for the planar convex quad `corners` (in order around
    /// its perimeter), wound counter-clockwise around `facing`.
    fn quad(corners: [DVec3; 4], facing: DVec3) -> Vec<[DVec3; 3]> {
        let [a, b, c, d] = corners;
        if (b - a).cross(c - a).dot(facing) > 0.0 {
            vec![[a, b, c], [a, c, d]]
        } else {
            vec![[a, c, b], [a, d, c]]
        }
    }
    /// An axis-aligned box rotated by `degrees` about +Y around its centre
    /// (x, z) standing on y = 0: top and four sides, normals outward.
    fn block(centre: (f64, f64), half: f64, height: f64, degrees: f64) -> Vec<[DVec3; 3]> {
        let (sin, cos) = degrees.to_radians().sin_cos();
        let at = |x: f64, y: f64, z: f64| {
            DVec3::new(
                centre.0 + x * cos + z * sin,
                y,
                centre.1 - x * sin + z * cos,
            )
        };
        let middle = DVec3::new(centre.0, height * 0.5, centre.1);
        let h = half;
        let corners = [(-h, -h), (h, -h), (h, h), (-h, h)];
        let mut triangles = quad(corners.map(|(x, z)| at(x, height, z)), DVec3::Y);
        for k in 0..4 {
            let (x0, z0) = corners[k];
            let (x1, z1) = corners[(k + 1) % 4];
            let side = [
                at(x0, 0.0, z0),
                at(x1, 0.0, z1),
                at(x1, height, z1),
                at(x0, height, z0),
            ];
            let outward = (side[0] + side[2]) * 0.5 - middle;
            triangles.extend(quad(side, DVec3::new(outward.x, 0.0, outward.z)));
        }
        triangles
    }
    let p = DVec3::new;
    let (lx, lz, ly) = (0.234, 0.188, 1.995);
    let objects = [
        Object {
            name: "floor",
            material: "white",
            triangles: quad(
                [
                    p(-1.0, 0.0, -1.0),
                    p(1.0, 0.0, -1.0),
                    p(1.0, 0.0, 1.0),
                    p(-1.0, 0.0, 1.0),
                ],
                DVec3::Y,
            ),
        },
        Object {
            name: "ceiling",
            material: "white",
            triangles: quad(
                [
                    p(-1.0, 2.0, -1.0),
                    p(1.0, 2.0, -1.0),
                    p(1.0, 2.0, 1.0),
                    p(-1.0, 2.0, 1.0),
                ],
                DVec3::NEG_Y,
            ),
        },
        Object {
            name: "back",
            material: "white",
            triangles: quad(
                [
                    p(-1.0, 0.0, -1.0),
                    p(1.0, 0.0, -1.0),
                    p(1.0, 2.0, -1.0),
                    p(-1.0, 2.0, -1.0),
                ],
                DVec3::Z,
            ),
        },
        Object {
            name: "left",
            material: "red",
            triangles: quad(
                [
                    p(-1.0, 0.0, -1.0),
                    p(-1.0, 0.0, 1.0),
                    p(-1.0, 2.0, 1.0),
                    p(-1.0, 2.0, -1.0),
                ],
                DVec3::X,
            ),
        },
        Object {
            name: "right",
            material: "green",
            triangles: quad(
                [
                    p(1.0, 0.0, -1.0),
                    p(1.0, 0.0, 1.0),
                    p(1.0, 2.0, 1.0),
                    p(1.0, 2.0, -1.0),
                ],
                DVec3::NEG_X,
            ),
        },
        Object {
            name: "short_box",
            material: "white",
            triangles: block((0.33, 0.40), 0.3, 0.6, -17.0),
        },
        Object {
            name: "tall_box",
            material: "mirror",
            triangles: block((-0.33, -0.26), 0.3, 1.2, 45.0),
        },
        Object {
            name: "light_panel",
            material: "light",
            triangles: quad(
                [
                    p(-lx, ly, -lz),
                    p(lx, ly, -lz),
                    p(lx, ly, lz),
                    p(-lx, ly, lz),
                ],
                DVec3::NEG_Y,
            ),
        },
    ];
    let count: usize = objects.iter().map(|o| o.triangles.len()).sum();
    assert_eq!(count, 32);

    let mut out = String::new();
    let _ = writeln!(out, "# rayterm: the Cornell box, {count} triangles.");
    let _ = writeln!(
        out,
        "# Box (-1, 0, -1)..(1, 2, 1), open toward +Z (camera at about (0, 1, 3.4) looking at\n\
         # (0, 1, 0)); red wall at x = -1, green at x = +1, light panel at y = {ly}.\n\
         # Walls wind counter-clockwise seen from inside, the blocks from outside.\n\
         # Generated by `cargo run --release --example gen_assets`."
    );
    let _ = writeln!(out, "mtllib cornell.mtl");
    let mut base = 0;
    for object in &objects {
        let _ = writeln!(out, "\no {}\nusemtl {}", object.name, object.material);
        // Each object lists its own corners once (quads share their diagonal).
        let mut corners: Vec<DVec3> = Vec::new();
        let mut faces = Vec::new();
        for t in &object.triangles {
            faces.push(t.map(|v| match corners.iter().position(|&c| c == v) {
                Some(i) => i,
                None => {
                    corners.push(v);
                    corners.len() - 1
                }
            }));
        }
        for v in &corners {
            let _ = writeln!(out, "v {} {} {}", num(v.x), num(v.y), num(v.z));
        }
        for f in &faces {
            let _ = writeln!(
                out,
                "f {} {} {}",
                base + f[0] + 1,
                base + f[1] + 1,
                base + f[2] + 1
            );
        }
        base += corners.len();
    }
    out
}

// ---------------------------------------------------------------------------
// Materials
// ---------------------------------------------------------------------------

const CUBE_MTL: &str = "\
# rayterm: material of cube.obj (texture path relative to this file)
newmtl checker
Kd 1.000000 1.000000 1.000000
Ks 0.000000 0.000000 0.000000
Ns 10.000000
d 1.000000
illum 1
map_Kd checker.png
";

const CORNELL_MTL: &str = "\
# rayterm: materials of cornell.obj
newmtl white
Kd 0.730000 0.730000 0.730000
Ks 0.000000 0.000000 0.000000
Ns 1.000000
d 1.000000
illum 1

newmtl red
Kd 0.630000 0.065000 0.050000
Ks 0.000000 0.000000 0.000000
Ns 1.000000
d 1.000000
illum 1

newmtl green
Kd 0.140000 0.450000 0.091000
Ks 0.000000 0.000000 0.000000
Ns 1.000000
d 1.000000
illum 1

# the tall box: a mirror
newmtl mirror
Kd 0.050000 0.050000 0.050000
Ks 0.900000 0.900000 0.900000
Ns 10000.000000
d 1.000000
illum 3

# the light panel: bright white, no emission
newmtl light
Kd 1.000000 1.000000 1.000000
Ks 0.000000 0.000000 0.000000
Ns 1.000000
d 1.000000
illum 1
";

const MIRRORS_MTL: &str = "\
# rayterm: materials of the mirrors scene
newmtl mirror
Kd 0.020000 0.020000 0.020000
Ks 0.950000 0.950000 0.950000
Ns 100000.000000
d 1.000000
illum 3

newmtl red_glossy
Kd 0.500000 0.050000 0.050000
Ks 0.400000 0.400000 0.400000
Ns 200.000000
d 1.000000
illum 2

newmtl blue
Kd 0.100000 0.150000 0.600000
Ks 0.500000 0.500000 0.500000
Ns 100000.000000
d 1.000000
illum 3

newmtl gold
Kd 0.300000 0.220000 0.050000
Ks 0.700000 0.550000 0.200000
Ns 100000.000000
d 1.000000
illum 3

newmtl floor_mirror
Kd 0.150000 0.150000 0.170000
Ks 0.800000 0.800000 0.800000
Ns 100000.000000
d 1.000000
illum 3
";
