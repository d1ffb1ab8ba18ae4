//! Before the first step: how many steps a run will take, how much memory it needs and roughly
//! how long it will run, and the set-up refusals that follow from them (a run that cannot fit
//! the machine, an absurd step count, a travel covered in too few steps).

use super::explicit::SolverSettings;
use super::model::Model;
use crate::contact::NodeContact;
use crate::element::bending::BendingPatch;
use crate::element::MembraneElement;
use crate::material::{LaminateState, MembraneResponse};
use nalgebra::Vector3;

/// More steps than this is not a run anyone waits for (days at the rates below): refused.
pub const MAX_STEPS: f64 = 1e9;

/// A crosshead or punch travel covered in fewer steps than this is not resolved: the sheet
/// cannot follow (its waves cross an element in a step) and the result is an impact.
pub const MIN_TRAVEL_STEPS: f64 = 500.0;

/// Element-steps per second and thread for the wall-time guess (a quadrilateral counts as two
/// elements): the measured rate of the forming examples (bending, contact) is 3e5 to 1e6 per
/// thread, of the bare sheet tests up to 2e6 (docs/dev/performance-history.md); the guess is
/// good to a factor of about 3.
pub const ELEMENT_STEPS_PER_THREAD_SECOND: f64 = 5e5;

/// Mass scaling that adds more than this many times the blank's own mass makes every force an
/// inertia force: refused.
pub const MAX_ADDED_MASS_RATIO: f64 = 1e4;

/// The sizes of a run's big arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RunSize {
    pub elements: usize,
    /// Of the elements, the quadrilaterals: each costs about two triangles a step (four
    /// corners, the hourglass, a bending patch of four triangles' patches).
    pub quads: usize,
    pub nodes: usize,
    /// Layers of the laminate (per-element state variables).
    pub layers: usize,
    pub bending: bool,
    pub tools: usize,
    /// Triangles of all tool surfaces together.
    pub tool_triangles: usize,
}

/// What a run will take.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunEstimate {
    pub size: RunSize,
    /// Step at rest, mass scaling and safety factor included (s).
    pub time_step: f64,
    pub steps: f64,
    /// Peak memory (bytes): what the process holds now plus the run's arrays.
    pub memory: f64,
    pub wall_seconds: f64,
    /// Mass added by mass scaling over the physical mass.
    pub added_mass_ratio: f64,
}

impl RunEstimate {
    /// The line printed before the first step.
    pub fn describe(&self) -> String {
        format!(
            "estimate: {:.3e} steps of {:.3e} s on {} elements, {} of memory, about {} on {} \
             threads{}",
            self.steps,
            self.time_step,
            self.size.elements,
            format_bytes(self.memory),
            format_seconds(self.wall_seconds),
            rayon::current_num_threads(),
            if self.added_mass_ratio > 0.0 {
                format!(
                    "; mass scaling adds {:.3} x the blank's mass",
                    self.added_mass_ratio
                )
            } else {
                String::new()
            }
        )
    }
}

impl RunEstimate {
    /// The line printed before an implicit run: its increments at most, memory and wall time.
    pub fn describe_increments(&self) -> String {
        format!(
            "estimate: implicit quasi-static run at the physical punch speed, about {:.0} \
             increments of at most {:.3e} s on {} elements, {} of memory, about {} on {} threads",
            self.steps,
            self.time_step,
            self.size.elements,
            format_bytes(self.memory),
            format_seconds(self.wall_seconds),
            rayon::current_num_threads(),
        )
    }
}

/// Bytes a heap allocation of `bytes` takes (the allocator's header and rounding).
fn heap(bytes: usize) -> usize {
    bytes.max(24).next_multiple_of(16) + 16
}

/// Memory of the model, the solver's state and its work arrays and one output frame (bytes).
pub fn run_memory(size: &RunSize) -> f64 {
    let (element, node, tool_triangle) = item_bytes(size.layers, size.bending, size.tools);
    size.elements as f64 * element
        + size.nodes as f64 * node
        + size.tool_triangles as f64 * tool_triangle
        + RESIDENT_SLACK
}

/// Bytes per element, per node and per tool triangle of a run on a laminate of `layers`
/// layers, with or without bending, with `tools` tools, counted from the arrays' element
/// sizes (a node's contact keeps per-tool lists). In floating point, so that an absurd mesh
/// asked for in a scenario is sized without overflow before it is built.
pub fn item_bytes(layers: usize, bending: bool, tools: usize) -> (f64, f64, f64) {
    let v3 = size_of::<Vector3<f64>>();
    let per_element = size_of::<[usize; 3]>()
        + size_of::<MembraneElement>()
        + size_of::<MembraneResponse>()
        + size_of::<LaminateState>()
        + 2 * heap(layers * size_of::<f64>())
        + size_of::<f64>()
        // the element loop's results: three forces, the step and the damping power
        + 3 * v3 + 2 * size_of::<f64>()
        // node-to-element lists
        + 3 * 2 * size_of::<usize>()
        // one frame's cell data: about 30 numbers per element
        + 30 * size_of::<f64>();
    // a bending patch per element: its triangle and 1-ring, about 12 nodes
    let patch_nodes = 12;
    let per_patch = size_of::<BendingPatch>()
        + heap(patch_nodes * size_of::<usize>())
        + heap(patch_nodes * v3)
        + patch_nodes * (v3 + 2 * size_of::<usize>());
    // the near-triangle list holds about 8 indices
    let per_tool_contact = v3 + size_of::<f64>() + size_of::<[usize; 8]>() + 64;
    let per_node = 10 * v3
        + 6 * size_of::<f64>()
        + size_of::<NodeContact>()
        + 3 * heap(tools * per_tool_contact / 3 + 1)
        // one frame's point data: about 20 numbers per node
        + 20 * size_of::<f64>();
    // vertices, triangles, bounding spheres and the search grid's lists
    let per_tool_triangle = 200;
    let element = per_element + if bending { per_patch } else { 0 };
    (element as f64, per_node as f64, per_tool_triangle as f64)
}

/// Memory a run holds beyond its arrays, for buffers and the histories (bytes).
const RESIDENT_SLACK: f64 = 8.0 * 1024.0 * 1024.0;

/// The step the solver starts with: `safety x min_e max(dt_e, target)`, `dt_e` the element's
/// membrane (and bending) step at rest on the physical density, as mass scaling brings every
/// element below the target up to it. Also the mass it adds over the physical mass.
pub fn rest_step(model: &Model, settings: &SolverSettings) -> Result<(f64, f64), String> {
    let mut step = f64::INFINITY;
    let (mut added, mut physical) = (0.0, 0.0);
    for (k, e) in model.elements.iter().enumerate() {
        let (laminate, density) = (model.laminate(k), model.density(k));
        let thickness = laminate.reference_thickness();
        let kin = model.rest_kinematics(k);
        let modulus = laminate
            .wave_modulus(&kin, &laminate.initial_state())
            .map_err(|err| format!("element {k}: {err}"))?;
        let mut element_step = e.altitude * (density / modulus).sqrt();
        if let Some(bending) = &model.bending {
            element_step =
                element_step.min(bending.stable_step(&bending.patches[k], density * thickness));
        }
        let mass = density * thickness * e.area;
        physical += mass;
        if let Some(target) = settings.target_time_step {
            if element_step < target {
                added += mass * ((target / element_step).powi(2) - 1.0);
                element_step = target;
            }
        }
        step = step.min(element_step);
    }
    let ratio = if physical > 0.0 {
        added / physical
    } else {
        0.0
    };
    Ok((settings.time_step_safety * step, ratio))
}

/// The estimate of a built model: steps from the step at rest, memory from the arrays plus what
/// the process holds now, wall time at [`ELEMENT_STEPS_PER_THREAD_SECOND`].
pub fn estimate(model: &Model, settings: &SolverSettings) -> Result<RunEstimate, String> {
    let (time_step, added_mass_ratio) = rest_step(model, settings)?;
    let size = RunSize {
        elements: model.elements.len(),
        quads: model.elements.iter().filter(|e| e.cell.is_quad()).count(),
        nodes: model.mesh.nodes.len(),
        layers: model.plies[0]
            .laminate
            .initial_state()
            .thickness_stretch
            .len(),
        bending: model.bending.is_some(),
        tools: model.tools.len(),
        tool_triangles: model.tools.iter().map(|t| t.surface.triangles.len()).sum(),
    };
    let steps = (settings.end_time / time_step).ceil();
    let rate = ELEMENT_STEPS_PER_THREAD_SECOND * rayon::current_num_threads() as f64;
    Ok(RunEstimate {
        size,
        time_step,
        steps,
        memory: resident_memory().unwrap_or(0.0) + run_memory(&size),
        wall_seconds: steps * (size.elements + size.quads) as f64 / rate,
        added_mass_ratio,
    })
}

/// Refuses a run whose memory would not fit what the machine has free; `keys` names what
/// sets its size (the scenario keys or command-line options).
pub fn check_memory(memory: f64, keys: &str) -> Result<(), String> {
    match available_memory() {
        Some(free) if memory > free => Err(format!(
            "the run would need {} of memory and the machine has {} free: coarsen {keys}",
            match format_bytes(memory) {
                unbounded if unbounded.starts_with("more") => unbounded,
                bytes => format!("about {bytes}"),
            },
            format_bytes(free)
        )),
        _ => Ok(()),
    }
}

/// Refuses an absurd step count (more than [`MAX_STEPS`]) or a travel covered in fewer than
/// [`MIN_TRAVEL_STEPS`] steps, and mass scaling past [`MAX_ADDED_MASS_RATIO`]. `(step_keys,
/// speed_keys, mass_keys)`: what sets the step, what sets the travel's duration, what sets the
/// mass scaling, for the messages.
pub fn check_steps(
    estimate: &RunEstimate,
    (step_keys, speed_keys, mass_keys): (&str, &str, &str),
) -> Result<(), String> {
    check_excess(estimate, (step_keys, speed_keys, mass_keys))?;
    if estimate.steps < MIN_TRAVEL_STEPS {
        return Err(format!(
            "the travel would be covered in {:.0} steps of {:.3e} s (fewer than {MIN_TRAVEL_STEPS}): \
             the sheet cannot follow and the result is an impact; lower {speed_keys}",
            estimate.steps, estimate.time_step
        ));
    }
    Ok(())
}

/// The refusals of [`check_steps`] that a lower bound of the steps and of the added mass can
/// make: more than [`MAX_STEPS`] steps, mass scaling past [`MAX_ADDED_MASS_RATIO`].
pub fn check_excess(
    estimate: &RunEstimate,
    (step_keys, speed_keys, mass_keys): (&str, &str, &str),
) -> Result<(), String> {
    if estimate.steps.is_nan() || estimate.steps > MAX_STEPS {
        return Err(format!(
            "the run would take {:.3e} steps of {:.3e} s (more than {MAX_STEPS:.0e}): raise \
             {speed_keys}, or {step_keys}",
            estimate.steps, estimate.time_step
        ));
    }
    if estimate.added_mass_ratio > MAX_ADDED_MASS_RATIO {
        return Err(format!(
            "mass scaling would add {:.3e} times the blank's own mass (more than \
             {MAX_ADDED_MASS_RATIO:.0e}): every force would be an inertia force; lower \
             {mass_keys}, or check the card's stiffness and density",
            estimate.added_mass_ratio
        ));
    }
    Ok(())
}

/// A tool that moves more than this fraction of the ply's thickness in one step passes
/// through the blank: the penalty spring `k = s m / dt^2` (s = 0.1) takes about
/// `1/sqrt(s) = 3` steps to bring a node up to the tool's speed, so the node sinks about three
/// steps' travel into the tool, and beyond a thickness the contact lets go.
pub const TOOL_TRAVEL_FRACTION: f64 = 0.3;

/// Refuses a tool moving at `speed` (simulated mm/s) more than [`TOOL_TRAVEL_FRACTION`] of the
/// ply's `thickness` per step of the estimate; `(tool, keys)` for the message.
pub fn check_tool_travel(
    estimate: &RunEstimate,
    speed: f64,
    thickness: f64,
    (tool, keys): (&str, &str),
) -> Result<(), String> {
    let travel = speed.abs() * estimate.time_step;
    if travel > TOOL_TRAVEL_FRACTION * thickness {
        return Err(format!(
            "the {tool} would move {travel:.3e} mm per step of {:.3e} s, more than {} of the \
             ply's {thickness} mm thickness: it would pass through the blank; lower {keys}",
            estimate.time_step, TOOL_TRAVEL_FRACTION
        ));
    }
    Ok(())
}

/// `MemAvailable` of `/proc/meminfo` (bytes); `None` where there is no such file.
pub fn available_memory() -> Option<f64> {
    proc_kilobytes("/proc/meminfo", "MemAvailable:")
}

/// What this process holds now, `VmRSS` (bytes); `None` off Linux.
pub fn resident_memory() -> Option<f64> {
    proc_kilobytes("/proc/self/status", "VmRSS:")
}

/// The most this process has held, `VmHWM` (bytes); `None` off Linux.
pub fn peak_memory() -> Option<f64> {
    proc_kilobytes("/proc/self/status", "VmHWM:")
}

/// A `key:   1234 kB` line of a `/proc` file, in bytes.
fn proc_kilobytes(file: &str, key: &str) -> Option<f64> {
    let text = std::fs::read_to_string(file).ok()?;
    let line = text.lines().find(|l| l.starts_with(key))?;
    let kb: f64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kb * 1024.0)
}

/// `1.5 GiB`, `320 MiB`.
pub fn format_bytes(bytes: f64) -> String {
    const MIB: f64 = 1024.0 * 1024.0;
    if !bytes.is_finite() || bytes >= 1e18 {
        "more than 1e18 bytes".into()
    } else if bytes >= 1024.0 * MIB {
        format!("{:.1} GiB", bytes / (1024.0 * MIB))
    } else {
        format!("{:.0} MiB", bytes / MIB)
    }
}

/// `40 s`, `12 min`, `3.1 h`.
pub fn format_seconds(s: f64) -> String {
    if s < 120.0 {
        format!("{s:.0} s")
    } else if s < 7200.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

/// The kinetic energy of the whole sheet carried at the tool's (or crosshead's) `speed`
/// (simulated mm/s), `M v^2 / 2` with the mass after mass scaling (N·mm). Until the sheet has
/// taken that much internal work its kinetic energy is of the size of the internal work in any
/// run (a punch lifting a blank carries it along), so the kinetic energy stops a run only
/// after it.
pub fn carried_kinetic_energy(
    model: &Model,
    settings: &SolverSettings,
    speed: f64,
) -> Result<f64, String> {
    let (_, added_ratio) = rest_step(model, settings)?;
    let mass = model.physical_mass() * (1.0 + added_ratio);
    Ok(0.5 * mass * speed * speed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_grows_with_the_mesh_and_counts_bending_and_tools() {
        let base = RunSize {
            elements: 100_000,
            nodes: 50_000,
            layers: 3,
            ..RunSize::default()
        };
        let plain = run_memory(&base) - RESIDENT_SLACK;
        let double = run_memory(&RunSize {
            elements: 200_000,
            nodes: 100_000,
            ..base
        }) - RESIDENT_SLACK;
        assert!((double / plain - 2.0).abs() < 1e-9);
        // a few hundred bytes per element: the solver's arrays are not free
        assert!(plain / 100_000.0 > 300.0 && plain / 100_000.0 < 3000.0);
        let bending = run_memory(&RunSize {
            bending: true,
            ..base
        }) - RESIDENT_SLACK;
        assert!(bending > 1.3 * plain);
        let tools = run_memory(&RunSize {
            tools: 3,
            tool_triangles: 100_000,
            ..base
        }) - RESIDENT_SLACK;
        assert!(tools > plain + 100_000.0 * 100.0);
    }

    #[test]
    fn steps_out_of_range_are_refused_naming_the_keys() {
        let estimate = |steps: f64, added_mass_ratio: f64| RunEstimate {
            size: RunSize::default(),
            time_step: 1e-6,
            steps,
            memory: 0.0,
            wall_seconds: 0.0,
            added_mass_ratio,
        };
        let keys = ("STEP", "SPEED", "MASS");
        assert!(check_steps(&estimate(1e5, 10.0), keys).is_ok());
        let many = check_steps(&estimate(2e9, 0.0), keys).unwrap_err();
        assert!(many.contains("SPEED") && many.contains("STEP"), "{many}");
        let few = check_steps(&estimate(8.0, 0.0), keys).unwrap_err();
        assert!(few.contains("8 steps") && few.contains("SPEED"), "{few}");
        let nan = check_steps(&estimate(f64::NAN, 0.0), keys);
        assert!(nan.is_err());
        let heavy = check_steps(&estimate(1e5, 1e296), keys).unwrap_err();
        assert!(heavy.contains("MASS"), "{heavy}");
    }

    #[test]
    fn memory_beyond_what_is_free_is_refused() {
        if let Some(free) = available_memory() {
            assert!(check_memory(0.5 * free, "KEY").is_ok());
            let e = check_memory(2.0 * free, "KEY").unwrap_err();
            assert!(e.contains("coarsen KEY"), "{e}");
        }
    }

    #[test]
    fn proc_figures_are_read_on_linux() {
        if cfg!(target_os = "linux") {
            let rss = resident_memory().unwrap();
            let peak = peak_memory().unwrap();
            assert!(rss > 1e5 && peak >= rss);
        }
    }
}
