//! The 32-byte node.

use crate::geometry::Aabb;
use glam::Vec3;

/// Interior nodes have `count == 0` and children at `first` and `first + 1`;
/// leaves hold triangles `first .. first + count` of the leaf order.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub struct Node {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);

impl Node {
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from(self.min),
            max: Vec3::from(self.max),
        }
    }
}
