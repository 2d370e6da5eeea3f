//! What `rayterm render --debug` asks for, as it writes it: a view of the
//! whole image, or of one pixel's tree with its ray.

use std::fmt;
use std::str::FromStr;

use super::View;

/// What `--debug` asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DebugSpec {
    /// A view of the whole image: `bvh-…` or `bloom`.
    Image(View),
    /// `ray:X,Y[:VIEW[:N]]` and `samples:X,Y`.
    Pixel {
        x: u32,
        y: u32,
        view: View,
        ray: Option<usize>,
    },
}

/// Every form `--debug` takes, for its errors.
fn forms() -> String {
    let views: Vec<String> = super::PIXEL_VIEWS.iter().map(|v| v.to_string()).collect();
    format!(
        "--debug takes one of:\n  \
         bvh-level:K      the BVH's boxes at depth K (0 is the root)\n  \
         bvh-leaves       the leaves' boxes\n  \
         bvh-heat         BVH nodes each camera ray visits\n  \
         bvh-heat:tests   triangle tests of each camera ray\n  \
         bloom            the bright parts and the glow bloom adds\n  \
         ray:X,Y          pixel (X, Y)'s rays, drawn over the image\n  \
         ray:X,Y:VIEW     another overlay of that pixel; VIEW is one of\n                   \
         {}\n  \
         ray:X,Y:VIEW:N   ray N of the tree (0 is the camera ray), for the\n                   \
         traversal, normals, texture and environment views\n  \
         samples:X,Y      where pixel (X, Y)'s samples fall",
        views.join(", ")
    )
}

impl FromStr for DebugSpec {
    type Err = String;

    /// Reads a `--debug` value; an error ends with every form it takes.
    fn from_str(s: &str) -> Result<Self, String> {
        parse(s).map_err(|e| format!("{e}\n{}", forms()))
    }
}

fn parse(s: &str) -> Result<DebugSpec, String> {
    if s == "bloom" {
        return Ok(DebugSpec::Image(View::Bloom));
    }
    let example = if s.starts_with("samples") {
        "samples:400,300"
    } else {
        "ray:400,300"
    };
    let pixel = |p: &str| {
        let (x, y) = p
            .split_once(',')
            .ok_or_else(|| format!("'{s}': the pixel must be X,Y, as in {example}"))?;
        let coord = |c: &str, what: &str| {
            c.trim().parse::<u32>().map_err(|_| {
                format!("'{s}': {what} must be a whole number from 0, as in {example}")
            })
        };
        Ok::<_, String>((coord(x, "x")?, coord(y, "y")?))
    };
    if let Some(rest) = s.strip_prefix("samples:") {
        let (x, y) = pixel(rest)?;
        return Ok(DebugSpec::Pixel {
            x,
            y,
            view: View::Samples,
            ray: None,
        });
    }
    if let Some(rest) = s.strip_prefix("ray:") {
        let mut parts = rest.splitn(3, ':');
        let (x, y) = pixel(parts.next().unwrap_or(""))?;
        let view = match parts.next() {
            None => View::Rays,
            Some(v) => View::parse_pixel(v).map_err(|e| format!("'{s}': {e}"))?,
        };
        let ray = match parts.next() {
            None => None,
            Some(_) if !view.one_ray() => {
                return Err(format!(
                    "'{s}': the {view} overlay draws the whole tree; a ray number is for \
                         traversal, normals, texture and environment"
                ))
            }
            Some(n) => Some(n.trim().parse::<usize>().map_err(|_| {
                format!("'{s}': the ray number must be a whole number from 0 (0 is the camera ray)")
            })?),
        };
        return Ok(DebugSpec::Pixel { x, y, view, ray });
    }
    if s.starts_with("bvh") {
        return View::parse_bvh(s).map(DebugSpec::Image);
    }
    Err(format!("unknown debug view '{s}'"))
}

impl fmt::Display for DebugSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DebugSpec::Image(v) => v.fmt(f),
            DebugSpec::Pixel {
                x,
                y,
                view: View::Samples,
                ..
            } => write!(f, "samples:{x},{y}"),
            DebugSpec::Pixel { x, y, view, ray } => {
                write!(f, "ray:{x},{y}:{view}")?;
                match ray {
                    Some(n) => write!(f, ":{n}"),
                    None => Ok(()),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_read_back_as_written() {
        for s in [
            "bvh-leaves",
            "bvh-level:2",
            "bloom",
            "ray:3,4:rays",
            "ray:3,4:traversal:2",
            "ray:0,7:environment",
            "samples:5,6",
        ] {
            let spec: DebugSpec = s.parse().unwrap();
            assert_eq!(spec.to_string(), s);
        }
        assert_eq!(
            "ray:3,4".parse(),
            Ok(DebugSpec::Pixel {
                x: 3,
                y: 4,
                view: View::Rays,
                ray: None
            })
        );
        assert_eq!(
            "ray:1,2:color".parse::<DebugSpec>().unwrap().to_string(),
            "ray:1,2:colour"
        );
        assert_eq!(
            "ray:1,2:samples".parse::<DebugSpec>().unwrap().to_string(),
            "samples:1,2"
        );
        let e = "samples:1,x".parse::<DebugSpec>().unwrap_err();
        assert!(e.contains("as in samples:400,300"), "{e}");
    }
}
