//! Thermo-stamping runs (docs/model.md §6): a scenario file, the model it describes (blank, card,
//! tools), the run with its histories, and the formed blank written for the next analysis.

pub mod advice;
pub mod drape_preview;
pub mod export;
pub mod heat;
pub mod layup;
pub mod motion;
pub mod motion_setup;
pub mod outline;
pub mod output;
pub mod pictures;
pub mod preflight;
pub mod run;
pub mod scenario;
pub mod setup;
pub mod supports;

pub use run::{FormingRecord, FormingRun, Wrinkles};
pub use scenario::{Scenario, ScenarioError};
pub use setup::FormingModel;
