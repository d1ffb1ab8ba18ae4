//! The kinematic draping preview of a forming scenario (`thermostamp drape`): the pin-jointed
//! net of the blank's fabric laid on the part of the punch that the stroke forms, in seconds,
//! with the same shear-angle outputs as a forming run.

use super::scenario::Scenario;
use crate::drape::{drape, DrapeParams, DrapeResult, DrapeSurface, Hemisphere};

/// The hemispherical punch of the scenario down to the stroke's depth: the part of the dome
/// the blank is pressed onto (the preview ignores the wall between punch and die).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormedCap {
    pub dome: Hemisphere,
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
        dome: Hemisphere {
            radius: s.tools.punch_radius,
        },
        depth: s.process.stroke.min(s.tools.punch_radius),
    };
    let cell = s.blank.element_size;
    let reach = 0.5 * std::f64::consts::PI * s.tools.punch_radius;
    let params = DrapeParams {
        cell,
        start: (0.0, 0.0),
        warp_angle_deg: s.blank.ply_angle,
        max_cells: (reach / cell).ceil() as usize + 1,
    };
    drape(&surface, &params)
}
