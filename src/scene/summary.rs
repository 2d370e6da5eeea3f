//! What `--explain` says of a scene's materials and lights: the shading
//! model each material takes and each light with its units.

use glam::Vec3;

use super::{Environment, Light, Scene};
use crate::scene::show::show3;

/// A light's colour or intensity, three channels or one where they agree.
fn value(v: Vec3) -> String {
    if v.x == v.y && v.y == v.z {
        format!("{}", v.x)
    } else {
        show3(v.as_dvec3())
    }
}

/// One line per light.
fn light(l: &Light) -> String {
    match l {
        Light::Point { position, color } => format!(
            "point at {}, colour {} (Phong units: a white Phong surface facing it shows it)",
            show3(position.as_dvec3()),
            value(*color)
        ),
        Light::Segment { a, b, .. } => format!(
            "segment from {} to {} (Phong units)",
            show3(a.as_dvec3()),
            show3(b.as_dvec3())
        ),
        Light::Parallelogram { corner, .. } => format!(
            "parallelogram at {} (Phong units)",
            show3(corner.as_dvec3())
        ),
        Light::Photometric {
            position,
            intensity,
            range,
            cone,
        } => {
            let kind = match cone {
                None => "point".to_string(),
                Some(c) => format!(
                    "spot along {}, cone {:.1}° to {:.1}°",
                    show3(c.axis.as_dvec3()),
                    c.cos_inner.clamp(-1.0, 1.0).acos().to_degrees(),
                    c.cos_outer.clamp(-1.0, 1.0).acos().to_degrees()
                ),
            };
            let range = range.map_or(String::new(), |r| format!(", range {r}"));
            format!(
                "{kind} at {}, {} cd, falling off with the square of the distance{range}",
                show3(position.as_dvec3()),
                value(*intensity)
            )
        }
        Light::Directional {
            direction,
            illuminance,
        } => format!(
            "directional along {}, {} lux",
            show3(direction.as_dvec3()),
            value(*illuminance)
        ),
    }
}

/// The materials' shading models and the lights, for `--explain`; `paths`
/// says whether paths are traced (what lights the scene then differs).
pub(crate) fn explain(scene: &Scene, paths: bool) -> String {
    let pbr = scene.materials.iter().filter(|m| m.pbr.is_some()).count();
    let phong = scene.materials.len() - pbr;
    let emissive = scene.materials.iter().filter(|m| m.emissive()).count();
    let mut out = String::from("materials:\n");
    if pbr > 0 {
        out += &format!(
            "  {pbr} metallic-roughness (glTF 2.0: Lambert and GGX, Smith height-correlated, \
             Schlick's Fresnel){}\n",
            match emissive {
                0 => String::new(),
                n => format!(", {n} emissive"),
            }
        );
    }
    if phong > 0 {
        out += &format!("  {phong} Phong\n");
    }
    out += "lights:\n";
    if scene.lights.is_empty() {
        out += "  none\n";
    }
    for l in &scene.lights {
        out += &format!("  {}\n", light(l));
    }
    match paths {
        true => out += "ambient: none (paths find the light it stands in for)\n",
        false => out += &format!("ambient: {}\n", value(scene.settings.ambient)),
    }
    out += &format!("environment: {}", environment(&scene.environment, paths));
    out
}

/// What rays leaving the scene see, and whether it lights the scene.
fn environment(e: &Environment, paths: bool) -> String {
    match e {
        Environment::Color(c) if paths => format!(
            "background {} (seen by the camera and in mirrors; lights nothing)",
            value(*c)
        ),
        Environment::Color(c) => format!("background {} (lights nothing)", value(*c)),
        Environment::CubeMap(_) if paths => {
            "cube map (seen and reflected; lights what paths reach it from)".into()
        }
        Environment::CubeMap(_) => "cube map (seen and reflected; lights nothing)".into(),
        Environment::Light(l) => {
            let what = match (l.color(), l.map()) {
                (Some(c), _) => format!("constant radiance {}", value(c)),
                (_, Some(t)) => format!("map {} ({}x{})", t.name, t.width, t.height),
                _ => "nothing".into(),
            };
            format!(
                "light, {what}, strength {}, turned {}° about +Y, importance-sampled \
                 (`--no environment` turns it off)",
                l.strength(),
                l.rotation()
            )
        }
    }
}
