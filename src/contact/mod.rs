//! Rigid tools and their contact with the blank (MODEL.md §6): triangulated surfaces, the
//! standard tool shapes, and penalty contact with Coulomb friction.

pub mod surface;

pub use surface::{closest_point_on_triangle, Projection, TriangleSurface};
