//! Rigid tools and their contact with the blank (docs/model.md §6): triangulated surfaces, the
//! standard tool shapes, and penalty contact with Coulomb friction.

pub mod blended_surface;
pub mod film_friction;
pub mod penalty;
pub mod ply_contact;
pub mod ply_potential;
pub mod potential;
pub mod rigid_tool;
pub mod stl;
pub mod surface;
pub mod swept_profile;
pub mod tool_path;
pub mod tools;

pub use blended_surface::{BlendedDistance, BlendedSurface};
pub use penalty::{ContactSettings, NodeContact, ToolLoad};
pub use rigid_tool::{NearTriangles, RigidTool, ToolMotion};
pub use stl::{parse_stl, read_stl, write_stl_ascii, write_stl_binary, StlError};
pub use surface::{closest_point_on_triangle, Facing, Footing, Projection, TriangleSurface};
pub use swept_profile::{ProfilePiece, SurfacePoint, SweptProfile};
pub use tool_path::ToolPath;
pub use tools::{
    blank_holder, distance_from_ridge, double_dome_die, double_dome_die_shape, double_dome_holder,
    double_dome_holder_shape, double_dome_matched_die, double_dome_matched_die_shape,
    double_dome_punch, double_dome_punch_shape, hemisphere_die, hemisphere_punch,
    hemisphere_punch_with_skirt, DieShape, MatchedDie,
};
