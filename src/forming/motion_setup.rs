//! The scenario's tool motions applied to the tools built for it: each tool's own `motion`
//! table and the compiled `[[process.stages]]` ([`super::motion`]), with the checks that need
//! the tools' surfaces (a stage that closes to a gap).

use super::motion::{default_direction, stage_plan, StageTools, TOOL_NAMES};
use super::scenario::{Scenario, Tools};
use super::setup::HOLDER_MASS_RATIO;
use crate::contact::{RigidTool, ToolMotion, ToolPath};
use crate::experiment::sheet_test::Crosshead;
use nalgebra::Vector3;
use std::sync::Arc;

/// The motions of a run whose tools move along paths: the punch's, the end and the stages.
#[derive(Clone, Debug)]
pub struct MotionPlan {
    pub punch: Option<Arc<ToolPath>>,
    pub end_time: f64,
    /// Each stage's start and end (s) and travel (mm).
    pub stages: Vec<(f64, f64, f64)>,
    /// The fastest tool's top speed (mm/s).
    pub top_speed: f64,
}

impl MotionPlan {
    /// What the explicit run's checks read of the punch: the fastest tool's speed and a ramp
    /// of a twentieth of the run.
    pub fn crosshead(&self) -> Crosshead {
        Crosshead {
            speed: self.top_speed.max(f64::MIN_POSITIVE),
            ramp_time: 0.05 * self.end_time,
        }
    }
}

/// The scenario's names of the model's tools: punch, die and, where there is one, holder.
pub fn tool_names(holder: Option<usize>) -> Vec<&'static str> {
    TOOL_NAMES[..if holder.is_some() { 3 } else { 2 }].to_vec()
}

/// The punch's travel the die must leave room for (mm): the stroke, or where stages move the
/// tools, the punch's own height.
pub fn planned_stroke(s: &Scenario, t: &Tools) -> f64 {
    match s.process.stroke.is_nan() {
        true => 2.0 * t.punch_radius,
        false => s.process.stroke,
    }
}

/// Gives `tools` (punch, die, holder where there is one) the motions of their `motion` tables
/// and of the stages, `stack` the blank's thickness; the plan where the punch moves along a
/// path rather than the single stroke.
pub fn apply_motions(
    s: &Scenario,
    tools: &mut [RigidTool],
    stack: f64,
    blank_mass: f64,
) -> Result<Option<MotionPlan>, String> {
    let staged: Vec<&str> = s
        .process
        .stages
        .iter()
        .flat_map(|st| st.tools.iter().map(String::as_str))
        .collect();
    if s.moves_by_paths() {
        // no single stroke: the punch stands still unless its table or a stage moves it
        tools[0].motion = ToolMotion::Fixed;
    }
    let mut directions: Vec<Vector3<f64>> = Vec::with_capacity(tools.len());
    for (k, name) in TOOL_NAMES.iter().enumerate() {
        let key = format!("tools.{name}.motion");
        let Some(table) = &s.motions[k] else {
            directions.push(default_direction(name));
            continue;
        };
        if k >= tools.len() {
            return Err(format!(
                "{key}: the scenario has no holder; give process.blank_holder_gap, where the \
                 holder starts below the blank"
            ));
        }
        let motion = table.motion(&key, name, HOLDER_MASS_RATIO * blank_mass)?;
        directions.push(match &motion {
            Some(ToolMotion::Path(p)) => p.direction(),
            Some(ToolMotion::Force { force, .. }) => force.normalize(),
            _ => table
                .direction
                .map_or(default_direction(name), |d| Vector3::from(d).normalize()),
        });
        if let Some(start) = table.start {
            if !start.is_finite() {
                return Err(format!("{key}.start must be a finite number (mm)"));
            }
            let by = directions[k] * start;
            tools[k] = tools[k]
                .moved(by)
                .map_err(|e| format!("{key}.start: {e}"))?;
        }
        let Some(motion) = motion else { continue };
        if staged.contains(name) {
            return Err(format!(
                "{key} and process.stages both move the {name}: give one"
            ));
        }
        if k == 2 && s.process.blank_holder_force > 0.0 {
            return Err(format!(
                "{key}: process.blank_holder_force already drives the holder: give one"
            ));
        }
        tools[k].motion = motion;
    }
    directions.truncate(tools.len());
    let mut spans = Vec::new();
    if !s.process.stages.is_empty() {
        let view = StagedTools {
            tools,
            directions: &directions,
        };
        let plan = stage_plan(&s.process.stages, &view, tools.len(), stack)?;
        spans = plan.stages;
        for (tool, path) in tools.iter_mut().zip(plan.paths) {
            if let Some(path) = path {
                tool.motion = ToolMotion::Path(Arc::new(path));
            }
        }
    }
    if !s.moves_by_paths() {
        return Ok(None);
    }
    if s.process.time_scaling != 1.0 {
        return Err(
            "process.time_scaling runs the single stroke faster; with stages or motion tables \
             give the times you want the explicit solver to run, or mass scaling \
             (process.target_time_step)"
                .into(),
        );
    }
    let paths: Vec<&ToolPath> = tools
        .iter()
        .filter_map(|t| match &t.motion {
            ToolMotion::Path(p) => Some(p.as_ref()),
            _ => None,
        })
        .collect();
    let punch = match &tools[0].motion {
        ToolMotion::Path(p) => Some(p.clone()),
        _ => None,
    };
    Ok(Some(MotionPlan {
        punch,
        end_time: paths.iter().map(|p| p.end_time()).fold(0.0, f64::max),
        stages: spans,
        top_speed: paths.iter().map(|p| p.top_speed()).fold(0.0, f64::max),
    }))
}

/// The tools as the stages see them.
struct StagedTools<'a> {
    tools: &'a [RigidTool],
    directions: &'a [Vector3<f64>],
}

impl StageTools for StagedTools<'_> {
    fn index(&self, name: &str) -> Option<usize> {
        TOOL_NAMES[..self.tools.len()]
            .iter()
            .position(|n| *n == name)
    }

    fn direction(&self, tool: usize) -> Vector3<f64> {
        self.directions[tool]
    }

    fn force_driven(&self, tool: usize) -> bool {
        matches!(self.tools[tool].motion, ToolMotion::Force { .. })
    }

    fn travel_to_gap(
        &self,
        tool: usize,
        other: usize,
        at: &[Vector3<f64>],
        gap: f64,
    ) -> Option<f64> {
        let (lo, hi) = self.tools[tool].surface.bounds();
        let (olo, ohi) = self.tools[other].surface.bounds();
        let reach = (hi - lo).norm() + (ohi - olo).norm();
        super::motion::closing_travel(
            (&self.tools[tool], at[tool]),
            self.directions[tool],
            (&self.tools[other], at[other]),
            gap,
            reach,
        )
    }
}
