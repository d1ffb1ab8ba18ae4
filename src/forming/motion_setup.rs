//! The scenario's tool motions applied to the tools built for it: each tool's own `motion`
//! table and the compiled `[[process.stages]]` ([`super::motion`]), with the checks that need
//! the tools' surfaces (a stage that closes to a gap).

use super::motion::{default_direction, stage_plan, MotionTable, StageTools, TOOL_NAMES};
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

/// The scenario's names of the model's tools: punch, die, the holder where there is one, then
/// the extra tools.
pub fn tool_names(s: &Scenario, holder: Option<usize>) -> Vec<String> {
    let standard = TOOL_NAMES[..if holder.is_some() { 3 } else { 2 }].iter();
    standard
        .map(|n| n.to_string())
        .chain(s.extra_tools.iter().map(|t| t.name.clone()))
        .collect()
}

/// One tool as its motion is written: its name, its table's key, the table, its default
/// direction, and its place among the model's tools (none: a holder the scenario lacks).
struct Slot<'a> {
    name: &'a str,
    key: String,
    table: Option<&'a MotionTable>,
    default: Vector3<f64>,
    place: Option<usize>,
}

/// The tools' slots: punch, die, holder, then the extras (after the standard tools).
fn slots<'a>(s: &'a Scenario, standard: usize) -> Vec<Slot<'a>> {
    let mut slots: Vec<Slot> = TOOL_NAMES
        .iter()
        .enumerate()
        .map(|(k, name)| Slot {
            name,
            key: format!("tools.{name}.motion"),
            table: s.motions[k].as_ref(),
            default: default_direction(name),
            place: (k < standard).then_some(k),
        })
        .collect();
    for (i, tool) in s.extra_tools.iter().enumerate() {
        let above = tool.above("").unwrap_or(false);
        slots.push(Slot {
            name: &tool.name,
            key: format!("tools.extra[{}].motion", i + 1),
            table: tool.motion.as_ref(),
            default: if above { -Vector3::z() } else { Vector3::z() },
            place: Some(standard + i),
        });
    }
    slots
}

/// The punch's travel the die must leave room for (mm): the stroke, or where stages move the
/// tools, the punch's own height.
pub fn planned_stroke(s: &Scenario, t: &Tools) -> f64 {
    match s.process.stroke.is_nan() {
        true => 2.0 * t.punch_radius,
        false => s.process.stroke,
    }
}

/// Gives `tools` (punch, die, holder where there is one, the extras; their scenario names
/// `names`, [`tool_names`]) the motions of their `motion` tables and of the stages, `stack` the
/// blank's thickness; the plan where the punch moves along a path rather than the single
/// stroke.
pub fn apply_motions(
    s: &Scenario,
    (tools, names): (&mut [RigidTool], &[String]),
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
    let standard = tools.len() - s.extra_tools.len();
    let mut directions = vec![Vector3::z(); tools.len()];
    for slot in slots(s, standard) {
        let key = &slot.key;
        let Some(k) = slot.place else {
            if slot.table.is_some() {
                return Err(format!(
                    "{key}: the scenario has no holder; give process.blank_holder_gap, where \
                     the holder starts below the blank"
                ));
            }
            continue;
        };
        directions[k] = slot.default;
        let Some(table) = slot.table else { continue };
        let motion = table.motion(key, slot.name, HOLDER_MASS_RATIO * blank_mass)?;
        directions[k] = match &motion {
            Some(ToolMotion::Path(p)) => p.direction(),
            Some(ToolMotion::Force { force, .. }) => force.normalize(),
            _ => table
                .direction
                .map_or(slot.default, |d| Vector3::from(d).normalize()),
        };
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
        if staged.contains(&slot.name) {
            return Err(format!(
                "{key} and process.stages both move the {}: give one",
                slot.name
            ));
        }
        if slot.name == "holder" && s.process.blank_holder_force > 0.0 {
            return Err(format!(
                "{key}: process.blank_holder_force already drives the holder: give one"
            ));
        }
        tools[k].motion = motion;
    }
    let mut spans = Vec::new();
    if !s.process.stages.is_empty() {
        let view = StagedTools {
            tools,
            directions: &directions,
            names,
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
    names: &'a [String],
}

impl StageTools for StagedTools<'_> {
    fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
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
