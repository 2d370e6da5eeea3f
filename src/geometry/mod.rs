//! Geometric primitives that know nothing of scenes, BVHs or the UI.

pub(crate) mod aabb;
pub mod offset;
pub mod ray;
pub mod sampling;
pub mod triangle;

pub use aabb::Aabb;
pub use ray::Ray;

/// The largest coordinate magnitude rayterm renders. Shading works in f32
/// and squares lengths (normalising the direction to a light, a reflected
/// ray, the camera's view), which overflows beyond about 1.8e19 for the
/// difference of two points; this leaves room for sums of three squares.
/// The triangle test itself works far beyond it (in f64 where needed).
pub(crate) const MAX_COORDINATE: f32 = 1e18;

/// pbrt's γₙ = n u / (1 - n u), with u the unit roundoff: the relative error
/// bound of n chained floating-point operations.
#[inline(always)]
pub(crate) const fn gamma(n: i32) -> f32 {
    let nu = n as f32 * f32::EPSILON * 0.5;
    nu / (1.0 - nu)
}
