//! Finite elements of the sheet.

pub mod bending;
pub mod membrane;

pub use bending::{Bending, BendingRigidity};
pub use membrane::MembraneElement;
