//! Textures (linear RGB, repeat, clamped or mirrored wrapping, nearest or
//! bilinear lookup) and cube maps in the OpenGL face convention.

use crate::color::srgb_to_linear;
use std::sync::Arc;

use anyhow::{bail, Result};
use glam::{Vec2, Vec3};
use image::ImageDecoder;

use crate::memory;

/// A decoded image and how a material looks it up. Cloning one shares its
/// texels: every material of an image (or of a file) holds them once.
#[derive(Clone, Debug)]
pub struct Texture {
    pub(crate) name: String,
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Row 0 is the top of the image; values are linear (sRGB decoded).
    pub texels: Arc<Vec<Vec3>>,
    /// How coordinates outside 0..1 wrap, along u and v.
    pub wrap: [Wrap; 2],
    /// What every lookup is multiplied by (a glTF material's base colour
    /// factor).
    pub tint: Vec3,
    /// The texture coordinates it reads.
    pub uv: UvMap,
}

/// Which texture coordinates a texture reads, and how they are moved
/// before the lookup: glTF's `texCoord` and `KHR_texture_transform`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UvMap {
    /// The UV set: 0 (`TEXCOORD_0`, every format's) or 1 (`TEXCOORD_1`).
    pub set: u8,
    /// Applied to the coordinates (rayterm's, v up); `None` leaves them
    /// as they are, bit for bit.
    pub transform: Option<glam::Affine2>,
}

impl UvMap {
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        match &self.transform {
            Some(m) => m.transform_point2(uv),
            None => uv,
        }
    }
}

/// How texture coordinates outside 0..1 (and neighbours across an edge)
/// are found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    #[default]
    Repeat,
    Clamp,
    Mirror,
}

impl Wrap {
    /// A coordinate brought into 0..1.
    #[inline]
    fn unit(self, x: f32) -> f32 {
        match self {
            Wrap::Repeat => x - x.floor(),
            Wrap::Clamp => x.clamp(0.0, 1.0),
            Wrap::Mirror => {
                let k = x.rem_euclid(2.0);
                if k > 1.0 {
                    2.0 - k
                } else {
                    k
                }
            }
        }
    }

    /// A texel index brought into 0..n.
    #[inline]
    fn index(self, i: i64, n: i64) -> usize {
        (match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let k = i.rem_euclid(2 * n);
                if k >= n {
                    2 * n - 1 - k
                } else {
                    k
                }
            }
        }) as usize
    }
}

/// How an image's 8-bit values become linear ones: colours are sRGB
/// encoded, data (normals, roughness, occlusion) are stored linearly, and
/// an alpha channel is stored linearly in every component (1 for an image
/// without one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(crate) enum Encoding {
    #[default]
    Srgb,
    Linear,
    Alpha,
}

/// Most memory one texture may take to decode and store (12 bytes a texel
/// once stored, plus the decoder's buffers): 1.5 GiB, enough for 8192x8192
/// RGBA or 10000x10000 RGB. Also never more than the memory available
/// ([`memory::check`]).
pub(crate) const TEXTURE_BUDGET: u64 = 1536 << 20;

/// A decoder's error as one message: its text already holds its cause,
/// which an error chain would repeat.
pub(super) fn image_error(e: image::ImageError) -> anyhow::Error {
    match e {
        // The decoder's own check of the header against the budget.
        image::ImageError::Limits(_) => anyhow::anyhow!(
            "the image's header asks for more than the {} per texture",
            crate::memory::bytes(TEXTURE_BUDGET)
        ),
        image::ImageError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            anyhow::anyhow!("the file ends before the pixels its header declares (truncated?)")
        }
        e => anyhow::anyhow!("{e}"),
    }
}

/// Bytes a stored texel takes.
pub(super) const TEXEL_BYTES: u64 = std::mem::size_of::<Vec3>() as u64;

impl Texture {
    pub(crate) fn from_image(name: &str, img: image::DynamicImage, encoding: Encoding) -> Self {
        let (width, height) = (img.width(), img.height());
        let lut: Vec<f32> = (0..256)
            .map(|i| i as f32 / 255.0)
            .map(|c| match encoding {
                Encoding::Srgb => srgb_to_linear(c),
                Encoding::Linear | Encoding::Alpha => c,
            })
            .collect();
        let texels = match encoding {
            Encoding::Alpha => img
                .into_rgba8()
                .pixels()
                .map(|p| Vec3::splat(lut[p[3] as usize]))
                .collect(),
            _ => img
                .into_rgb8()
                .pixels()
                .map(|p| Vec3::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
                .collect(),
        };
        Self {
            name: name.to_string(),
            width,
            height,
            texels: Arc::new(texels),
            wrap: [Wrap::Repeat; 2],
            tint: Vec3::ONE,
            uv: UvMap::default(),
        }
    }

    /// Decodes an image file's bytes. An image without pixels, or one that
    /// would take more than [`TEXTURE_BUDGET`] (or the memory available) to
    /// decode and store, is refused before anything large is allocated.
    pub(crate) fn decode(name: &str, bytes: &[u8], encoding: Encoding) -> Result<Self> {
        // Formats of GPU textures, which the decoder would call unknown.
        for (magic, what) in [
            (&b"\xABKTX 20\xBB\r\n\x1A\n"[..], "KTX2 (Basis Universal)"),
            (b"DDS ", "DDS"),
        ] {
            if bytes.starts_with(magic) {
                bail!(
                    "a {what} image, which rayterm does not decode (it reads PNG, JPEG and WebP)"
                );
            }
        }
        let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let mut limits = image::Limits::default();
        limits.max_alloc = Some(TEXTURE_BUDGET);
        reader.limits(limits);
        let decoder = reader.into_decoder().map_err(image_error)?;
        let (w, h) = decoder.dimensions();
        if w == 0 || h == 0 {
            bail!("the image has no pixels ({w}x{h})");
        }
        let texels = w as u64 * h as u64;
        let converted = match (decoder.color_type(), encoding) {
            (image::ColorType::Rgb8, Encoding::Srgb | Encoding::Linear) => 0,
            (image::ColorType::Rgba8, Encoding::Alpha) => 0,
            (_, Encoding::Alpha) => 4,
            _ => 3,
        };
        let needed = decoder.total_bytes() + texels * (converted + TEXEL_BYTES);
        memory::check(
            &format!("a {w}x{h} texture"),
            needed,
            Some((TEXTURE_BUDGET, "per texture")),
        )?;
        Ok(Self::from_image(
            name,
            image::DynamicImage::from_decoder(decoder).map_err(image_error)?,
            encoding,
        ))
    }

    #[inline]
    pub(super) fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = self.wrap[0].index(x, self.width as i64);
        let y = self.wrap[1].index(y, self.height as i64);
        self.texels[y * self.width as usize + x]
    }

    /// Texel coordinates of `uv` (OBJ convention: v = 0 at the bottom).
    #[inline]
    fn coords(&self, uv: Vec2) -> (f32, f32) {
        let u = if uv.x.is_finite() { uv.x } else { 0.0 };
        let v = if uv.y.is_finite() { uv.y } else { 0.0 };
        (
            self.wrap[0].unit(u) * self.width as f32,
            (1.0 - self.wrap[1].unit(v)) * self.height as f32,
        )
    }

    pub(crate) fn nearest(&self, uv: Vec2) -> Vec3 {
        let (x, y) = self.coords(uv);
        self.texel(x as i64, y as i64) * self.tint
    }

    pub(crate) fn bilinear(&self, uv: Vec2) -> Vec3 {
        let (x, y) = self.coords(uv);
        self.bilinear_px(x, y) * self.tint
    }

    /// Bilinear lookup at pixel coordinates (texel centres at +0.5).
    pub(super) fn bilinear_px(&self, x: f32, y: f32) -> Vec3 {
        let (x, y) = (x - 0.5, y - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }

    /// Bilinear lookup clamped to the edge (cube faces must not wrap around).
    fn bilinear_clamped(&self, s: f32, t: f32) -> Vec3 {
        let (w, h) = (self.width as f32, self.height as f32);
        let x = (s * w).clamp(0.5, w - 0.5);
        let y = (t * h).clamp(0.5, h - 0.5);
        self.bilinear_px(x, y)
    }
}

/// Cube-map faces in the OpenGL order +X, -X, +Y, -Y, +Z, -Z.
pub(crate) const FACE_NAMES: [&str; 6] = ["posx", "negx", "posy", "negy", "posz", "negz"];

#[derive(Clone, Debug)]
pub struct CubeMap {
    pub(crate) faces: [Texture; 6],
}

/// Face and (s, t) in `[0,1]^2` (t from the top row) for a direction, as in
/// the OpenGL specification's major-axis table.
pub(crate) fn cube_face_uv(d: Vec3) -> (usize, Vec2) {
    let a = d.abs();
    let (face, ma, sc, tc) = if a.x >= a.y && a.x >= a.z {
        if d.x >= 0.0 {
            (0, a.x, -d.z, -d.y)
        } else {
            (1, a.x, d.z, -d.y)
        }
    } else if a.y >= a.z {
        if d.y >= 0.0 {
            (2, a.y, d.x, d.z)
        } else {
            (3, a.y, d.x, -d.z)
        }
    } else if d.z >= 0.0 {
        (4, a.z, d.x, -d.y)
    } else {
        (5, a.z, -d.x, -d.y)
    };
    let ma = if ma > 0.0 { ma } else { 1.0 };
    (
        face,
        Vec2::new((sc / ma + 1.0) * 0.5, (tc / ma + 1.0) * 0.5),
    )
}

impl CubeMap {
    pub(crate) fn lookup(&self, d: Vec3) -> Vec3 {
        let (face, st) = cube_face_uv(d);
        self.faces[face].bilinear_clamped(st.x, st.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32, f: impl Fn(u32, u32) -> Vec3) -> Texture {
        Texture {
            name: "t".into(),
            width: w,
            height: h,
            texels: Arc::new(
                (0..h)
                    .flat_map(|y| (0..w).map(move |x| (x, y)))
                    .map(|(x, y)| f(x, y))
                    .collect(),
            ),
            wrap: [Wrap::Repeat; 2],
            tint: Vec3::ONE,
            uv: UvMap::default(),
        }
    }

    #[test]
    fn nearest_and_bilinear_with_repeat() {
        let t = tex(2, 2, |x, y| Vec3::splat((x + 2 * y) as f32));
        // v = 0.75 is the top row (y = 0) in OBJ convention.
        assert_eq!(t.nearest(Vec2::new(0.25, 0.75)), Vec3::splat(0.0));
        assert_eq!(t.nearest(Vec2::new(0.75, 0.25)), Vec3::splat(3.0));
        assert_eq!(t.nearest(Vec2::new(1.25, 1.75)), Vec3::splat(0.0));
        assert_eq!(t.nearest(Vec2::new(-0.75, 0.75)), Vec3::splat(0.0));
        // Halfway between texel centres of the top row.
        assert!((t.bilinear(Vec2::new(0.5, 0.75)).x - 0.5).abs() < 1e-6);
        // Across the wrap: between x=1 and x=0 of the top row.
        assert!((t.bilinear(Vec2::new(0.0, 0.75)).x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn clamped_and_mirrored_wrapping() {
        let mut t = tex(2, 1, |x, _| Vec3::splat(x as f32));
        t.wrap = [Wrap::Clamp; 2];
        assert_eq!(t.nearest(Vec2::new(1.75, 0.5)), Vec3::ONE);
        assert_eq!(t.nearest(Vec2::new(-3.0, 0.5)), Vec3::ZERO);
        // No blending with the far edge across u = 0.
        assert_eq!(t.bilinear(Vec2::new(0.0, 0.5)), Vec3::ZERO);
        t.wrap = [Wrap::Mirror; 2];
        assert_eq!(t.nearest(Vec2::new(1.25, 0.5)), Vec3::ONE);
        assert_eq!(t.nearest(Vec2::new(1.75, 0.5)), Vec3::ZERO);
        assert_eq!(t.nearest(Vec2::new(-0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.bilinear(Vec2::new(1.0, 0.5)), Vec3::ONE);
    }

    /// WebP decodes as PNG does (a lossless 2x1 image of a red and a blue
    /// texel, from the image crate's encoder); KTX2 is named.
    #[test]
    fn webp_decodes_and_ktx2_is_named() {
        let img = image::RgbImage::from_fn(2, 1, |x, _| match x {
            0 => image::Rgb([255, 0, 0]),
            _ => image::Rgb([0, 0, 255]),
        });
        let mut webp = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut webp),
            image::ImageFormat::WebP,
        )
        .unwrap();
        assert!(webp.starts_with(b"RIFF") && &webp[8..12] == b"WEBP");
        let t = Texture::decode("t.webp", &webp, Encoding::Srgb).unwrap();
        assert_eq!((t.width, t.height), (2, 1));
        assert_eq!(t.texels[..], [Vec3::X, Vec3::Z]);
        let mut ktx2 = b"\xABKTX 20\xBB\r\n\x1A\n".to_vec();
        ktx2.extend([0; 64]);
        let e = Texture::decode("t.ktx2", &ktx2, Encoding::Srgb)
            .unwrap_err()
            .to_string();
        assert!(e.contains("KTX2 (Basis Universal)"), "{e}");
    }

    #[test]
    fn cube_faces_follow_opengl() {
        assert_eq!(cube_face_uv(Vec3::X).0, 0);
        assert_eq!(cube_face_uv(Vec3::NEG_X).0, 1);
        assert_eq!(cube_face_uv(Vec3::Y).0, 2);
        assert_eq!(cube_face_uv(Vec3::NEG_Y).0, 3);
        assert_eq!(cube_face_uv(Vec3::Z).0, 4);
        assert_eq!(cube_face_uv(Vec3::NEG_Z).0, 5);
        // +Z face: +x to the right (s grows), +y up (t shrinks).
        let (_, a) = cube_face_uv(Vec3::new(0.5, 0.5, 1.0));
        assert!(a.x > 0.5 && a.y < 0.5);
        // Zero direction does not produce NaN.
        let (_, z) = cube_face_uv(Vec3::ZERO);
        assert!(z.is_finite());
    }
}
