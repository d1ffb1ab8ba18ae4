//! From a scenario to a model: the meshed blank on its card, and the tools placed around it.
//!
//! Conventions of `contact::tools`: stroke axis z, blank mid-plane in z = 0 at the start, the
//! punch below moving up, the die above, the holder below around the punch. Each tool is
//! moved off the mid-plane by half the blank's thickness, so that it touches a face of the
//! blank at the start.

use super::scenario::Scenario;
use crate::contact::{
    distance_from_ridge, double_dome_die, double_dome_holder, double_dome_punch, ContactSettings,
    DieShape, RigidTool, ToolMotion, TriangleSurface,
};
use crate::experiment::sheet_test::Crosshead;
use crate::material::MaterialCard;
use crate::mesh::rectangle;
use crate::solver::{Model, SolverSettings};
use nalgebra::Vector3;
use std::sync::Arc;

/// Contact penalty `s` of `k = s m / dt^2` (MODEL.md §6).
const PENALTY_SCALE: f64 = 0.1;

/// The holder's inertia in blank masses: heavy enough to stay stable on the contact springs of
/// every node it touches, light enough to follow the flange.
const HOLDER_MASS_RATIO: f64 = 10.0;

/// A scenario made ready to run.
pub struct FormingModel {
    pub model: Model,
    pub card: MaterialCard,
    pub punch: Crosshead,
    pub settings: SolverSettings,
    /// Distance from the punch's ridge (axis) beyond which the blank lies on the die's flat
    /// face: the flange (mm).
    pub flange_radius: f64,
    /// Half-length of the punch's ridge (mm); 0 for a hemisphere.
    pub ridge_half_length: f64,
    /// Target element size of the blank (mm).
    pub element_size: f64,
    /// Indices of the punch, die and holder (if any) in `model.tools`.
    pub punch_tool: usize,
    pub die_tool: usize,
    pub holder_tool: Option<usize>,
}

impl FormingModel {
    pub fn new(s: &Scenario) -> Result<Self, String> {
        let card = MaterialCard::load(&s.blank.card).map_err(|e| e.to_string())?;
        let thickness = card.laminate.reference_thickness();
        let clearance = s.tools.die_opening_radius - s.tools.punch_radius;
        if clearance < thickness {
            return Err(format!(
                "{}: the die opening leaves {clearance} mm around the punch, less than the ply's \
                 {thickness} mm",
                s.origin
            ));
        }
        let (b, p) = (&s.blank, &s.process);
        let cells = |side: f64| (side / b.element_size).round().max(1.0) as usize;
        let mesh = rectangle(
            b.width,
            b.length,
            cells(b.width),
            cells(b.length),
            b.pattern,
        );
        let angle = b.ply_angle.to_radians();
        let mut model = Model::new(
            mesh,
            card.laminate.time_scaled(p.time_scaling),
            card.density,
            p.temperature,
            Vector3::new(angle.cos(), angle.sin(), 0.0),
            Vec::new(),
        )
        .map_err(|e| e.to_string())?;
        if let Some(rigidity) = card.bending {
            model = model.with_bending(rigidity).map_err(|e| e.to_string())?;
        }
        let simulated = p.punch_speed * p.time_scaling;
        let punch = Crosshead {
            speed: simulated,
            ramp_time: 0.05 * p.stroke / simulated,
        };
        let blank_mass = card.density * thickness * b.width * b.length;
        let (tools, holder_tool) = tool_set(s, thickness, punch, blank_mass)?;
        let contact = ContactSettings {
            offset: 0.5 * thickness,
            penalty_scale: PENALTY_SCALE,
            max_penetration: thickness,
        };
        let model = model.with_tools(tools, contact);
        let end_time = punch.time_to(p.stroke);
        let settings = SolverSettings {
            end_time,
            time_step_safety: 0.9,
            target_time_step: p.target_time_step,
            output_interval: end_time / s.output.history_points as f64,
            damping: 0.0,
            yarn_damping: 0.06,
        };
        Ok(Self {
            model,
            card,
            punch,
            settings,
            flange_radius: s.tools.die_opening_radius + s.tools.die_fillet_radius,
            ridge_half_length: s.ridge_half_length(),
            element_size: s.blank.element_size,
            punch_tool: 0,
            die_tool: 1,
            holder_tool,
        })
    }
}

impl FormingModel {
    /// Distance of a point of the blank from the punch's ridge (axis) in the x-y plane (mm).
    pub fn distance_from_ridge(&self, x: &Vector3<f64>) -> f64 {
        distance_from_ridge(self.ridge_half_length, x.x, x.y)
    }

    /// Whether a point of the blank (current position) lies over the die's flat face.
    pub fn in_flange(&self, x: &Vector3<f64>) -> bool {
        self.distance_from_ridge(x) > self.flange_radius
    }

    /// Which band around the part a flange point lies in: bands one element size wide,
    /// counted outward from the flange's inner edge (see `run::Wrinkles`).
    pub fn flange_band(&self, x: &Vector3<f64>) -> usize {
        let beyond = self.distance_from_ridge(x) - self.flange_radius;
        (beyond.max(0.0) / self.element_size).floor() as usize
    }
}

/// Punch, die and (with a blank-holder force) holder, placed off the blank's faces.
fn tool_set(
    s: &Scenario,
    thickness: f64,
    punch: Crosshead,
    blank_mass: f64,
) -> Result<(Vec<RigidTool>, Option<usize>), String> {
    let t = &s.tools;
    let half = 0.5 * thickness;
    let ridge = s.ridge_half_length();
    let outer = s.distance_from_ridge(0.5 * s.blank.width, 0.5 * s.blank.length) + 10.0;
    let depth = s.process.stroke + t.die_fillet_radius + 10.0;
    let shifted = |surface: TriangleSurface, dz: f64| TriangleSurface {
        vertices: surface
            .vertices
            .into_iter()
            .map(|v| v + Vector3::new(0.0, 0.0, dz))
            .collect(),
        ..surface
    };
    let skirt = t.punch_radius;
    let punch_surface = shifted(
        double_dome_punch(ridge, t.punch_radius, skirt, t.resolution)?,
        -half,
    );
    let die = DieShape {
        opening_radius: t.die_opening_radius,
        fillet_radius: t.die_fillet_radius,
        outer_radius: outer,
        depth,
    };
    let die_surface = shifted(double_dome_die(ridge, &die, t.resolution)?, half);
    let friction = &s.process.friction;
    let punch_motion = ToolMotion::Velocity(Arc::new(move |time| {
        Vector3::new(0.0, 0.0, punch.velocity(time))
    }));
    let mut tools = vec![
        RigidTool::new(
            "punch",
            punch_surface,
            punch_motion,
            friction.punch,
            thickness,
        )?,
        RigidTool::new(
            "die",
            die_surface,
            ToolMotion::Fixed,
            friction.die,
            thickness,
        )?,
    ];
    let (holder_motion, gap) = match (s.process.blank_holder_gap, s.process.blank_holder_force) {
        (Some(gap), _) => (ToolMotion::Fixed, gap),
        (None, force) if force > 0.0 => (
            ToolMotion::Force {
                force: Vector3::new(0.0, 0.0, force),
                mass: HOLDER_MASS_RATIO * blank_mass,
            },
            0.0,
        ),
        (None, _) => return Ok((tools, None)),
    };
    let holder_surface = shifted(
        double_dome_holder(ridge, s.holder_inner_radius(), outer, t.resolution)?,
        -half - gap,
    );
    tools.push(RigidTool::new(
        "blank holder",
        holder_surface,
        holder_motion,
        friction.holder,
        thickness,
    )?);
    Ok((tools, Some(2)))
}
