//! Property tests of intersection: random triangles and rays, near-degenerate
//! ones included (needles, slivers, tiny and huge triangles, rays through
//! vertices and edges, direction components of 0, -0 and below 1e-30), never
//! give a NaN or out-of-range hit, spawned rays never re-hit their triangle,
//! and the BVH agrees with brute force on every ray with both builders.
//!
//! And of the loaders: a byte-order mark, CRLF or CR-only line endings and
//! line continuations change nothing; a w component (a curve weight) is
//! ignored; a vertex beyond f32 (huge exponents) leaves out the faces
//! that use it, with a warning at its line, and one within f32 loads; a mesh far from the origin loads as
//! it does near it; TOML arrays of the wrong length are errors at their
//! position.

use crate::campaign;

use glam::Vec3;
use proptest::prelude::*;
use rayterm::bvh::{self, Simd};
use rayterm::geometry::offset::{geometric_normal, hit_point, offset_origin};
use rayterm::geometry::triangle::{intersect, RayShear};
use rayterm::geometry::Ray;
use rayterm::report::stability::grazing;
use rayterm::scene::load::obj::{self, Parts, Placement};
use rayterm::scene::load::source::Memory;
use rayterm::scene::load::{self, Opening};
use rayterm::scene::{Builder, Geometry};

fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -10.0f32..10.0,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(1.0f32),
        1 => -1e6f32..1e6,
        1 => -1e-6f32..1e-6,
    ]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// Magnitudes at which a direction component stops mattering, and zeros.
fn tiny() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(1e-30f32),
        Just(-1e-30f32),
        Just(1e-38f32),
        Just(-1e-45f32),
        Just(1e-7f32),
        -1e-3f32..1e-3,
    ]
}

/// Ordinary, needle, sliver, tiny and huge triangles.
fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    prop_oneof![
        3 => (point(), point(), point()).prop_map(|(a, b, c)| [a, b, c]),
        // A needle: the third corner a hair off the segment between the others.
        1 => (point(), point(), 0.0f32..1.0, point(), tiny())
            .prop_map(|(a, b, t, d, e)| [a, b, a.lerp(b, t) + d.normalize_or_zero() * e]),
        // A sliver: two corners a hair apart.
        1 => (point(), point(), point(), tiny())
            .prop_map(|(a, b, d, e)| [a, b, a + d.normalize_or_zero() * e]),
        // Tiny, somewhere.
        1 => (point(), point(), point(), 1e-30f32..1e-3)
            .prop_map(|(c, d, e, s)| [c, c + d * s, c + e * s]),
        // Huge (the loaders warn from 1e18).
        1 => (point(), point(), point(), 1.0f32..1e11)
            .prop_map(|(a, b, c, s)| [a * s, b * s, c * s]),
    ]
}

/// A ray from `origin`: aimed at a point of the triangle (vertices and
/// edges included) or in a direction with grazing components.
fn ray_for(tri: [Vec3; 3]) -> impl Strategy<Value = Ray> {
    let weights = prop_oneof![
        Just([1.0f32, 0.0, 0.0]),
        Just([0.0, 1.0, 0.0]),
        Just([0.5, 0.5, 0.0]),
        (0.0f32..1.0).prop_map(|t| [t, 1.0 - t, 0.0]),
        (0.0f32..1.0, 0.0f32..1.0).prop_map(|(a, b)| [a * (1.0 - b), (1.0 - a) * (1.0 - b), b]),
    ];
    let grazing = (tiny(), tiny(), coord(), 0usize..3).prop_map(|(a, b, c, k)| {
        let mut d = [a, b, a];
        d[k] = if c == 0.0 { 1.0 } else { c };
        d[(k + 1) % 3] = b;
        Vec3::from_array(d)
    });
    (point(), weights, grazing, any::<bool>()).prop_map(move |(o, w, g, aim)| {
        let target = tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2];
        let dir = if aim { target - o } else { g };
        Ray::new(o, dir)
    })
}

fn tri_and_ray() -> impl Strategy<Value = ([Vec3; 3], Ray)> {
    triangle().prop_flat_map(|t| (Just(t), ray_for(t)))
}

/// The SIMD levels this CPU runs, saying once which it lacks: their
/// kernels go untested here.
fn simd_levels() -> Vec<Simd> {
    static SAID: std::sync::Once = std::sync::Once::new();
    let levels = Simd::available();
    SAID.call_once(|| {
        if !levels.contains(&Simd::Avx512) {
            eprintln!("note: this CPU has no AVX-512: its kernels are not tested here");
        }
    });
    levels
}

/// Spawned rays closer than this (as a cosine) to their surface's plane are
/// not checked for re-hits.
const GRAZING: f32 = 1e-5;

proptest! {
    #![proptest_config(campaign::config(256))]

    #[test]
    fn hits_are_finite_and_inside_the_triangle(
        (tri, ray) in tri_and_ray(),
        tmax in prop_oneof![Just(f32::INFINITY), 0.0f32..1e3],
        w in point(),
    ) {
        let t = tri.map(|p| p.to_array());
        let s = RayShear::new(ray.origin, ray.dir);
        if let Some(h) = intersect(&s, &t[0], &t[1], &t[2], tmax) {
            prop_assert!(h.t.is_finite() && h.t > 0.0 && h.t <= tmax, "t = {}", h.t);
            prop_assert!((0.0..=1.0).contains(&h.u) && (0.0..=1.0).contains(&h.v), "{h:?}");
            // The third weight is 1 - u - v: at worst a few roundings below 0.
            prop_assert!(1.0 - h.u - h.v >= -4.0 * f32::EPSILON, "{h:?}");
            let (p, err) = hit_point(tri, h.u, h.v);
            prop_assert!(p.is_finite() && err.is_finite());
            // A ray spawned from the hit never hits it again: along the
            // normal either way, on through the surface and back the way it
            // came. Directions within GRAZING of the plane are left out: the
            // plane crossing of such a ray is below f32 resolution.
            let ng = geometric_normal(tri);
            if ng != Vec3::ZERO {
                let through = ray.dir.normalize_or_zero();
                let ws = [through, -through, ng, -ng, w.normalize_or_zero()];
                for w in ws.into_iter().filter(|w| w.dot(ng).abs() >= GRAZING) {
                    let o = offset_origin(p, err, ng, w);
                    prop_assert!(o.is_finite());
                    let again = intersect(&RayShear::new(o, w), &t[0], &t[1], &t[2], f32::INFINITY);
                    prop_assert!(again.is_none(), "re-hit {again:?} from {o} along {w}");
                }
            }
        }
    }

    #[test]
    fn bvh_agrees_with_brute_force(
        tris in prop::collection::vec(triangle(), 1..48),
        seeds in prop::collection::vec((0usize..48, any::<prop::sample::Index>()), 24),
        free in prop::collection::vec((point(), point()), 8),
    ) {
        // Rays aimed at the soup's own corners, edges and faces, and free ones.
        let mut rays: Vec<Ray> = seeds
            .iter()
            .map(|(i, w)| {
                let t = tris[i % tris.len()];
                let o = t[(i + 1) % 3] * 2.0 - t[i % 3] + Vec3::new(0.3, -0.2, 0.1);
                let target = match w.index(4) {
                    0 => t[0],
                    1 => t[1].lerp(t[2], 0.5),
                    2 => (t[0] + t[1] + t[2]) / 3.0,
                    _ => t[2],
                };
                Ray::new(o, target - o)
            })
            .collect();
        rays.extend(free.iter().map(|(o, d)| Ray::new(*o, *d)));
        let g = Geometry::from_triangles(&tris);
        for builder in [Builder::Sah, Builder::Median] {
            let b = bvh::build(&g, builder);
            let anc = grazing::ancestors(&b);
            for ray in &rays {
                let r = grazing::check_rays(&b, &anc, std::slice::from_ref(ray));
                prop_assert_eq!(
                    (r.nan, r.disagree, r.box_misses),
                    (0, 0, 0),
                    "{:?} {} {:?}: bvh {:?} brute {:?}",
                    r,
                    builder,
                    ray,
                    b.intersect::<false>(ray, &mut Default::default()),
                    b.intersect_brute(ray)
                );
            }
        }
    }

    #[test]
    fn packets_agree_with_single_rays(
        tris in prop::collection::vec(triangle(), 1..24),
        at in any::<prop::sample::Index>(),
        o in point(),
        spread in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 64),
        tmax in prop_oneof![Just(f32::INFINITY), 0.0f32..1e3],
    ) {
        // A packet from one origin aimed across one triangle of the soup:
        // its vertices, edges and inside, as a tile's rays cross a wall.
        let t = tris[at.index(tris.len())];
        let rays: Vec<Ray> = spread
            .iter()
            .enumerate()
            .map(|(k, &(a, b))| {
                let w = match k % 8 {
                    0 => [1.0, 0.0, 0.0],
                    1 => [0.0, 1.0, 0.0],
                    2 => [0.0, 0.0, 1.0],
                    3 => [a, 1.0 - a, 0.0],
                    _ => [a * (1.0 - b), (1.0 - a) * (1.0 - b), b],
                };
                let target = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
                Ray::segment(o, target - o, if k % 3 == 0 { tmax } else { f32::INFINITY })
            })
            .collect();
        let g = Geometry::from_triangles(&tris);
        for builder in [Builder::Sah, Builder::Median] {
            let mut b = bvh::build(&g, builder);
            // Every SIMD level this CPU has, widest first (each cap narrows).
            for simd in simd_levels().into_iter().rev() {
                b.cap_simd(simd);
                prop_assert_eq!(b.simd(), simd);
                let mut hits = vec![None; rays.len()];
                let mut blocked = vec![false; rays.len()];
                b.intersect_packet(&rays, &mut hits);
                b.occluded_packet(&rays, &mut blocked);
                for (i, ray) in rays.iter().enumerate() {
                    let mut st = Default::default();
                    let want = b.intersect::<false>(ray, &mut st);
                    prop_assert_eq!(hits[i], want, "ray {} {:?} {} {}", i, ray, builder, simd);
                    let any = b.occluded::<false>(ray, &mut st).is_some();
                    prop_assert_eq!(blocked[i], any, "ray {} {:?} {} {}", i, ray, builder, simd);
                }
            }
        }
    }

    #[test]
    fn grazing_rays_agree_on_the_lattice(
        d in (tiny(), tiny(), prop_oneof![Just(1.0f32), Just(-1.0f32), -1.0f32..1.0], 0usize..3),
        o in (0u8..4, 0u8..4, 0u8..4),
    ) {
        // Along the lattice's integer planes and edges, with zeros and tiny
        // components in the direction.
        let (a, b, c, k) = d;
        let mut dir = [a, b, a];
        dir[k] = if c == 0.0 { 1.0 } else { c };
        dir[(k + 1) % 3] = b;
        let dir = Vec3::from_array(dir);
        let mut origin = Vec3::new(o.0 as f32, o.1 as f32, o.2 as f32);
        origin[k] = if dir[k] > 0.0 { -1.0 } else { 4.0 };
        let g = Geometry::from_triangles(&grazing::lattice());
        for builder in [Builder::Sah, Builder::Median] {
            let b = bvh::build(&g, builder);
            let r = grazing::check_rays(&b, &grazing::ancestors(&b), &[Ray::new(origin, dir)]);
            prop_assert_eq!((r.nan, r.disagree, r.box_misses), (0, 0, 0), "{:?} {}", r, builder);
        }
    }
}

/// Loads `text` as the OBJ `m.obj`: its positions and triangles, or the error.
fn load_obj(text: impl Into<Vec<u8>>) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), String> {
    let src = Memory::default().with("m.obj", text);
    let mut parts = Parts::default();
    obj::load_into(
        &mut parts,
        &src,
        std::path::Path::new("m.obj"),
        &Placement::default(),
        None,
    )
    .map_err(|e| format!("{e:#}"))?;
    Ok((
        parts.geometry.positions().to_vec(),
        parts.geometry.indices().to_vec(),
    ))
}

/// Opens the scene file `s.toml` of `src`.
fn open_toml(src: &Memory) -> anyhow::Result<rayterm::scene::Scene> {
    let how = Opening {
        source: Some(src),
        ..Default::default()
    };
    load::open("s.toml", &how).map(|o| o.scene)
}

/// A small mesh as OBJ text: vertices written with `write`, then faces
/// (triangles and quads, some with relative indices).
fn obj_text(points: &[Vec3], write: impl Fn(usize, Vec3) -> String) -> String {
    let mut s = String::new();
    for (i, p) in points.iter().enumerate() {
        s += &write(i, *p);
        s.push('\n');
    }
    let n = points.len();
    for i in 0..n - 2 {
        if i % 3 == 2 && i + 3 < n {
            s += &format!("f {} {} {} {}\n", i + 1, i + 2, i + 3, i + 4);
        } else {
            s += &format!("f {} -{} {}\n", i + 1, n - i - 1, i + 3);
        }
    }
    s
}

fn points() -> impl Strategy<Value = Vec<Vec3>> {
    prop::collection::vec(point(), 3..12)
}

/// Points of a mesh about 20 across, on a grid of eighths: exact in f32
/// and f64, also once moved by a multiple of an eighth.
fn grid_points() -> impl Strategy<Value = Vec<Vec3>> {
    prop::collection::vec(
        (-80i32..=80, -80i32..=80, -80i32..=80)
            .prop_map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32) / 8.0),
        3..12,
    )
}

fn plain(_: usize, p: Vec3) -> String {
    format!("v {} {} {}", p.x, p.y, p.z)
}

proptest! {
    #![proptest_config(campaign::config(128))]

    #[test]
    fn boms_line_endings_and_continuations_change_nothing(
        pts in points(),
        bom in any::<bool>(),
        ending in prop::sample::select(vec!["\n", "\r\n", "\r"]),
        continued in any::<bool>(),
    ) {
        let written = obj_text(&pts, plain);
        let expected = load_obj(written.clone());
        let mut text = written.replace('\n', ending);
        if continued {
            text = text.replacen("f ", "f \\\n", 1).replace("\\\n", &format!("\\{ending}"));
        }
        if bom {
            text.insert(0, '\u{feff}');
        }
        prop_assert_eq!(load_obj(text), expected);
    }

    #[test]
    fn w_components_are_ignored(pts in points(), k in -20i32..20) {
        // A curve weight: polygons keep x, y and z as written.
        let w = 2f64.powi(k);
        let unweighted = load_obj(obj_text(&pts, plain));
        let weighted = obj_text(&pts, |_, p| format!("v {} {} {} {w}", p.x, p.y, p.z));
        prop_assert_eq!(load_obj(weighted), unweighted);
    }

    #[test]
    fn vertices_beyond_f32_leave_out_the_faces_using_them(
        pts in points(),
        which in any::<prop::sample::Index>(),
        mantissa in 1.0f64..9.99,
        exponent in prop_oneof![39i32..=45, 300i32..=400, Just(99999)],
    ) {
        let bad = which.index(pts.len());
        let text = obj_text(&pts, |i, p| match i == bad {
            false => plain(i, p),
            true => format!("v {} {mantissa}e{exponent} {}", p.x, p.z),
        });
        // As the file without the faces that use the vertex.
        let n = pts.len() as i64;
        let uses_bad = |face: &str| {
            face.split_whitespace().skip(1).any(|w| {
                let k: i64 = w.parse().unwrap();
                (if k > 0 { k - 1 } else { n + k }) == bad as i64
            })
        };
        let without: String = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !(l.starts_with("f ") && uses_bad(l)))
            .map(|(i, l)| if i == bad { "v 0 0 0\n".to_string() } else { format!("{l}\n") })
            .collect();
        prop_assert_eq!(load_obj(text.clone()), load_obj(without));
        let mut parts = Parts::default();
        let src = Memory::default().with("m.obj", text);
        obj::load_into(&mut parts, &src, std::path::Path::new("m.obj"), &Placement::default(), None)
            .map_err(|e| TestCaseError::fail(format!("{e:#}")))?;
        let at = format!("m.obj:{}: vertex ", bad + 1);
        prop_assert!(
            parts.warnings.iter().any(|w| w.starts_with(&at)
                && ["32-bit floats", "not a finite number"].iter().any(|k| w.contains(k))),
            "{:?}",
            parts.warnings
        );
    }

    #[test]
    fn huge_exponents_within_f32_load_finite(pts in grid_points(), exponent in 18i32..=37) {
        let text = obj_text(&pts, |_, p| format!("v {}e{exponent} {} {}", p.x, p.y, p.z));
        let (positions, _) = load_obj(text).map_err(TestCaseError::fail)?;
        prop_assert!(positions.iter().all(|p| p.is_finite()));
    }

    #[test]
    fn far_meshes_load_as_near_ones(
        pts in grid_points(),
        offset in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        distance in prop_oneof![Just(1e5), Just(1e7), Just(1e9)],
    ) {
        // Written 1e5 to 1e9 sizes out (exactly, in f64), loaded through
        // the scene loader, which moves it back in f64: every edge and
        // triangle as in the mesh written near the origin.
        let off = (glam::DVec3::new(offset.0, offset.1, offset.2) * distance * 20.0 * 8.0).round() / 8.0;
        let far_text = obj_text(&pts, |_, p| {
            let q = p.as_dvec3() + off;
            format!("v {} {} {}", q.x, q.y, q.z)
        });
        let near = load_obj(obj_text(&pts, plain));
        let src = Memory::default()
            .with("s.toml", "[[mesh]]\nfile = \"m.obj\"\n")
            .with("m.obj", far_text);
        let far = open_toml(&src);
        match (near, far) {
            (Ok((np, ni)), Ok(scene)) => {
                let fp = scene.geometry.positions();
                prop_assert_eq!(scene.geometry.indices(), &ni[..]);
                for (a, b) in np.iter().zip(fp) {
                    prop_assert_eq!(*a - np[0], *b - fp[0]);
                }
            }
            (Err(_), Err(_)) => {}
            (near, far) => prop_assert!(false, "near {:?}, far {:?}", near.map(|_| ()), far.map(|_| ())),
        }
    }

    #[test]
    fn toml_arrays_of_the_wrong_length_are_errors_at_their_position(n in 0usize..7) {
        let values = vec!["1"; n].join(", ");
        let text = format!(
            "[[mesh]]\nfile = \"m.obj\"\n[[light]]\ntype = \"point\"\ncolor = [1, 1, 1]\n\
             position = [{values}]\n"
        );
        let src = Memory::default()
            .with("s.toml", text)
            .with("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        let r = open_toml(&src);
        if n == 3 {
            prop_assert!(r.is_ok());
        } else {
            let e = format!("{:#}", r.expect_err("wrong length"));
            prop_assert!(
                e.starts_with("loading scene 's.toml': s.toml:6:12: invalid length"),
                "{}",
                e
            );
        }
    }
}
