//! The common shapes of a binary PLY read on every core: a vertex element
//! of scalars and a face element of triangles are fixed-size records, so
//! each core can take a run of them. Anything else, and any record this
//! reading does not take as it stands (a polygon, an index out of range,
//! an unusable or absurd number, a property given twice), is left to the
//! value-by-value reader, which reads the element again and says what is
//! wrong and where.

use std::sync::atomic::{AtomicBool, Ordering};

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::{Element, Kind, Role, Scalar};
use crate::color::srgb_to_linear;
use crate::scene::load::numbers::{self, ABSURD};

/// Records a core takes at a time, at least.
const RUN: usize = 1 << 14;

/// Scalar `t` at the start of `b`, in the file's byte order.
#[inline(always)]
pub(crate) fn scalar(b: &[u8], t: Scalar, big: bool) -> f64 {
    macro_rules! read {
        ($ty:ty) => {{
            let a = b[..std::mem::size_of::<$ty>()].try_into().unwrap();
            (if big {
                <$ty>::from_be_bytes(a)
            } else {
                <$ty>::from_le_bytes(a)
            }) as f64
        }};
    }
    match t {
        Scalar::I8 => read!(i8),
        Scalar::U8 => read!(u8),
        Scalar::I16 => read!(i16),
        Scalar::U16 => read!(u16),
        Scalar::I32 => read!(i32),
        Scalar::U32 => read!(u32),
        Scalar::F32 => read!(f32),
        Scalar::F64 => read!(f64),
    }
}

/// An element read in bulk.
pub(crate) enum Read {
    Vertices(Vertices),
    Triangles(Vec<[u32; 3]>),
}

/// What a vertex element holds; the optional attributes empty where absent.
pub(crate) struct Vertices {
    pub(crate) positions: Vec<DVec3>,
    pub(crate) normals: Vec<DVec3>,
    pub(crate) uvs: Vec<Vec2>,
    pub(crate) colors: Vec<Vec3>,
}

/// The vertex element `e`, whose records start `body`, and the bytes they
/// take; `None` where the value-by-value reader must read it.
/// `color_full` is the value of full intensity of its colours.
pub(crate) fn vertices(
    e: &Element,
    body: &[u8],
    big: bool,
    color_full: f64,
) -> Option<(Read, usize)> {
    let mut fields = Vec::with_capacity(e.props.len());
    let mut stride = 0;
    for p in &e.props {
        let Kind::Scalar(t) = p.kind else {
            return None;
        };
        fields.push((stride, t, p.role));
        stride += t.size();
    }
    let len = stride.checked_mul(usize::try_from(e.count).ok()?)?;
    let records = body.get(..len)?;
    // The fields of one role, by component: all of them, once each.
    fn group<const N: usize>(
        fields: &[(usize, Scalar, Role)],
        which: impl Fn(Role) -> Option<usize>,
    ) -> Option<Option<[(usize, Scalar); N]>> {
        let mut at = [None; N];
        let mut n = 0;
        for &(offset, t, role) in fields {
            if let Some(k) = which(role) {
                if at[k].replace((offset, t)).is_some() {
                    return None;
                }
                n += 1;
            }
        }
        match n {
            0 => Some(None),
            _ if n == N => Some(Some(at.map(|a| a.unwrap()))),
            _ => None,
        }
    }
    if fields.iter().any(|f| {
        !matches!(
            f.2,
            Role::Ignored | Role::Position(_) | Role::Normal(_) | Role::Uv(_) | Role::Color(_)
        )
    }) {
        return None;
    }
    let position = group::<3>(&fields, |r| match r {
        Role::Position(k) => Some(k),
        _ => None,
    })??;
    let normal = group::<3>(&fields, |r| match r {
        Role::Normal(k) => Some(k),
        _ => None,
    })?;
    let uv = group::<2>(&fields, |r| match r {
        Role::Uv(k) => Some(k),
        _ => None,
    })?;
    let color = group::<3>(&fields, |r| match r {
        Role::Color(k) => Some(k),
        _ => None,
    })?;
    let usable = |x: f64| numbers::unusable(x).is_none();
    let positions = column(
        records,
        stride,
        big,
        position,
        |x| usable(x) && x.abs() <= ABSURD,
        DVec3::from_array,
    )?;
    let normals = match normal {
        Some(at) => column(records, stride, big, at, usable, DVec3::from_array)?,
        None => Vec::new(),
    };
    let uvs = match uv {
        Some(at) => column(records, stride, big, at, usable, |[u, v]| {
            Vec2::new(u as f32, v as f32)
        })?,
        None => Vec::new(),
    };
    let colors = match color {
        Some(at) => column(records, stride, big, at, usable, |c| {
            Vec3::from_array(c.map(|c| srgb_to_linear((c / color_full).clamp(0.0, 1.0) as f32)))
        })?,
        None => Vec::new(),
    };
    let v = Vertices {
        positions,
        normals,
        uvs,
        colors,
    };
    Some((Read::Vertices(v), len))
}

/// One attribute of every record of `records`, the fields `at` of each
/// made a `T` by `make`, on every core; `None` if `keep` refuses a value.
fn column<const N: usize, T: Send>(
    records: &[u8],
    stride: usize,
    big: bool,
    at: [(usize, Scalar); N],
    keep: impl Fn(f64) -> bool + Sync,
    make: impl Fn([f64; N]) -> T + Sync,
) -> Option<Vec<T>> {
    let refused = AtomicBool::new(false);
    let mut out = Vec::new();
    records
        .par_chunks_exact(stride)
        .with_min_len(RUN)
        .map(|r| {
            let v = at.map(|(offset, t)| scalar(&r[offset..], t, big));
            if !v.iter().all(|&x| keep(x)) {
                refused.store(true, Ordering::Relaxed);
            }
            make(v)
        })
        .collect_into_vec(&mut out);
    (!refused.into_inner()).then_some(out)
}

/// The face element `e` of one list of vertex indices, every face a
/// triangle, whose records start `body`, and the bytes they take; `None`
/// where the value-by-value reader must read it.
pub(crate) fn triangles(
    e: &Element,
    body: &[u8],
    big: bool,
    vertex_count: usize,
) -> Option<(Read, usize)> {
    let [p] = &e.props[..] else {
        return None;
    };
    let (Kind::List(count, item), Role::Indices) = (p.kind, p.role) else {
        return None;
    };
    let (head, size) = (count.size(), item.size());
    let stride = head + 3 * size;
    let len = stride.checked_mul(usize::try_from(e.count).ok()?)?;
    let records = body.get(..len)?;
    let refused = AtomicBool::new(false);
    let mut triangles = Vec::new();
    records
        .par_chunks_exact(stride)
        .with_min_len(RUN)
        .map(|r| {
            // Every record is a triangle if each one read as if all were
            // says so: the first is where it would be, and so on.
            let i = [0, 1, 2].map(|k| scalar(&r[head + k * size..], item, big));
            let fits = |i: f64| i >= 0.0 && i < vertex_count as f64;
            if scalar(r, count, big) != 3.0 || !i.iter().all(|&i| fits(i)) {
                refused.store(true, Ordering::Relaxed);
            }
            i.map(|i| i as u32)
        })
        .collect_into_vec(&mut triangles);
    (!refused.into_inner()).then_some((Read::Triangles(triangles), len))
}
