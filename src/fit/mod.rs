//! Identification of material parameters from test curves (MODEL.md §5).
//!
//! - [`least_squares`]: Levenberg–Marquardt with standard errors and the RMS residual;
//! - [`tension_data`]: the manifest and CSV curves of neat-resin tension tests;
//! - [`matrix`]: `C10(T)`, `eta1(T)` and `D1(T)` of the matrix law;
//! - [`card_section`]: the fitted `[matrix]` section of a material card;
//! - [`synthetic`]: seeded synthetic curves for round-trip checks and examples.
//!
//! Fabric tension and shear fits (`fit fabric-tension`, `fit shear`) are to come.

pub mod card_section;
pub mod least_squares;
pub mod matrix;
pub mod synthetic;
pub mod tension_data;
