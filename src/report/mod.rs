pub mod converge;
pub mod stability;
