//! The blank of a layup (`blank.ply_angles` or `[[blank.plies]]`, docs/forming.md "Layups"):
//! every ply the blank's outline, cut from its own card at its own angle, stacked from the
//! punch's side upwards each on the one below it, each held as the scenario's `[[boundary]]`
//! sets say, neighbours joined by the friction of `blank.interply` or `[[blank.interfaces]]`.

use super::scenario::{Layup, PlySpec, Scenario};
use crate::contact::ply_contact::PlyInterface;
use crate::element::BendingRigidity;
use crate::material::MaterialCard;
use crate::mesh::orientation::reference_warp;
use crate::mesh::outline::Outline;
use crate::mesh::Mesh;
use crate::solver::model::PlySheet;
use crate::solver::{Constraint, Model};

/// The layup's cards, each checked at the run's temperature.
pub fn ply_cards(s: &Scenario, layup: &Layup) -> Result<Vec<MaterialCard>, String> {
    layup
        .plies
        .iter()
        .enumerate()
        .map(|(i, ply)| {
            let key = format!("blank.plies[{}].card", i + 1);
            let card = MaterialCard::load(&ply.card).map_err(|e| format!("{key}: {e}"))?;
            card.check_temperature("process.temperature", s.process.temperature)
                .map_err(|e| format!("{}: {e} ({})", s.origin, ply.card.display()))?;
            Ok(card)
        })
        .collect()
}

/// Each ply's reference thickness (mm), from the punch's side.
pub fn ply_thicknesses(cards: &[MaterialCard]) -> Vec<f64> {
    cards
        .iter()
        .map(|c| c.laminate.reference_thickness())
        .collect()
}

/// Where each ply's mid-surface lies above the stack's middle (mm): the plies of
/// `thicknesses` stacked from below, each on the one under it.
pub fn ply_lifts(thicknesses: &[f64]) -> Vec<f64> {
    let total: f64 = thicknesses.iter().sum();
    let mut below = 0.0;
    thicknesses
        .iter()
        .map(|t| {
            let lift = below + 0.5 * t - 0.5 * total;
            below += t;
            lift
        })
        .collect()
}

/// The model of the layup on each ply's mesh (`meshes`, from the punch's side, each with its
/// mid-surface in z = 0, lifted here to its place in the stack), each ply with its own
/// `constraints` on its mesh's nodes.
pub fn layup_model(
    s: &Scenario,
    layup: &Layup,
    cards: &[MaterialCard],
    meshes: Vec<Mesh>,
    constraints: Vec<Vec<Constraint>>,
) -> Result<Model, String> {
    for (ply, mesh) in layup.plies.iter().zip(&meshes) {
        check_upward(s, ply, mesh)?;
    }
    check_plies_between(s, layup, &meshes)?;
    let p = &s.process;
    let n = layup.plies.len();
    let lifts = ply_lifts(&ply_thicknesses(cards));
    let mut first_node = 0;
    let mut held = Vec::new();
    let mut sheets = Vec::with_capacity(n);
    for (((ply, card), (mut mesh, own)), lift) in layup
        .plies
        .iter()
        .zip(cards)
        .zip(meshes.into_iter().zip(constraints))
        .zip(lifts)
    {
        for x in &mut mesh.nodes {
            x.z += lift;
        }
        held.extend(own.into_iter().map(|c| Constraint {
            name: format!("{}: {}", ply.name, c.name),
            nodes: c.nodes.iter().map(|i| i + first_node).collect(),
            motion: c.motion,
        }));
        first_node += mesh.nodes.len();
        sheets.push(PlySheet {
            name: ply.name.clone(),
            mesh,
            laminate: card.laminate.time_scaled(p.time_scaling),
            density: card.density,
            warp_direction: reference_warp(s.blank.reference_direction, ply.angle),
        });
    }
    let mut model = Model::layup(sheets, p.temperature, held).map_err(|e| e.to_string())?;
    if cards.iter().any(|c| c.bending.is_some()) {
        let none = BendingRigidity {
            warp: 0.0,
            weft: 0.0,
        };
        let rigidities = cards
            .iter()
            .map(|c| c.bending.as_ref().map_or(Ok(none), |b| b.at(p.temperature)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| format!("process.temperature: {e}"))?;
        model = model
            .with_ply_bending(&rigidities)
            .map_err(|e| e.to_string())?;
    }
    // the film sees the physical slip speed, as the matrix's eta1 does (docs/model.md §6)
    let interfaces = (1..n)
        .map(|k| PlyInterface {
            lower: k - 1,
            upper: k,
            friction: layup.interfaces[k - 1].time_scaled(p.time_scaling),
        })
        .collect();
    model.with_interfaces(interfaces).map_err(|e| e.to_string())
}

/// The plies are stacked along +z, and the contact between them takes the upper ply on the
/// side the cells' normals point to: a mesh whose cells run clockwise seen from +z is refused.
fn check_upward(s: &Scenario, ply: &PlySpec, mesh: &Mesh) -> Result<(), String> {
    let up: f64 = (0..mesh.cells.len())
        .map(|c| mesh.cells[c].area_vector(&mesh.nodes).z)
        .sum();
    if up > 0.0 {
        return Ok(());
    }
    let whose = match &ply.shape {
        Some(_) => format!("ply \"{}\"'s", ply.name),
        None => "the blank's".into(),
    };
    Err(format!(
        "{}: {whose} cells run clockwise seen from +z (their normals point down): the plies of \
         a layup are stacked upwards from the punch and need the cells counter-clockwise; \
         reverse the cells' node order in the mesh file",
        s.origin
    ))
}

/// Each ply touches the plies next to it in the stack, and no other (docs/forming.md,
/// "Layups"): where a ply lies over (or under) one that is not its neighbour, the plies between
/// them must lie there too, or the two would pass through each other unseen. Checked at every
/// node of every ply, seen along z, where a ply has an outline of its own.
fn check_plies_between(s: &Scenario, layup: &Layup, meshes: &[Mesh]) -> Result<(), String> {
    if layup.plies.iter().all(|p| p.shape.is_none()) {
        return Ok(());
    }
    let outlines: Vec<Outline> = meshes.iter().map(Outline::of).collect();
    for (j, mesh) in meshes.iter().enumerate() {
        for x in &mesh.nodes {
            let over: Vec<bool> = outlines.iter().map(|o| o.contains(&x.xy())).collect();
            let gap = (0..meshes.len())
                .filter(|&k| over[k] && k.abs_diff(j) > 1)
                .find_map(|k| (k.min(j) + 1..k.max(j)).find(|&m| !over[m]).map(|m| (k, m)));
            if let Some((k, missing)) = gap {
                let name = |i: usize| format!("\"{}\" (ply {})", layup.plies[i].name, i + 1);
                return Err(format!(
                    "{}: ply {} and ply {} both lie at ({:.1}, {:.1}) mm, and ply {} between them \
                     does not: plies touch only their neighbours in the stack, so two plies \
                     apart must have every ply between them wherever they overlap; give the \
                     plies outlines that nest (docs/forming.md, \"Layups\")",
                    s.origin,
                    name(j.min(k)),
                    name(j.max(k)),
                    x.x,
                    x.y,
                    name(missing)
                ));
            }
        }
    }
    Ok(())
}
