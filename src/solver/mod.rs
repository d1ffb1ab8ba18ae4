//! The solvers of the sheet over one shared [`Model`]: explicit dynamics (docs/model.md §6,
//! central differences with lumped mass, stable step from the current wave speed, optional mass
//! scaling) and quasi-static implicit increments (docs/solver.md). Both advance the same
//! [`State`], report to the same [`Observer`], stop with the same [`SolverError`] and are
//! watched by the same [`checks`]; `explicit` and `implicit` are siblings over those and do not
//! import each other.

pub mod checks;
pub mod energy;
pub mod error;
pub mod estimate;
pub mod explicit;
pub mod heat;
pub mod implicit;
pub mod model;
pub mod observer;
pub mod state;
pub mod threads;
pub mod yarn_damping;

pub use energy::Energies;
pub use error::{CheckStop, SolverError};
pub use explicit::{run, InternalForces, SolverSettings};
pub use model::{Constraint, Model, Motion};
pub use observer::Observer;
pub use state::State;

/// Which solver runs a model (docs/solver.md, "Which solver").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Central differences with lumped mass (`explicit`): the reference, and the tool for fast
    /// events; quasi-static runs need mass or time scaling.
    Explicit,
    /// Quasi-static Newton increments at the physical speed (`implicit`): a scenario's solver
    /// where it does not choose.
    #[default]
    Implicit,
}

impl SolverKind {
    /// From its name in scenario files and on the command line.
    pub fn parse(name: &str) -> Result<Self, String> {
        match name {
            "explicit" => Ok(Self::Explicit),
            "implicit" => Ok(Self::Implicit),
            other => Err(format!(
                "unknown solver \"{other}\": \"explicit\" or \"implicit\""
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Explicit => "explicit",
            Self::Implicit => "implicit",
        }
    }
}
