//! Finite elements of the sheet.

pub mod membrane_triangle;

pub use membrane_triangle::MembraneTriangle;
