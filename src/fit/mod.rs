//! Identification of material parameters from test curves (docs/model.md §5).
//!
//! - [`least_squares`]: Levenberg–Marquardt with standard errors and the RMS residual;
//! - [`tension_data`]: the manifest and CSV curves of neat-resin tension tests;
//! - [`matrix`]: `C10(T)`, `eta1(T)` and `D1(T)` of the matrix law;
//! - [`strip_data`], [`fabric_tension`]: strip tension curves and the yarn tension `A_k`;
//! - [`shear`]: shear coefficients `c_k` from bias-extension or picture-frame curves;
//! - [`shear_fe`]: those coefficients refined by the FE bias-extension test in the loop;
//! - [`shear_matrix`]: the matrix layers' share of a shear test's force, subtracted first;
//! - [`card_section`]: the fitted `[matrix]` section and `[fabric] shear` key of a card;
//! - [`card_key`]: one key of a card section replaced in the card's text;
//! - [`synthetic`]: seeded synthetic curves for round-trip checks and examples.

pub mod card_key;
pub mod card_section;
pub mod commands;
pub mod fabric_tension;
pub mod least_squares;
pub mod matrix;
pub mod shear;
pub mod shear_fe;
pub mod shear_matrix;
pub mod strip_data;
pub mod synthetic;
pub mod tension_data;
