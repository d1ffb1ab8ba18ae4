//! Explicit dynamics of the sheet (docs/model.md §6): central differences with lumped mass, stable
//! step from the current wave speed, optional mass scaling, energy bookkeeping.

pub mod checks;
pub mod energy;
pub mod estimate;
pub mod explicit;
pub mod model;
pub mod yarn_damping;

pub use energy::Energies;
pub use explicit::{run, InternalForces, Observer, SolverError, SolverSettings, State};
pub use model::{Constraint, Model, Motion};
