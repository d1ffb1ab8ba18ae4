//! The flat blank outline that gives a trimmed part (`thermostamp blank-outline`): which
//! outline to cut so that the formed part covers a trim line with a margin.
//!
//! The trim line ([`trim`]) is mapped back onto the flat blank, first through the kinematic
//! drape of the fabric on the punch ([`mapping::flat_from_drape`]), and offset outward by the
//! margin ([`polygon::offset_mitre`]): the first outline. Each iteration ([`iterate`]) meshes
//! the blank to the outline ([`mesher`]), runs the forming, maps the trim line back through
//! the formed blank ([`mapping::flat_from_formed`]) and measures each trim point's distance
//! inside the blank's edge on the flat blank (the distance along the part, up to the fabric's
//! stretch); the next outline is that mapped line offset by the margin. It stops when every
//! point's margin is within the tolerance of the one asked for, or after the iterations
//! asked for.

pub mod iterate;
pub mod mapping;
pub mod mesher;
pub mod polygon;
pub mod trim;

pub use iterate::{iterate, Coverage, IterationRecord, OutlineResult, OutlineSettings};
pub use trim::{read_trim_csv, trim_circle, TrimLine};
