//! Geometric primitives that know nothing of scenes, BVHs or the UI.

pub mod aabb;
pub mod offset;
pub mod ray;
pub mod sampling;
pub mod triangle;

pub use aabb::Aabb;
pub use ray::Ray;

/// pbrt's γₙ = n u / (1 - n u), with u the unit roundoff: the relative error
/// bound of n chained floating-point operations.
#[inline(always)]
pub const fn gamma(n: i32) -> f32 {
    let nu = n as f32 * f32::EPSILON * 0.5;
    nu / (1.0 - nu)
}
