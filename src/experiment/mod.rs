//! Virtual material tests: deformation histories imposed on the material models.

pub mod material_point;
