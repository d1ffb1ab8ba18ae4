//! Thermo-stamping runs (MODEL.md §6): a scenario file, the model it describes (blank, card,
//! tools), and the run with its histories.

pub mod drape_preview;
pub mod run;
pub mod scenario;
pub mod setup;

pub use run::{FormingRecord, FormingRun, Wrinkles};
pub use scenario::{Scenario, ScenarioError};
pub use setup::FormingModel;
