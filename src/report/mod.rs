pub mod converge;
