//! The blank's supports of a scenario (docs/guide/scenario.md, "Springs, grippers and
//! gravity"): `[[springs]]` and `[[grippers]]` on node sets chosen by a mesh's set, a place on
//! the blank or a distance from its outline, and `process.gravity`; built into the model's
//! [`Supports`].

use crate::contact::potential::penalty_stiffness;
use crate::limits::shown;
use crate::solver::model::rest_moduli;
use crate::solver::Model;
use crate::support::{Gravity, GripperSet, Release, SpringNode, SpringSet, Supports};
use nalgebra::{Vector2, Vector3};
use serde::Deserialize;
use std::collections::HashMap;

/// One `[[springs]]` table: a spring from a node set to anchors.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringTable {
    pub name: Option<String>,
    pub node_set: Option<String>,
    pub at: Option<[f64; 2]>,
    pub radius: Option<f64>,
    pub edge_within: Option<f64>,
    /// Stiffness of the spring (N/mm), shared among its nodes.
    pub stiffness: f64,
    /// Its length without force (mm).
    pub free_length: f64,
    /// Its force at the start (N): the anchors stand `free_length + preload / stiffness` from
    /// the nodes.
    #[serde(default)]
    pub preload: f64,
    /// From the nodes towards the anchors; outward in plan, from the blank's centre through the
    /// set's, by default.
    pub direction: Option<[f64; 3]>,
    /// The tool that carries the anchors ("punch", "die", "holder"); fixed by default.
    pub moves_with: Option<String>,
}

/// One `[[grippers]]` table: a node set held where it is, released at a time or a force.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GripperTable {
    pub name: Option<String>,
    pub node_set: Option<String>,
    pub at: Option<[f64; 2]>,
    pub radius: Option<f64>,
    pub edge_within: Option<f64>,
    pub moves_with: Option<String>,
    pub release_time: Option<f64>,
    pub release_force: Option<f64>,
}

/// Which nodes of the blank: a node set of its mesh, the nodes within `radius` of a point in
/// plan (the nearest where no radius is given), or those within `edge_within` of its outline.
#[derive(Clone, Debug, Default, PartialEq)]
struct NodeChoice {
    node_set: Option<String>,
    at: Option<[f64; 2]>,
    radius: Option<f64>,
    edge_within: Option<f64>,
}

macro_rules! node_choice {
    ($table:expr) => {
        NodeChoice {
            node_set: $table.node_set.clone(),
            at: $table.at,
            radius: $table.radius,
            edge_within: $table.edge_within,
        }
    };
}

/// The scenario's supports as written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SupportScenario {
    pub springs: Vec<SpringTable>,
    pub grippers: Vec<GripperTable>,
    /// `process.gravity` (mm/s^2); standard gravity down by default where the blank hangs on
    /// springs or grippers, none otherwise.
    pub gravity: Option<[f64; 3]>,
}

impl SupportScenario {
    /// Whether the blank hangs on springs or grippers.
    pub fn holds_the_blank(&self) -> bool {
        !self.springs.is_empty() || !self.grippers.is_empty()
    }

    /// The gravity of the run: `process.gravity`, or the default.
    pub fn gravity(&self) -> Result<Option<Gravity>, String> {
        match self.gravity {
            Some(g) if g.iter().all(|c| c.is_finite()) => {
                let acceleration = Vector3::from(g);
                Ok((acceleration.norm() > 0.0).then_some(Gravity { acceleration }))
            }
            Some(_) => Err("process.gravity must be three finite numbers (mm/s^2)".into()),
            None => Ok(self.holds_the_blank().then(Gravity::standard)),
        }
    }
}

/// The supports on `model`, tool names resolved by `tool_index`; every set checked, the first
/// wrong named by its key.
pub fn build_supports(
    s: &SupportScenario,
    model: &Model,
    tool_index: &dyn Fn(&str) -> Option<usize>,
) -> Result<Supports, String> {
    let outline = Outline::of(model);
    let mut springs = Vec::with_capacity(s.springs.len());
    for (i, spring) in s.springs.iter().enumerate() {
        let key = format!("springs[{}]", i + 1);
        springs.push(spring_set(spring, &key, model, &outline, tool_index)?);
    }
    let grip = gripper_stiffness(model)?;
    let mut grippers = Vec::with_capacity(s.grippers.len());
    for (i, g) in s.grippers.iter().enumerate() {
        let key = format!("grippers[{}]", i + 1);
        let nodes = node_choice!(g).select(&key, model, &outline)?;
        let release = Release {
            time: positive(&format!("{key}.release_time"), g.release_time)?,
            force: positive(&format!("{key}.release_force"), g.release_force)?,
        };
        let name = g.name.clone();
        grippers.push(GripperSet::new(
            name.unwrap_or_else(|| format!("gripper {}", i + 1)),
            (&nodes, &model.mesh.nodes),
            grip,
            carrier(&g.moves_with, &key, tool_index)?,
            release,
        ));
    }
    Ok(Supports {
        gravity: s.gravity()?,
        springs,
        grippers,
    })
}

fn spring_set(
    spring: &SpringTable,
    key: &str,
    model: &Model,
    outline: &Outline,
    tool_index: &dyn Fn(&str) -> Option<usize>,
) -> Result<SpringSet, String> {
    if !(spring.stiffness.is_finite() && spring.stiffness > 0.0) {
        return Err(format!(
            "{key}.stiffness = {} N/mm must be positive",
            shown(spring.stiffness)
        ));
    }
    if !(spring.free_length.is_finite() && spring.free_length >= 0.0) {
        return Err(format!(
            "{key}.free_length = {} mm must be zero or positive",
            shown(spring.free_length)
        ));
    }
    if !(spring.preload.is_finite() && spring.preload >= 0.0) {
        return Err(format!(
            "{key}.preload = {} N must be zero or positive (a spring that pulls)",
            shown(spring.preload)
        ));
    }
    let nodes = node_choice!(spring).select(key, model, outline)?;
    let direction = spring_direction(spring, key, model, &nodes)?;
    let reach = spring.free_length + spring.preload / spring.stiffness;
    Ok(SpringSet {
        name: spring
            .name
            .clone()
            .unwrap_or_else(|| key.replace("springs[", "spring ").replace(']', "")),
        nodes: nodes
            .iter()
            .map(|&n| SpringNode {
                node: n,
                anchor: model.mesh.nodes[n] + direction * reach,
            })
            .collect(),
        stiffness: spring.stiffness / nodes.len() as f64,
        free_length: spring.free_length,
        carrier: carrier(&spring.moves_with, key, tool_index)?,
    })
}

/// The unit direction from the nodes to the anchors: the table's, or outward in plan from
/// the blank's centre through the nodes' centre.
fn spring_direction(
    spring: &SpringTable,
    key: &str,
    model: &Model,
    nodes: &[usize],
) -> Result<Vector3<f64>, String> {
    if let Some(d) = spring.direction {
        let d = Vector3::from(d);
        let length = d.norm();
        return match length.is_finite() && length > 0.0 {
            true => Ok(d / length),
            false => Err(format!("{key}.direction must be a finite vector, not zero")),
        };
    }
    let centre = |ns: &mut dyn Iterator<Item = Vector3<f64>>| {
        let (sum, count) = ns.fold((Vector3::zeros(), 0.0), |(s, c), x| (s + x, c + 1.0));
        sum / count
    };
    let blank = centre(&mut model.mesh.nodes.iter().copied());
    let set = centre(&mut nodes.iter().map(|&n| model.mesh.nodes[n]));
    let outward = Vector3::new(set.x - blank.x, set.y - blank.y, 0.0);
    if outward.norm() < 1e-9 * model.mean_cell_size() {
        return Err(format!(
            "{key}: its nodes are centred on the blank, so no direction outward is known: give \
             {key}.direction"
        ));
    }
    Ok(outward.normalize())
}

/// Contact spring scale `s` the grippers take, the tools' (`forming::setup`).
const GRIP_SCALE: f64 = 0.1;

/// A gripper holds its nodes as stiffly as the tools' contact does, `s E t0 A / h^2` on the
/// sheet's mean cell (`A = h^2`) of its stiffest ply: stiff against the sheet, and within the
/// explicit solver's stable step.
fn gripper_stiffness(model: &Model) -> Result<f64, String> {
    let mut wave: f64 = 0.0;
    for ply in &model.plies {
        let rest = rest_moduli(&ply.laminate, model.temperature).map_err(|e| e.to_string())?;
        wave = wave.max(rest.yarn);
    }
    let h = model.mean_cell_size();
    Ok(penalty_stiffness(GRIP_SCALE, wave, h * h, h))
}

fn carrier(
    tool: &Option<String>,
    key: &str,
    tool_index: &dyn Fn(&str) -> Option<usize>,
) -> Result<Option<usize>, String> {
    match tool {
        None => Ok(None),
        Some(name) => tool_index(name).map(Some).ok_or_else(|| {
            format!("{key}.moves_with: \"{name}\" is not a tool of this scenario moved by a path")
        }),
    }
}

fn positive(key: &str, value: Option<f64>) -> Result<Option<f64>, String> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => {
            Err(format!("{key} = {} must be positive", shown(v)))
        }
        v => Ok(v),
    }
}

impl NodeChoice {
    /// The nodes chosen on `model`'s blank, `key` the table in messages; refused if none.
    fn select(&self, key: &str, model: &Model, outline: &Outline) -> Result<Vec<usize>, String> {
        let nodes = match (&self.node_set, self.at, self.edge_within) {
            (Some(set), None, None) => model
                .mesh
                .node_set(set)
                .map(<[usize]>::to_vec)
                .map_err(|e| format!("{key}.node_set: {e}"))?,
            (None, Some(at), None) => self.near(key, model, Vector2::from(at))?,
            (None, None, Some(d)) if d.is_finite() && d >= 0.0 => outline.within(model, d),
            (None, None, Some(d)) => {
                return Err(format!("{key}.edge_within = {} mm must be >= 0", shown(d)))
            }
            _ => {
                return Err(format!(
                    "{key} chooses its nodes by one of node_set, at (with radius) and \
                     edge_within"
                ))
            }
        };
        if self.radius.is_some() && self.at.is_none() {
            return Err(format!("{key}.radius goes with {key}.at"));
        }
        if nodes.is_empty() {
            return Err(format!("{key}: the set of nodes it holds is empty"));
        }
        Ok(nodes)
    }

    /// The nodes within `radius` of `at` in plan, or the nearest one of each ply.
    fn near(&self, key: &str, model: &Model, at: Vector2<f64>) -> Result<Vec<usize>, String> {
        let plan = |n: usize| (model.mesh.nodes[n].xy() - at).norm();
        if let Some(r) = self.radius {
            if !(r.is_finite() && r > 0.0) {
                return Err(format!("{key}.radius = {} mm must be positive", shown(r)));
            }
            return Ok((0..model.mesh.nodes.len())
                .filter(|&n| plan(n) <= r)
                .collect());
        }
        Ok(model
            .plies
            .iter()
            .filter_map(|p| p.nodes.clone().min_by(|&a, &b| plan(a).total_cmp(&plan(b))))
            .collect())
    }
}

/// The blank's outline in plan: the cell edges that belong to one cell only.
struct Outline {
    edges: Vec<[usize; 2]>,
}

impl Outline {
    fn of(model: &Model) -> Self {
        let mut count: HashMap<[usize; 2], usize> = HashMap::new();
        for cell in &model.mesh.cells {
            for (a, b) in cell.edges() {
                *count.entry([a.min(b), a.max(b)]).or_default() += 1;
            }
        }
        let mut edges: Vec<[usize; 2]> = count
            .into_iter()
            .filter(|(_, c)| *c == 1)
            .map(|(e, _)| e)
            .collect();
        edges.sort_unstable();
        Self { edges }
    }

    /// The nodes within `d` of the outline in plan.
    fn within(&self, model: &Model, d: f64) -> Vec<usize> {
        let x = &model.mesh.nodes;
        (0..x.len())
            .filter(|&n| {
                self.edges
                    .iter()
                    .any(|&[a, b]| segment_distance(x[n].xy(), x[a].xy(), x[b].xy()) <= d + 1e-9)
            })
            .collect()
    }
}

fn segment_distance(p: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}
