//! Images as data: drawing onto them.

pub mod canvas;
