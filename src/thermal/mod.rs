//! Heat in the blank of a non-isothermal run (docs/model.md §9): each node of the shell carries
//! a column of cells through its ply's thickness (the thin-shell split), so that a matrix skin
//! on a cold tool cools before the fabric under it; the columns conduct in the plane along the
//! yarns, exchange heat with the tools, the room and the neighbouring plies, and release the
//! latent heat of the crystallising matrix.
//!
//! - [`properties`]: a ply's thermal card (specific heat, conductivities, crystallisation);
//! - [`column`]: conduction through the thickness of one column (Eqs. (H3)–(H4));
//! - [`in_plane`]: conduction in the plane of the deforming shell, along the yarns (H2);
//! - [`air`]: convection and radiation to the room (H5);
//! - [`crystallisation`]: Nakamura's kinetics (H7);
//! - [`blank`]: the field over the whole blank and its heat account (H10).

pub mod air;
pub mod blank;
pub mod column;
pub mod crystallisation;
pub mod in_plane;
pub mod properties;

pub use blank::{BlankHeat, HeatAccount, ThermalState};
pub use properties::ThermalProperties;
