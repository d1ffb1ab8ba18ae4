//! The set-up refusals of a forming run that follow from its size and its step, each naming
//! the scenario keys to change: a mesh or tool set that would not fit the machine (sized from
//! the keys, before anything is built), an absurd step count, a stroke covered in too few
//! steps, a punch that would pass through the blank in a step, absurd mass scaling, a holder
//! pressing the blank harder than any composite is formed.

use super::scenario::{BlankShape, Scenario, ToolSet};
use crate::limits::{shown, HOLDER_PRESSURE};
use crate::material::MaterialCard;
use crate::solver::estimate::{self, item_bytes, RunEstimate};
use crate::solver::{implicit, Model, SolverSettings};

/// What sets the size of a built-in rectangle, of a file blank, of built-in tools.
const RECTANGLE_KEYS: &str = "blank.element_size (or shrink blank.width, blank.length)";
const FILE_KEYS: &str = "the blank's mesh (blank.mesh)";
/// The built-in tools are meshed over the blank's reach, so a huge blank makes huge tools too.
const TOOL_KEYS: &str = "tools.resolution (or shrink blank.width, blank.length)";

/// Refuses a built-in rectangle (and built-in tool set) that would not fit the memory the
/// machine has free, from the scenario's numbers alone: called before the mesh is made, so
/// that a hundredth-of-a-millimetre element size is refused at once instead of failing an
/// allocation.
pub fn check_before_mesh(s: &Scenario, card: &MaterialCard) -> Result<(), String> {
    let BlankShape::Rectangle {
        width,
        length,
        element_size,
        pattern,
    } = &s.blank.shape
    else {
        return Ok(());
    };
    let cells = |side: f64| (side / element_size).round().max(1.0);
    let (nx, ny) = (cells(*width), cells(*length));
    let (elements, nodes) = pattern.counts(nx, ny);
    let tool_triangles = match &s.tools {
        ToolSet::BuiltIn(t) => {
            // punch, die and holder each about as wide as the blank plus 10 mm, in
            // right triangles of the resolution's size
            let reach = 0.5 * width.hypot(*length) + t.ridge_half_length() + 10.0;
            3.0 * 2.0 * (2.0 * reach / t.resolution).powi(2)
        }
        ToolSet::Files(_) => 0.0,
    };
    let layers = card.laminate.initial_state().thickness_stretch.len();
    let (per_element, per_node, per_triangle) = item_bytes(layers, card.bending.is_some(), 3);
    let blank = elements * per_element + nodes * per_node;
    let tools = tool_triangles * per_triangle;
    let keys = if blank >= tools {
        RECTANGLE_KEYS
    } else {
        TOOL_KEYS
    };
    estimate::check_memory(blank + tools, keys).map_err(|e| format!("{}: {e}", s.origin))
}

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
    let thickness = model.laminate.reference_thickness();
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
    estimate::check_steps(
        &estimate,
        (
            &step_keys,
            "process.punch_speed or process.time_scaling",
            "process.target_time_step",
        ),
    )
    .map_err(on)?;
    Ok(estimate)
}

/// The estimate of the built model for the implicit solver, its sparse tangent and factor
/// counted, refused only when its memory does not fit: its increments do not follow the
/// explicit stable step.
pub fn check_memory_of(
    s: &Scenario,
    model: &Model,
    settings: &SolverSettings,
) -> Result<RunEstimate, String> {
    let on = |e: String| format!("{}: {e}", s.origin);
    let mut estimate = estimate::estimate(model, settings).map_err(on)?;
    estimate.memory += implicit::sparse_memory(model).map_err(on)?;
    estimate::check_memory(estimate.memory, RECTANGLE_KEYS).map_err(on)?;
    Ok(estimate)
}
