//! Wavefront OBJ + MTL through tobj, with errors that name file and line,
//! non-finite values rejected, and missing MTL or textures downgraded to warnings.

use std::cell::{Cell, RefCell};
use std::io::BufRead;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use glam::{Affine3A, Vec2, Vec3};

use super::source::{resolve, Disk, Source};
use super::{Camera, Environment, Geometry, Light, Material, MeshInfo, Scene, Settings, Texture};

/// Coordinates beyond this are legal but almost certainly a mistake.
pub const ABSURD: f32 = 1e18;

/// Statements holding vertex data in OBJ files.
const OBJ_NUMBERS: &[&str] = &["v", "vn", "vt"];
/// Statements holding numbers in MTL files (colours, exponents, opacity).
const MTL_NUMBERS: &[&str] = &["Ka", "Kd", "Ks", "Ke", "Tf", "Ns", "Ni", "d", "Tr"];

/// A `BufRead` over bytes that yields at most one line per `fill_buf`, so the
/// number of lines handed to tobj is the line it failed on.
struct LineCounter<'a> {
    bytes: &'a [u8],
    pos: usize,
    lines: &'a Cell<usize>,
}

impl std::io::Read for LineCounter<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(buf.len());
        buf[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl BufRead for LineCounter<'_> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        let rest = &self.bytes[self.pos..];
        let end = rest
            .iter()
            .position(|&b| b == b'\n')
            .map_or(rest.len(), |i| i + 1);
        Ok(&rest[..end])
    }

    fn consume(&mut self, amt: usize) {
        if amt > 0 && (self.pos == 0 || self.bytes[self.pos - 1] == b'\n') {
            self.lines.set(self.lines.get() + 1);
        }
        self.pos += amt;
    }
}

/// Runs a tobj parser on `bytes`, turning its error into one with a line number.
fn with_lines<T>(
    file: &Path,
    bytes: &[u8],
    parse: impl FnOnce(&mut LineCounter) -> Result<T, tobj::LoadError>,
) -> Result<T> {
    let lines = Cell::new(0);
    let mut r = LineCounter {
        bytes,
        pos: 0,
        lines: &lines,
    };
    parse(&mut r).map_err(|e| anyhow!("{}:{}: {e}", file.display(), lines.get().max(1)))
}

/// Rejects NaN/inf in the numbers of the `statements` (tobj accepts them)
/// and warns on absurd magnitudes, naming the line.
fn check_numbers(
    file: &Path,
    text: &str,
    statements: &[&str],
    warnings: &mut Vec<String>,
) -> Result<()> {
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if !words.next().is_some_and(|w| statements.contains(&w)) {
            continue;
        }
        for w in words {
            if let Ok(x) = w.parse::<f32>() {
                if !x.is_finite() {
                    bail!("{}:{}: non-finite value '{w}'", file.display(), i + 1);
                }
                if x.abs() > ABSURD {
                    warnings.push(format!("{}:{}: absurd value {w}", file.display(), i + 1));
                }
            }
        }
    }
    Ok(())
}

/// Mesh placement from a scene file.
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub transform: Affine3A,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            transform: Affine3A::IDENTITY,
        }
    }
}

/// Accumulates meshes, materials and textures into one scene.
#[derive(Debug, Default)]
pub struct Parts {
    pub geometry: Geometry,
    pub meshes: Vec<MeshInfo>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub warnings: Vec<String>,
    texture_ids: Vec<(PathBuf, Option<u32>)>,
}

/// One mesh to add: positions and optional per-vertex normals and UVs.
pub struct MeshData<'a> {
    pub name: String,
    pub positions: &'a [Vec3],
    pub normals: Option<&'a [Vec3]>,
    pub uvs: Option<&'a [Vec2]>,
    pub indices: &'a [[u32; 3]],
    pub material: u32,
}

impl Parts {
    /// Loads a texture once per path; `None` (with a warning) when missing or broken.
    pub fn texture(&mut self, src: &dyn Source, path: &Path, from: &Path) -> Option<u32> {
        if let Some((_, id)) = self.texture_ids.iter().find(|(p, _)| p == path) {
            return *id;
        }
        let id = match src.read(path) {
            Ok(bytes) => match Texture::decode(&path.display().to_string(), &bytes) {
                Ok(t) => {
                    self.textures.push(t);
                    Some(self.textures.len() as u32 - 1)
                }
                Err(e) => {
                    self.warnings.push(format!(
                        "{}: texture {} unreadable ({e}); using the material colour",
                        from.display(),
                        path.display()
                    ));
                    None
                }
            },
            Err(e) => {
                self.warnings.push(format!(
                    "{}: texture {} not found ({e}); using the material colour",
                    from.display(),
                    path.display()
                ));
                None
            }
        };
        self.texture_ids.push((path.to_path_buf(), id));
        id
    }

    /// Adds a mesh, transformed; drops zero-area triangles and counts them.
    pub fn add_mesh(&mut self, m: MeshData, place: &Placement) {
        let xf = place.transform;
        let nxf = glam::Mat3::from(xf.matrix3).inverse().transpose();
        let base = self.geometry.positions.len() as u32;
        let mesh_id = self.meshes.len() as u32;
        let smooth = m.normals.is_some();
        let textured = m.uvs.is_some();
        self.geometry
            .positions
            .extend(m.positions.iter().map(|&p| xf.transform_point3(p)));
        match m.normals {
            Some(n) => self
                .geometry
                .normals
                .extend(n.iter().map(|&n| (nxf * n).normalize_or_zero())),
            None => self
                .geometry
                .normals
                .extend(std::iter::repeat_n(Vec3::ZERO, m.positions.len())),
        }
        match m.uvs {
            Some(uv) => self.geometry.uvs.extend_from_slice(uv),
            None => self
                .geometry
                .uvs
                .extend(std::iter::repeat_n(Vec2::ZERO, m.positions.len())),
        }
        let mut degenerate = 0;
        for tri in m.indices {
            let t = tri.map(|i| i + base);
            let [a, b, c] = t.map(|i| self.geometry.positions[i as usize]);
            if (b - a).cross(c - a).length_squared() == 0.0 {
                degenerate += 1;
                continue;
            }
            self.geometry.indices.push(t);
            self.geometry.tri_material.push(m.material);
            self.geometry.tri_mesh.push(mesh_id);
        }
        if degenerate > 0 {
            self.warnings.push(format!(
                "{}: skipped {degenerate} degenerate (zero-area) triangle{}",
                m.name,
                if degenerate == 1 { "" } else { "s" }
            ));
        }
        self.meshes.push(MeshInfo {
            name: m.name,
            smooth,
            textured,
        });
    }

    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        self.materials.len() as u32 - 1
    }
}

fn convert_material(
    parts: &mut Parts,
    src: &dyn Source,
    mtl_path: &Path,
    m: &tobj::Material,
) -> Material {
    let d = Material::default();
    let v3 =
        |a: Option<[f32; 3]>, def: Vec3| a.map(Vec3::from).filter(|v| v.is_finite()).unwrap_or(def);
    let texture = m
        .diffuse_texture
        .as_ref()
        .and_then(|t| parts.texture(src, &resolve(mtl_path, t), mtl_path));
    Material {
        name: m.name.clone(),
        kd: v3(m.diffuse, d.kd),
        ks: v3(m.specular, d.ks),
        ns: m
            .shininess
            .filter(|s| s.is_finite() && *s >= 0.0)
            .unwrap_or(d.ns),
        dissolve: m
            .dissolve
            .filter(|x| x.is_finite())
            .unwrap_or(1.0)
            .clamp(0.0, 1.0),
        texture,
    }
}

/// Loads an OBJ (and its MTL files) into `parts`. `material` overrides every
/// material of the file when given.
pub fn load_into(
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    place: &Placement,
    material: Option<&Material>,
) -> Result<()> {
    let bytes = src
        .read(path)
        .with_context(|| format!("cannot read {}", path.display()))?;
    let text = String::from_utf8_lossy(&bytes);
    check_numbers(path, &text, OBJ_NUMBERS, &mut parts.warnings)?;
    let opts = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mtl_error: RefCell<Option<anyhow::Error>> = RefCell::new(None);
    let mtl_files: RefCell<Vec<PathBuf>> = RefCell::new(Vec::new());
    let warnings: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let (models, materials) = with_lines(path, &bytes, |r| {
        tobj::load_obj_buf(r, &opts, |mtl| {
            let mtl_path = resolve(path, &mtl.to_string_lossy());
            match src.read(&mtl_path) {
                Ok(mb) => {
                    let checked = check_numbers(
                        &mtl_path,
                        &String::from_utf8_lossy(&mb),
                        MTL_NUMBERS,
                        &mut warnings.borrow_mut(),
                    );
                    let res = checked
                        .and_then(|()| with_lines(&mtl_path, &mb, |r| tobj::load_mtl_buf(r)));
                    match res {
                        Ok(ok) => {
                            mtl_files.borrow_mut().push(mtl_path);
                            Ok(ok)
                        }
                        Err(e) => {
                            mtl_error.borrow_mut().get_or_insert(e);
                            Err(tobj::LoadError::MaterialParseError)
                        }
                    }
                }
                Err(e) => {
                    warnings.borrow_mut().push(format!(
                        "{}: material library {} not found ({e}); using the default material",
                        path.display(),
                        mtl_path.display()
                    ));
                    Err(tobj::LoadError::OpenFileFailed)
                }
            }
        })
    })?;
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    parts.warnings.extend(warnings.into_inner());
    let materials = materials.unwrap_or_default();
    let mtl_path = mtl_files
        .borrow()
        .first()
        .cloned()
        .unwrap_or_else(|| path.to_path_buf());
    let first_mat = parts.materials.len() as u32;
    let mut default_mat = None;
    match material {
        Some(m) => {
            parts.add_material(m.clone());
        }
        None => {
            for m in &materials {
                let conv = convert_material(parts, src, &mtl_path, m);
                parts.add_material(conv);
            }
        }
    }
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    for model in &models {
        let mesh = &model.mesh;
        if mesh.indices.is_empty() {
            continue;
        }
        let positions: Vec<Vec3> = mesh
            .positions
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let normals: Vec<Vec3> = mesh
            .normals
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let uvs: Vec<Vec2> = mesh
            .texcoords
            .chunks_exact(2)
            .map(|c| Vec2::new(c[0], c[1]))
            .collect();
        let indices: Vec<[u32; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let mat = match (material, mesh.material_id) {
            (Some(_), _) => first_mat,
            (None, Some(id)) if id < materials.len() => first_mat + id as u32,
            _ => *default_mat.get_or_insert_with(|| parts.add_material(Material::default())),
        };
        let name = if model.name.is_empty() || model.name == "unnamed_object" {
            stem.clone()
        } else {
            model.name.clone()
        };
        parts.add_mesh(
            MeshData {
                name,
                positions: &positions,
                normals: (normals.len() == positions.len()).then_some(&normals[..]),
                uvs: (uvs.len() == positions.len()).then_some(&uvs[..]),
                indices: &indices,
                material: mat,
            },
            place,
        );
    }
    Ok(())
}

/// A bare OBJ: the shared workload's auto camera and point light.
pub fn load_bare(path: &Path) -> Result<Scene> {
    let mut parts = Parts::default();
    load_into(&mut parts, &Disk, path, &Placement::default(), None)?;
    if parts.geometry.indices.is_empty() {
        bail!("{}: no triangles", path.display());
    }
    let b = parts.geometry.bounds();
    let name = path.display().to_string();
    Ok(Scene {
        description: format!("mesh {name}"),
        name,
        camera: Camera::auto(&b),
        lights: vec![Light::Point {
            position: Camera::auto_light(&b),
            color: Vec3::ONE,
        }],
        environment: Environment::Color(Vec3::ZERO),
        settings: Settings {
            ambient: Vec3::splat(0.1),
            ..Settings::default()
        },
        geometry: parts.geometry,
        meshes: parts.meshes,
        materials: parts.materials,
        textures: parts.textures,
        warnings: parts.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Mem(Vec<(&'static str, String)>);
    impl Source for Mem {
        fn read(&self, p: &Path) -> std::io::Result<Vec<u8>> {
            self.0
                .iter()
                .find(|(n, _)| Path::new(n) == p)
                .map(|(_, t)| t.as_bytes().to_vec())
                .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "missing"))
        }
    }

    fn load(files: Vec<(&'static str, String)>) -> Result<Parts> {
        let mut p = Parts::default();
        load_into(
            &mut p,
            &Mem(files),
            Path::new("m/a.obj"),
            &Placement::default(),
            None,
        )?;
        Ok(p)
    }

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

    #[test]
    fn quad_is_two_triangles_with_default_material() {
        let p = load(vec![("m/a.obj", QUAD.into())]).unwrap();
        assert_eq!(p.geometry.indices.len(), 2);
        assert_eq!(p.materials.len(), 1);
        assert_eq!(p.materials[0], Material::default());
    }

    #[test]
    fn bad_face_index_names_line() {
        let e = load(vec![("m/a.obj", format!("{QUAD}\n# c\nf 1 2 9\n"))]).unwrap_err();
        let s = format!("{e:#}");
        assert!(s.contains("m/a.obj:8"), "{s}");
    }

    #[test]
    fn nan_vertex_names_line() {
        let e = load(vec![(
            "m/a.obj",
            "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".into(),
        )])
        .unwrap_err();
        assert!(format!("{e}").contains("m/a.obj:2"), "{e}");
    }

    #[test]
    fn missing_mtl_and_texture_warn() {
        let obj = format!("mtllib nope.mtl\nusemtl x\n{QUAD}");
        let p = load(vec![("m/a.obj", obj)]).unwrap();
        assert!(
            p.warnings.iter().any(|w| w.contains("nope.mtl")),
            "{:?}",
            p.warnings
        );
        let obj = format!("mtllib sub\\my mat.mtl\nusemtl x\n{QUAD}");
        let mtl = "newmtl x\nKd 1 0 0\nKs 0.5 0.5 0.5\nNs 50\nd 0.5\nmap_Kd ..\\tex dir\\t 1.png\n";
        let p = load(vec![("m/a.obj", obj), ("m/sub/my mat.mtl", mtl.into())]).unwrap();
        assert_eq!(p.materials[0].kd, Vec3::X);
        assert_eq!(p.materials[0].ns, 50.0);
        assert_eq!(p.materials[0].dissolve, 0.5);
        assert!(
            p.warnings.iter().any(|w| w.contains("m/tex dir/t 1.png")),
            "{:?}",
            p.warnings
        );
    }

    #[test]
    fn non_finite_mtl_numbers_are_errors_and_absurd_ones_warn() {
        let obj = format!("mtllib a.mtl\nusemtl x\n{QUAD}");
        for (mtl, line) in [
            ("newmtl x\nKd nan 0 0\n", 2),
            ("newmtl x\nKd 1 1 1\nNs inf\n", 3),
            ("newmtl x\n\nd -infinity\n", 3),
            ("newmtl x\nKs 0 0 1e39\n", 2),
        ] {
            let e = load(vec![("m/a.obj", obj.clone()), ("m/a.mtl", mtl.into())]).unwrap_err();
            assert!(format!("{e}").contains(&format!("m/a.mtl:{line}")), "{e}");
        }
        // A texture named like a number is not a number.
        let mtl = "newmtl x\nmap_Kd nan\nKs 1e30 0 0\n";
        let p = load(vec![("m/a.obj", obj), ("m/a.mtl", mtl.into())]).unwrap();
        assert!(
            p.warnings.iter().any(|w| w.contains("m/a.mtl:3: absurd")),
            "{:?}",
            p.warnings
        );
    }

    #[test]
    fn broken_mtl_is_an_error_with_line() {
        let obj = format!("mtllib a.mtl\nusemtl x\n{QUAD}");
        let mtl = "newmtl x\nKd 1 0 0\nKd 1 zz\n";
        let e = load(vec![("m/a.obj", obj), ("m/a.mtl", mtl.into())]).unwrap_err();
        assert!(format!("{e}").contains("m/a.mtl:3"), "{e}");
    }

    #[test]
    fn degenerate_triangles_are_skipped_and_counted() {
        let p = load(vec![(
            "m/a.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n".into(),
        )])
        .unwrap();
        assert_eq!(p.geometry.indices.len(), 1);
        assert!(p.warnings.iter().any(|w| w.contains("1 degenerate")));
    }
}
