//! Virtual material tests: deformation histories imposed on the material models.

pub mod kinematics;
pub mod material_point;
