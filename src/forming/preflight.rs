//! The set-up refusals of a forming run that follow from its size and its step, each naming
//! the scenario keys to change: a mesh or tool set that would not fit the machine (sized from
//! the keys, before anything is built), an absurd step count, a stroke covered in too few
//! steps, a punch that would pass through the blank in a step, absurd mass scaling, a holder
//! pressing the blank harder than any composite is formed.

use super::scenario::{BlankShape, Scenario, ToolSet};
use crate::experiment::sheet_test::Crosshead;
use crate::limits::{shown, HOLDER_PRESSURE};
use crate::material::{MaterialCard, MembraneKinematics};
use crate::mesh::{DiagonalPattern, Mesh};
use crate::solver::estimate::{self, item_bytes, RunEstimate, RunSize};
use crate::solver::{implicit, Model, SolverKind, SolverSettings};
use nalgebra::{Matrix2, Vector3};

/// What sets the size of a built-in rectangle, of a file blank, of built-in tools.
const RECTANGLE_KEYS: &str = "blank.element_size (or shrink blank.width, blank.length)";
const FILE_KEYS: &str = "the blank's mesh (blank.mesh)";
/// The built-in tools are meshed over the blank's reach, so a huge blank makes huge tools too.
const TOOL_KEYS: &str = "tools.resolution (or shrink blank.width, blank.length)";

/// What the blank will be, as far as the run's cost goes: its cell and node counts, the
/// smallest altitude of its cells (mm), which sets the explicit solver's step, and half the
/// diagonal of its bounding box (mm), which sets the built-in tools' size.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlankSize {
    pub elements: f64,
    pub quads: f64,
    pub nodes: f64,
    pub altitude: f64,
    pub reach: f64,
}

impl BlankSize {
    /// The size of `plies` such blanks (a layup's).
    pub fn times(self, plies: usize) -> Self {
        let n = plies as f64;
        Self {
            elements: self.elements * n,
            quads: self.quads * n,
            nodes: self.nodes * n,
            ..self
        }
    }

    /// The built-in rectangle's, from the scenario's keys alone; `None` for a mesh file.
    pub fn of_rectangle(s: &Scenario) -> Option<Self> {
        let BlankShape::Rectangle {
            width,
            length,
            element_size,
            pattern,
        } = &s.blank.shape
        else {
            return None;
        };
        let cells = |side: f64| (side / element_size).round().max(1.0);
        let (nx, ny) = (cells(*width), cells(*length));
        let (elements, nodes) = pattern.counts(nx, ny);
        let (quads, altitude) = match pattern {
            DiagonalPattern::Quad => (elements, *element_size),
            DiagonalPattern::Crossed => (0.0, 0.5 * element_size),
            _ => (0.0, element_size * std::f64::consts::FRAC_1_SQRT_2),
        };
        Some(Self {
            elements,
            quads,
            nodes,
            altitude,
            reach: 0.5 * width.hypot(*length),
        })
    }

    /// The plies of `meshes` together: their cells and nodes summed, the smallest altitude
    /// and the largest reach.
    pub fn of_meshes(meshes: &[Mesh]) -> Self {
        meshes.iter().map(Self::of_mesh).fold(
            Self {
                elements: 0.0,
                quads: 0.0,
                nodes: 0.0,
                altitude: f64::INFINITY,
                reach: 0.0,
            },
            |all, m| Self {
                elements: all.elements + m.elements,
                quads: all.quads + m.quads,
                nodes: all.nodes + m.nodes,
                altitude: all.altitude.min(m.altitude),
                reach: all.reach.max(m.reach),
            },
        )
    }

    /// A mesh's, once read from its file.
    pub fn of_mesh(mesh: &Mesh) -> Self {
        let quads = mesh.cells.iter().filter(|c| c.is_quad()).count();
        // no cell of area A has a smallest altitude above sqrt(sqrt(3) A) (the equilateral
        // triangle's): an upper bound, so that the steps are not overestimated
        let smallest_side = (0..mesh.cells.len())
            .map(|t| (3f64.sqrt() * mesh.area(t)).sqrt())
            .fold(f64::INFINITY, f64::min);
        let (low, high) = mesh.nodes.iter().fold(
            (
                Vector3::repeat(f64::INFINITY),
                Vector3::repeat(f64::NEG_INFINITY),
            ),
            |(low, high), x| (low.inf(x), high.sup(x)),
        );
        Self {
            elements: mesh.cells.len() as f64,
            quads: quads as f64,
            nodes: mesh.nodes.len() as f64,
            altitude: smallest_side,
            reach: 0.5 * (high - low).norm(),
        }
    }
}

/// The run's steps (or increments), memory and wall time from the scenario's keys and the
/// blank's size, before the model is built (a rectangle is not meshed yet): printed first, so
/// that a run of millions of cells answers at once. Refused when it cannot fit the memory the
/// machine has free, or (explicit) when even the membrane's step at rest, an upper bound of the
/// step the run will take, gives more than [`estimate::MAX_STEPS`] steps. The estimate of the
/// built model follows ([`check_model`], [`check_memory_of`]).
pub fn estimate_from_keys(
    s: &Scenario,
    card: &MaterialCard,
    blank: BlankSize,
) -> Result<RunEstimate, String> {
    let on = |e: String| format!("{}: {e}", s.origin);
    let p = &s.process;
    let tool_triangles = match &s.tools {
        ToolSet::BuiltIn(t) => {
            // punch, die and holder each about as wide as the blank's reach plus 10 mm, in
            // right triangles of the resolution's size
            let reach = blank.reach + t.ridge_half_length() + 10.0;
            3.0 * 2.0 * (2.0 * reach / t.resolution).powi(2)
        }
        ToolSet::Files(_) => 0.0,
    };
    let size = RunSize {
        elements: blank.elements as usize,
        quads: blank.quads as usize,
        nodes: blank.nodes as usize,
        layers: card.laminate.initial_state().thickness_stretch.len(),
        bending: card.bending.is_some(),
        tools: 3,
        tool_triangles: tool_triangles.min(usize::MAX as f64) as usize,
    };
    let blank_keys = match s.blank.shape {
        BlankShape::Rectangle { .. } => RECTANGLE_KEYS,
        BlankShape::File { .. } => FILE_KEYS,
    };
    let (per_element, per_node, per_triangle) = item_bytes(size.layers, size.bending, 3);
    let arrays = blank.elements * per_element + blank.nodes * per_node;
    let tools = tool_triangles * per_triangle;
    let resident = estimate::resident_memory().unwrap_or(0.0);
    let simulated = p.punch_speed * p.time_scaling;
    let punch = Crosshead {
        speed: simulated,
        ramp_time: 0.05 * p.stroke / simulated,
    };
    let end_time = punch.time_to(p.stroke);
    let threads = rayon::current_num_threads();
    let estimate = match p.solver {
        SolverKind::Explicit => {
            let modulus = card
                .laminate
                .wave_modulus(
                    &MembraneKinematics {
                        c: Matrix2::identity(),
                        c_dot: Matrix2::zeros(),
                        temperature: p.temperature.into(),
                        fibres: Default::default(),
                    },
                    &card.laminate.initial_state(),
                )
                .map_err(|e| on(e.to_string()))?;
            let membrane = blank.altitude * (card.density / modulus).sqrt();
            let (step, added_mass_ratio) = match p.target_time_step {
                Some(target) if target > membrane => (target, (target / membrane).powi(2) - 1.0),
                _ => (membrane, 0.0),
            };
            let time_step = SAFETY * step;
            let steps = (end_time / time_step).ceil();
            RunEstimate {
                size,
                time_step,
                steps,
                memory: resident + arrays + tools,
                wall_seconds: steps * (blank.elements + blank.quads)
                    / (estimate::ELEMENT_STEPS_PER_THREAD_SECOND * threads as f64),
                added_mass_ratio,
            }
        }
        SolverKind::Implicit => {
            let travel = p
                .max_increment
                .unwrap_or(p.stroke / implicit::DEFAULT_INCREMENTS);
            let increments = (p.stroke / travel).ceil();
            RunEstimate {
                size,
                time_step: travel / simulated,
                steps: increments,
                memory: resident + arrays + tools + implicit::sparse_memory_of_size(blank.nodes),
                wall_seconds: implicit::wall_seconds_of_size(blank.elements, increments, threads),
                added_mass_ratio: 0.0,
            }
        }
    };
    let keys = if tools > arrays && blank_keys == RECTANGLE_KEYS {
        TOOL_KEYS
    } else {
        blank_keys
    };
    estimate::check_memory(estimate.memory, keys).map_err(on)?;
    if p.solver == SolverKind::Explicit {
        // the membrane's step at rest is the largest the run can take: its step count and
        // added mass are the least the run will have, so refusing them now refuses nothing the
        // built model would run; too few steps waits for the built model's step
        let step_keys = format!("{blank_keys} or process.target_time_step (the step)");
        estimate::check_excess(&estimate, step_count_keys(&step_keys)).map_err(on)?;
    }
    Ok(estimate)
}

/// What sets an explicit run's step count, for the refusals' messages: `step_keys` (what sets
/// the step), what sets the stroke's duration, what sets the mass scaling.
fn step_count_keys(step_keys: &str) -> (&str, &str, &str) {
    (
        step_keys,
        "process.punch_speed or process.time_scaling",
        "process.target_time_step",
    )
}

/// An explicit run's estimated wall time from which its estimate is followed by the implicit
/// solver's on the same blank, and how to choose it (s) **(choice)**: ten minutes.
pub const IMPLICIT_ADVICE_SECONDS: f64 = 600.0;

/// For an explicit run of `s` estimated (`estimate`) at more than [`IMPLICIT_ADVICE_SECONDS`]:
/// that the implicit solver exists, its estimate on the same blank (its default increments,
/// docs/solver.md "Increments") and how to choose it.
pub fn implicit_advice(s: &Scenario, estimate: &RunEstimate) -> Option<String> {
    if s.process.solver != SolverKind::Explicit || estimate.wall_seconds <= IMPLICIT_ADVICE_SECONDS
    {
        return None;
    }
    let implicit = implicit::wall_seconds_of_size(
        estimate.size.elements as f64,
        implicit::DEFAULT_INCREMENTS,
        rayon::current_num_threads(),
    );
    Some(format!(
        "the explicit solver needs about {} for this run; the implicit solver forms the same \
         stroke quasi-statically at the physical punch speed in about {}: set process.solver = \
         \"implicit\" (the default where the scenario does not choose) and leave out \
         process.time_scaling and process.target_time_step (docs/solver.md, \"Which solver\")",
        estimate::format_seconds(estimate.wall_seconds),
        estimate::format_seconds(implicit),
    ))
}

/// The explicit solver's safety factor on its stable step (`SolverSettings::time_step_safety`
/// of a forming run).
pub const SAFETY: f64 = 0.9;

/// Refuses a blank-holder force that would press the blank harder than any composite is
/// formed: its mean pressure over the whole blank (`blank_area`, mm^2) beyond
/// [`HOLDER_PRESSURE`]. The holder presses the flange only, so the true pressure is higher still.
pub fn check_holder_pressure(s: &Scenario, blank_area: f64) -> Result<(), String> {
    let force = s.process.blank_holder_force;
    // a mesh without area is refused by its own checks, with a better message than a pressure
    if force == 0.0 || blank_area.is_nan() || blank_area <= 0.0 {
        return Ok(());
    }
    let key = format!(
        "process.blank_holder_force = {} N on the blank's {} mm^2: the mean pressure",
        shown(force),
        shown(blank_area)
    );
    HOLDER_PRESSURE
        .check(&key, force / blank_area)
        .map_err(|e| format!("{}: {e}", s.origin))
}

/// The estimate of the built model, and the refusals it allows: memory, step count, the
/// stroke's steps, the punch's travel per step (at `punch_speed`, simulated mm/s) against the
/// ply's thickness, mass scaling.
pub fn check_model(
    s: &Scenario,
    model: &Model,
    settings: &SolverSettings,
    punch_speed: f64,
) -> Result<RunEstimate, String> {
    let on = |e: String| format!("{}: {e}", s.origin);
    let estimate = estimate::estimate(model, settings).map_err(on)?;
    let blank_keys = match s.blank.shape {
        BlankShape::Rectangle { .. } => RECTANGLE_KEYS,
        BlankShape::File { .. } => FILE_KEYS,
    };
    let keys = match s.tools {
        ToolSet::BuiltIn(_) => format!("{blank_keys} or {TOOL_KEYS}"),
        ToolSet::Files(_) => blank_keys.to_string(),
    };
    estimate::check_memory(estimate.memory, &keys).map_err(on)?;
    let thickness = model.thinnest_ply();
    estimate::check_tool_travel(
        &estimate,
        punch_speed,
        thickness,
        (
            "punch",
            "process.punch_speed or process.time_scaling (or process.target_time_step)",
        ),
    )
    .map_err(on)?;
    let step_keys = format!("{blank_keys} or process.target_time_step (the step)");
    estimate::check_steps(&estimate, step_count_keys(&step_keys)).map_err(on)?;
    Ok(estimate)
}

/// The estimate of the built model for the implicit solver in increments of at most
/// `max_increment` (s), its sparse tangent and factor
/// counted ([`implicit::sparse_memory_of_size`]: the exact count would take an ordering of the
/// tangent, seconds on large meshes), refused only when its memory does not fit: its
/// increments do not follow the explicit stable step.
pub fn check_memory_of(
    s: &Scenario,
    model: &Model,
    settings: &SolverSettings,
    max_increment: f64,
) -> Result<RunEstimate, String> {
    let on = |e: String| format!("{}: {e}", s.origin);
    let mut estimate = estimate::estimate(model, settings).map_err(on)?;
    estimate.memory += implicit::sparse_memory_of_size(model.mesh.nodes.len() as f64);
    estimate.time_step = max_increment;
    estimate.steps = (settings.end_time / max_increment).ceil();
    estimate.added_mass_ratio = 0.0;
    estimate.wall_seconds = implicit::wall_seconds_of_size(
        model.elements.len() as f64,
        estimate.steps,
        rayon::current_num_threads(),
    );
    let keys = match s.blank.shape {
        BlankShape::Rectangle { .. } => RECTANGLE_KEYS,
        BlankShape::File { .. } => FILE_KEYS,
    };
    estimate::check_memory(estimate.memory, keys).map_err(on)?;
    Ok(estimate)
}
