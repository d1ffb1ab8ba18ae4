//! What the solver integrates: the meshed sheet, its laminate, and the constraints.

use crate::contact::{ContactSettings, RigidTool};
use crate::element::bending::BendingError;
use crate::element::membrane::ElementError;
use crate::element::membrane::HourglassModuli;
use crate::element::{Bending, BendingRigidity, MembraneElement};
use crate::material::{FibreDirections, Laminate, MaterialError, MembraneKinematics};
use crate::mesh::{Mesh, MeshError};
use nalgebra::Vector3;
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

/// A blank ready to be integrated.
#[derive(Clone, Debug)]
pub struct Model {
    pub mesh: Mesh,
    pub elements: Vec<MembraneElement>,
    /// Bending stiffness; `None` for a membrane.
    pub bending: Option<Bending>,
    /// Rigid tools in contact with the blank, and how the contact is computed.
    pub tools: Vec<RigidTool>,
    pub contact: ContactSettings,
    pub laminate: Laminate,
    /// What holds the hourglass mode of the quadrilaterals
    /// ([`MembraneElement::hourglass_forces`]): the laminate's shear and yarn stiffness at
    /// rest; zero on a mesh of triangles.
    pub hourglass: HourglassModuli,
    /// Density of the ply (tonne/mm^3).
    pub density: f64,
    /// Isothermal temperature of the run (°C).
    pub temperature: f64,
    pub constraints: Vec<Constraint>,
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
    #[error("density {0} must be > 0")]
    Density(f64),
    #[error("laminate at the run's temperature: {0}")]
    Material(String),
    #[error("bending: {0}")]
    Bending(#[from] BendingError),
}

impl Model {
    /// Builds the elements of `mesh` with the warp along `warp_direction` projected on each, or
    /// along the mesh's own per-triangle directions where it has them (a mesh file's
    /// orientations, `Mesh::warp_directions`).
    pub fn new(
        mesh: Mesh,
        laminate: Laminate,
        density: f64,
        temperature: f64,
        warp_direction: Vector3<f64>,
        constraints: Vec<Constraint>,
    ) -> Result<Self, ModelError> {
        mesh.validate()?;
        if !(density.is_finite() && density > 0.0) {
            return Err(ModelError::Density(density));
        }
        let elements = mesh
            .cells
            .iter()
            .enumerate()
            .map(|(element, &cell)| {
                let warp = mesh
                    .warp_directions
                    .as_ref()
                    .map_or(warp_direction, |d| d[element]);
                MembraneElement::new(cell, &mesh.nodes, &warp)
                    .map_err(|error| ModelError::Element { element, error })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut used = vec![false; mesh.nodes.len()];
        for t in &mesh.cells {
            for &n in t.nodes() {
                used[n] = true;
            }
        }
        if let Some(node) = used.iter().position(|u| !u) {
            return Err(ModelError::OrphanNode(node));
        }
        let hourglass = match mesh.has_quads() {
            true => hourglass_moduli(&laminate, temperature)
                .map_err(|e| ModelError::Material(e.to_string()))?,
            false => HourglassModuli::default(),
        };
        let mut owner: Vec<Option<usize>> = vec![None; mesh.nodes.len()];
        for (c, constraint) in constraints.iter().enumerate() {
            for &node in &constraint.nodes {
                if node >= owner.len() {
                    return Err(ModelError::UnknownNode {
                        name: constraint.name.clone(),
                        node,
                        nodes: owner.len(),
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
        Ok(Self {
            mesh,
            elements,
            bending: None,
            tools: Vec::new(),
            contact: ContactSettings {
                offset: laminate.reference_thickness() / 2.0,
                penalty_scale: 0.1,
                max_penetration: laminate.reference_thickness(),
            },
            hourglass,
            // The run is isothermal: the laws' temperature tables are interpolated once here.
            laminate: laminate.at_temperature(temperature),
            density,
            temperature,
            constraints,
        })
    }

    /// The same sheet with bending stiffness: a rotation-free bending patch per triangle
    /// (docs/model.md §4, `element::bending`), the reference mesh's curvature at rest.
    pub fn with_bending(mut self, rigidity: BendingRigidity) -> Result<Self, ModelError> {
        self.bending = Some(Bending::new(&self.mesh, &self.elements, rigidity)?);
        Ok(self)
    }

    /// The same sheet between rigid tools, with the contact settings given.
    pub fn with_tools(mut self, tools: Vec<RigidTool>, contact: ContactSettings) -> Self {
        self.tools = tools;
        self.contact = contact;
        self
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
fn hourglass_moduli(
    laminate: &Laminate,
    temperature: f64,
) -> Result<HourglassModuli, MaterialError> {
    let t0 = laminate.reference_thickness();
    let rest = MembraneKinematics {
        c: nalgebra::Matrix2::identity(),
        c_dot: nalgebra::Matrix2::zeros(),
        temperature,
        fibres: FibreDirections::default(),
    };
    Ok(HourglassModuli {
        shear: laminate.shear_modulus(temperature)? * t0,
        yarn: laminate.wave_modulus(&rest, &laminate.initial_state())? * t0,
    })
}
