//! The blank of a layup (`blank.ply_angles` or `[[blank.plies]]`, docs/forming.md "Layups"):
//! every ply the blank's outline, cut from its own card at its own angle, stacked from the
//! punch's side upwards with their mid-surfaces one ply apart, each held as the scenario's
//! `[[boundary]]` sets say, neighbours joined by `blank.interply`'s friction.

use super::scenario::{Layup, Scenario};
use crate::contact::ply_contact::PlyInterface;
use crate::element::BendingRigidity;
use crate::material::MaterialCard;
use crate::mesh::orientation::reference_warp;
use crate::mesh::Mesh;
use crate::solver::model::PlySheet;
use crate::solver::{Constraint, Model};

/// The layup's cards, each checked at the run's temperature, all of one thickness (the tools
/// and the contact offsets are placed for plies of one thickness).
pub fn ply_cards(s: &Scenario, layup: &Layup) -> Result<Vec<MaterialCard>, String> {
    let mut cards: Vec<MaterialCard> = Vec::with_capacity(layup.plies.len());
    for (i, ply) in layup.plies.iter().enumerate() {
        let key = format!("blank.plies[{}].card", i + 1);
        let card = MaterialCard::load(&ply.card).map_err(|e| format!("{key}: {e}"))?;
        card.check_temperature("process.temperature", s.process.temperature)
            .map_err(|e| format!("{}: {e} ({})", s.origin, ply.card.display()))?;
        if let Some(first) = cards.first() {
            let (t, t0) = (
                card.laminate.reference_thickness(),
                first.laminate.reference_thickness(),
            );
            if (t / t0 - 1.0).abs() > 1e-9 {
                return Err(format!(
                    "{}: {key} ({}) is {t} mm thick, the first ply {t0} mm: the plies of a \
                     layup must be of one thickness",
                    s.origin,
                    ply.card.display()
                ));
            }
        }
        cards.push(card);
    }
    Ok(cards)
}

/// The model of the layup on the blank's `mesh` (one ply's outline, its mid-surface at the
/// stack's middle), with `constraints` on that mesh's nodes repeated on every ply.
pub fn layup_model(
    s: &Scenario,
    layup: &Layup,
    cards: &[MaterialCard],
    mesh: &Mesh,
    constraints: &[Constraint],
) -> Result<Model, String> {
    check_upward(s, mesh)?;
    let p = &s.process;
    let t = cards[0].laminate.reference_thickness();
    let n = layup.plies.len();
    let sheets = layup
        .plies
        .iter()
        .zip(cards)
        .enumerate()
        .map(|(k, (ply, card))| {
            let mut mesh = mesh.clone();
            let lift = (k as f64 + 0.5 - 0.5 * n as f64) * t;
            for x in &mut mesh.nodes {
                x.z += lift;
            }
            PlySheet {
                name: ply.name.clone(),
                mesh,
                laminate: card.laminate.time_scaled(p.time_scaling),
                density: card.density,
                warp_direction: reference_warp(s.blank.reference_direction, ply.angle),
            }
        })
        .collect();
    let per_ply = mesh.nodes.len();
    let constraints = (0..n)
        .flat_map(|k| {
            constraints.iter().map(move |c| Constraint {
                name: format!("{}: {}", layup.plies[k].name, c.name),
                nodes: c.nodes.iter().map(|i| i + k * per_ply).collect(),
                motion: c.motion.clone(),
            })
        })
        .collect();
    let mut model = Model::layup(sheets, p.temperature, constraints).map_err(|e| e.to_string())?;
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
    let friction = layup.interply.time_scaled(p.time_scaling);
    let interfaces = (1..n)
        .map(|k| PlyInterface {
            lower: k - 1,
            upper: k,
            friction,
        })
        .collect();
    model.with_interfaces(interfaces).map_err(|e| e.to_string())
}

/// The plies are stacked along +z, and the contact between them takes the upper ply on the
/// side the cells' normals point to: a mesh whose cells run clockwise seen from +z is refused.
fn check_upward(s: &Scenario, mesh: &Mesh) -> Result<(), String> {
    let up: f64 = (0..mesh.cells.len())
        .map(|c| mesh.cells[c].area_vector(&mesh.nodes).z)
        .sum();
    if up > 0.0 {
        return Ok(());
    }
    Err(format!(
        "{}: the blank's cells run clockwise seen from +z (their normals point down): the \
         plies of a layup are stacked upwards from the punch and need the cells \
         counter-clockwise; reverse the cells' node order in the mesh file",
        s.origin
    ))
}
