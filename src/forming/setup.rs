//! From a scenario to a model: the blank's mesh (built in or read from a file) on its card,
//! its boundary conditions, and the tools placed around it (built in or read from files).
//!
//! Conventions of `contact::tools`: stroke axis z, blank mid-plane in z = 0 at the start, the
//! punch below moving up, the die above, the holder below around the punch. Each built-in tool
//! is moved off the mid-plane by half the blank's thickness, so that it touches a face of the
//! blank at the start; tools read from files are used where the files put them.

use super::export::FORMED_INP;
use super::layup;
use super::motion_setup::{apply_motions, planned_stroke, tool_names};
use super::preflight;
use super::scenario::{BlankShape, Scenario, SetKind, ToolFile, ToolFiles, ToolSet, Tools};
use super::supports::build_supports;
use crate::contact::{
    distance_from_ridge, double_dome_die, double_dome_die_shape, double_dome_holder,
    double_dome_holder_shape, double_dome_matched_die, double_dome_matched_die_shape,
    double_dome_punch, double_dome_punch_shape, read_stl, ContactSettings, DieShape, Facing,
    MatchedDie, RigidTool, SweptProfile, ToolMotion, ToolPath, TriangleSurface,
};
use crate::experiment::sheet_test::Crosshead;
use crate::limits::{shown, shown_apart};
use crate::material::MaterialCard;
use crate::mesh::abaqus::check_set_names;
use crate::mesh::orientation::{describe_poor_projections, poor_projections, reference_warp};
use crate::mesh::{read_mesh_file, rectangle, DiagonalPattern, Mesh};
use crate::solver::estimate::RunEstimate;
use crate::solver::{implicit, SolverKind};
use crate::solver::{Constraint, Model, Motion, SolverSettings};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// Contact penalty `s` of `k = s m / dt^2` (docs/model.md §6).
const PENALTY_SCALE: f64 = 0.1;

/// The places of the punch and the die in the model's tools (the holder, if any, follows).
const PUNCH: usize = 0;
const DIE: usize = 1;

/// The holder's inertia in blank masses: heavy enough to stay stable on the contact springs of
/// every node it touches, light enough to follow the flange.
pub(super) const HOLDER_MASS_RATIO: f64 = 10.0;

/// A blank node may start this far (in ply thicknesses) inside a tool read from a file before
/// the placement is refused: the contact would fling it out at the first step.
const START_PENETRATION_LIMIT: f64 = 0.1;

/// A scenario made ready to run.
pub struct FormingModel {
    pub model: Model,
    pub card: MaterialCard,
    pub punch: Crosshead,
    /// The punch's path where stages or its own motion table move it (then `punch` holds its
    /// top speed and a ramp for the explicit run's checks only).
    pub punch_path: Option<Arc<ToolPath>>,
    /// The punch's whole travel (mm): `process.stroke`, or its path's.
    pub stroke: f64,
    /// Each stage's start and end (s) and travel (mm), where the scenario has stages.
    pub stages: Vec<(f64, f64, f64)>,
    pub settings: SolverSettings,
    /// Which solver runs the model (`process.solver`); the implicit one takes the end time and
    /// output interval of `settings`.
    pub solver: SolverKind,
    /// The implicit solver's largest increment (s): `process.max_increment` of punch travel at
    /// the punch's speed, a sixtieth of the stroke by default.
    pub max_increment: f64,
    /// Distance from the punch's ridge (axis) beyond which the blank lies on the die's flat
    /// face: the flange (mm); infinite when unknown (tools from files without
    /// `tools.flange_radius`), which turns the flange measures off.
    pub flange_radius: f64,
    /// Half-length of the punch's ridge (mm); 0 for a hemisphere.
    pub ridge_half_length: f64,
    /// Element size of the blank (mm): the rectangle's, or `Mesh::element_size` of a file's.
    pub element_size: f64,
    /// Indices of the punch, die and holder (if any) in `model.tools`.
    pub punch_tool: usize,
    pub die_tool: usize,
    pub holder_tool: Option<usize>,
    /// What the user should know before the run: notes of the mesh readers, tool surfaces
    /// flipped, fibre projections that are ill-conditioned; one line each.
    pub notes: Vec<String>,
    /// Steps, memory and wall time the run will take (`preflight`).
    pub estimate: RunEstimate,
}

impl FormingModel {
    pub fn new(s: &Scenario) -> Result<Self, String> {
        Self::reporting(s, &mut |_| {})
    }

    /// As [`FormingModel::new`], handing `early` the estimate from the scenario's keys
    /// ([`preflight::estimate_from_keys`]) as soon as it is known: before the rectangle is
    /// meshed, right after a mesh file is read, before the rest is built.
    pub fn reporting(s: &Scenario, early: &mut dyn FnMut(&RunEstimate)) -> Result<Self, String> {
        let card = MaterialCard::load(&s.blank.card).map_err(|e| e.to_string())?;
        card.check_temperature("process.temperature", s.process.temperature)
            .map_err(|e| format!("{}: {e} ({})", s.origin, s.blank.card.display()))?;
        let ply_cards = match &s.blank.layup {
            Some(l) => Some(layup::ply_cards(s, l)?),
            None => None,
        };
        let plies = ply_cards.as_ref().map_or(1, Vec::len);
        let own_outlines = s
            .blank
            .layup
            .iter()
            .flat_map(|l| &l.plies)
            .any(|p| p.shape.is_some());
        let keyed = preflight::BlankSize::of_rectangle(s)
            .filter(|_| !own_outlines && !s.moves_by_paths())
            .map(|b| b.times(plies));
        if let Some(size) = keyed {
            early(&preflight::estimate_from_keys(s, &card, size)?);
        }
        // each ply's, and the stack's that the tools are placed for
        let cards = ply_cards.as_deref().unwrap_or(std::slice::from_ref(&card));
        let thicknesses = layup::ply_thicknesses(cards);
        let thickness: f64 = thicknesses.iter().sum();
        let (mesh, mut notes) = blank_mesh(s)?;
        let element_size = match s.blank.shape {
            BlankShape::Rectangle { element_size, .. } => element_size,
            BlankShape::File { .. } => mesh.element_size(),
        };
        let meshes = ply_meshes(s, mesh, &mut notes)?;
        if keyed.is_none() && !s.moves_by_paths() {
            early(&preflight::estimate_from_keys(
                s,
                &card,
                preflight::BlankSize::of_meshes(&meshes),
            )?);
        }
        let reach = match &s.tools {
            ToolSet::BuiltIn(t) => {
                let reach = meshes.iter().map(|m| blank_reach(m, t)).fold(0.0, f64::max);
                check_built_in_fit(s, t, reach, thickness, element_size)?;
                reach
            }
            ToolSet::Files(_) => 0.0,
        };
        let warp = reference_warp(s.blank.reference_direction, s.blank.ply_angle);
        check_file_orientations(s, &meshes)?;
        notes.extend(describe_poor_projections(
            &poor_projections(&meshes[0], &warp),
            meshes[0].cells.len(),
        ));
        let constraints = ply_constraints(s, &meshes, &mut notes)?;
        let largest = meshes.iter().map(Mesh::total_area).fold(0.0, f64::max);
        preflight::check_holder_pressure(s, largest)?;
        let blank_mass = cards
            .iter()
            .zip(&thicknesses)
            .zip(&meshes)
            .map(|((c, t), m)| c.density * t * m.total_area())
            .sum();
        let p = &s.process;
        let mut model = match (&s.blank.layup, &ply_cards) {
            (Some(l), Some(cards)) => layup::layup_model(s, l, cards, meshes, constraints)?,
            _ => {
                let (mesh, constraints) =
                    meshes.into_iter().zip(constraints).next().ok_or("no ply")?;
                Model::new(
                    mesh,
                    card.laminate.time_scaled(p.time_scaling),
                    card.density,
                    p.temperature,
                    warp,
                    constraints,
                )
                .map_err(|e| e.to_string())?
            }
        };
        if let (Some(bending), None) = (&card.bending, &s.blank.layup) {
            let rigidity = bending
                .at(p.temperature)
                .map_err(|e| format!("process.temperature: {e}"))?;
            model = model.with_bending(rigidity).map_err(|e| e.to_string())?;
            notes.extend(soft_bending_note(s));
        }
        let single = !s.moves_by_paths();
        let simulated = match single {
            true => p.punch_speed * p.time_scaling,
            false => 1.0,
        };
        let mut punch = Crosshead {
            speed: simulated,
            ramp_time: 0.05 * p.stroke / simulated,
        };
        let (mut tools, holder_tool) = match &s.tools {
            ToolSet::BuiltIn(t) => built_in_tool_set(s, t, (thickness, reach), punch, blank_mass)?,
            ToolSet::Files(f) => file_tool_set(s, f, (thickness, blank_mass), punch, &mut notes)?,
        };
        let above = push_extra_tools(s, &mut tools, thickness, &mut notes)?;
        let names = tool_names(s, holder_tool);
        let paths = apply_motions(s, (&mut tools, &names), thickness, blank_mass)
            .map_err(|e| format!("{}: {e}", s.origin))?;
        let mut model = with_tools_on_the_outer_plies(model, tools, &above);
        let index = |name: &str| names.iter().position(|n| n == name);
        let supports = build_supports(&s.supports, &model, &index)
            .map_err(|e| format!("{}: {e}", s.origin))?;
        model = model.with_supports(supports);
        if let Some(heat) = &s.heat {
            let paths: Vec<&Path> = match &s.blank.layup {
                Some(l) => l.plies.iter().map(|p| p.card.as_path()).collect(),
                None => vec![s.blank.card.as_path()],
            };
            let with_paths: Vec<(&MaterialCard, &Path)> = cards.iter().zip(paths).collect();
            let heat_model = super::heat::heat_model(s, heat, &with_paths, &model)
                .map_err(|e| format!("{}: {e}", s.origin))?;
            model = model.with_heat(heat_model);
        }
        if matches!(s.tools, ToolSet::Files(_)) || !s.extra_tools.is_empty() {
            check_start_positions(&model)?;
        }
        let (end_time, stroke, punch_path) = match &paths {
            Some(plan) => {
                punch = plan.crosshead();
                let punch_path = plan.punch.clone();
                let stroke = punch_path
                    .as_ref()
                    .map_or(0.0, |path| path.travel(plan.end_time));
                (plan.end_time, stroke, punch_path)
            }
            None => (punch.time_to(p.stroke), p.stroke, None),
        };
        let settings = SolverSettings {
            end_time,
            time_step_safety: preflight::SAFETY,
            target_time_step: p.target_time_step,
            output_interval: end_time / s.output.history_points as f64,
            damping: 0.0,
            yarn_damping: 0.06,
        };
        let max_increment = match (p.max_increment, &paths) {
            (Some(travel), _) => travel / punch.speed,
            (None, None) => p.stroke / implicit::DEFAULT_INCREMENTS / punch.speed,
            (None, Some(_)) => end_time / implicit::DEFAULT_INCREMENTS,
        };
        let estimate = match p.solver {
            SolverKind::Explicit => preflight::check_model(s, &model, &settings, punch.speed)?,
            SolverKind::Implicit => {
                preflight::check_memory_of(s, &model, &settings, max_increment)?
            }
        };
        let flange_radius = match &s.tools {
            ToolSet::BuiltIn(t) => t.die_opening_radius + t.die_fillet_radius,
            ToolSet::Files(f) => f.flange_radius.unwrap_or(f64::INFINITY),
        };
        Ok(Self {
            model,
            card,
            punch,
            punch_path,
            stroke,
            stages: paths.map_or_else(Vec::new, |p| p.stages),
            settings,
            solver: p.solver,
            max_increment,
            flange_radius,
            ridge_half_length: s.ridge_half_length(),
            element_size,
            punch_tool: PUNCH,
            die_tool: DIE,
            holder_tool,
            notes,
            estimate,
        })
    }
}

impl FormingModel {
    /// The punch's travel at `t` (mm).
    pub fn punch_travel(&self, t: f64) -> f64 {
        match &self.punch_path {
            Some(path) => path.travel(t),
            None => self.punch.displacement(t),
        }
    }

    /// Distance of a point of the blank from the punch's ridge (axis) in the x-y plane (mm).
    pub fn distance_from_ridge(&self, x: &Vector3<f64>) -> f64 {
        distance_from_ridge(self.ridge_half_length, x.x, x.y)
    }

    /// Whether a point of the blank (current position) lies over the die's flat face.
    pub fn in_flange(&self, x: &Vector3<f64>) -> bool {
        self.distance_from_ridge(x) > self.flange_radius
    }

    /// Whether the flange is known, so that its wrinkle measures mean something.
    pub fn measures_flange(&self) -> bool {
        self.flange_radius.is_finite()
    }

    /// Which band around the part a flange point lies in: bands one element size wide,
    /// counted outward from the flange's inner edge (see `run::Wrinkles`).
    pub fn flange_band(&self, x: &Vector3<f64>) -> usize {
        let beyond = self.distance_from_ridge(x) - self.flange_radius;
        (beyond.max(0.0) / self.element_size).floor() as usize
    }
}

/// A note for a rectangle cut with alternating or crossed diagonals: their valence-4 nodes
/// let the bending patches relax into a wavy state (a pinned strip buckles at 0.90 and 0.56
/// of the Euler load, `tests/bending.rs`), so wrinkles come too easily.
fn soft_bending_note(s: &Scenario) -> Option<String> {
    let BlankShape::Rectangle { pattern, .. } = s.blank.shape else {
        return None;
    };
    let euler = match pattern {
        DiagonalPattern::Alternating => 0.90,
        DiagonalPattern::Crossed => 0.56,
        DiagonalPattern::Quad | DiagonalPattern::Right => return None,
    };
    Some(format!(
        "blank.pattern = \"{}\": the bending of these triangles is soft (a pinned strip buckles \
         at {euler} of the Euler load), so the part wrinkles too easily; \"quad\" (the default) \
         or \"right\" bend within 5 % of it (docs/forming.md, \"Bending\")",
        format!("{pattern:?}").to_lowercase()
    ))
}

/// The blank's mesh: the rectangle, or the file's (restricted to `element_set` if named), with
/// the reader's notes. A file's must be one sheet of shell or membrane elements
/// (`MeshImport::into_blank`).
pub fn blank_mesh(s: &Scenario) -> Result<(Mesh, Vec<String>), String> {
    shape_mesh(&s.blank.shape, "blank")
}

/// The mesh of `shape`, the outline of the blank or of a ply (`key` its table, named in
/// messages), with the reader's notes.
fn shape_mesh(shape: &BlankShape, key: &str) -> Result<(Mesh, Vec<String>), String> {
    match shape {
        BlankShape::Rectangle {
            width,
            length,
            element_size,
            pattern,
        } => {
            let cells = |side: f64| (side / element_size).round().max(1.0) as usize;
            let mesh = rectangle(*width, *length, cells(*width), cells(*length), *pattern);
            Ok((mesh, Vec::new()))
        }
        BlankShape::File { mesh, element_set } => {
            let import = read_mesh_file(mesh).map_err(|e| e.to_string())?;
            let file = mesh.display();
            let import = match element_set {
                Some(set) => import
                    .restricted_to(set)
                    .map_err(|e| format!("{file}: {key}.element_set: {e}"))?,
                None => import,
            };
            let (mesh, notes) = import.into_blank().map_err(|e| e.to_string())?;
            let notes = notes.iter().map(|n| format!("{file}: {n}")).collect();
            // the formed blank's deck, written at the end of the run, carries the mesh's sets:
            // a name it cannot write is refused now rather than after the whole stroke
            check_set_names(&mesh).map_err(|e| {
                format!(
                    "{file}: {e}; the formed blank ({FORMED_INP}) keeps the mesh's sets (its \
                     physical groups, *NSET and *ELSET) by name: rename it in the file"
                )
            })?;
            Ok((mesh, notes))
        }
    }
}

/// Each ply's mesh from the punch's side, `blank` where a ply has no outline of its own (the
/// blank's alone for a blank of one ply), the readers' notes added to `notes`.
fn ply_meshes(s: &Scenario, blank: Mesh, notes: &mut Vec<String>) -> Result<Vec<Mesh>, String> {
    let Some(layup) = &s.blank.layup else {
        return Ok(vec![blank]);
    };
    let mut meshes = Vec::with_capacity(layup.plies.len());
    for (i, ply) in layup.plies.iter().enumerate() {
        let mesh = match &ply.shape {
            Some(shape) => {
                let (mesh, read) = shape_mesh(shape, &format!("blank.plies[{}]", i + 1))?;
                notes.extend(read);
                mesh
            }
            None => blank.clone(),
        };
        meshes.push(mesh);
    }
    Ok(meshes)
}

/// A mesh file's own warp directions stand for a blank of one ply at `blank.ply_angle = 0`;
/// a layup turns each ply by its own angle.
fn check_file_orientations(s: &Scenario, meshes: &[Mesh]) -> Result<(), String> {
    if !meshes.iter().any(|m| m.warp_directions.is_some()) {
        return Ok(());
    }
    if s.blank.layup.is_some() {
        return Err(format!(
            "{}: a mesh file of the layup gives the warp direction of every element, and a \
             layup turns each ply's by its own angle: remove the file's orientations \
             (*ORIENTATION) and give the angles in blank.ply_angles or [[blank.plies]]",
            s.origin
        ));
    }
    if s.blank.ply_angle != 0.0 {
        return Err(format!(
            "{}: the blank's mesh file gives the warp direction of every element; \
             blank.ply_angle = {} would turn it again: set it in the file (*ORIENTATION) or \
             leave blank.ply_angle out",
            s.origin, s.blank.ply_angle
        ));
    }
    Ok(())
}

/// Each ply's constraints on its own mesh: the `[[boundary]]` sets, and where no friction
/// holds the blank a locating pin at its node nearest the punch's axis (said in `notes`).
fn ply_constraints(
    s: &Scenario,
    meshes: &[Mesh],
    notes: &mut Vec<String>,
) -> Result<Vec<Vec<Constraint>>, String> {
    let mut all = Vec::with_capacity(meshes.len());
    for (i, mesh) in meshes.iter().enumerate() {
        let mut constraints = boundary_constraints(s, mesh).map_err(|e| match &s.blank.layup {
            Some(l) => format!("{e} (on blank.plies[{}], \"{}\")", i + 1, l.plies[i].name),
            None => e,
        })?;
        if let Some(pin) = locating_pin(s, mesh, &constraints) {
            if i == 0 {
                let at = mesh.nodes[pin.nodes[0]];
                notes.push(format!(
                    "no friction holds the blank across the stroke: its node at ({:.1}, {:.1}) \
                     mm, the nearest the punch's axis, is held in x and y, as a locating pin \
                     would (docs/solver.md, \"A frictionless blank is located\")",
                    at.x, at.y
                ));
            }
            constraints.push(pin);
        }
        all.push(constraints);
    }
    Ok(all)
}

/// The built-in tools' checks that need the blank's mesh: the clearance, the element size
/// against the punch, and a file's blank reaching (`reach` from the ridge) over the holder.
fn check_built_in_fit(
    s: &Scenario,
    t: &Tools,
    reach: f64,
    thickness: f64,
    element_size: f64,
) -> Result<(), String> {
    let clearance = t.die_opening_radius - t.punch_radius;
    if clearance < thickness {
        return Err(format!(
            "{}: the die opening leaves {} mm around the punch, less than the blank's {} mm \
             thickness (a layup's: its plies together)",
            s.origin,
            shown_apart(clearance, thickness),
            shown(thickness)
        ));
    }
    if let BlankShape::File { mesh: file, .. } = &s.blank.shape {
        let what = format!("the element size of {}", file.display());
        t.check_element_size(element_size, &what)
            .map_err(|e| format!("{}: {e}", s.origin))?;
        let holder = t.holder_inner_radius();
        if s.has_holder() && reach <= holder {
            return Err(format!(
                "{}: the blank of {} reaches {} mm from the punch axis, not over the blank \
                 holder (inner radius {} mm): it cannot be held",
                s.origin,
                file.display(),
                shown_apart(reach, holder),
                shown(holder)
            ));
        }
    }
    Ok(())
}

/// The `[[boundary]]` sets as constraints: each node held along every axis that a boundary
/// containing it names. A node in several sets (the corner of two symmetry planes) is held
/// along all their axes, in one constraint named after them ("symmetry_x+symmetry_y").
fn boundary_constraints(s: &Scenario, mesh: &Mesh) -> Result<Vec<Constraint>, String> {
    let mut held: BTreeMap<usize, ([bool; 3], Vec<&str>)> = BTreeMap::new();
    for b in &s.boundary {
        let (name, kind) = b.set().map_err(|e| format!("{}: {e}", s.origin))?;
        let mask = b.mask().map_err(|e| format!("{}: {e}", s.origin))?;
        let nodes = match kind {
            SetKind::Node => mesh.node_set(name).map(<[usize]>::to_vec),
            SetKind::Element => mesh.nodes_of_element_set(name),
        }
        .map_err(|e| format!("{}: boundary: {e}", s.origin))?;
        for n in nodes {
            let entry = held.entry(n).or_insert(([false; 3], Vec::new()));
            entry.0 = std::array::from_fn(|k| entry.0[k] || mask[k]);
            if !entry.1.contains(&name) {
                entry.1.push(name);
            }
        }
    }
    let mut groups: BTreeMap<(String, [bool; 3]), Vec<usize>> = BTreeMap::new();
    for (node, (mask, names)) in held {
        groups
            .entry((names.join("+"), mask))
            .or_default()
            .push(node);
    }
    Ok(groups
        .into_iter()
        .map(|((name, mask), nodes)| Constraint {
            name,
            nodes,
            motion: Motion::Components(mask),
        })
        .collect())
}

/// The pin that locates a blank on frictionless built-in tools (docs/solver.md, "A
/// frictionless blank is located"): the node nearest the punch's axis held across the stroke
/// (x and y), unless a `[[boundary]]` already holds it. Without friction nothing holds the blank
/// across the stroke on tools that are round about that axis (hemisphere) or straight along it
/// (double dome's ridge) but the solver's drag, and its centred shape is not stable there: the
/// hemisphere's blank slid 7.8 mm off the axis on 8 mm cells, off the punch on 4 mm, and the
/// implicit solver cut its increments until inertia held it. A press locates such a blank; with
/// any friction the stick does.
fn locating_pin(s: &Scenario, mesh: &Mesh, constraints: &[Constraint]) -> Option<Constraint> {
    let f = &s.process.friction;
    let frictionless = f.punch == 0.0 && f.die == 0.0 && f.holder == 0.0;
    if !frictionless || !matches!(s.tools, ToolSet::BuiltIn(_)) {
        return None;
    }
    let axis_distance = |n: usize| mesh.nodes[n].xy().norm();
    let node =
        (0..mesh.nodes.len()).min_by(|&a, &b| axis_distance(a).total_cmp(&axis_distance(b)))?;
    let held = constraints.iter().any(|c| c.nodes.contains(&node));
    (!held).then(|| Constraint {
        name: "locating pin".into(),
        nodes: vec![node],
        motion: Motion::Components([true, true, false]),
    })
}

/// The tools and the holder's index among them (punch and die are 0 and 1).
type ToolSetup = (Vec<RigidTool>, Option<usize>);

/// Punch, die and (with a blank-holder force or gap) holder, placed off the blank's faces.
/// The die and holder reach 10 mm beyond the blank (`reach` from the ridge).
fn built_in_tool_set(
    s: &Scenario,
    t: &Tools,
    (thickness, reach): (f64, f64),
    punch: Crosshead,
    blank_mass: f64,
) -> Result<ToolSetup, String> {
    let half = 0.5 * thickness;
    let ridge = t.ridge_half_length();
    let outer = reach + 10.0;
    let depth = planned_stroke(s, t) + t.die_fillet_radius + 10.0;
    let skirt = t.punch_radius;
    let punch_shape = double_dome_punch_shape(ridge, t.punch_radius, skirt)?.lifted(-half);
    let punch_surface = shifted(
        double_dome_punch(ridge, t.punch_radius, skirt, t.resolution)?,
        -half,
    );
    let die_surface = die_of(t, (outer, depth), half)?;
    let mut tools = punch_and_die(
        s,
        (punch_surface, Some(punch_shape)),
        die_surface,
        punch,
        thickness,
    )?;
    let Some((motion, gap)) = holder_drive(s, blank_mass) else {
        return Ok((tools, None));
    };
    let inner = t.holder_inner_radius();
    let holder_surface = shifted(
        double_dome_holder(ridge, inner, outer, t.resolution)?,
        -half - gap,
    );
    let holder_shape = double_dome_holder_shape(ridge, inner, outer)?.lifted(-half - gap);
    let friction = s.process.friction.holder;
    tools.push(
        RigidTool::new("blank holder", holder_surface, motion, friction, thickness)?
            .with_exact_surface(holder_shape),
    );
    Ok((tools, Some(2)))
}

/// The die of the built-in set, `outer` its reach from the ridge and `depth` its hole's
/// (mm), placed `half` above the blank's mid-plane: the ring die, or the matched die whose
/// cavity the punch fills with the gap `die_opening_radius - punch_radius` once it has
/// travelled `part_depth` beyond touching the blank.
fn die_of(t: &Tools, (outer, depth): (f64, f64), half: f64) -> Result<ToolSurface, String> {
    let ridge = t.ridge_half_length();
    if let Some(travel) = t.matched_depth {
        let die = MatchedDie {
            punch_radius: t.punch_radius,
            gap: t.die_opening_radius - t.punch_radius,
            fillet_radius: t.die_fillet_radius,
            outer_radius: outer,
            closed_travel: travel,
        };
        let shape = double_dome_matched_die_shape(ridge, &die)?.lifted(half);
        let surface = shifted(double_dome_matched_die(ridge, &die, t.resolution)?, half);
        return Ok((surface, Some(shape)));
    }
    let die = DieShape {
        opening_radius: t.die_opening_radius,
        fillet_radius: t.die_fillet_radius,
        outer_radius: outer,
        depth,
    };
    let shape = double_dome_die_shape(ridge, &die)?.lifted(half);
    Ok((
        shifted(double_dome_die(ridge, &die, t.resolution)?, half),
        Some(shape),
    ))
}

/// How far the blank reaches from the punch's ridge (mm): its farthest node (for the built-in
/// rectangle, a corner).
fn blank_reach(mesh: &Mesh, t: &Tools) -> f64 {
    mesh.nodes
        .iter()
        .map(|x| distance_from_ridge(t.ridge_half_length(), x.x, x.y))
        .fold(0.0, f64::max)
}

/// A tool's triangles and, for a built-in tool, the exact surface they were made from.
type ToolSurface = (TriangleSurface, Option<SweptProfile>);

/// The punch (velocity-driven along +z) and the fixed die, with the scenario's friction.
fn punch_and_die(
    s: &Scenario,
    punch_surface: ToolSurface,
    die_surface: ToolSurface,
    punch: Crosshead,
    thickness: f64,
) -> Result<Vec<RigidTool>, String> {
    let friction = &s.process.friction;
    let punch_motion = ToolMotion::Velocity(Arc::new(move |time| {
        Vector3::new(0.0, 0.0, punch.velocity(time))
    }));
    let tool = |name: &str, (surface, exact): ToolSurface, motion, friction| {
        let tool = RigidTool::new(name, surface, motion, friction, thickness)?;
        Ok::<_, String>(match exact {
            Some(exact) => tool.with_exact_surface(exact),
            None => tool.with_blended_surface(),
        })
    };
    Ok(vec![
        tool("punch", punch_surface, punch_motion, friction.punch)?,
        tool("die", die_surface, ToolMotion::Fixed, friction.die)?,
    ])
}

/// The holder's motion and its gap below its touching position, when the scenario has one:
/// pushed with the blank-holder force (free along z), or fixed at the gap.
fn holder_drive(s: &Scenario, blank_mass: f64) -> Option<(ToolMotion, f64)> {
    match (s.process.blank_holder_gap, s.process.blank_holder_force) {
        (Some(gap), _) => Some((ToolMotion::Fixed, gap)),
        (None, force) if force > 0.0 => Some((
            ToolMotion::Force {
                force: Vector3::new(0.0, 0.0, force),
                mass: HOLDER_MASS_RATIO * blank_mass,
            },
            0.0,
        )),
        (None, _) => None,
    }
}

/// `surface` moved by `dz` along the stroke axis.
fn shifted(surface: TriangleSurface, dz: f64) -> TriangleSurface {
    TriangleSurface {
        vertices: surface
            .vertices
            .into_iter()
            .map(|v| v + Vector3::new(0.0, 0.0, dz))
            .collect(),
        ..surface
    }
}

/// Tools read from files, each checked for coherent normals and turned to face the blank
/// (the punch and holder from below, the die from above); a holder fixed at a gap is moved
/// down by it. Their contact sees the smooth surfaces blended over their facets
/// (docs/model.md §6, "Blended tool surfaces"). What was noticed goes to `notes`.
fn file_tool_set(
    s: &Scenario,
    f: &ToolFiles,
    (thickness, blank_mass): (f64, f64),
    punch: Crosshead,
    notes: &mut Vec<String>,
) -> Result<ToolSetup, String> {
    let up = Vector3::z();
    let punch_surface = tool_surface("punch", &f.punch, &up, notes)?;
    let die_surface = tool_surface("die", &f.die, &-up, notes)?;
    check_stroke(s, &punch_surface, &f.punch.file)?;
    let mut tools = punch_and_die(
        s,
        (punch_surface, None),
        (die_surface, None),
        punch,
        thickness,
    )?;
    let (Some(holder), Some((motion, gap))) = (&f.holder, holder_drive(s, blank_mass)) else {
        if f.holder.is_some() {
            notes.push(
                "tools.holder is given but neither process.blank_holder_force nor \
                 blank_holder_gap: the holder is left out"
                    .into(),
            );
        }
        return Ok((tools, None));
    };
    let holder_surface = shifted(tool_surface("holder", holder, &up, notes)?, -gap);
    tools.push(
        RigidTool::new(
            "blank holder",
            holder_surface,
            motion,
            s.process.friction.holder,
            thickness,
        )?
        .with_blended_surface(),
    );
    Ok((tools, Some(2)))
}

/// A tool's surface from its file (STL, Gmsh or Abaqus, by extension), facing `blank_side`:
/// a coherent surface whose normals point away is flipped, with a note.
fn tool_surface(
    name: &str,
    tool: &ToolFile,
    blank_side: &Vector3<f64>,
    notes: &mut Vec<String>,
) -> Result<TriangleSurface, String> {
    let file = tool.file.display().to_string();
    let surface = read_tool_file(tool)?;
    match surface.facing(blank_side) {
        Ok(Facing::Towards) => {
            notes.push(format!(
                "{name}: {} triangles from {file}, normals towards the blank",
                surface.triangles.len()
            ));
            Ok(surface)
        }
        Ok(Facing::Away) => {
            notes.push(format!(
                "{name}: {} triangles from {file}; their normals pointed away from the blank \
                 and were flipped",
                surface.triangles.len()
            ));
            Ok(surface.flipped())
        }
        Err(e) => Err(format!("{file} ({name}): {e}")),
    }
}

/// The triangles of a tool file: every facet of an STL; the elements (or `element_set`) of a
/// mesh file, rigid or not.
fn read_tool_file(tool: &ToolFile) -> Result<TriangleSurface, String> {
    let is_stl = tool
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
    if is_stl {
        if tool.element_set.is_some() {
            return Err(format!(
                "{}: element_set is for mesh files; an STL file is one surface",
                tool.file.display()
            ));
        }
        return read_stl(&tool.file).map_err(|e| e.to_string());
    }
    let import = read_mesh_file(&tool.file).map_err(|e| e.to_string())?;
    let mesh = match &tool.element_set {
        Some(set) => {
            import
                .mesh
                .restricted_to(set)
                .map_err(|e| format!("{}: {e}", tool.file.display()))?
                .0
        }
        None => import.mesh,
    };
    Ok(TriangleSurface {
        vertices: mesh.nodes,
        triangles: mesh.cells.iter().flat_map(|c| c.triangles()).collect(),
    })
}

/// The punch must be at least as tall as the stroke, or the blank would be pushed by nothing.
fn check_stroke(s: &Scenario, punch: &TriangleSurface, file: &Path) -> Result<(), String> {
    let (lo, hi) = punch.bounds();
    let height = hi.z - lo.z;
    if s.process.stroke > height {
        return Err(format!(
            "{}: process.stroke = {} mm is more than the height of the punch of {} ({} mm)",
            s.origin,
            shown_apart(s.process.stroke, height),
            file.display(),
            shown_apart(height, s.process.stroke)
        ));
    }
    Ok(())
}

/// `model` with `tools`, the punch and holder below the blank touching its first ply (from the
/// punch's side), the die above it the last: each tool's contact offset half the thickness of
/// the ply next to it, the contact's reach the thinnest ply's.
fn with_tools_on_the_outer_plies(model: Model, tools: Vec<RigidTool>, above: &[usize]) -> Model {
    // a model has a ply at least (`Model::layup`)
    let thickness = |k: usize| model.plies[k].laminate.reference_thickness();
    let (first, last) = (thickness(0), thickness(model.plies.len() - 1));
    let contact = ContactSettings {
        offset: 0.5 * first,
        penalty_scale: PENALTY_SCALE,
        max_penetration: model.thinnest_ply(),
    };
    let mut model = model
        .with_tools(tools, contact)
        .with_tool_offset(DIE, 0.5 * last);
    for &k in above {
        model = model.with_tool_offset(k, 0.5 * last);
    }
    model
}

/// Appends `[[tools.extra]]` to `tools`, each read from its file and turned to face the blank
/// from its side (what was noticed goes to `notes`); the places of those above the blank, which
/// touch its last ply. Not in a non-isothermal run, whose tools have a temperature each.
fn push_extra_tools(
    s: &Scenario,
    tools: &mut Vec<RigidTool>,
    thickness: f64,
    notes: &mut Vec<String>,
) -> Result<Vec<usize>, String> {
    if s.heat.is_some() && !s.extra_tools.is_empty() {
        return Err(format!(
            "{}: tools.extra in a non-isothermal run: an extra tool has no temperature of its \
             own yet; run it isothermal, or give the tool's surface to the punch, die or holder",
            s.origin
        ));
    }
    let mut above = Vec::new();
    for (i, extra) in s.extra_tools.iter().enumerate() {
        let key = format!("tools.extra[{}]", i + 1);
        let up = extra
            .above(&key)
            .map_err(|e| format!("{}: {e}", s.origin))?;
        let side = if up { -Vector3::z() } else { Vector3::z() };
        let file = ToolFile {
            file: extra.file.clone(),
            element_set: extra.element_set.clone(),
        };
        let surface = tool_surface(&extra.name, &file, &side, notes)?;
        if up {
            above.push(tools.len());
        }
        let tool = RigidTool::new(
            &extra.name,
            surface,
            ToolMotion::Fixed,
            extra.friction,
            thickness,
        )?;
        tools.push(tool.with_blended_surface());
    }
    Ok(above)
}

/// No blank node may start inside a tool: the first contact force would fling it out.
fn check_start_positions(model: &Model) -> Result<(), String> {
    for (k, tool) in model.tools.iter().enumerate() {
        let half = model.tool_contact(k).offset;
        for (node, x) in model.mesh.nodes.iter().enumerate() {
            let gap = tool.gap(x, half);
            if gap < -START_PENETRATION_LIMIT * 2.0 * half {
                return Err(format!(
                    "the blank starts {:.3} mm inside the {} at node {node} ({:.2}, {:.2}, \
                     {:.2}) mm: place the tool surfaces as at the start of the stroke, half the \
                     ply's thickness ({half} mm) off its mid-plane",
                    -gap, tool.name, x.x, x.y, x.z
                ));
            }
        }
    }
    Ok(())
}
