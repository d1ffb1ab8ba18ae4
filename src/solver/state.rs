//! The state of a run that both solvers advance and every observer, check and writer reads:
//! positions, velocities, masses, the laminate's state variables, tool travel and loads,
//! contact and the energy bookkeeping.

use super::energy::Energies;
use super::model::Model;
use crate::contact::penalty::{NodeContact, ToolLoad};
use crate::contact::ply_contact::{FilmFriction, InterplyNode};
use crate::element::bending::{BendingPatch, BendingRigidity};
use crate::material::{
    LaminateState, LayerTemperatures, MaterialError, MembraneKinematics, MembraneResponse,
};
use crate::support::SupportState;
use crate::thermal::ThermalState;
use nalgebra::{Matrix2, Vector3};
use rayon::prelude::*;

/// The integrated state at one instant.
#[derive(Clone, Debug)]
pub struct State {
    pub step: usize,
    pub time: f64,
    /// Current positions (mm).
    pub positions: Vec<Vector3<f64>>,
    /// Velocities at the last half step (mm/s).
    pub velocities: Vec<Vector3<f64>>,
    /// Lumped nodal masses, mass scaling included (tonne).
    pub masses: Vec<f64>,
    /// Internal nodal forces (N).
    pub internal_forces: Vec<Vector3<f64>>,
    /// Reaction forces at constrained nodes, zero elsewhere (N).
    pub reactions: Vec<Vector3<f64>>,
    /// Membrane resultant and thickness per element.
    pub membrane: Vec<MembraneResponse>,
    /// Laminate state variables per element.
    pub laminate_states: Vec<LaminateState>,
    /// Per-element density after mass scaling (tonne/mm^3).
    pub densities: Vec<f64>,
    /// Step that led here (s).
    pub time_step: f64,
    pub energies: Energies,
    /// Mass added by mass scaling (tonne).
    pub added_mass: f64,
    /// Translation of each tool from its place at the start (mm), and its velocity over the
    /// last step (mm/s).
    pub tool_translations: Vec<Vector3<f64>>,
    pub tool_velocities: Vec<Vector3<f64>>,
    /// Force of the blank on each tool at the last step (N): minus the punch force etc.
    pub tool_loads: Vec<ToolLoad>,
    /// Time integral of each tool's load force since the start (N·s): its difference between
    /// two records over their time apart is the mean force in between, free of the step-to-step
    /// ringing of the contact springs.
    pub tool_impulses: Vec<Vector3<f64>>,
    /// Contact of each node with the tools (force on the node, per-tool normal and
    /// tangential forces).
    pub contacts: Vec<NodeContact>,
    /// Contact of each node with the plies next to its own; empty without interfaces.
    pub interply: Vec<InterplyNode>,
    /// The temperature field of the blank (docs/model.md §9); `None` in an isothermal run.
    pub thermal: Option<ThermalState>,
    /// The temperature of each layer of each element, from [`Self::thermal`]; empty in an
    /// isothermal run, where every layer is at the model's temperature.
    pub temperatures: Vec<LayerTemperatures>,
    /// The bending rigidity of each element at its temperature; empty in an isothermal run,
    /// where each bending patch's own holds.
    pub bending_rigidities: Vec<BendingRigidity>,
    /// The friction of each interface of a layup at its temperature; empty in an isothermal
    /// run, where the model's interfaces' hold.
    pub interface_frictions: Vec<FilmFriction>,
    /// Gravity's, the springs' and the grippers' loads at the last step, and which grippers
    /// have let go.
    pub supports: SupportState,
}

impl State {
    /// The undeformed model at rest at `t = 0`, with these lumped masses and element densities
    /// (mass scaling `added_mass` included): the start of either solver.
    pub(crate) fn undeformed(
        model: &Model,
        masses: Vec<f64>,
        densities: Vec<f64>,
        added_mass: f64,
    ) -> State {
        let n_nodes = model.mesh.nodes.len();
        let elements = 0..model.elements.len();
        State {
            step: 0,
            time: 0.0,
            positions: model.mesh.nodes.clone(),
            velocities: vec![Vector3::zeros(); n_nodes],
            masses,
            internal_forces: vec![Vector3::zeros(); n_nodes],
            reactions: vec![Vector3::zeros(); n_nodes],
            membrane: elements
                .clone()
                .map(|k| MembraneResponse {
                    n: Matrix2::zeros(),
                    thickness: model.thickness(k),
                })
                .collect(),
            laminate_states: elements
                .map(|k| model.laminate(k).initial_state())
                .collect(),
            densities,
            time_step: 0.0,
            energies: Energies::default(),
            added_mass,
            tool_translations: vec![Vector3::zeros(); model.tools.len()],
            tool_velocities: vec![Vector3::zeros(); model.tools.len()],
            tool_loads: vec![ToolLoad::default(); model.tools.len()],
            tool_impulses: vec![Vector3::zeros(); model.tools.len()],
            contacts: vec![NodeContact::default(); n_nodes],
            interply: match model.interfaces.is_empty() {
                true => Vec::new(),
                false => vec![InterplyNode::default(); n_nodes],
            },
            thermal: None,
            temperatures: Vec::new(),
            bending_rigidities: Vec::new(),
            interface_frictions: Vec::new(),
            supports: model.supports.start(n_nodes),
        }
    }

    /// The bending rigidity of patch `k` now: its own, or the one at its temperature.
    pub fn bending_rigidity<'a>(
        &'a self,
        patch: &'a BendingPatch,
        k: usize,
    ) -> &'a BendingRigidity {
        self.bending_rigidities.get(k).unwrap_or(&patch.rigidity)
    }

    /// The temperature of each layer of element `k` (°C).
    pub fn element_temperature(&self, model: &Model, k: usize) -> LayerTemperatures {
        model.element_temperature(&self.temperatures, k)
    }

    /// Elastic energy stored in the sheet, `sum_e A0 sum_k t_k W_k` plus the hinges' bending
    /// energy. The per-element energies are computed in parallel and summed in element order, so
    /// the total is the same on any thread count (it is only needed at the records).
    pub fn elastic_energy(&self, model: &Model) -> Result<f64, (usize, MaterialError)> {
        let membrane: Vec<Result<f64, (usize, MaterialError)>> = model
            .elements
            .par_iter()
            .enumerate()
            .map(|(k, e)| {
                let f = e.gradient(&self.positions);
                let f_dot = e.gradient(&self.velocities);
                let temperature = self.element_temperature(model, k);
                let kin = MembraneKinematics::from_deformation(&f, &f_dot, temperature, e.fibres);
                let w = model
                    .laminate(k)
                    .stored_energy(&kin, &self.laminate_states[k])
                    .map_err(|err| (k, err))?;
                Ok(e.area * w + e.hourglass_energy(&self.positions, model.hourglass(k)))
            })
            .collect();
        let membrane: f64 = membrane.into_iter().sum::<Result<f64, _>>()?;
        let bending: f64 = model.bending.as_ref().map_or(0.0, |b| {
            let energies: Vec<f64> = b
                .patches
                .par_iter()
                .enumerate()
                .map(|(k, t)| b.energy_with(t, self.bending_rigidity(t, k), &self.positions))
                .collect();
            energies.iter().sum()
        });
        Ok(membrane + bending)
    }
}
