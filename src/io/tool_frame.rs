//! The tools as ParaView data: their surfaces where they are at a state, to be shown with the
//! sheet (`io::vtk::PvdSeries` writes them as a part of each frame).

use super::vtk::{Field, FieldData};
use crate::mesh::Cell;
use crate::solver::{Model, State};

/// Points and triangles of every tool's surface, owned, with the cell code `tool` saying which
/// tool each triangle is of (its meanings are the tools' names).
pub struct ToolFrame {
    pub points: Vec<[f64; 3]>,
    pub cells: Vec<Cell>,
    pub cell_data: Vec<Field>,
}

/// The tools' triangulated surfaces (the meshes of `tools.resolution`, or the STL files),
/// moved by each tool's translation at `state`; `None` without tools.
pub fn tool_frame(model: &Model, state: &State) -> Option<ToolFrame> {
    if model.tools.is_empty() {
        return None;
    }
    let mut points = Vec::new();
    let mut cells = Vec::new();
    let mut codes = Vec::new();
    for (k, tool) in model.tools.iter().enumerate() {
        let first = points.len();
        points.extend(
            tool.vertices_at(state.tool_translations[k])
                .map(|x| [x.x, x.y, x.z]),
        );
        for t in &tool.surface.triangles {
            cells.push(Cell::Triangle(t.map(|n| first + n)));
            codes.push(k as u32);
        }
    }
    let cell_data = vec![Field {
        name: "tool".into(),
        data: FieldData::Codes {
            values: codes,
            meanings: model.tools.iter().map(|t| t.name.clone()).collect(),
        },
    }];
    Some(ToolFrame {
        points,
        cells,
        cell_data,
    })
}
