//! The formed blank for the next analysis: an Abaqus deck (which CalculiX reads as well) with
//! the nodes where the forming left them, its S4R (or S3) elements, and per element the formed
//! warp and weft directions and the formed thickness (docs/meshes.md, "What the writer
//! writes"), so that a structural model starts from the yarn angles and thicknesses of the
//! part; and a `.vtu` of the final state with every field.

use crate::io::sheet_frame::sheet_frame;
use crate::io::vtk::{write_vtu, VtuFrame};
use crate::mesh::abaqus::{write_inp, ElementOutput};
use crate::mesh::Mesh;
use crate::solver::{Model, State};
use anyhow::Context;
use std::path::{Path, PathBuf};

/// Names of the files written, in the output folder.
pub const FORMED_INP: &str = "formed-blank.inp";
pub const FORMED_VTU: &str = "formed-blank.vtu";

/// The blank at `state`: the reference mesh's cells and sets on the current positions,
/// and per element the current warp `F a0 / |F a0|`, weft `F b0 / |F b0|` and thickness.
pub fn formed_blank(model: &Model, state: &State) -> (Mesh, ElementOutput) {
    let mesh = Mesh {
        nodes: state.positions.clone(),
        cells: model.mesh.cells.clone(),
        node_sets: model.mesh.node_sets.clone(),
        element_sets: model.mesh.element_sets.clone(),
        warp_directions: None,
    };
    let yarn = |pick: fn(&crate::element::membrane::MembraneElement) -> nalgebra::Vector2<f64>| {
        model
            .elements
            .iter()
            .map(|e| (e.gradient(&state.positions) * pick(e)).normalize())
            .collect()
    };
    let warp = yarn(|e| e.fibres.warp.xy());
    let weft = yarn(|e| e.fibres.weft.xy());
    let thickness = state.membrane.iter().map(|m| m.thickness).collect();
    (
        mesh,
        ElementOutput {
            warp,
            weft: Some(weft),
            thickness,
        },
    )
}

/// Writes [`FORMED_INP`] and [`FORMED_VTU`] into `dir`; returns their paths.
pub fn write_formed_blank(
    dir: &Path,
    model: &Model,
    state: &State,
) -> anyhow::Result<Vec<PathBuf>> {
    let (mesh, elements) = formed_blank(model, state);
    let inp = dir.join(FORMED_INP);
    write_inp(&inp, &mesh, Some(&elements))?;
    let frame = sheet_frame(model, state)?;
    let vtu = dir.join(FORMED_VTU);
    write_vtu(
        &vtu,
        &VtuFrame {
            points: &frame.points,
            cells: &model.mesh.cells,
            point_data: &frame.point_data,
            cell_data: &frame.cell_data,
        },
    )
    .with_context(|| format!("cannot write {}", vtu.display()))?;
    Ok(vec![inp, vtu])
}
