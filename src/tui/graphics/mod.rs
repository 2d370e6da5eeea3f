//! The viewport's picture on the terminal: `symbols` fits block symbols
//! and two colours to each cell.

pub mod symbols;
