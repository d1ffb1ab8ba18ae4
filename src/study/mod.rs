//! Process studies (`thermostamp sweep`, docs/study.md): a base forming scenario run over the
//! full factorial of parameter values or over cases sampled from them (a Latin hypercube, a
//! Sobol sequence), each case in its own folder, resumable, and summarised in one table and
//! charts; one study per folder, recorded there.

pub mod design;
pub mod file;
pub mod folder;
pub mod identity;
pub mod run;
pub mod summary;

pub use design::{Design, Method, Sampling};
pub use file::{Case, Parameter, Study, StudyError, Values};
