pub mod stability;
