//! What a forming run that stopped tells the user to try: for an implicit increment that did
//! not converge, where the residual was largest and the scenario keys that change what the
//! solver meets there (docs/solver.md, "When an increment does not converge").

use super::run::FormingRun;
use super::scenario::{BlankShape, Scenario, ToolSet};
use super::setup::FormingModel;
use crate::solver::{SolverError, SolverKind};

/// The advice for `run` of `scenario`, where it stopped because an implicit increment did not
/// converge; `None` otherwise.
pub fn stop_advice(
    scenario: &Scenario,
    forming: &FormingModel,
    run: &FormingRun,
) -> Option<String> {
    let Err(SolverError::NotConverged { worst_nodes, .. }) = &run.outcome else {
        return None;
    };
    if forming.solver != SolverKind::Implicit {
        return None;
    }
    let mut lines = Vec::new();
    if let Some(place) = where_it_stalled(forming, run, worst_nodes) {
        lines.push(place);
    }
    let stroke = forming.stroke;
    let travel = forming.max_increment * forming.punch.speed;
    lines.push(format!(
        "shorter increments: process.max_increment = {} (now {} mm of the {stroke} mm stroke)",
        round(0.5 * travel),
        round(travel)
    ));
    lines.push(match &scenario.blank.shape {
        BlankShape::Rectangle { element_size, .. } => format!(
            "a finer blank, so that its cells follow the tools' fillets: blank.element_size = {} \
             (now {element_size} mm)",
            round(0.5 * element_size)
        ),
        BlankShape::File { mesh, .. } => format!(
            "a finer blank mesh ({}), so that its cells follow the tools' fillets",
            mesh.display()
        ),
    });
    if let ToolSet::Files(files) = &scenario.tools {
        let mut named = vec![
            format!("tools.punch ({})", files.punch.file.display()),
            format!("tools.die ({})", files.die.file.display()),
        ];
        if let Some(holder) = &files.holder {
            named.push(format!("tools.holder ({})", holder.file.display()));
        }
        lines.push(format!(
            "finer facets where the tools are curved: {}",
            named.join(", ")
        ));
    }
    lines.push(
        "or the explicit solver, which has no increments to converge: process.solver = \
         \"explicit\", with process.time_scaling and process.target_time_step to keep its cost \
         (docs/solver.md, \"Which solver\")"
            .into(),
    );
    let kept = run.formed_state().map_or(String::new(), |_| {
        let reached = run.records.last().map_or(0.0, |r| r.stroke);
        format!(
            "The part as formed at {reached:.2} mm of stroke, the last converged increment, is \
             written (history, frames, shear map, punch-force plot, formed blank)."
        )
    });
    Some(format!(
        "what to try (an increment did not converge, see the error below):\n  - {}\n{kept}",
        lines.join("\n  - ")
    ))
}

/// Where the residual was largest: the node, its position in the last converged state and the
/// tools it touched there.
fn where_it_stalled(forming: &FormingModel, run: &FormingRun, worst: &[usize]) -> Option<String> {
    let state = run.formed_state()?;
    let &node = worst.first()?;
    let x = state.positions.get(node)?;
    let touching: Vec<&str> = state
        .contacts
        .get(node)
        .map(|c| {
            c.normal_force
                .iter()
                .zip(&forming.model.tools)
                .filter(|(&f, _)| f > 0.0)
                .map(|(_, tool)| tool.name.as_str())
                .collect()
        })
        .unwrap_or_default();
    let on = if touching.is_empty() {
        "touching no tool".to_string()
    } else {
        format!("on the {}", touching.join(" and the "))
    };
    Some(format!(
        "the residual was largest at node {node}, at ({:.1}, {:.1}, {:.1}) mm, {on}: look \
         there in the last frame",
        x.x, x.y, x.z
    ))
}

/// A key value to suggest: three significant digits.
fn round(value: f64) -> String {
    format!("{}", format!("{value:.3e}").parse::<f64>().unwrap_or(value))
}
