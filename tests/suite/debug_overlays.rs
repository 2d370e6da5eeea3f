//! The selected pixel's overlays and the bloom view: each draws what the
//! recorded tree says (checked against the BVH, the camera's projection and
//! the tree's numbers), nothing when its feature does not apply, and
//! `render --debug` writes them or refuses a bad spec with nothing written.

use std::collections::HashSet;
use std::path::Path;
use std::process::Command;

use glam::Vec3;
use rayterm::inspect::{inspect_pixel, tree_rays, PixelTree, RayNode};
use rayterm::render::recorder::RayKind;
use rayterm::render::{SceneRequest, Session, Tracer};
use rayterm::scene::BloomSettings;
use rayterm::viz::bloom::{bloom_view, BRIGHT, GLOW};
use rayterm::viz::draw::Layer;
use rayterm::viz::pixel::{
    self as overlay, draw, INTERPOLATED, OFF_PATH, ON_PATH, TRIANGLE, VERTEX_NORMAL,
};
use rayterm::viz::View;

fn session(spec: &str) -> Session {
    Session::open(&SceneRequest::new(spec)).unwrap().0
}

fn tracer(s: &Session, w: u32, h: u32) -> Tracer<'_> {
    s.tracer_for(&s.plan, &s.camera, (w, h))
}

fn count(layer: &Layer, c: Vec3) -> usize {
    layer.pixels().iter().filter(|p| **p == Some(c)).count()
}

/// Whether a pixel within `r` of `(x, y)` has colour `c`.
fn near(layer: &Layer, (x, y): (f64, f64), r: i64, c: Vec3) -> bool {
    (-r..=r).any(|dy| {
        (-r..=r).any(|dx| {
            let (px, py) = (x.floor() as i64 + dx, y.floor() as i64 + dy);
            px >= 0 && py >= 0 && layer.get(px as u32, py as u32) == Some(Some(c))
        })
    })
}

/// The first pixel on a grid whose sample-0 tree satisfies `want`.
/// The legend of `view` over a pixel of cornell, which has no vertex
/// normals, no environment, no texture coordinates and no glossy surface:
/// the view must draw nothing.
fn blank_on_cornell(view: View) -> String {
    let c = session("cornell");
    let t = tracer(&c, 64, 64);
    let o = draw(&t, &inspect_pixel(&t, 32, 40, 0), view, None, 1).unwrap();
    assert!(o.layer.is_blank(), "{view:?}");
    overlay_text(&o.legend)
}

fn find(t: &Tracer, want: impl Fn(&PixelTree) -> bool) -> PixelTree {
    for y in (0..t.height).step_by(3) {
        for x in (0..t.width).step_by(3) {
            let tree = inspect_pixel(t, x, y, 0);
            if want(&tree) {
                return tree;
            }
        }
    }
    panic!("no pixel of {} fits", t.scene.name);
}

fn all_nodes(n: &RayNode) -> Vec<&RayNode> {
    let mut out = vec![n];
    for c in &n.children {
        out.extend(all_nodes(c));
    }
    out
}

#[test]
fn traversal_boxes_are_the_walk_green_on_the_path_to_the_hit_red_elsewhere() {
    let s = session("cornell");
    let t = tracer(&s, 96, 96);
    let bvh = &s.bvh;
    let mut checked = 0;
    for (x, y) in [(48, 60), (20, 48), (70, 30), (48, 90)] {
        let tree = inspect_pixel(&t, x, y, 0);
        let hit = tree.root.hit.as_ref().expect("the box fills the view");
        let ray = tree_rays(&tree)[0].ray();
        let log = bvh.walk_log(&ray, false);
        // The logged walk is the renderer's: same triangle, same counts.
        assert_eq!(log.found, Some(hit.triangle));
        assert_eq!(log.stats, tree.root.bvh);
        let path = bvh.path_to(hit.triangle);
        assert_eq!(path[0], 0, "the path starts at the root");
        for w in path.windows(2) {
            let parent = &bvh.nodes()[w[0] as usize];
            assert!(!parent.is_leaf() && (w[1] == parent.first || w[1] == parent.first + 1));
        }
        let leaf = &bvh.nodes()[*path.last().unwrap() as usize];
        let slot = bvh.prims().iter().position(|&p| p == hit.triangle).unwrap() as u32;
        assert!(leaf.is_leaf() && (leaf.first..leaf.first + leaf.count).contains(&slot));
        let visited: HashSet<u32> = log.visited.iter().copied().collect();
        assert_eq!(visited.len(), log.visited.len(), "each node once");
        assert!(visited.contains(&0) && visited.contains(path.last().unwrap()));
        let o = draw(&t, &tree, View::Traversal, None, 1).unwrap();
        let on = log.visited.iter().filter(|n| path.contains(n)).count();
        let off = log.visited.len() - on;
        let legend = overlay_text(&o.legend);
        assert!(legend.contains(&format!("{on} box")), "{legend}");
        assert!(legend.contains(&format!("{off} box")), "{legend}");
        assert!(count(&o.layer, ON_PATH) > 0, "no green box");
        assert_eq!(count(&o.layer, OFF_PATH) > 0, off > 0);
        // The hit triangle is outlined: its edges' midpoints are yellow.
        let g = &s.scene.geometry;
        let v = g.indices()[hit.triangle as usize].map(|i| g.positions()[i as usize]);
        let mut outlined = 0;
        for k in 0..3 {
            if let Some(p) = t.frame.project((v[k] + v[(k + 1) % 3]) * 0.5) {
                if p.0 >= 1.0 && p.1 >= 1.0 && p.0 < 95.0 && p.1 < 95.0 {
                    assert!(near(&o.layer, p, 1, TRIANGLE), "edge {k} at {p:?}");
                    outlined += 1;
                }
            }
        }
        checked += outlined;
    }
    assert!(checked > 0, "no triangle edge was in view");
}

#[test]
fn the_logged_walk_is_the_traversal_to_the_count() {
    use rayterm::bvh::TraversalStats;
    let s = session("mirrors");
    let t = tracer(&s, 48, 36);
    for y in 0..36 {
        for x in 0..48 {
            let ray = t.frame.ray(x as f64 + 0.5, y as f64 + 0.5);
            let mut st = TraversalStats::default();
            let hit = s.bvh.intersect::<true>(&ray, &mut st);
            let log = s.bvh.walk_log(&ray, false);
            assert_eq!((log.stats, log.found), (st, hit.map(|h| h.prim)));
            // Every wide node and leaf maps to a distinct binary node.
            assert!(log.visited.len() as u32 <= st.nodes_visited + st.leaves);
            assert!(log
                .visited
                .iter()
                .all(|&n| (n as usize) < s.bvh.nodes().len()));
            // Any-hit walks of the same ray, shortened to its hit.
            if let Some(h) = hit {
                let short = rayterm::geometry::Ray::segment(ray.origin, ray.dir, h.t * 0.5);
                let mut st = TraversalStats::default();
                let blocked = s.bvh.occluded::<true>(&short, &mut st);
                let log = s.bvh.walk_log(&short, true);
                assert_eq!((log.stats, log.found), (st, blocked));
            }
        }
    }
}

#[test]
fn traversal_of_a_shadow_ray_and_of_a_ray_that_misses() {
    let s = session("cornell");
    let t = tracer(&s, 64, 64);
    let tree = find(&t, |tr| tree_rays(tr).iter().any(|r| r.shadow.is_some()));
    let rays = tree_rays(&tree);
    let (i, shadow) = rays
        .iter()
        .enumerate()
        .find(|(_, r)| r.shadow.is_some())
        .unwrap();
    let log = s.bvh.walk_log(&shadow.ray(), true);
    let (_, sample) = shadow.shadow.unwrap();
    assert_eq!(log.found, sample.occluder.as_ref().map(|o| o.1));
    let o = draw(&t, &tree, View::Traversal, Some(i), 1).unwrap();
    assert!(overlay_text(&o.legend).contains("shadow ray"));
    assert!(!o.layer.is_blank());
    // A camera ray into the sky hits nothing: no green box, the ray red.
    let env = session("env");
    let t = tracer(&env, 64, 36);
    let tree = inspect_pixel(&t, 32, 1, 0);
    assert!(tree.root.miss.is_some());
    let o = draw(&t, &tree, View::Traversal, None, 1).unwrap();
    assert_eq!(count(&o.layer, ON_PATH), 0);
    assert!(overlay_text(&o.legend).contains("hits nothing"));
    // A ray number past the tree is an error naming the rays there are.
    let n = tree_rays(&tree).len();
    let e = draw(&t, &tree, View::Traversal, Some(n), 1)
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains(&format!("rays 0 to {}", n - 1)), "{e}");
}

fn overlay_text(legend: &[(Option<Vec3>, String)]) -> String {
    rayterm::viz::draw::legend_line(&legend.to_vec())
}

#[test]
fn normals_are_drawn_where_the_tree_puts_them_and_not_on_flat_meshes() {
    let s = session("mirrors");
    let (w, h) = (160, 120);
    let t = tracer(&s, w, h);
    let tree = find(&t, |tr| {
        tr.root
            .hit
            .as_ref()
            .is_some_and(|h| h.vertex_normals.is_some() && h.mesh == "sphere_red")
    });
    let hit = tree.root.hit.as_ref().unwrap();
    let o = draw(&t, &tree, View::Normals, None, 1).unwrap();
    assert!(count(&o.layer, VERTEX_NORMAL) > 0);
    assert!(count(&o.layer, INTERPOLATED) > 0);
    // The green normal starts at the hit point and runs along the tree's
    // shading normal: pixels next to both ends' projections are green.
    let legend = overlay_text(&o.legend);
    let len: f32 = legend
        .split("normals drawn ")
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{legend}"));
    let a = t.frame.project(hit.point).unwrap();
    let b = t
        .frame
        .project(hit.point + hit.shading_normal * len)
        .unwrap();
    assert!(near(&o.layer, a, 1, INTERPOLATED), "{a:?}");
    let mid = ((a.0 + b.0) / 2.0, (a.1 + b.1) / 2.0);
    assert!(near(&o.layer, mid, 1, INTERPOLATED), "{mid:?}");
    // Each vertex normal starts at its vertex (the green one, drawn last,
    // may cover the one of the vertex nearest the hit).
    let g = &s.scene.geometry;
    let mut red = 0;
    for (k, vi) in g.indices()[hit.triangle as usize].iter().enumerate() {
        let v = g.positions()[*vi as usize];
        let n = hit.vertex_normals.unwrap()[k].normalize();
        let p = t.frame.project(v + n * len * 0.5).unwrap();
        if near(&o.layer, p, 1, VERTEX_NORMAL) {
            red += 1;
        } else {
            assert!(near(&o.layer, p, 1, INTERPOLATED), "vertex {k}: {p:?}");
        }
    }
    assert!(red >= 2, "{red} vertex normals seen");
    // Cornell's boxes are flat-shaded: nothing drawn, and the legend says why.
    assert!(blank_on_cornell(View::Normals).contains("flat-shaded"));
}

#[test]
fn environment_ray_is_drawn_in_the_colour_the_tree_found_and_its_face_named() {
    let s = session("env");
    let t = tracer(&s, 128, 72);
    let tree = find(&t, |tr| {
        tr.root.miss.as_ref().is_some_and(|m| m.face.is_some())
            && tr.root.miss.as_ref().unwrap().color != Vec3::ZERO
    });
    let miss = tree.root.miss.as_ref().unwrap();
    let o = draw(&t, &tree, View::Environment, None, 1).unwrap();
    assert!(count(&o.layer, miss.color) > 0);
    let face = miss.face.as_ref().unwrap();
    assert!(overlay_text(&o.legend).contains(&format!("face {face}")));
    // The face's name is written on the picture, in white.
    assert!(count(&o.layer, overlay::MARK) > 0);
    // Cornell is closed: no ray misses, nothing drawn.
    blank_on_cornell(View::Environment);
}

#[test]
fn texture_outlines_the_texels_the_lookup_reads_and_nothing_without_uv() {
    let s = session("cube-textured");
    let t = tracer(&s, 160, 120);
    let tree = find(&t, |tr| {
        tr.root.hit.as_ref().is_some_and(|h| h.texel.is_some())
    });
    let o = draw(&t, &tree, View::Texture, None, 1).unwrap();
    let legend = overlay_text(&o.legend);
    assert!(legend.contains("four texels bilinear"), "{legend}");
    assert!(count(&o.layer, overlay::MARK) > 20, "no outline");
    // The zoom shows the texture's own texel colours.
    let tex = &s.scene.textures[0];
    assert!(tex.texels.iter().any(|c| count(&o.layer, *c) > 4));
    // Cornell has no texture coordinates: nothing drawn, and why.
    assert!(blank_on_cornell(View::Texture).contains("no texture coordinates"));
}

#[test]
fn glossy_rays_are_drawn_in_their_contributions_with_the_lobe_axis() {
    let s = session("mirrors");
    let t = tracer(&s, 160, 120);
    let glossy = |n: &RayNode| n.children.iter().any(|c| c.kind == RayKind::Glossy);
    let tree = find(&t, |tr| glossy(&tr.root));
    let o = draw(&t, &tree, View::Glossy, None, 1).unwrap();
    let lobe: Vec<&RayNode> = tree
        .root
        .children
        .iter()
        .filter(|c| c.kind == RayKind::Glossy)
        .collect();
    let shown = lobe
        .iter()
        .filter(|c| count(&o.layer, c.contribution * o.exposure) > 0)
        .count();
    // The exposure brings the brightest to full strength, and only brightens.
    let most = lobe
        .iter()
        .map(|c| c.contribution.max_element())
        .fold(0.0, f32::max);
    assert!(o.exposure >= 1.0);
    assert!(o.exposure == 1.0 || (most * o.exposure - 1.0).abs() < 1e-5);
    // Rays may hide one another where they cross; most must show.
    assert!(shown * 2 >= lobe.len(), "{shown} of {}", lobe.len());
    assert!(count(&o.layer, overlay::LOBE_AXIS) > 0, "no lobe axis");
    let legend = overlay_text(&o.legend);
    let n = lobe.len();
    let rays = if n == 1 { "ray" } else { "rays" };
    assert!(legend.contains(&format!("{n} glossy {rays},")), "{legend}");
    // Cornell has no glossy surface.
    blank_on_cornell(View::Glossy);
}

#[test]
fn rays_in_colour_use_the_contributions_and_lights_show_their_samples() {
    let s = session("cornell-area");
    let t = tracer(&s, 200, 200);
    let tree = find(&t, |tr| {
        tr.root
            .lights
            .iter()
            .any(|l| l.samples.iter().filter(|s| s.shadow_ray.is_some()).count() > 4)
    });
    let o = draw(&t, &tree, View::Lights, None, 1).unwrap();
    let samples: Vec<_> = all_nodes(&tree.root)
        .into_iter()
        .flat_map(|n| n.lights.iter().flat_map(|l| &l.samples))
        .collect();
    let shown = samples
        .iter()
        .filter(|s| count(&o.layer, s.color) > 0)
        .count();
    assert!(shown * 2 >= samples.len(), "{shown} of {}", samples.len());
    assert!(overlay_text(&o.legend).contains(&format!("{} points", samples.len())));
    // Rays by colour: the camera ray's colour is what it adds to the pixel,
    // the by-kind view draws the kind's colour instead.
    let by_colour = draw(&t, &tree, View::Colour, None, 1).unwrap();
    let by_kind = draw(&t, &tree, View::Rays, None, 1).unwrap();
    assert!(count(&by_kind.layer, overlay::kind_color(RayKind::Camera)) > 0);
    assert!(count(&by_colour.layer, overlay::kind_color(RayKind::Camera)) == 0);
    assert!(
        count(
            &by_colour.layer,
            tree.root.contribution * by_colour.exposure
        ) > 0
    );
}

#[test]
fn sample_zoom_places_each_sample_in_its_stratum_in_its_colour() {
    let s = session("cornell");
    let t = tracer(&s, 96, 96);
    let spp = 16;
    let tree = inspect_pixel(&t, 20, 70, 0);
    let o = draw(&t, &tree, View::Samples, None, spp).unwrap();
    let mut strata = HashSet::new();
    for k in 0..spp {
        let tk = inspect_pixel(&t, 20, 70, k);
        let st = tk.stratum.expect("cornell stratifies");
        let cell = (st % 4, st / 4);
        assert!(
            (tk.offset.x * 4.0).floor() as u32 == cell.0
                && (tk.offset.y * 4.0).floor() as u32 == cell.1,
            "sample {k} at {:?} outside stratum {st}",
            tk.offset
        );
        strata.insert(st);
    }
    assert_eq!(strata.len(), 16, "16 samples visit the 16 strata");
    let legend = overlay_text(&o.legend);
    assert!(legend.contains("16 samples") && legend.contains("4x4 strata"));
    // The zoom is across from the pixel (left half, lower half): on the
    // right, at the bottom.
    let zoomed: Vec<u32> = (0..96 * 96)
        .filter(|&i| o.layer.pixels()[i as usize] == Some(overlay::MARK))
        .map(|i| i % 96)
        .collect();
    assert!(zoomed.iter().filter(|&&x| x > 48).count() > 40);
}

#[test]
fn bloom_view_marks_the_bright_pixels_and_the_glow_around_them() {
    let (w, h) = (41, 41);
    let mut img = vec![Vec3::splat(0.2); (w * h) as usize];
    img[(20 * w + 20) as usize] = Vec3::splat(8.0);
    let s = BloomSettings::default();
    let (out, legend) = bloom_view(&img, w, h, &s);
    assert_eq!(out[(20 * w + 20) as usize], BRIGHT);
    assert_eq!(out.iter().filter(|c| **c == BRIGHT).count(), 1);
    // Next to it the glow is at its strongest (orange), far away nothing.
    let next = out[(20 * w + 21) as usize];
    assert!(next.x > next.z + 0.3, "{next:?}");
    let far = out[0];
    assert!((far.x - far.z).abs() < 1e-6, "{far:?}");
    let text = overlay_text(&legend);
    assert!(
        text.contains("cyan: 1 pixel over the threshold (luminance > 1)"),
        "{text}"
    );
    assert!(text.contains("kernel 25x25"), "{text}");
    let (_, legend) = bloom_view(&[Vec3::splat(0.2); 16], 4, 4, &s);
    assert!(overlay_text(&legend).contains("no pixel is over the threshold"));
    let _ = GLOW;
}

fn rayterm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(args)
        .output()
        .unwrap()
}

fn read_png(p: &Path) -> image::RgbImage {
    image::open(p).unwrap().to_rgb8()
}

/// Renders `scene` at `size` with `--debug spec` to `png`, which must
/// succeed; returns what it printed and the image.
fn debug_png(scene: &str, size: &str, spec: &str, png: &Path) -> (String, image::RgbImage) {
    let p = png.to_str().unwrap();
    let args = [
        "render", scene, "--size", size, "--spp", "1", "--debug", spec, "-o", p,
    ];
    let out = rayterm(&args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    (stdout, read_png(png))
}

#[test]
fn cli_writes_the_traversal_and_normals_overlays() {
    let dir = std::env::temp_dir().join(format!("rayterm-debug-ov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (stdout, img) = debug_png(
        "cornell",
        "96x96",
        "ray:48,60:traversal",
        &dir.join("trav.png"),
    );
    assert!(stdout.contains("on the path to triangle"), "{stdout}");
    assert!(stdout.contains("  0  camera ray, hits"), "{stdout}");
    assert_eq!(img.dimensions(), (96, 96));
    let has = |c: [u8; 3]| img.pixels().filter(|p| p.0 == c).count();
    assert!(has([0, 255, 0]) > 20, "green boxes");
    assert!(has([255, 255, 0]) > 5, "the triangle's outline");
    let (_, img) = debug_png(
        "mirrors",
        "160x120",
        "ray:80,70:normals",
        &dir.join("normals.png"),
    );
    let red = img.pixels().filter(|p| p.0 == [255, 0, 0]).count();
    let green = img.pixels().filter(|p| p.0 == [0, 255, 0]).count();
    assert!(red > 3 && green > 3, "red {red}, green {green}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_refuses_bad_specs_and_leaves_no_file() {
    let dir = std::env::temp_dir().join(format!("rayterm-debug-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("bad.png");
    let p = png.to_str().unwrap();
    let cases: &[(&[&str], &str)] = &[
        (&["--debug", "ray:96,10"], "outside the 96x96 image"),
        (&["--debug", "samples:3,200"], "outside the 96x96 image"),
        (&["--debug", "ray:10,10:wobble"], "unknown overlay 'wobble'"),
        (&["--debug", "ray:10,10:traversal:99"], "is not in the tree"),
        (&["--debug", "ray:10,10:traversal:x"], "ray number"),
        (&["--debug", "ray:10,10:rays:1"], "draws the whole tree"),
        (&["--debug", "ray:10"], "X,Y"),
        (&["--debug", "ray:-1,3"], "whole number"),
        (&["--debug", "blooms"], "unknown debug view"),
        (&["--debug", "bvh-leaves", "--spp", "4"], "--spp is for"),
    ];
    for (extra, says) in cases {
        let mut args = vec!["render", "cornell", "--size", "96x96", "-o", p];
        args.extend_from_slice(extra);
        let out = rayterm(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{extra:?} succeeded");
        assert!(err.contains(says), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{extra:?}: {err}");
        assert!(!png.exists(), "{extra:?} left a file");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_text_numbers_the_rays_as_the_overlays_do() {
    use rayterm::inspect::{lines, LineKind};
    let s = session("cornell-area");
    let t = tracer(&s, 48, 48);
    let tree = find(&t, |tr| tree_rays(tr).len() > 8);
    let rays = tree_rays(&tree);
    let open = lines(&tree, &|_| true);
    let numbered: Vec<(usize, LineKind)> = open
        .iter()
        .filter_map(|l| l.ray.map(|r| (r, l.kind)))
        .collect();
    assert_eq!(
        numbered.iter().map(|n| n.0).collect::<Vec<_>>(),
        (0..rays.len()).collect::<Vec<_>>()
    );
    for (i, kind) in numbered {
        let shadow = rays[i].shadow.is_some();
        assert_eq!(
            shadow,
            matches!(kind, LineKind::Occluded | LineKind::Visible),
            "ray {i}"
        );
    }
    // Folded, the samples' lines go but the numbers after them stay.
    let folded = lines(&tree, &|_| false);
    let after: Vec<_> = folded.iter().filter(|l| l.ray.is_some()).collect();
    assert!(after.len() < rays.len());
    for l in after {
        let same = open.iter().find(|o| o.ray == l.ray).unwrap();
        assert_eq!(same.text, l.text);
    }
}
