//! The heat equation of a non-isothermal run, advanced by both solvers after their mechanics
//! (docs/model.md §9, docs/solver.md "Non-isothermal runs"): what the blank's temperature field
//! sees of the state (the sheet's shape, its yarns and thickness, which face touches which
//! tool and how hard, the friction work), and the temperature of each layer of each element
//! that the laminate is then evaluated at.

use super::error::SolverError;
use super::model::Model;
use super::state::State;
use crate::contact::ply_contact::FilmFriction;
use crate::contact::ply_contact::InterplyNode;
use crate::element::bending::BendingRigidity;
use crate::material::card::BendingCard;
use crate::material::LayerTemperatures;
use crate::thermal::blank::{BlankHeat, Face, HeatError, PlyExchange, SheetNow};
use nalgebra::Vector3;
use std::sync::Arc;

/// The heat problem of a run and its process: where the blank starts.
#[derive(Clone, Debug)]
pub struct HeatModel {
    pub blank: BlankHeat,
    /// Temperature of the blank out of the oven (°C).
    pub blank_temperature: f64,
    /// Time in air between the oven and the stroke (s).
    pub transfer_time: f64,
    /// How many times faster than the process the solver runs (the explicit solver's time
    /// scaling): the heat equation runs in process time.
    pub time_scaling: f64,
    /// Each ply's bending rigidity table (its card's `[bending]`), evaluated at each element's
    /// temperature; `None` for a ply without bending.
    pub bending: Vec<Option<BendingCard>>,
    /// Each ply's card's mechanical tables' common range (°C); `None` where nothing is
    /// tabulated.
    pub card_ranges: Vec<Option<(f64, f64)>>,
    /// The friction law of each interface of a layup at a temperature (°C), time-scaled as the
    /// model's interfaces are (docs/model.md §9, "The law at the local temperature"); empty for
    /// one ply.
    pub interface_friction: Vec<InterfaceFriction>,
}

/// An interface's friction law: the friction at a temperature (°C), or why there is none (a
/// temperature outside its tables, named).
pub trait FrictionLaw: std::fmt::Debug + Send + Sync {
    fn at(&self, temperature: f64) -> Result<FilmFriction, String>;
}

/// An interface's friction law as the model holds it.
pub type InterfaceFriction = Arc<dyn FrictionLaw>;

/// The blank out of the oven and carried through the air for the transfer time, at rest on no
/// tool: the state's temperature field and its layers' temperatures. Nothing in an isothermal
/// run.
pub fn start(model: &Model, state: &mut State) -> Result<(), SolverError> {
    let Some(heat) = &model.heat else {
        return Ok(());
    };
    let mut thermal = heat.blank.uniform(heat.blank_temperature);
    let sheet = Sheet::at_rest(model, state);
    heat.blank
        .advance(&mut thermal, &sheet.view(), heat.transfer_time)
        .map_err(|e| heat_failure(state, model, e, "in the transfer from the oven"))?;
    state.thermal = Some(thermal);
    update_layer_temperatures(model, state)
}

/// Advances the temperature field over a step of `dt` of the solver's time (the heat
/// equation's is `dt` times the time scaling), with the contacts and the shape of the state.
pub fn advance(model: &Model, state: &mut State, dt: f64) -> Result<(), SolverError> {
    let Some(heat) = &model.heat else {
        return Ok(());
    };
    let Some(mut thermal) = state.thermal.take() else {
        return Ok(());
    };
    let sheet = Sheet::of(model, state);
    let outcome = heat
        .blank
        .advance(&mut thermal, &sheet.view(), dt * heat.time_scaling);
    state.thermal = Some(thermal);
    outcome.map_err(|e| heat_failure(state, model, e, "in the stroke"))?;
    update_layer_temperatures(model, state)
}

/// The state's per-element layer temperatures from its field, and the bending rigidity of each
/// element at its mean temperature (docs/model.md §9): a temperature outside the bending table
/// stops the run, naming the element.
fn update_layer_temperatures(model: &Model, state: &mut State) -> Result<(), SolverError> {
    let (Some(heat), Some(thermal)) = (&model.heat, &state.thermal) else {
        return Ok(());
    };
    let layers = heat.blank.layers();
    let means = heat.blank.element_layer_temperatures(thermal);
    state.temperatures = means
        .chunks(layers)
        .map(|t| LayerTemperatures::per_layer(t).unwrap_or_else(|_| t[0].into()))
        .collect();
    check_card_ranges(model, heat, state)?;
    update_interface_frictions(model, heat, state)?;
    if model.bending.is_none() {
        return Ok(());
    }
    let shares = heat.blank.layer_thickness_shares();
    let mut rigidities = Vec::with_capacity(model.elements.len());
    for (k, t) in means.chunks(layers).enumerate() {
        let p = model.ply_index(k);
        let Some(table) = &heat.bending[p] else {
            rigidities.push(BendingRigidity {
                warp: 0.0,
                weft: 0.0,
            });
            continue;
        };
        let mean: f64 = t.iter().zip(&shares[p]).map(|(t, w)| t * w).sum();
        let rigidity = table.at(mean).map_err(|e| SolverError::Temperature {
            step: state.step,
            time: state.time,
            element: k,
            reason: format!("bending rigidity at the element's temperature: {e}"),
        })?;
        rigidities.push(rigidity);
    }
    state.bending_rigidities = rigidities;
    Ok(())
}

/// A failure of the heat equation as the solvers report one: the element is one of the node's.
fn heat_failure(state: &State, model: &Model, error: HeatError, when: &str) -> SolverError {
    let element = model
        .elements
        .iter()
        .position(|e| e.nodes().contains(&error.node))
        .unwrap_or(0);
    SolverError::Temperature {
        step: state.step,
        time: state.time,
        element,
        reason: format!("{when}, at node {}: {}", error.node, error.reason),
    }
}

/// Each interface's friction at its temperature: the area-weighted mean of the two facing
/// skins, the top layer of the ply below and the bottom layer of the ply above.
fn update_interface_frictions(
    model: &Model,
    heat: &HeatModel,
    state: &mut State,
) -> Result<(), SolverError> {
    if heat.interface_friction.is_empty() {
        return Ok(());
    }
    let layers = heat.blank.layers();
    let mut frictions = Vec::with_capacity(model.interfaces.len());
    for (law, face) in heat.interface_friction.iter().zip(&model.interfaces) {
        let facing = [(face.lower, layers - 1), (face.upper, 0)];
        let (mut sum, mut area) = (0.0, 0.0);
        for (ply, layer) in facing {
            for k in model.plies[ply].elements.clone() {
                sum += model.elements[k].area * state.temperatures[k].layer(layer);
                area += model.elements[k].area;
            }
        }
        let temperature = sum / area;
        let friction = law.at(temperature).map_err(|e| SolverError::Temperature {
            step: state.step,
            time: state.time,
            element: model.plies[face.lower].elements.start,
            reason: format!(
                "the friction between plies {} and {} at {temperature:.2} °C: {e}",
                face.lower + 1,
                face.upper + 1
            ),
        })?;
        frictions.push(friction);
    }
    state.interface_frictions = frictions;
    Ok(())
}

/// Every layer of every element within its card's mechanical tables (`[matrix]`, `[bending]`):
/// a layer cooled below them stops the run naming the element, rather than the next increment
/// failing on it.
fn check_card_ranges(model: &Model, heat: &HeatModel, state: &State) -> Result<(), SolverError> {
    let layers = heat.blank.layers();
    for (k, t) in state.temperatures.iter().enumerate() {
        let Some((low, high)) = heat.card_ranges[model.ply_index(k)] else {
            continue;
        };
        for layer in 0..layers {
            let value = t.layer(layer);
            if !crate::limits::between(value, low, high) {
                return Err(SolverError::Temperature {
                    step: state.step,
                    time: state.time,
                    element: k,
                    reason: format!(
                        "layer {} ({}) at {value:.2} °C, outside the card's [matrix] and \
                         [bending] tables ({low} to {high} °C)",
                        layer + 1,
                        model.laminate(k).layers()[layer].law.name()
                    ),
                });
            }
        }
    }
    Ok(())
}

/// What the heat equation reads of a state, gathered once per step.
struct Sheet<'a> {
    positions: &'a [Vector3<f64>],
    yarns: Vec<(Vector3<f64>, Vector3<f64>)>,
    stretch: Vec<f64>,
    faces: Vec<[Face; 2]>,
    ply_exchanges: Vec<PlyExchange>,
    friction_power: Vec<f64>,
}

impl<'a> Sheet<'a> {
    /// The blank as it is in `state`, its faces on the tools it touches.
    fn of(model: &Model, state: &'a State) -> Self {
        let normals = node_normals(model, &state.positions);
        let areas = model.nodal_areas();
        let faces: Vec<[Face; 2]> = state
            .contacts
            .iter()
            .zip(&normals)
            .zip(&areas)
            .map(|((contact, n), area)| {
                let mut faces = [Face::Air; 2];
                for (tool, (&fn_k, normal)) in contact
                    .normal_force
                    .iter()
                    .zip(&contact.normals)
                    .enumerate()
                {
                    if fn_k > 0.0 {
                        // the tool pushes the node away from itself: from below the shell's
                        // normal it touches the bottom face
                        let side = if normal.dot(n) > 0.0 { 0 } else { 1 };
                        faces[side] = Face::Tool {
                            tool,
                            pressure: fn_k / area,
                        };
                    }
                }
                faces
            })
            .collect();
        let friction_power = state
            .contacts
            .iter()
            .zip(&state.velocities)
            .map(|(contact, v)| {
                contact
                    .tangential
                    .iter()
                    .zip(&state.tool_velocities)
                    .map(|(f, v_tool)| f.dot(&(v - v_tool)).abs())
                    .sum()
            })
            .collect();
        let ply_exchanges = ply_exchanges(model, &state.positions, &state.interply);
        Self::with_plies(model, state, (faces, ply_exchanges), friction_power)
    }

    /// The blank at rest in the air: its outer faces in the air, the plies of a layup on one
    /// another.
    fn at_rest(model: &Model, state: &'a State) -> Self {
        let nodes = state.positions.len();
        let ply_exchanges = match model.ply_contact(1.0) {
            Some(mut plies) => {
                let mut lists = vec![InterplyNode::default(); nodes];
                plies.relist_if_moved(&state.positions, &mut lists);
                ply_exchanges(model, &state.positions, &lists)
            }
            None => Vec::new(),
        };
        let faces = vec![[Face::Air; 2]; nodes];
        Self::with_plies(model, state, (faces, ply_exchanges), vec![0.0; nodes])
    }

    /// The sheet of `state` with these faces, the faces across which plies exchange heat
    /// turned to [`Face::Ply`].
    fn with_plies(
        model: &Model,
        state: &'a State,
        (mut faces, ply_exchanges): (Vec<[Face; 2]>, Vec<PlyExchange>),
        friction_power: Vec<f64>,
    ) -> Self {
        for x in &ply_exchanges {
            faces[x.node][x.face] = Face::Ply;
        }
        Self {
            positions: &state.positions,
            yarns: yarns(model, &state.positions),
            stretch: stretches(model, state),
            faces,
            ply_exchanges,
            friction_power,
        }
    }

    fn view(&self) -> SheetNow<'_> {
        SheetNow {
            positions: self.positions,
            yarns: &self.yarns,
            stretch: &self.stretch,
            faces: &self.faces,
            ply_exchanges: &self.ply_exchanges,
            friction_power: &self.friction_power,
        }
    }
}

/// Two plies touch where the gap between their faces is below this share of the thinner
/// ply's thickness **(choice)**: pressed together the penalty contact leaves them a small
/// overlap; a gap of a tenth of a ply is air between them.
const TOUCHING_GAP: f64 = 0.1;

/// Where the plies of a layup touch: each node over the face of the ply across each of its
/// sides (the triangles the contact lists near it), with half its area (the node of the other
/// ply across the same film carries the other half).
fn ply_exchanges(
    model: &Model,
    positions: &[Vector3<f64>],
    lists: &[InterplyNode],
) -> Vec<PlyExchange> {
    let Some(plies) = model.ply_contact(1.0) else {
        return Vec::new();
    };
    let limit = TOUCHING_GAP * model.thinnest_ply();
    let mut exchanges = Vec::new();
    for (a, node) in lists.iter().enumerate() {
        for (face, side) in node.sides.iter().enumerate() {
            let touch = plies.nearest(a, face, side.candidates(), positions);
            if let Some(t) = touch.filter(|t| t.gap < limit) {
                exchanges.push(PlyExchange {
                    node: a,
                    face,
                    others: t.corners,
                    weights: t.shares,
                    area: 0.5 * plies.area(a),
                });
            }
        }
    }
    exchanges
}

/// Current warp and weft of each element, `F a0` and `F b0`.
fn yarns(model: &Model, positions: &[Vector3<f64>]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    model
        .elements
        .iter()
        .map(|e| {
            let f = e.gradient(positions);
            (f * e.fibres.warp.xy(), f * e.fibres.weft.xy())
        })
        .collect()
}

/// Thickness stretch of each layer of each element, element by element.
fn stretches(model: &Model, state: &State) -> Vec<f64> {
    state
        .laminate_states
        .iter()
        .take(model.elements.len())
        .flat_map(|s| s.thickness_stretch.iter().copied())
        .collect()
}

/// The unit normal of the shell at each node: the mean of its elements' normals (their
/// corners' winding), the side a tool is on is told against.
fn node_normals(model: &Model, positions: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let mut normals = vec![Vector3::zeros(); positions.len()];
    for e in &model.elements {
        let nodes = e.nodes();
        let (a, b, c) = (nodes[0], nodes[1], nodes[nodes.len() - 1]);
        let n = (positions[b] - positions[a]).cross(&(positions[c] - positions[a]));
        for &node in nodes {
            normals[node] += n;
        }
    }
    normals
        .into_iter()
        .map(|n| n.try_normalize(0.0).unwrap_or_else(Vector3::z))
        .collect()
}
