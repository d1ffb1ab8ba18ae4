//! The kinematic draping preview of a forming scenario (`thermostamp drape`): the pin-jointed
//! net of the blank's fabric laid on the part of the punch that the stroke forms, in seconds,
//! with the same shear-angle outputs as a forming run.

use super::scenario::{BlankShape, Scenario};
use super::setup::blank_mesh;
use crate::drape::{drape, DoubleDome, DrapeParams, DrapeResult, DrapeSurface};

/// The punch of the scenario (hemisphere or double dome) down to the stroke's depth: the part
/// of the dome the blank is pressed onto (the preview ignores the wall between punch and die).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormedCap {
    pub dome: DoubleDome,
    /// Depth below the apex where the formed part ends (mm).
    pub depth: f64,
}

impl DrapeSurface for FormedCap {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.dome.height(x, y).filter(|z| *z >= -self.depth)
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        self.height(x, y)?;
        self.dome.gradient(x, y)
    }
}

/// Where the net starts and how it is oriented.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Generators {
    /// Start point in plan (mm): where the two generators cross.
    pub start: (f64, f64),
    /// Plan angle of the warp generator from x (degrees); the weft is at +90°.
    pub warp_angle: f64,
}

impl Generators {
    /// From the punch's apex (the middle of the ridge), warp at the blank's ply angle: the
    /// net a blank centred on the punch makes.
    pub fn of(s: &Scenario) -> Self {
        Self {
            start: (0.0, 0.0),
            warp_angle: s.blank.ply_angle,
        }
    }
}

/// Drapes the scenario's fabric (cells of the blank's element size) from the generators'
/// start over the formed cap.
/// A blank read from a file is draped with cells of its element size (`Mesh::element_size`).
pub fn drape_preview(s: &Scenario, generators: &Generators) -> Result<DrapeResult, String> {
    let tools = s.built_in_tools("the drape preview")?;
    let surface = FormedCap {
        dome: DoubleDome {
            radius: tools.punch_radius,
            half_length: tools.ridge_half_length(),
        },
        depth: s.process.stroke.min(tools.punch_radius),
    };
    let cell = match s.blank.shape {
        BlankShape::Rectangle { element_size, .. } => element_size,
        BlankShape::File { .. } => blank_mesh(s)?.0.element_size(),
    };
    let (x0, y0) = generators.start;
    let reach =
        0.5 * std::f64::consts::PI * tools.punch_radius + tools.ridge_half_length() + x0.hypot(y0);
    let params = DrapeParams {
        cell,
        start: generators.start,
        warp_angle_deg: generators.warp_angle,
        max_cells: (reach / cell).ceil() as usize + 1,
    };
    drape(&surface, &params)
}
