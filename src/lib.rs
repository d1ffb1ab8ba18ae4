//! thermostamp — thermo-stamping simulation of woven-fabric-reinforced thermoplastic prepregs
//! with the lamination model of Gong et al., Composite Structures 2018 (see `docs/model.md`).
//!
//! Units everywhere: mm, N, s, MPa, tonne/mm^3, °C.
//!
//! - [`material`]: constitutive laws of the layers and the A:B:A laminate, material cards;
//! - [`experiment`]: virtual material tests, starting with the material-point driver;
//! - [`contact`]: rigid tools (triangulated surfaces) and their contact with the blank;
//! - [`fit`]: identification of material parameters from test curves (`thermostamp fit`);
//! - [`drape`]: kinematic (pin-jointed net) draping, a quick shear preview before forming;
//! - [`support`]: gravity, springs and grippers holding the blank;
//! - [`forming`]: thermo-stamping runs from a scenario file (blank, tools, process);
//! - [`io`]: readers and writers of the files users hand in and get back;
//! - [`limits`]: the range of every number a user gives, and how numbers show in messages;
//! - [`cli`]: the `thermostamp` command line.

pub mod cli;
pub mod contact;
pub mod drape;
pub mod element;
pub mod experiment;
pub mod fit;
pub mod forming;
pub mod io;
pub mod limits;
pub mod material;
pub mod mesh;
pub mod solver;
pub mod study;
pub mod support;
pub mod thermal;
