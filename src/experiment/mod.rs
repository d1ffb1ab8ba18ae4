//! Virtual material tests: deformation histories imposed on the material models.

pub mod bias_extension;
pub mod ideal_net;
pub mod kinematics;
pub mod material_point;
pub mod picture_frame;
pub mod sheet_test;
pub mod uniaxial;
pub mod virtual_test;
