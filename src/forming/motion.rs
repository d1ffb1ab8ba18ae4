//! How the tools of a scenario move (docs/guide/scenario.md, "Tool motions"): a tool's own
//! `motion` table (a displacement or speed table along its direction, or a force), or the press's
//! `[[process.stages]]`, each moving some tools by a travel or until a gap to another tool, at a
//! speed. Stages are compiled into one path per tool, so both solvers see tools moved by
//! [`ToolMotion::Path`].

use crate::contact::{RigidTool, ToolMotion, ToolPath};
use crate::limits::shown;
use nalgebra::Vector3;
use serde::Deserialize;
use std::sync::Arc;

/// Fraction of a stage's duration over which its speed rises from 0 and falls back: the
/// smooth start of the single stroke (`Crosshead`), which keeps the first stress wave of an
/// explicit run from ringing.
const RAMP_FRACTION: f64 = 0.05;

/// `tools.<tool>.motion` as written.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionTable {
    /// Direction of travel (any length); the tool's default where not given.
    pub direction: Option<[f64; 3]>,
    /// `[[time, displacement], ...]` (s, mm).
    pub displacement: Option<Vec<[f64; 2]>>,
    /// `[[time, speed], ...]` (s, mm/s).
    pub speed: Option<Vec<[f64; 2]>>,
    /// A constant force (N) pushing the tool along its direction.
    pub force: Option<f64>,
    /// Where the tool starts along its direction (mm) from where the scenario places it (a
    /// negative value: back from touching the blank); 0 by default.
    pub start: Option<f64>,
}

/// One `[[process.stages]]` table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stage {
    pub name: Option<String>,
    /// The tools that move in it: "punch", "die", "holder".
    pub tools: Vec<String>,
    /// Their speed along their directions (mm/s).
    pub speed: f64,
    /// How far they move (mm) ...
    pub travel: Option<f64>,
    /// ... or until the gap between the one tool moving and this one is `gap` (mm; the stack's
    /// thickness by default).
    pub close_to: Option<String>,
    pub gap: Option<f64>,
}

/// The tool names the scenario knows, in the order of the model's tools.
pub const TOOL_NAMES: [&str; 3] = ["punch", "die", "holder"];

/// Each tool's default direction of travel: the punch up, the die down, the holder up.
pub fn default_direction(tool: &str) -> Vector3<f64> {
    match tool {
        "die" => -Vector3::z(),
        _ => Vector3::z(),
    }
}

impl MotionTable {
    /// The tool's direction (unit), `key` its table.
    fn direction(&self, key: &str, tool: &str) -> Result<Vector3<f64>, String> {
        let Some(d) = self.direction else {
            return Ok(default_direction(tool));
        };
        let d = Vector3::from(d);
        let length = d.norm();
        if !(length.is_finite() && length > 0.0) {
            return Err(format!("{key}.direction must be a finite vector, not zero"));
        }
        Ok(d / length)
    }

    /// The motion it asks for, `key` its table; `None` where it gives a direction only (the
    /// tool moves in stages).
    pub fn motion(&self, key: &str, tool: &str, mass: f64) -> Result<Option<ToolMotion>, String> {
        let direction = self.direction(key, tool)?;
        let path = |p: Result<ToolPath, String>| {
            p.map(|p| Some(ToolMotion::Path(Arc::new(p))))
                .map_err(|e| format!("{key}: {e}"))
        };
        match (&self.displacement, &self.speed, self.force) {
            (Some(table), None, None) => path(ToolPath::from_displacements(direction, table)),
            (None, Some(table), None) => path(ToolPath::from_speeds(direction, table)),
            (None, None, Some(force)) if force.is_finite() && force > 0.0 => {
                Ok(Some(ToolMotion::Force {
                    force: direction * force,
                    mass,
                }))
            }
            (None, None, Some(force)) => Err(format!(
                "{key}.force = {} N must be positive: it pushes the tool along {key}.direction",
                shown(force)
            )),
            (None, None, None) => Ok(None),
            _ => Err(format!(
                "{key} gives more than one of displacement, speed and force: give one"
            )),
        }
    }
}

/// What the stages need of the tools: each one's direction, whether a force drives it, and the
/// travel that brings it to a gap with another.
pub trait StageTools {
    /// The index of tool `name` in the model, if the scenario has it.
    fn index(&self, name: &str) -> Option<usize>;
    fn direction(&self, tool: usize) -> Vector3<f64>;
    fn force_driven(&self, tool: usize) -> bool;
    /// The travel of `tool` along its direction, from the translations `at`, after which its
    /// surface is `gap` from `other`'s; `None` if it never comes that near.
    fn travel_to_gap(
        &self,
        tool: usize,
        other: usize,
        at: &[Vector3<f64>],
        gap: f64,
    ) -> Option<f64>;
}

/// The stages compiled: each tool's path (for the tools that move) and the end time.
#[derive(Clone, Debug, PartialEq)]
pub struct StagePlan {
    pub paths: Vec<Option<ToolPath>>,
    /// Each stage's start and end (s) and travel (mm).
    pub stages: Vec<(f64, f64, f64)>,
    pub end_time: f64,
}

/// The stages one after the other, each tool's speed table the stages' trapezoids; `stack` the
/// blank's thickness, the default gap of `close_to`. Stages that cannot run are refused naming
/// their key.
pub fn stage_plan(
    stages: &[Stage],
    tools: &dyn StageTools,
    count: usize,
    stack: f64,
) -> Result<StagePlan, String> {
    let mut knots: Vec<Vec<[f64; 2]>> = vec![vec![[0.0, 0.0]]; count];
    let mut at = vec![Vector3::zeros(); count];
    let mut spans = Vec::with_capacity(stages.len());
    let mut time = 0.0;
    for (i, stage) in stages.iter().enumerate() {
        let key = format!("process.stages[{}]", i + 1);
        let moving = stage_tools(stage, tools, &key)?;
        let travel = stage_travel(stage, tools, (&moving, &at), stack, &key)?;
        if !(stage.speed.is_finite() && stage.speed > 0.0) {
            return Err(format!(
                "{key}.speed = {} mm/s must be positive: the stage would never end",
                shown(stage.speed)
            ));
        }
        let cruise = travel / stage.speed;
        let ramp = RAMP_FRACTION * cruise;
        let end = time + cruise + ramp;
        for &k in &moving {
            knots[k].extend([
                [time, 0.0],
                [time + ramp, stage.speed],
                [end - ramp, stage.speed],
                [end, 0.0],
            ]);
            at[k] += tools.direction(k) * travel;
        }
        spans.push((time, end, travel));
        time = end;
    }
    let paths = knots
        .into_iter()
        .enumerate()
        .map(|(k, table)| {
            let table = merged(table);
            (table.len() > 1)
                .then(|| ToolPath::from_speeds(tools.direction(k), &table))
                .transpose()
        })
        .collect::<Result<_, _>>()?;
    Ok(StagePlan {
        paths,
        stages: spans,
        end_time: time,
    })
}

/// Knots at the same time merged (a stage starting where the last ended).
fn merged(table: Vec<[f64; 2]>) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::with_capacity(table.len());
    for knot in table {
        match out.last() {
            Some(last) if last[0] == knot[0] => {}
            _ => out.push(knot),
        }
    }
    out
}

/// The tools a stage moves, known and not force-driven, one only where it closes to a gap.
fn stage_tools(stage: &Stage, tools: &dyn StageTools, key: &str) -> Result<Vec<usize>, String> {
    if stage.tools.is_empty() {
        return Err(format!(
            "{key}.tools is empty: name the tools the stage moves"
        ));
    }
    let mut moving = Vec::new();
    for name in &stage.tools {
        let k = tools.index(name).ok_or_else(|| {
            format!(
                "{key}.tools: \"{name}\" is not a tool of this scenario (punch, die, the holder \
                 where the scenario has one, and the names of tools.extra)"
            )
        })?;
        if tools.force_driven(k) {
            return Err(format!(
                "{key}.tools: the {name} is driven by a force; a stage moves a tool by a travel \
                 or to a gap"
            ));
        }
        moving.push(k);
    }
    if stage.close_to.is_some() && moving.len() != 1 {
        return Err(format!(
            "{key}.close_to: one tool closes to a gap; {key}.tools names {}",
            moving.len()
        ));
    }
    Ok(moving)
}

/// How far the stage moves its tools (mm): its travel, or the travel that closes the gap.
fn stage_travel(
    stage: &Stage,
    tools: &dyn StageTools,
    (moving, at): (&[usize], &[Vector3<f64>]),
    stack: f64,
    key: &str,
) -> Result<f64, String> {
    match (stage.travel, &stage.close_to) {
        (Some(travel), None) if travel.is_finite() && travel > 0.0 => Ok(travel),
        (Some(travel), None) => Err(format!(
            "{key}.travel = {} mm must be positive",
            shown(travel)
        )),
        (None, Some(other)) => {
            let o = tools.index(other).ok_or_else(|| {
                format!("{key}.close_to: \"{other}\" is not a tool of this scenario")
            })?;
            let gap = stage.gap.unwrap_or(stack);
            if !(gap.is_finite() && gap >= stack * (1.0 - 1e-9)) {
                return Err(format!(
                    "{key}.gap = {} mm is less than the blank's thickness, {} mm: the tools \
                     would crush it",
                    shown(gap),
                    shown(stack)
                ));
            }
            let k = moving[0];
            match tools.travel_to_gap(k, o, at, gap) {
                Some(t) if t > 0.0 => Ok(t),
                _ => Err(format!(
                    "{key}: the {} moving along [{}] never closes to {} mm from the {other}: the \
                     stage would never end",
                    stage.tools[0],
                    direction_text(&tools.direction(k)),
                    shown(gap)
                )),
            }
        }
        (None, None) => Err(format!(
            "{key} needs travel (mm) or close_to (a tool) to know when it ends"
        )),
        (Some(_), Some(_)) => Err(format!(
            "{key}.travel and {key}.close_to both end the stage: give one"
        )),
    }
}

fn direction_text(d: &Vector3<f64>) -> String {
    d.iter().map(|c| shown(*c)).collect::<Vec<_>>().join(", ")
}

/// The travel of tool `moving` (placed at `from_moving`, moved along `direction`) at which the
/// nearest pair of points of its surface and `other`'s (placed at `from_other`) is `gap` apart:
/// the distance measured from each one's vertices to the other's surface. `None` where it never
/// comes that near within `reach` of travel.
pub fn closing_travel(
    (moving, from_moving): (&RigidTool, Vector3<f64>),
    direction: Vector3<f64>,
    (other, from_other): (&RigidTool, Vector3<f64>),
    gap: f64,
    reach: f64,
) -> Option<f64> {
    let distance = |s: f64| {
        let shift = from_moving + direction * s - from_other;
        let forth = moving
            .surface
            .vertices
            .iter()
            .map(|v| other.gap(&(v + shift), 0.0))
            .fold(f64::INFINITY, f64::min);
        let back = other
            .surface
            .vertices
            .iter()
            .map(|v| moving.gap(&(v - shift), 0.0))
            .fold(f64::INFINITY, f64::min);
        forth.min(back)
    };
    if distance(0.0) <= gap {
        return None;
    }
    let (mut lo, mut hi) = (0.0, reach);
    if distance(hi) > gap {
        return None;
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if distance(mid) > gap {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Line;

    impl StageTools for Line {
        fn index(&self, name: &str) -> Option<usize> {
            TOOL_NAMES.iter().position(|n| *n == name)
        }
        fn direction(&self, tool: usize) -> Vector3<f64> {
            default_direction(TOOL_NAMES[tool])
        }
        fn force_driven(&self, tool: usize) -> bool {
            tool == 2
        }
        fn travel_to_gap(&self, _: usize, _: usize, at: &[Vector3<f64>], gap: f64) -> Option<f64> {
            // punch and die 10 mm apart at the start, closing along z
            let apart = 10.0 + at[1].z - at[0].z;
            (apart > gap).then_some(apart - gap)
        }
    }

    fn stage(tools: &[&str], travel: Option<f64>, close_to: Option<&str>) -> Stage {
        Stage {
            name: None,
            tools: tools.iter().map(|t| t.to_string()).collect(),
            speed: 2.0,
            travel,
            close_to: close_to.map(String::from),
            gap: None,
        }
    }

    #[test]
    fn stages_follow_one_another_and_close_to_the_gap() {
        let stages = [
            stage(&["die"], Some(3.0), None),
            stage(&["punch"], None, Some("die")),
        ];
        let plan = stage_plan(&stages, &Line, 3, 1.5).unwrap();
        let punch = plan.paths[0].as_ref().unwrap();
        let die = plan.paths[1].as_ref().unwrap();
        assert!(plan.paths[2].is_none());
        // the die moves 3 mm down, then the punch closes the 7 mm left to 1.5 mm
        assert!((die.travel(plan.end_time) - 3.0).abs() < 1e-12);
        assert!((punch.travel(plan.end_time) - 5.5).abs() < 1e-12);
        assert_eq!(punch.travel(plan.stages[0].1), 0.0);
        assert!((plan.stages[1].0 - plan.stages[0].1).abs() < 1e-15);
        assert!((plan.end_time - (1.5 * 1.05 + 2.75 * 1.05)).abs() < 1e-12);
    }

    #[test]
    fn stages_that_cannot_end_are_refused_naming_their_key() {
        let refused = |stages: &[Stage]| stage_plan(stages, &Line, 3, 1.5).unwrap_err();
        let e = refused(&[stage(&["punch"], None, Some("die")), {
            let mut s = stage(&["punch"], None, Some("die"));
            s.gap = Some(3.0);
            s
        }]);
        assert!(
            e.contains("process.stages[2]") && e.contains("never"),
            "{e}"
        );
        let mut thin = stage(&["punch"], None, Some("die"));
        thin.gap = Some(1.0);
        let e = refused(&[thin]);
        assert!(
            e.contains("process.stages[1].gap") && e.contains("thickness"),
            "{e}"
        );
        let mut still = stage(&["punch"], Some(1.0), None);
        still.speed = 0.0;
        assert!(refused(&[still]).contains("process.stages[1].speed"));
        assert!(refused(&[stage(&["holder"], Some(1.0), None)]).contains("force"));
        assert!(refused(&[stage(&["ram"], Some(1.0), None)]).contains("\"ram\""));
        assert!(refused(&[stage(&["punch"], None, None)]).contains("travel"));
    }

    #[test]
    fn a_motion_table_gives_one_motion() {
        let table = MotionTable {
            direction: Some([1.0, 0.0, 0.0]),
            displacement: Some(vec![[0.0, 0.0], [1.0, 2.0]]),
            ..MotionTable::default()
        };
        let Some(ToolMotion::Path(p)) = table.motion("tools.die.motion", "die", 1.0).unwrap()
        else {
            panic!("a path")
        };
        assert!((p.displacement(0.5) - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        let both = MotionTable {
            force: Some(3.0),
            ..table
        };
        assert!(both
            .motion("tools.die.motion", "die", 1.0)
            .unwrap_err()
            .contains("one"));
    }
}
