//! Finite elements of the sheet.

pub mod bending_triangle;
pub mod membrane_triangle;

pub use bending_triangle::{Bending, BendingRigidity};
pub use membrane_triangle::MembraneTriangle;
