//! What the solver integrates: the meshed plies of the blank, each with its laminate, and the
//! constraints. The plies' nodes and elements are numbered one ply after the other in one mesh,
//! so that the solvers, the tangent and the writers see one set of nodes; each ply knows its
//! ranges.

use super::heat::HeatModel;
use crate::contact::ply_contact::{PlyContact, PlyInterface, PlySurface};
use crate::contact::{ContactSettings, RigidTool};
use crate::element::bending::BendingError;
use crate::element::membrane::ElementError;
use crate::element::membrane::HourglassModuli;
use crate::element::{Bending, BendingRigidity, MembraneElement};
use crate::material::{
    FibreDirections, Laminate, LayerTemperatures, MaterialError, MembraneKinematics,
};
use crate::mesh::{Mesh, MeshError};
use crate::support::Supports;
use nalgebra::{Matrix2, Vector3};
use std::ops::Range;
use std::sync::Arc;

/// Velocity of a constrained node at time `t` given its reference position.
pub type VelocityField = Arc<dyn Fn(f64, &Vector3<f64>) -> Vector3<f64> + Send + Sync>;

/// How the nodes of a constraint move.
#[derive(Clone)]
pub enum Motion {
    /// Held in place.
    Fixed,
    /// Moved with a prescribed velocity (all three components).
    Velocity(VelocityField),
    /// Held along the global axes marked `true` (x, y, z), free along the others: a symmetry
    /// plane or a guide.
    Components([bool; 3]),
}

impl std::fmt::Debug for Motion {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Motion::Fixed => write!(f, "Fixed"),
            Motion::Velocity(_) => write!(f, "Velocity(..)"),
            Motion::Components(held) => write!(f, "Components({held:?})"),
        }
    }
}

/// A named group of nodes whose motion is prescribed; its reaction force is reported.
#[derive(Clone, Debug)]
pub struct Constraint {
    pub name: String,
    pub nodes: Vec<usize>,
    pub motion: Motion,
}

/// One sheet of the blank: its nodes and elements in the model's numbering and its material.
#[derive(Clone, Debug)]
pub struct Ply {
    pub name: String,
    pub nodes: Range<usize>,
    pub elements: Range<usize>,
    /// The ply's laminate, its temperature tables interpolated once at the run's temperature
    /// (the run is isothermal).
    pub laminate: Laminate,
    /// What holds the hourglass mode of its quadrilaterals
    /// ([`MembraneElement::hourglass_forces`]): the laminate's shear and yarn stiffness at
    /// rest; zero on a mesh of triangles.
    pub hourglass: HourglassModuli,
    /// Density of the ply (tonne/mm^3).
    pub density: f64,
}

/// A ply as it is given to [`Model::layup`]: its own mesh, laminate and warp direction.
#[derive(Clone, Debug)]
pub struct PlySheet {
    pub name: String,
    pub mesh: Mesh,
    pub laminate: Laminate,
    /// Density (tonne/mm^3).
    pub density: f64,
    /// Projected onto each element, unless the mesh gives its own per-element directions
    /// (`Mesh::warp_directions`).
    pub warp_direction: Vector3<f64>,
}

/// A blank ready to be integrated.
#[derive(Clone, Debug)]
pub struct Model {
    /// Every ply's nodes and cells, one ply after the other.
    pub mesh: Mesh,
    pub elements: Vec<MembraneElement>,
    /// Bending stiffness; `None` for a membrane.
    pub bending: Option<Bending>,
    /// Rigid tools in contact with the blank, and how the contact is computed.
    pub tools: Vec<RigidTool>,
    /// How the contact with the tools is computed; its `offset` is every tool's unless
    /// [`Self::with_tool_offset`] gives a tool its own.
    pub contact: ContactSettings,
    /// Per tool, where given, the distance from the mid-surface of the ply it touches to its
    /// face (mm): half that ply's thickness, for a layup of plies of several thicknesses.
    tool_offsets: Vec<Option<f64>>,
    pub plies: Vec<Ply>,
    /// The plies that touch, with the friction between them (docs/model.md §6, "Ply–ply
    /// contact"); none on a blank of one ply.
    pub interfaces: Vec<PlyInterface>,
    /// The ply of each element.
    element_ply: Vec<usize>,
    /// Isothermal temperature of the run (°C); in a non-isothermal run, the blank's out of the
    /// oven, at which what is not evaluated at the local temperature is taken.
    pub temperature: f64,
    pub constraints: Vec<Constraint>,
    /// The heat problem of a non-isothermal run (docs/model.md §9); `None`: isothermal.
    pub heat: Option<HeatModel>,
    /// Gravity, springs and grippers (docs/model.md §10); empty by default.
    pub supports: Supports,
}

/// Why a model cannot be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    #[error("element {element}: {error}")]
    Element { element: usize, error: ElementError },
    #[error("node {node} belongs to constraints '{first}' and '{second}'")]
    DoublyConstrained {
        node: usize,
        first: String,
        second: String,
    },
    #[error("constraint '{name}' names node {node}, but the mesh has {nodes} nodes")]
    UnknownNode {
        name: String,
        node: usize,
        nodes: usize,
    },
    #[error("node {0} belongs to no element: it would have no mass")]
    OrphanNode(usize),
    #[error("ply '{ply}': density {density} must be > 0")]
    Density { ply: String, density: f64 },
    #[error("a blank needs at least one ply")]
    NoPly,
    #[error(
        "ply '{ply}': its laminate has {layers} layers, the first ply's {first}: the plies' \
         cards must have the same layers"
    )]
    Layers {
        ply: String,
        layers: usize,
        first: usize,
    },
    #[error("laminate at the run's temperature: {0}")]
    Material(String),
    #[error("bending: {0}")]
    Bending(#[from] BendingError),
    #[error("interface {index} (plies {lower} and {upper}): {reason}")]
    Interface {
        index: usize,
        lower: usize,
        upper: usize,
        reason: String,
    },
}

impl Model {
    /// Element `k` undeformed and at rest, at the model's temperature: what the stable
    /// step at rest and the run's estimate and checks evaluate the laminate on.
    pub fn rest_kinematics(&self, k: usize) -> MembraneKinematics {
        MembraneKinematics {
            c: Matrix2::identity(),
            c_dot: Matrix2::zeros(),
            temperature: self.temperature.into(),
            fibres: self.elements[k].fibres,
        }
    }

    /// A blank of one ply: the elements of `mesh` with the warp along `warp_direction` projected
    /// on each, or along the mesh's own per-element directions where it has them (a mesh
    /// file's orientations, `Mesh::warp_directions`).
    pub fn new(
        mesh: Mesh,
        laminate: Laminate,
        density: f64,
        temperature: f64,
        warp_direction: Vector3<f64>,
        constraints: Vec<Constraint>,
    ) -> Result<Self, ModelError> {
        let ply = PlySheet {
            name: "ply 1".into(),
            mesh,
            laminate,
            density,
            warp_direction,
        };
        Self::layup(vec![ply], temperature, constraints)
    }

    /// A blank of several plies, numbered in the order given; `constraints` name nodes in the
    /// model's numbering (the first ply's nodes first).
    pub fn layup(
        sheets: Vec<PlySheet>,
        temperature: f64,
        constraints: Vec<Constraint>,
    ) -> Result<Self, ModelError> {
        let first_layers = match sheets.first() {
            Some(first) => first.laminate.layers().len(),
            None => return Err(ModelError::NoPly),
        };
        let mut mesh = Mesh::default();
        let mut elements = Vec::new();
        let mut plies = Vec::with_capacity(sheets.len());
        let single = sheets.len() == 1;
        for sheet in sheets {
            sheet.mesh.validate()?;
            check_ply_material(&sheet, first_layers)?;
            let sheet_elements = ply_elements(&sheet.mesh, &sheet.warp_direction, elements.len())?;
            let hourglass = match sheet.mesh.has_quads() {
                true => rest_moduli(&sheet.laminate, temperature)
                    .map_err(|e| ModelError::Material(e.to_string()))?,
                false => HourglassModuli::default(),
            };
            let nodes = mesh.nodes.len()..mesh.nodes.len() + sheet.mesh.nodes.len();
            let element_range = elements.len()..elements.len() + sheet_elements.len();
            let prefix = if single {
                String::new()
            } else {
                format!("{}/", sheet.name)
            };
            mesh.append(sheet.mesh, &prefix);
            elements.extend(sheet_elements.into_iter().map(|mut e| {
                e.cell = e.cell.map(|n| n + nodes.start);
                e
            }));
            plies.push(Ply {
                name: sheet.name,
                nodes,
                elements: element_range,
                laminate: sheet.laminate.at_temperature(temperature),
                hourglass,
                density: sheet.density,
            });
        }
        check_every_node_used(&mesh)?;
        check_constraints(&constraints, mesh.nodes.len())?;
        let element_ply = plies
            .iter()
            .enumerate()
            .flat_map(|(i, p)| p.elements.clone().map(move |_| i))
            .collect();
        let thickness = plies[0].laminate.reference_thickness();
        Ok(Self {
            mesh,
            elements,
            bending: None,
            tools: Vec::new(),
            tool_offsets: Vec::new(),
            contact: ContactSettings {
                offset: thickness / 2.0,
                penalty_scale: 0.1,
                max_penetration: thickness,
            },
            plies,
            interfaces: Vec::new(),
            element_ply,
            temperature,
            constraints,
            heat: None,
            supports: Supports::default(),
        })
    }

    /// The temperature of each layer of element `k` (°C) in a field of per-element
    /// `temperatures`; the model's own where the field is empty (an isothermal run).
    pub fn element_temperature(
        &self,
        temperatures: &[LayerTemperatures],
        k: usize,
    ) -> LayerTemperatures {
        temperatures
            .get(k)
            .copied()
            .unwrap_or_else(|| self.temperature.into())
    }

    /// The same blank under gravity, held by springs or grippers.
    pub fn with_supports(mut self, supports: Supports) -> Self {
        self.supports = supports;
        self
    }

    /// Each node's physical mass, `sum_e rho t A / corners` over its elements (tonne): what
    /// gravity acts on, whatever mass scaling adds.
    pub fn physical_nodal_masses(&self) -> Vec<f64> {
        let mut masses = vec![0.0; self.mesh.nodes.len()];
        for (k, e) in self.elements.iter().enumerate() {
            let share = self.density(k) * self.thickness(k) * e.area / e.nodes().len() as f64;
            for &a in e.nodes() {
                masses[a] += share;
            }
        }
        masses
    }

    /// The same blank with a temperature field: a non-isothermal run.
    pub fn with_heat(mut self, heat: HeatModel) -> Self {
        self.heat = Some(heat);
        self
    }

    /// The ply element `k` belongs to.
    pub fn ply_of(&self, k: usize) -> &Ply {
        &self.plies[self.element_ply[k]]
    }

    /// The index in [`Self::plies`] of the ply element `k` belongs to.
    pub fn ply_index(&self, k: usize) -> usize {
        self.element_ply[k]
    }

    /// The laminate of element `k`.
    pub fn laminate(&self, k: usize) -> &Laminate {
        &self.ply_of(k).laminate
    }

    /// The reference thickness of element `k` (mm).
    pub fn thickness(&self, k: usize) -> f64 {
        self.laminate(k).reference_thickness()
    }

    /// The density of element `k` (tonne/mm^3).
    pub fn density(&self, k: usize) -> f64 {
        self.ply_of(k).density
    }

    /// The hourglass moduli of element `k`.
    pub fn hourglass(&self, k: usize) -> &HourglassModuli {
        &self.ply_of(k).hourglass
    }

    /// The same sheet with bending stiffness: a rotation-free bending patch per triangle
    /// (docs/model.md §4, `element::bending`), the reference mesh's curvature at rest.
    pub fn with_bending(self, rigidity: BendingRigidity) -> Result<Self, ModelError> {
        let rigidities = vec![rigidity; self.plies.len()];
        self.with_ply_bending(&rigidities)
    }

    /// The same blank with each ply's own bending rigidity (in the order of [`Self::plies`]).
    pub fn with_ply_bending(mut self, rigidities: &[BendingRigidity]) -> Result<Self, ModelError> {
        let per_element: Vec<BendingRigidity> =
            self.element_ply.iter().map(|&p| rigidities[p]).collect();
        self.bending = Some(Bending::new(&self.mesh, &self.elements, &per_element)?);
        Ok(self)
    }

    /// The same blank with contact and friction across `interfaces`, each between two
    /// different plies of the blank (in the order of [`Self::plies`]), no pair twice.
    pub fn with_interfaces(mut self, interfaces: Vec<PlyInterface>) -> Result<Self, ModelError> {
        for (index, face) in interfaces.iter().enumerate() {
            let refuse = |reason: String| ModelError::Interface {
                index,
                lower: face.lower,
                upper: face.upper,
                reason,
            };
            let plies = self.plies.len();
            if face.lower >= plies || face.upper >= plies {
                return Err(refuse(format!("the blank has {plies} plies")));
            }
            if face.lower == face.upper {
                return Err(refuse("a ply does not touch itself".into()));
            }
            let taken = interfaces[..index]
                .iter()
                .any(|f| f.upper == face.upper || f.lower == face.lower);
            if taken {
                return Err(refuse(
                    "a ply has one interface below and one above it at most".into(),
                ));
            }
            face.friction.validate().map_err(refuse)?;
        }
        self.interfaces = interfaces;
        Ok(self)
    }

    /// Each ply as the ply–ply contact sees it: its cells cut into triangles.
    pub fn ply_surfaces(&self) -> Vec<PlySurface> {
        self.plies
            .iter()
            .map(|ply| PlySurface {
                nodes: ply.nodes.clone(),
                triangles: self.elements[ply.elements.clone()]
                    .iter()
                    .flat_map(|e| match *e.nodes() {
                        [a, b, c] => vec![[a, b, c]],
                        [a, b, c, d] => vec![[a, b, c], [a, c, d]],
                        _ => vec![],
                    })
                    .collect(),
                half_thickness: 0.5 * ply.laminate.reference_thickness(),
            })
            .collect()
    }

    /// The contact between the plies across [`Self::interfaces`], with a Verlet margin of
    /// `margin_cells` mean cell sizes; `None` without any interface.
    pub fn ply_contact(&self, margin_cells: f64) -> Option<PlyContact> {
        if self.interfaces.is_empty() {
            return None;
        }
        let settings = (
            self.contact.penalty_scale,
            self.thinnest_ply(),
            margin_cells * self.mean_cell_size(),
        );
        Some(PlyContact::new(
            self.ply_surfaces(),
            self.interfaces.clone(),
            self.nodal_areas(),
            settings,
        ))
    }

    /// The mean of the cells' square roots of area (mm).
    pub fn mean_cell_size(&self) -> f64 {
        self.elements.iter().map(|e| e.area.sqrt()).sum::<f64>() / self.elements.len().max(1) as f64
    }

    /// The same sheet between rigid tools, with the contact settings given.
    pub fn with_tools(mut self, tools: Vec<RigidTool>, contact: ContactSettings) -> Self {
        self.tool_offsets = vec![None; tools.len()];
        self.tools = tools;
        self.contact = contact;
        self
    }

    /// The same model with tool `k` touching a ply whose mid-surface lies `offset` (mm) from
    /// the tool's face: half the thickness of the ply next to it.
    pub fn with_tool_offset(mut self, k: usize, offset: f64) -> Self {
        self.tool_offsets[k] = Some(offset);
        self
    }

    /// The contact of tool `k` with the blank: [`Self::contact`] with the tool's own offset.
    pub fn tool_contact(&self, k: usize) -> ContactSettings {
        let offset = self.tool_offsets.get(k).copied().flatten();
        ContactSettings {
            offset: offset.unwrap_or(self.contact.offset),
            ..self.contact
        }
    }

    /// Every tool's [`Self::tool_contact`], in the order of [`Self::tools`].
    pub fn tool_contacts(&self) -> Vec<ContactSettings> {
        (0..self.tools.len())
            .map(|k| self.tool_contact(k))
            .collect()
    }

    /// The blank's mass without mass scaling, `sum_e rho t A` (tonne).
    pub fn physical_mass(&self) -> f64 {
        (0..self.elements.len())
            .map(|k| self.density(k) * self.thickness(k) * self.elements[k].area)
            .sum()
    }

    /// The thinnest ply's reference thickness (mm).
    pub fn thinnest_ply(&self) -> f64 {
        self.plies
            .iter()
            .map(|p| p.laminate.reference_thickness())
            .fold(f64::INFINITY, f64::min)
    }

    /// An equal share of the reference area of each element at each of its corners (mm^2).
    pub fn nodal_areas(&self) -> Vec<f64> {
        let mut area = vec![0.0; self.mesh.nodes.len()];
        for e in &self.elements {
            for &n in e.nodes() {
                area[n] += e.area / e.nodes().len() as f64;
            }
        }
        area
    }
}

/// `G t0` and `E t0` of the laminate at rest at `temperature` (`E` its wave modulus along a
/// yarn, what sets the stable step).
pub(crate) fn rest_moduli(
    laminate: &Laminate,
    temperature: f64,
) -> Result<HourglassModuli, MaterialError> {
    let t0 = laminate.reference_thickness();
    let rest = MembraneKinematics {
        c: nalgebra::Matrix2::identity(),
        c_dot: nalgebra::Matrix2::zeros(),
        temperature: temperature.into(),
        fibres: FibreDirections::default(),
    };
    Ok(HourglassModuli {
        shear: laminate.shear_modulus(temperature)? * t0,
        yarn: laminate.wave_modulus(&rest, &laminate.initial_state())? * t0,
    })
}

/// The elements of one ply's `mesh`, numbered from `first` in the errors.
fn ply_elements(
    mesh: &Mesh,
    warp_direction: &Vector3<f64>,
    first: usize,
) -> Result<Vec<MembraneElement>, ModelError> {
    mesh.cells
        .iter()
        .enumerate()
        .map(|(element, &cell)| {
            let warp = mesh
                .warp_directions
                .as_ref()
                .map_or(*warp_direction, |d| d[element]);
            MembraneElement::new(cell, &mesh.nodes, &warp).map_err(|error| ModelError::Element {
                element: first + element,
                error,
            })
        })
        .collect()
}

/// A positive density, and the same layers as the first ply's (the frames write per-layer
/// arrays).
fn check_ply_material(sheet: &PlySheet, first_layers: usize) -> Result<(), ModelError> {
    if !(sheet.density.is_finite() && sheet.density > 0.0) {
        return Err(ModelError::Density {
            ply: sheet.name.clone(),
            density: sheet.density,
        });
    }
    let layers = sheet.laminate.layers().len();
    if layers != first_layers {
        return Err(ModelError::Layers {
            ply: sheet.name.clone(),
            layers,
            first: first_layers,
        });
    }
    Ok(())
}

/// Every node in some cell: a node in none would have no mass.
fn check_every_node_used(mesh: &Mesh) -> Result<(), ModelError> {
    let mut used = vec![false; mesh.nodes.len()];
    for t in &mesh.cells {
        for &n in t.nodes() {
            used[n] = true;
        }
    }
    match used.iter().position(|u| !u) {
        Some(node) => Err(ModelError::OrphanNode(node)),
        None => Ok(()),
    }
}

/// Every constrained node exists and belongs to one constraint only.
fn check_constraints(constraints: &[Constraint], nodes: usize) -> Result<(), ModelError> {
    let mut owner: Vec<Option<usize>> = vec![None; nodes];
    for (c, constraint) in constraints.iter().enumerate() {
        for &node in &constraint.nodes {
            if node >= nodes {
                return Err(ModelError::UnknownNode {
                    name: constraint.name.clone(),
                    node,
                    nodes,
                });
            }
            if let Some(first) = owner[node] {
                return Err(ModelError::DoublyConstrained {
                    node,
                    first: constraints[first].name.clone(),
                    second: constraint.name.clone(),
                });
            }
            owner[node] = Some(c);
        }
    }
    Ok(())
}
