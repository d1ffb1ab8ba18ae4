//! The temperature field of a blank (docs/model.md §9): each node of the shell carries a column
//! of cells through its ply's thickness (the thin-shell split), the matrix skins and the fabric
//! each cut into cells; the columns exchange heat in the plane through the cells of the same
//! level, with the tools, the room or the neighbouring ply through their faces, and release
//! the latent heat of the crystallising matrix.
//!
//! One step of `dt` (process time): the in-plane and ply-to-ply exchanges from the temperatures
//! at its start (explicit, sub-stepped within their stable step), then each column backward
//! Euler with its faces (`column`), then crystallisation (Eq. (H7)) and its latent heat (H8).
//! Every heat flow is booked once, so that the blank's heat content changes by exactly what
//! went in and out ([`HeatAccount`], Eq. (H10)).

use super::air::AirExchange;
use super::column::{
    step_column, ColumnGrid, ColumnLayer, ColumnScratch, ColumnStep, FaceExchange,
};
use super::crystallisation::latent_heat_release;
use super::in_plane::{add_heat_rates, stable_step, CellConduction};
use super::properties::{ThermalProperties, HEAT_TRANSFER_UNIT};
use nalgebra::Vector3;
use rayon::prelude::*;

/// Which layer of a ply's stack a layer is: what conducts in it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayerKind {
    Matrix,
    Fabric,
}

/// One ply as the heat equation sees it.
#[derive(Clone, Debug)]
pub struct PlyHeat {
    pub properties: ThermalProperties,
    /// Density (tonne/mm³).
    pub density: f64,
    /// The stack, bottom face first, as the laminate's layers.
    pub layers: Vec<(LayerKind, f64)>,
}

/// How a face of a column exchanges heat over a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Face {
    /// With the room (convection and radiation, Eq. (H5)).
    Air,
    /// Pressed on tool `tool` at `pressure` (MPa): the contact conductance (H6).
    Tool { tool: usize, pressure: f64 },
    /// Against the neighbouring ply: its exchange is one of the step's [`PlyExchange`]s.
    Ply,
}

/// Heat passing between a node's face and the ply across it: the other ply's face at the
/// point the node touches, the barycentric `weights` of its `others` nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlyExchange {
    pub node: usize,
    /// 0: the node's bottom face (the other ply's top), 1: its top face.
    pub face: usize,
    pub others: [usize; 3],
    pub weights: [f64; 3],
    /// The area this pair stands for (mm²).
    pub area: f64,
}

/// The settings of the heat problem of a run (scenario `[thermal]`).
#[derive(Clone, Debug)]
pub struct HeatSettings {
    /// Cells through each layer of a ply.
    pub cells_per_layer: usize,
    /// Longest step of the heat equation (s): the contacts are sampled at this interval.
    pub time_step: f64,
    pub air: AirExchange,
    /// Contact conductance with a tool against the contact pressure: `(MPa, N/(mm·s·K))`.
    pub contact_conductance: Vec<(f64, f64)>,
    /// Conductance between plies in contact (N/(mm·s·K)).
    pub interply_conductance: f64,
    /// Share of the friction work on the tools that heats the blank (the rest heats the tool).
    pub friction_heat_fraction: f64,
}

impl HeatSettings {
    /// The contact conductance at `pressure` (MPa), linear in the table, held beyond its ends.
    pub fn contact_conductance_at(&self, pressure: f64) -> f64 {
        let table = &self.contact_conductance;
        match table.iter().position(|&(p, _)| pressure <= p) {
            None => table.last().map_or(0.0, |&(_, h)| h),
            Some(0) => table[0].1,
            Some(i) => {
                let ((p0, h0), (p1, h1)) = (table[i - 1], table[i]);
                h0 + (pressure - p0) / (p1 - p0) * (h1 - h0)
            }
        }
    }
}

/// The heat problem of a blank: its plies, their nodes and cells, the tools' temperatures.
#[derive(Clone, Debug)]
pub struct BlankHeat {
    pub plies: Vec<PlyHeat>,
    /// The column of each ply (every ply has as many cells).
    grids: Vec<ColumnGrid>,
    /// Ply of each node and of each element.
    node_ply: Vec<usize>,
    element_ply: Vec<usize>,
    /// Node lists of the elements (3 or 4 nodes), and the elements around each node.
    elements: Vec<Vec<usize>>,
    node_elements: Vec<Vec<usize>>,
    /// Reference area of each node's share of its elements (mm²).
    reference_areas: Vec<f64>,
    /// Temperature of each tool (°C).
    pub tool_temperatures: Vec<f64>,
    pub settings: HeatSettings,
}

/// Heat that went where since the start (N·mm = mJ), Eq. (H10):
/// `stored = latent + friction - sum(to_tools) - to_air` to round-off.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatAccount {
    /// Change of the blank's heat content, `sum C (T - T_start)` step by step.
    pub stored: f64,
    /// Heat that left into each tool and into the room.
    pub to_tools: Vec<f64>,
    pub to_air: f64,
    /// Latent heat released by crystallisation.
    pub latent: f64,
    /// Friction work that heated the blank.
    pub friction: f64,
}

impl HeatAccount {
    /// `stored - (latent + friction - to_tools - to_air)`: zero but for round-off.
    pub fn imbalance(&self) -> f64 {
        let out: f64 = self.to_tools.iter().sum::<f64>() + self.to_air;
        self.stored - (self.latent + self.friction - out)
    }

    /// The largest of the heat flows, what [`Self::imbalance`] is measured against.
    pub fn scale(&self) -> f64 {
        let out: f64 = self.to_tools.iter().map(|q| q.abs()).sum::<f64>() + self.to_air.abs();
        self.stored
            .abs()
            .max(out)
            .max(self.latent)
            .max(self.friction)
    }
}

/// The temperature field of a blank at one instant.
#[derive(Clone, Debug)]
pub struct ThermalState {
    /// Temperature of each cell (°C), node by node: `cells` per node.
    pub temperatures: Vec<f64>,
    /// Nakamura's `theta` of each cell (Eq. (H7)); empty without crystallisation.
    pub theta: Vec<f64>,
    pub cells: usize,
    /// Process time since the blank left the oven (s).
    pub time: f64,
    pub heat: HeatAccount,
    /// Wall time spent advancing the field (s): what the heat equation costs the run.
    pub wall_seconds: f64,
}

impl ThermalState {
    /// The column of node `a`.
    pub fn column(&self, a: usize) -> &[f64] {
        &self.temperatures[a * self.cells..(a + 1) * self.cells]
    }
}

/// Why the heat equation cannot go on: a temperature outside a card's table at a node.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("node {node}: {reason}")]
pub struct HeatError {
    pub node: usize,
    pub reason: String,
}

/// What the step sees of the deforming blank.
pub struct SheetNow<'a> {
    pub positions: &'a [Vector3<f64>],
    /// Current warp and weft of each element (3D, any length).
    pub yarns: &'a [(Vector3<f64>, Vector3<f64>)],
    /// Thickness stretch of each layer of each element, element by element.
    pub stretch: &'a [f64],
    /// The two faces of each node, bottom and top.
    pub faces: &'a [[Face; 2]],
    pub ply_exchanges: &'a [PlyExchange],
    /// Friction power on the tools at each node (N·mm/s), before the fraction that heats it.
    pub friction_power: &'a [f64],
}

/// Nodes per chunk of the parallel column solves: fixed, so that the heat sums do not depend on
/// the thread count.
const NODE_CHUNK: usize = 256;

impl BlankHeat {
    /// The heat problem of plies `plies`, the elements `elements` (node lists) of ply
    /// `element_ply[k]` over the reference `positions`, nodes numbered one ply after another.
    pub fn new(
        plies: Vec<PlyHeat>,
        elements: Vec<Vec<usize>>,
        element_ply: Vec<usize>,
        positions: &[Vector3<f64>],
        tool_temperatures: Vec<f64>,
        settings: HeatSettings,
    ) -> Result<Self, String> {
        let grids = plies
            .iter()
            .map(|p| ColumnGrid::new(&column_layers(p), settings.cells_per_layer))
            .collect::<Result<Vec<_>, _>>()?;
        if grids.windows(2).any(|g| g[0].cells() != g[1].cells()) {
            return Err("the plies' stacks must have as many layers".into());
        }
        let mut node_ply = vec![0; positions.len()];
        let mut node_elements = vec![Vec::new(); positions.len()];
        for (k, (nodes, &p)) in elements.iter().zip(&element_ply).enumerate() {
            for &a in nodes {
                node_ply[a] = p;
                node_elements[a].push(k);
            }
        }
        let reference_areas = nodal_areas(&elements, positions);
        Ok(Self {
            plies,
            grids,
            node_ply,
            element_ply,
            elements,
            node_elements,
            reference_areas,
            tool_temperatures,
            settings,
        })
    }

    /// Cells per column.
    pub fn cells(&self) -> usize {
        self.grids[0].cells()
    }

    /// Layers per ply.
    pub fn layers(&self) -> usize {
        self.grids[0].layers().len()
    }

    /// The blank at `temperature` (°C) everywhere, nothing crystallised.
    pub fn uniform(&self, temperature: f64) -> ThermalState {
        let cells = self.cells();
        let nodes = self.node_ply.len();
        let crystallises = self
            .plies
            .iter()
            .any(|p| p.properties.crystallisation.is_some());
        ThermalState {
            temperatures: vec![temperature; nodes * cells],
            theta: if crystallises {
                vec![0.0; nodes * cells]
            } else {
                Vec::new()
            },
            cells,
            time: 0.0,
            wall_seconds: 0.0,
            heat: HeatAccount {
                to_tools: vec![0.0; self.tool_temperatures.len()],
                ..HeatAccount::default()
            },
        }
    }

    /// Advances `state` by `dt` of process time, in sub-steps no longer than the settings' step
    /// and the explicit exchanges' stable step.
    pub fn advance(
        &self,
        state: &mut ThermalState,
        sheet: &SheetNow,
        dt: f64,
    ) -> Result<(), HeatError> {
        if dt <= 0.0 {
            return Ok(());
        }
        let started = std::time::Instant::now();
        let outcome = self.advance_timed(state, sheet, dt);
        state.wall_seconds += started.elapsed().as_secs_f64();
        outcome
    }

    /// [`Self::advance`] itself.
    fn advance_timed(
        &self,
        state: &mut ThermalState,
        sheet: &SheetNow,
        dt: f64,
    ) -> Result<(), HeatError> {
        let conduction = self.conduction(sheet)?;
        let areas = nodal_areas(&self.elements, sheet.positions);
        let capacities = self.capacities(state)?;
        let limit = self
            .settings
            .time_step
            .min(0.5 * self.explicit_limit(&conduction, &capacities, sheet));
        let substeps = (dt / limit).ceil().max(1.0);
        let h = dt / substeps;
        for _ in 0..substeps as usize {
            self.substep(state, sheet, (&conduction, &areas), h)?;
        }
        Ok(())
    }

    /// One sub-step of `dt`.
    fn substep(
        &self,
        state: &mut ThermalState,
        sheet: &SheetNow,
        (conduction, areas): (&[CellConduction], &[f64]),
        dt: f64,
    ) -> Result<(), HeatError> {
        let capacities = self.capacities(state)?;
        let mut sources = self.in_plane_sources(state, sheet, conduction, dt);
        self.add_ply_exchanges(state, sheet, &mut sources, dt);
        let friction = self.add_friction(sheet, &mut sources, dt);
        let before = state.temperatures.clone();
        let flows = self.solve_columns(state, sheet, (&capacities, &sources, areas), dt)?;
        let latent = self.crystallise(state, &before, &capacities, dt)?;
        let stored: f64 = capacities
            .iter()
            .zip(state.temperatures.iter().zip(&before))
            .enumerate()
            .map(|(i, (c, (t, t0)))| c * (t - t0) * self.reference_areas[i / state.cells])
            .sum();
        let heat = &mut state.heat;
        heat.stored += stored;
        heat.latent += latent;
        heat.friction += friction;
        heat.to_air += flows.air;
        for (q, f) in heat.to_tools.iter_mut().zip(&flows.tools) {
            *q += f;
        }
        state.time += dt;
        Ok(())
    }

    /// Per cell, `rho c(T) dz` (N/(mm·K)): the heat per unit reference area per kelvin.
    fn capacities(&self, state: &ThermalState) -> Result<Vec<f64>, HeatError> {
        let cells = state.cells;
        let mut out = vec![0.0; state.temperatures.len()];
        for (a, column) in out.chunks_mut(cells).enumerate() {
            let p = self.node_ply[a];
            let (ply, grid) = (&self.plies[p], &self.grids[p]);
            for (i, c) in column.iter_mut().enumerate() {
                let t = state.temperatures[a * cells + i];
                let specific = ply.properties.specific_heat.at(t).map_err(|e| HeatError {
                    node: a,
                    reason: e.to_string(),
                })?;
                *c = ply.density * specific * grid.cell_thickness(i);
            }
        }
        Ok(out)
    }

    /// The in-plane conduction of each element on the current sheet (Eq. (H2)).
    fn conduction(&self, sheet: &SheetNow) -> Result<Vec<CellConduction>, HeatError> {
        self.elements
            .iter()
            .zip(sheet.yarns)
            .map(|(nodes, (warp, weft))| {
                CellConduction::new(nodes, sheet.positions, warp, weft).map_err(|e| HeatError {
                    node: nodes.first().copied().unwrap_or(0),
                    reason: e.to_string(),
                })
            })
            .collect()
    }

    /// In-plane `k dz` of level `cell` in element `k`, warp and weft (N·mm/(s·K)).
    fn level_conductivity(&self, sheet: &SheetNow, k: usize, cell: usize) -> (f64, f64) {
        let p = self.element_ply[k];
        let grid = &self.grids[p];
        let layer = grid.layer_of(cell);
        let stretch = sheet.stretch[k * grid.layers().len() + layer];
        let dz = grid.cell_thickness(cell) * stretch;
        let props = &self.plies[p].properties;
        match self.plies[p].layers[layer].0 {
            LayerKind::Fabric => (props.conductivity_warp * dz, props.conductivity_weft * dz),
            LayerKind::Matrix => (
                props.matrix_conductivity * dz,
                props.matrix_conductivity * dz,
            ),
        }
    }

    /// Heat each cell gains over `dt` by conduction in the plane, per unit reference area
    /// (N/mm), from the temperatures at the step's start.
    fn in_plane_sources(
        &self,
        state: &ThermalState,
        sheet: &SheetNow,
        conduction: &[CellConduction],
        dt: f64,
    ) -> Vec<f64> {
        let cells = state.cells;
        let nodes = self.node_ply.len();
        let levels: Vec<Vec<f64>> = (0..cells)
            .into_par_iter()
            .map(|cell| {
                let level: Vec<f64> = (0..nodes)
                    .map(|a| state.temperatures[a * cells + cell])
                    .collect();
                let mut rates = vec![0.0; nodes];
                add_heat_rates(
                    conduction,
                    |k| self.level_conductivity(sheet, k, cell),
                    &level,
                    &mut rates,
                );
                rates
            })
            .collect();
        let mut sources = vec![0.0; nodes * cells];
        for (cell, rates) in levels.iter().enumerate() {
            for (a, rate) in rates.iter().enumerate() {
                sources[a * cells + cell] = rate * dt / self.reference_areas[a];
            }
        }
        sources
    }

    /// The ply-to-ply exchanges over `dt` into the face cells, from the temperatures at the
    /// step's start: each pair's heat taken from one side and given to the other.
    fn add_ply_exchanges(
        &self,
        state: &ThermalState,
        sheet: &SheetNow,
        sources: &mut [f64],
        dt: f64,
    ) {
        let cells = state.cells;
        let face_cell = |a: usize, face: usize| a * cells + if face == 0 { 0 } else { cells - 1 };
        let h = self.settings.interply_conductance;
        for x in sheet.ply_exchanges {
            let other_face = 1 - x.face;
            let own = state.temperatures[face_cell(x.node, x.face)];
            let across: f64 = x
                .others
                .iter()
                .zip(&x.weights)
                .map(|(&b, w)| w * state.temperatures[face_cell(b, other_face)])
                .sum();
            let q = h * x.area * dt * (own - across);
            sources[face_cell(x.node, x.face)] -= q / self.reference_areas[x.node];
            for (&b, w) in x.others.iter().zip(&x.weights) {
                sources[face_cell(b, other_face)] += w * q / self.reference_areas[b];
            }
        }
    }

    /// The friction work of the step that heats the blank, into the cell of the face on the
    /// tool; returns it (N·mm).
    fn add_friction(&self, sheet: &SheetNow, sources: &mut [f64], dt: f64) -> f64 {
        let cells = self.cells();
        let fraction = self.settings.friction_heat_fraction;
        let mut total = 0.0;
        for (a, &power) in sheet.friction_power.iter().enumerate() {
            if power <= 0.0 {
                continue;
            }
            let q = fraction * power * dt;
            let face = match sheet.faces[a] {
                [Face::Tool { .. }, _] => 0,
                _ => cells - 1,
            };
            sources[a * cells + face] += q / self.reference_areas[a];
            total += q;
        }
        total
    }

    /// The exchange of a face at `surface` (°C) over a step.
    fn face_exchange(&self, face: Face, surface: f64, emissivity: f64) -> FaceExchange {
        match face {
            Face::Air => AirExchange {
                emissivity,
                ..self.settings.air
            }
            .face(surface),
            Face::Tool { tool, pressure } => FaceExchange {
                conductance: self.settings.contact_conductance_at(pressure),
                temperature: self.tool_temperatures[tool],
            },
            Face::Ply => FaceExchange::insulated(),
        }
    }

    /// Every column's backward-Euler step with its faces (in parallel, chunks summed in
    /// order); the heat that left into the room and each tool.
    fn solve_columns(
        &self,
        state: &mut ThermalState,
        sheet: &SheetNow,
        (capacities, sources, areas): (&[f64], &[f64], &[f64]),
        dt: f64,
    ) -> Result<Flows, HeatError> {
        let cells = state.cells;
        let tools = self.tool_temperatures.len();
        let chunks: Vec<Flows> = state
            .temperatures
            .par_chunks_mut(NODE_CHUNK * cells)
            .enumerate()
            .map(|(c, chunk)| {
                let mut scratch = ColumnScratch::default();
                let mut flows = Flows::new(tools);
                let mut stretch = vec![1.0; self.layers()];
                for (i, temps) in chunk.chunks_mut(cells).enumerate() {
                    let a = c * NODE_CHUNK + i;
                    let p = self.node_ply[a];
                    let emissivity = self.plies[p].properties.emissivity;
                    let faces = [
                        self.face_exchange(sheet.faces[a][0], temps[0], emissivity),
                        self.face_exchange(sheet.faces[a][1], temps[cells - 1], emissivity),
                    ];
                    self.node_stretch(sheet, a, &mut stretch);
                    let range = a * cells..(a + 1) * cells;
                    let step = ColumnStep {
                        capacities: &capacities[range.clone()],
                        thickness_stretch: &stretch,
                        area_ratio: areas[a] / self.reference_areas[a],
                        faces,
                        sources: &sources[range],
                        dt,
                    };
                    let out = step_column(&self.grids[p], &step, temps, &mut scratch);
                    for (side, q) in out.iter().enumerate() {
                        let q = q * self.reference_areas[a];
                        match sheet.faces[a][side] {
                            Face::Air => flows.air += q,
                            Face::Tool { tool, .. } => flows.tools[tool] += q,
                            Face::Ply => {}
                        }
                    }
                }
                flows
            })
            .collect();
        let mut total = Flows::new(tools);
        for chunk in chunks {
            total.air += chunk.air;
            for (t, q) in total.tools.iter_mut().zip(chunk.tools) {
                *t += q;
            }
        }
        Ok(total)
    }

    /// Thickness stretch of each layer at node `a`: the mean over its elements.
    fn node_stretch(&self, sheet: &SheetNow, a: usize, out: &mut [f64]) {
        let layers = out.len();
        out.fill(0.0);
        let around = &self.node_elements[a];
        for &k in around {
            for (l, s) in out.iter_mut().enumerate() {
                *s += sheet.stretch[k * layers + l];
            }
        }
        let count = around.len().max(1) as f64;
        out.iter_mut().for_each(|s| *s /= count);
    }

    /// Advances every cell's crystallisation over the step from `before` to the current
    /// temperatures and releases its latent heat into the cell (Eq. (H8)); the heat released
    /// (N·mm).
    fn crystallise(
        &self,
        state: &mut ThermalState,
        before: &[f64],
        capacities: &[f64],
        dt: f64,
    ) -> Result<f64, HeatError> {
        if state.theta.is_empty() {
            return Ok(0.0);
        }
        let cells = state.cells;
        let mut released = 0.0;
        for a in 0..self.node_ply.len() {
            let p = self.node_ply[a];
            let Some(crystal) = &self.plies[p].properties.crystallisation else {
                continue;
            };
            for i in a * cells..(a + 1) * cells {
                let error = |reason: String| HeatError { node: a, reason };
                let theta = crystal
                    .kinetics
                    .advance(state.theta[i], before[i], state.temperatures[i], dt)
                    .map_err(|e| error(e.to_string()))?;
                let x_old = crystal.kinetics.fraction(state.theta[i]);
                let x_new = crystal.kinetics.fraction(theta);
                state.theta[i] = theta;
                if x_new > x_old {
                    // the heat stays in the cell, raising it by what the step's capacity says
                    // (the one the heat content is booked with)
                    let per_volume = latent_heat_release(
                        self.plies[p].density,
                        crystal.latent_heat,
                        x_old,
                        x_new,
                    );
                    let heat = per_volume * self.grids[p].cell_thickness(i - a * cells);
                    state.temperatures[i] += heat / capacities[i];
                    released += heat * self.reference_areas[a];
                }
            }
        }
        Ok(released)
    }

    /// The longest step the explicit exchanges allow: in-plane conduction and the ply-to-ply
    /// conductance against the capacity of a face cell.
    fn explicit_limit(
        &self,
        conduction: &[CellConduction],
        capacities: &[f64],
        sheet: &SheetNow,
    ) -> f64 {
        let cells = self.cells();
        let nodes = self.node_ply.len();
        let mut limit = f64::INFINITY;
        for cell in 0..cells {
            let level: Vec<f64> = (0..nodes)
                .map(|a| capacities[a * cells + cell] * self.reference_areas[a])
                .collect();
            let step = stable_step(
                conduction,
                |k| self.level_conductivity(sheet, k, cell),
                &level,
            );
            limit = limit.min(step);
        }
        let h = self.settings.interply_conductance;
        if h > 0.0 && !sheet.ply_exchanges.is_empty() {
            let thinnest = (0..nodes)
                .flat_map(|a| [capacities[a * cells], capacities[a * cells + cells - 1]])
                .fold(f64::INFINITY, f64::min);
            limit = limit.min(thinnest / h);
        }
        limit
    }

    /// Mean temperature of each layer of each element (°C), element by element: the mean over
    /// its nodes of each layer's thickness-weighted mean.
    pub fn element_layer_temperatures(&self, state: &ThermalState) -> Vec<f64> {
        self.element_layer_means(state, &state.temperatures)
    }

    /// Mean relative crystallinity of each layer of each element, element by element; zeros
    /// without crystallisation.
    pub fn element_layer_crystallinity(&self, state: &ThermalState) -> Vec<f64> {
        let layers = self.layers();
        if state.theta.is_empty() {
            return vec![0.0; self.elements.len() * layers];
        }
        let fractions: Vec<f64> = state
            .theta
            .iter()
            .enumerate()
            .map(|(i, &theta)| {
                let p = self.node_ply[i / state.cells];
                self.plies[p]
                    .properties
                    .crystallisation
                    .as_ref()
                    .map_or(0.0, |c| c.kinetics.fraction(theta))
            })
            .collect();
        self.element_layer_means(state, &fractions)
    }

    /// Per element and layer, the mean over its nodes of a cell field's layer means.
    fn element_layer_means(&self, state: &ThermalState, field: &[f64]) -> Vec<f64> {
        let (cells, layers) = (state.cells, self.layers());
        let mut node_means = vec![0.0; self.node_ply.len() * layers];
        for (a, means) in node_means.chunks_mut(layers).enumerate() {
            let grid = &self.grids[self.node_ply[a]];
            grid.layer_means(&field[a * cells..(a + 1) * cells], means);
        }
        let mut out = Vec::with_capacity(self.elements.len() * layers);
        for nodes in &self.elements {
            for layer in 0..layers {
                let sum: f64 = nodes.iter().map(|&a| node_means[a * layers + layer]).sum();
                out.push(sum / nodes.len() as f64);
            }
        }
        out
    }

    /// The thickness-weighted mean temperature through each node's column (°C).
    pub fn node_mean_temperatures(&self, state: &ThermalState) -> Vec<f64> {
        (0..self.node_ply.len())
            .map(|a| {
                let grid = &self.grids[self.node_ply[a]];
                let column = state.column(a);
                let total: f64 = (0..column.len()).map(|i| grid.cell_thickness(i)).sum();
                column
                    .iter()
                    .enumerate()
                    .map(|(i, t)| t * grid.cell_thickness(i))
                    .sum::<f64>()
                    / total
            })
            .collect()
    }

    /// The lowest and highest cell temperature and the mean through the blank, weighted by
    /// each cell's share of the heat capacity at rest (its mass) (°C).
    pub fn extremes(&self, state: &ThermalState) -> FieldExtremes {
        let cells = state.cells;
        let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
        let (mut weighted, mut mass) = (0.0, 0.0);
        for (a, column) in state.temperatures.chunks(cells).enumerate() {
            let p = self.node_ply[a];
            for (i, &t) in column.iter().enumerate() {
                low = low.min(t);
                high = high.max(t);
                let m = self.plies[p].density
                    * self.grids[p].cell_thickness(i)
                    * self.reference_areas[a];
                weighted += m * t;
                mass += m;
            }
        }
        FieldExtremes {
            min: low,
            mean: weighted / mass,
            max: high,
        }
    }

    /// The reference area (mm²) of the elements where each layer has frozen (its relative
    /// crystallinity past the card's `frozen_at`), layer by layer, and where any has.
    pub fn frozen_areas(&self, state: &ThermalState, areas: &[f64]) -> (Vec<f64>, f64) {
        let layers = self.layers();
        let crystallinity = self.element_layer_crystallinity(state);
        let mut per_layer = vec![0.0; layers];
        let mut any = 0.0;
        for (k, area) in areas.iter().enumerate() {
            let Some(limit) = self.frozen_at(k) else {
                continue;
            };
            let frozen: Vec<bool> = (0..layers)
                .map(|l| crystallinity[k * layers + l] >= limit)
                .collect();
            for (sum, &f) in per_layer.iter_mut().zip(&frozen) {
                if f {
                    *sum += area;
                }
            }
            if frozen.contains(&true) {
                any += area;
            }
        }
        (per_layer, any)
    }

    /// The ply of element `k`.
    pub fn ply_of_element(&self, k: usize) -> usize {
        self.element_ply[k]
    }

    /// Each ply's layers' shares of its thickness: the weights of a mean through it.
    pub fn layer_thickness_shares(&self) -> Vec<Vec<f64>> {
        self.plies
            .iter()
            .map(|p| {
                let total: f64 = p.layers.iter().map(|l| l.1).sum();
                p.layers.iter().map(|l| l.1 / total).collect()
            })
            .collect()
    }

    /// The frozen-at crystallinity of the ply of element `k`; `None` without crystallisation.
    pub fn frozen_at(&self, k: usize) -> Option<f64> {
        self.plies[self.element_ply[k]]
            .properties
            .crystallisation
            .as_ref()
            .map(|c| c.frozen_at)
    }
}

/// The coldest and hottest cell of the blank and its mean temperature (°C).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FieldExtremes {
    pub min: f64,
    pub mean: f64,
    pub max: f64,
}

/// The heat that left through the faces in a step (N·mm): to the room and to each tool.
struct Flows {
    air: f64,
    tools: Vec<f64>,
}

impl Flows {
    fn new(tools: usize) -> Self {
        Self {
            air: 0.0,
            tools: vec![0.0; tools],
        }
    }
}

/// The column layers of a ply: through-thickness conductivity of each (N/(s·K)).
fn column_layers(ply: &PlyHeat) -> Vec<ColumnLayer> {
    ply.layers
        .iter()
        .map(|&(kind, thickness)| ColumnLayer {
            thickness,
            conductivity: match kind {
                LayerKind::Fabric => ply.properties.conductivity_through,
                LayerKind::Matrix => ply.properties.matrix_conductivity,
            },
        })
        .collect()
}

/// An equal share of each element's area at each of its nodes (mm²), quadrilaterals as two
/// triangles.
fn nodal_areas(elements: &[Vec<usize>], positions: &[Vector3<f64>]) -> Vec<f64> {
    let mut areas = vec![0.0; positions.len()];
    let triangle = |a: usize, b: usize, c: usize| {
        0.5 * (positions[b] - positions[a])
            .cross(&(positions[c] - positions[a]))
            .norm()
    };
    for nodes in elements {
        let area = match nodes[..] {
            [a, b, c] => triangle(a, b, c),
            [a, b, c, d] => triangle(a, b, c) + triangle(a, c, d),
            _ => 0.0,
        };
        for &n in nodes {
            areas[n] += area / nodes.len() as f64;
        }
    }
    areas
}

/// W/(m²·K) of a scenario in the program's N/(mm·s·K).
pub fn heat_transfer(w_per_m2_k: f64) -> f64 {
    w_per_m2_k * HEAT_TRANSFER_UNIT
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::crystallisation::Nakamura;
    use crate::thermal::properties::{
        Crystallisation, Table, LATENT_HEAT_UNIT, SPECIFIC_HEAT_UNIT,
    };

    /// A flat blank of `n x n` square cells of `size` mm in z = 0, one ply of an A:B:A stack.
    fn blank(n: usize, size: f64, crystallises: bool) -> (BlankHeat, Vec<Vector3<f64>>) {
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                positions.push(Vector3::new(i as f64 * size, j as f64 * size, 0.0));
            }
        }
        let at = |i: usize, j: usize| j * (n + 1) + i;
        let elements: Vec<Vec<usize>> = (0..n)
            .flat_map(|j| (0..n).map(move |i| (i, j)))
            .map(|(i, j)| vec![at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])
            .collect();
        let crystallisation = crystallises.then(|| Crystallisation {
            kinetics: Nakamura::new(3.0, vec![100.0, 250.0], vec![0.5, 0.05]).unwrap(),
            latent_heat: 20.0 * LATENT_HEAT_UNIT,
            frozen_at: 0.5,
        });
        let properties = ThermalProperties {
            specific_heat: Table::new(
                "specific_heat",
                vec![0.0, 400.0],
                vec![900.0 * SPECIFIC_HEAT_UNIT, 1500.0 * SPECIFIC_HEAT_UNIT],
            )
            .unwrap(),
            conductivity_warp: 3.0,
            conductivity_weft: 1.0,
            conductivity_through: 0.35,
            matrix_conductivity: 0.3,
            emissivity: 0.9,
            crystallisation,
        };
        let ply = PlyHeat {
            properties,
            density: 1.56e-9,
            layers: vec![
                (LayerKind::Matrix, 0.04),
                (LayerKind::Fabric, 0.23),
                (LayerKind::Matrix, 0.04),
            ],
        };
        let settings = HeatSettings {
            cells_per_layer: 3,
            time_step: 0.01,
            air: AirExchange {
                convection: 0.01,
                emissivity: 0.0,
                room_temperature: 25.0,
            },
            contact_conductance: vec![(0.0, 0.5), (1.0, 2.0)],
            interply_conductance: 3.0,
            friction_heat_fraction: 0.5,
        };
        let count = elements.len();
        let heat = BlankHeat::new(
            vec![ply],
            elements,
            vec![0; count],
            &positions,
            vec![200.0],
            settings,
        )
        .unwrap();
        (heat, positions)
    }

    /// Half the blank on a tool, the rest in air, friction heating a corner, the matrix
    /// crystallising: the heat content changes by what went in and out (Eq. (H10)) to 1e-12,
    /// every flow is at work, and the tool side ends colder than the air side.
    #[test]
    fn heat_balances_with_every_flow_at_work() {
        let (heat, positions) = blank(4, 5.0, true);
        let nodes = positions.len();
        let faces: Vec<[Face; 2]> = positions
            .iter()
            .map(|x| match x.x < 10.0 {
                true => [
                    Face::Tool {
                        tool: 0,
                        pressure: 0.5,
                    },
                    Face::Air,
                ],
                false => [Face::Air, Face::Air],
            })
            .collect();
        let mut friction = vec![0.0; nodes];
        friction[0] = 50.0;
        let yarns = vec![(Vector3::x(), Vector3::y()); 16];
        let stretch = vec![1.0; 16 * 3];
        let sheet = SheetNow {
            positions: &positions,
            yarns: &yarns,
            stretch: &stretch,
            faces: &faces,
            ply_exchanges: &[],
            friction_power: &friction,
        };
        let mut state = heat.uniform(260.0);
        heat.advance(&mut state, &sheet, 0.3).unwrap();
        // node 5 lies at (0, 5 mm): on the tool, off the rubbed corner; the last in the air
        let (on_tool, in_air) = (state.column(5), state.column(nodes - 1));
        assert!(on_tool[0] < in_air[0], "{on_tool:?} against {in_air:?}");
        assert!(
            on_tool[0] < on_tool[8],
            "the face on the tool is colder: {on_tool:?}"
        );
        heat.advance(&mut state, &sheet, 2.7).unwrap();
        let q = &state.heat;
        assert!(q.to_tools[0] > 0.0 && q.to_air > 0.0 && q.latent > 0.0 && q.friction > 0.0);
        assert!(
            q.imbalance().abs() <= 1e-12 * q.scale(),
            "imbalance {:e} of {:e}",
            q.imbalance(),
            q.scale()
        );
    }

    /// Everything at one temperature, no friction: the field does not move by a bit, whatever
    /// the stretch of the sheet (the isothermal limit).
    #[test]
    fn a_uniform_field_at_its_surroundings_temperature_stays_put() {
        let (mut heat, positions) = blank(3, 4.0, false);
        heat.settings.air.room_temperature = 200.0;
        let moved: Vec<Vector3<f64>> = positions
            .iter()
            .map(|x| Vector3::new(1.1 * x.x, 0.9 * x.y, 0.05 * x.x))
            .collect();
        let faces = vec![
            [
                Face::Tool {
                    tool: 0,
                    pressure: 0.3
                },
                Face::Air
            ];
            positions.len()
        ];
        let yarns = vec![(Vector3::new(1.0, 0.2, 0.0), Vector3::y()); 9];
        let stretch = vec![0.95; 9 * 3];
        let friction = vec![0.0; positions.len()];
        let sheet = SheetNow {
            positions: &moved,
            yarns: &yarns,
            stretch: &stretch,
            faces: &faces,
            ply_exchanges: &[],
            friction_power: &friction,
        };
        let mut state = heat.uniform(200.0);
        heat.advance(&mut state, &sheet, 1.0).unwrap();
        assert!(state.temperatures.iter().all(|&t| t == 200.0));
        assert_eq!(state.heat.stored, 0.0);
    }

    /// Two plies stacked node over node exchange heat through their touching faces: a hot ply on
    /// a cold one warms it, the heat one loses the other gains.
    #[test]
    fn plies_in_contact_share_their_heat() {
        let (single, positions) = blank(2, 5.0, false);
        let n = positions.len();
        let mut stacked = positions.clone();
        stacked.extend(positions.iter().map(|x| x + Vector3::new(0.0, 0.0, 0.31)));
        let elements: Vec<Vec<usize>> = single
            .elements
            .iter()
            .cloned()
            .chain(
                single
                    .elements
                    .iter()
                    .map(|e| e.iter().map(|a| a + n).collect()),
            )
            .collect();
        let heat = BlankHeat::new(
            vec![single.plies[0].clone(), single.plies[0].clone()],
            elements,
            vec![0, 0, 0, 0, 1, 1, 1, 1],
            &stacked,
            vec![200.0],
            single.settings.clone(),
        )
        .unwrap();
        let exchanges: Vec<PlyExchange> = (0..n)
            .flat_map(|a| {
                let up = PlyExchange {
                    node: a,
                    face: 1,
                    others: [a + n, a + n, a + n],
                    weights: [1.0, 0.0, 0.0],
                    area: 0.5 * heat.reference_areas[a],
                };
                let down = PlyExchange {
                    node: a + n,
                    face: 0,
                    others: [a, a, a],
                    weights: [1.0, 0.0, 0.0],
                    area: 0.5 * heat.reference_areas[a],
                };
                [up, down]
            })
            .collect();
        let mut faces = vec![[Face::Air, Face::Ply]; n];
        faces.extend(vec![[Face::Ply, Face::Air]; n]);
        let yarns = vec![(Vector3::x(), Vector3::y()); 8];
        let stretch = vec![1.0; 8 * 3];
        let friction = vec![0.0; 2 * n];
        let sheet = SheetNow {
            positions: &stacked,
            yarns: &yarns,
            stretch: &stretch,
            faces: &faces,
            ply_exchanges: &exchanges,
            friction_power: &friction,
        };
        let mut state = heat.uniform(300.0);
        for t in state.temperatures[..n * state.cells].iter_mut() {
            *t = 250.0;
        }
        heat.advance(&mut state, &sheet, 0.5).unwrap();
        let lower = state.column(0)[8];
        let upper = state.column(n)[0];
        assert!(lower > 250.0 && upper < 300.0, "{lower} {upper}");
        let q = &state.heat;
        assert!(q.imbalance().abs() <= 1e-12 * q.scale());
    }
}
