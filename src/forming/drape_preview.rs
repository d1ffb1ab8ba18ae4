//! The kinematic draping preview of a forming scenario (`thermostamp drape`): the pin-jointed
//! net of the blank's fabric laid on the part of the punch that the stroke forms, in seconds,
//! with the same shear-angle outputs as a forming run.

use super::scenario::Scenario;
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

/// Drapes the scenario's fabric (cells of the blank's element size, warp at its ply angle)
/// from the punch's apex over the formed cap.
pub fn drape_preview(s: &Scenario) -> Result<DrapeResult, String> {
    let surface = FormedCap {
        dome: DoubleDome {
            radius: s.tools.punch_radius,
            half_length: s.ridge_half_length(),
        },
        depth: s.process.stroke.min(s.tools.punch_radius),
    };
    let cell = s.blank.element_size;
    let reach = 0.5 * std::f64::consts::PI * s.tools.punch_radius + s.ridge_half_length();
    let params = DrapeParams {
        cell,
        start: (0.0, 0.0),
        warp_angle_deg: s.blank.ply_angle,
        max_cells: (reach / cell).ceil() as usize + 1,
    };
    drape(&surface, &params)
}
