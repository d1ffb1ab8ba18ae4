//! The state of a sheet as ParaView fields: what an engineer colours the part by.

use super::vtk::{Field, FieldData};
use crate::contact::ply_contact::InterplyNode;
use crate::material::fabric::shear_angle;
use crate::material::laminate::Laminate;
use crate::material::{MaterialError, MembraneKinematics};
use crate::solver::{Model, State};
use crate::thermal::{BlankHeat, ThermalState};
use nalgebra::{Matrix2, Matrix3, Vector3};
use std::sync::Arc;

/// Points, triangles and fields of one frame, owned. The points are the sheet's reference
/// (flat) positions and `displacement` takes them to where the sheet is: ParaView's Warp By
/// Vector with `displacement` at scale 1 shows the part as formed, the convention of finite
/// element results (docs/forming.md, "ParaView output").
pub struct SheetFrame {
    pub points: Vec<[f64; 3]>,
    pub point_data: Vec<Field>,
    pub cell_data: Vec<Field>,
}

fn vector(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// In-plane components xx, yy, xy of a tensor given in global reference coordinates.
fn in_plane(t: &Matrix3<f64>) -> [f64; 3] {
    [t[(0, 0)], t[(1, 1)], t[(0, 1)]]
}

/// Point data: displacement, velocity, reaction (x, y, z); with tools, the contact pressure
/// (MPa), the contact status (0 free, `1 + k` when tool `k` presses hardest; the codes'
/// meanings are in the file's field data, `io::vtk`) and the gap of the blank's faces to
/// each tool (mm, `gap_<tool>`). Cell data: shear angle (degrees), current warp and weft
/// directions, thickness, membrane forces `membrane_force` (xx, yy, xy in the reference x–y
/// axes, N/mm), the yarn tensions `yarn_tension_warp` and `yarn_tension_weft` (N per mm of
/// reference width, docs/model.md §4) and the 2nd Piola–Kirchhoff stress of each material of the stack
/// (`stress_matrix`, `stress_fabric`: xx, yy, xy, MPa), whatever the card's stack. A blank of
/// several plies adds the ply of each cell (`ply`, numbered from 1 in the model's order) and,
/// where its plies touch, the pressure of the neighbouring plies on each node
/// (`interply_pressure`, MPa) and how far it has slid over them (`interply_slip`, mm).
pub fn sheet_frame(model: &Model, state: &State) -> Result<SheetFrame, MaterialError> {
    let points = model.mesh.nodes.iter().map(vector).collect();
    let displacement = state
        .positions
        .iter()
        .zip(&model.mesh.nodes)
        .map(|(x, x0)| vector(&(x - x0)))
        .collect();
    let point_data = vec![
        Field {
            name: "displacement".into(),
            data: FieldData::Vector(displacement),
        },
        Field {
            name: "velocity".into(),
            data: FieldData::Vector(state.velocities.iter().map(vector).collect()),
        },
        Field {
            name: "reaction".into(),
            data: FieldData::Vector(state.reactions.iter().map(vector).collect()),
        },
    ];
    let mut point_data = point_data;
    if !model.tools.is_empty() {
        point_data.extend(contact_fields(model, state));
    }
    if !state.interply.is_empty() {
        point_data.extend(interply_fields(model, state));
    }
    // every ply's laminate has the same layers (`Model::layup`)
    let n_layers = model.plies[0].laminate.layers().len();
    let mut gamma = Vec::with_capacity(model.elements.len());
    let mut warp = Vec::with_capacity(model.elements.len());
    let mut weft = Vec::with_capacity(model.elements.len());
    let mut membrane = Vec::with_capacity(model.elements.len());
    let mut yarn_tensions = Vec::with_capacity(model.elements.len());
    let mut layers = vec![Vec::with_capacity(model.elements.len()); n_layers];
    for (k, e) in model.elements.iter().enumerate() {
        let f = e.gradient(&state.positions);
        let f_dot = e.gradient(&state.velocities);
        let kin = MembraneKinematics::from_deformation(
            &f,
            &f_dot,
            state.element_temperature(model, k),
            e.fibres,
        );
        let mut c3 = Matrix3::identity();
        c3.fixed_view_mut::<2, 2>(0, 0).copy_from(&kin.c);
        gamma.push(shear_angle(&c3, &e.fibres).to_degrees());
        let yarn = |d: &Vector3<f64>| vector(&(f * d.xy()).normalize());
        warp.push(yarn(&e.fibres.warp));
        weft.push(yarn(&e.fibres.weft));
        membrane.push(in_plane(&e.to_global(&state.membrane[k].n)));
        yarn_tensions.push(
            model
                .laminate(k)
                .yarn_tensions(&kin, &state.laminate_states[k])?,
        );
        for (layer, out) in layers.iter_mut().enumerate() {
            let s = model
                .laminate(k)
                .layer_stress(layer, &kin, &state.laminate_states[k])?;
            let s2: Matrix2<f64> = s.fixed_view::<2, 2>(0, 0).into_owned();
            out.push(in_plane(&e.to_global(&s2)));
        }
    }
    let mut cell_data = vec![
        Field {
            name: "shear_angle_deg".into(),
            data: FieldData::Scalar(gamma),
        },
        Field {
            name: "warp".into(),
            data: FieldData::Vector(warp),
        },
        Field {
            name: "weft".into(),
            data: FieldData::Vector(weft),
        },
        Field {
            name: "thickness".into(),
            data: FieldData::Scalar(state.membrane.iter().map(|m| m.thickness).collect()),
        },
        Field {
            name: "membrane_force".into(),
            data: FieldData::InPlaneTensor(membrane),
        },
        Field {
            name: "yarn_tension_warp".into(),
            data: FieldData::Scalar(yarn_tensions.iter().map(|t| t[0]).collect()),
        },
        Field {
            name: "yarn_tension_weft".into(),
            data: FieldData::Scalar(yarn_tensions.iter().map(|t| t[1]).collect()),
        },
    ];
    for (values, name) in layers
        .into_iter()
        .zip(layer_names(&model.plies[0].laminate))
    {
        if let Some(name) = name {
            cell_data.push(Field {
                name,
                data: FieldData::InPlaneTensor(values),
            });
        }
    }
    if let (Some(heat), Some(thermal)) = (&model.heat, &state.thermal) {
        let (points, cells) = thermal_fields(&heat.blank, thermal, model.elements.len());
        point_data.extend(points);
        cell_data.extend(cells);
    }
    if model.plies.len() > 1 {
        cell_data.push(Field {
            name: "ply".into(),
            data: FieldData::Scalar(
                (0..model.elements.len())
                    .map(|k| (model.ply_index(k) + 1) as f64)
                    .collect(),
            ),
        });
    }
    Ok(SheetFrame {
        points,
        point_data,
        cell_data,
    })
}

/// The temperature field of a non-isothermal run (docs/model.md §9). Point data: the mean
/// temperature through each node's column and those of its bottom and top faces' cells
/// (`temperature`, `temperature_bottom`, `temperature_top`, °C). Cell data: each layer's
/// temperature and relative crystallinity (`temperature_layer_<k>`, `crystallinity_layer_<k>`,
/// layers from the bottom face, numbered from 1), the thickness-weighted mean temperature
/// (`temperature`) and whether any layer has frozen (`frozen`, 1 or 0).
fn thermal_fields(
    heat: &BlankHeat,
    thermal: &ThermalState,
    elements: usize,
) -> (Vec<Field>, Vec<Field>) {
    let cells = thermal.cells;
    let column = |a: usize| thermal.column(a);
    let nodes = thermal.temperatures.len() / cells;
    let mean = heat.node_mean_temperatures(thermal);
    let bottom = (0..nodes).map(|a| column(a)[0]).collect();
    let top = (0..nodes).map(|a| column(a)[cells - 1]).collect();
    let points = vec![
        scalar("temperature", mean),
        scalar("temperature_bottom", bottom),
        scalar("temperature_top", top),
    ];
    let layers = heat.layers();
    let temperatures = heat.element_layer_temperatures(thermal);
    let crystallinity = heat.element_layer_crystallinity(thermal);
    let by_layer = |values: &[f64], l: usize| -> Vec<f64> {
        (0..elements).map(|k| values[k * layers + l]).collect()
    };
    let mut cells_out = Vec::with_capacity(2 * layers + 2);
    let weights = heat.layer_thickness_shares();
    cells_out.push(scalar(
        "temperature",
        (0..elements)
            .map(|k| {
                (0..layers)
                    .map(|l| weights[heat.ply_of_element(k)][l] * temperatures[k * layers + l])
                    .sum()
            })
            .collect(),
    ));
    for l in 0..layers {
        cells_out.push(scalar(
            &format!("temperature_layer_{}", l + 1),
            by_layer(&temperatures, l),
        ));
    }
    for l in 0..layers {
        cells_out.push(scalar(
            &format!("crystallinity_layer_{}", l + 1),
            by_layer(&crystallinity, l),
        ));
    }
    let frozen = (0..elements)
        .map(|k| {
            let limit = heat.frozen_at(k).unwrap_or(f64::INFINITY);
            let any = (0..layers).any(|l| crystallinity[k * layers + l] >= limit);
            f64::from(u8::from(any))
        })
        .collect();
    cells_out.push(scalar("frozen", frozen));
    (points, cells_out)
}

fn scalar(name: &str, values: Vec<f64>) -> Field {
    Field {
        name: name.into(),
        data: FieldData::Scalar(values),
    }
}

/// The stress array's name of each layer: `stress_<material>` for the first layer of each
/// material (`stress_<material>_2`, ... for further materials of the same kind), `None` for a
/// layer that shares its law with an earlier one (the two matrix skins): its stress is the same.
fn layer_names(laminate: &Laminate) -> Vec<Option<String>> {
    let layers = laminate.layers();
    let mut names = Vec::with_capacity(layers.len());
    let mut kinds: Vec<&str> = Vec::new();
    for (k, layer) in layers.iter().enumerate() {
        if layers[..k].iter().any(|l| Arc::ptr_eq(&l.law, &layer.law)) {
            names.push(None);
            continue;
        }
        let kind = layer.law.name();
        let earlier = kinds.iter().filter(|&&n| n == kind).count();
        kinds.push(kind);
        names.push(Some(match earlier {
            0 => format!("stress_{kind}"),
            n => format!("stress_{kind}_{}", n + 1),
        }));
    }
    names
}

/// The plies' contact at each node: the pressure of its neighbours on it (MPa, both sides
/// summed) and how far it has slid over them (mm, the farther of its two sides).
fn interply_fields(model: &Model, state: &State) -> Vec<Field> {
    let nodal_area = model.nodal_areas();
    let pressure = state
        .interply
        .iter()
        .zip(&nodal_area)
        .map(|(c, a)| c.sides.iter().map(|s| s.normal_force).sum::<f64>() / a)
        .collect();
    let slip = state.interply.iter().map(InterplyNode::slip).collect();
    vec![
        Field {
            name: "interply_pressure".into(),
            data: FieldData::Scalar(pressure),
        },
        Field {
            name: "interply_slip".into(),
            data: FieldData::Scalar(slip),
        },
    ]
}

/// Contact pressure, status and gaps of every node (see [`sheet_frame`]).
fn contact_fields(model: &Model, state: &State) -> Vec<Field> {
    let nodal_area = model.nodal_areas();
    let pressure = state
        .contacts
        .iter()
        .zip(&nodal_area)
        .map(|(c, a)| c.normal_force.iter().sum::<f64>() / a)
        .collect();
    let status = state
        .contacts
        .iter()
        .map(|c| {
            c.normal_force
                .iter()
                .enumerate()
                .filter(|(_, &f)| f > 0.0)
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(k, _)| k as u32 + 1)
        })
        .collect();
    let meanings = std::iter::once("free".to_string())
        .chain(model.tools.iter().map(|t| t.name.clone()))
        .collect();
    let mut fields = vec![
        Field {
            name: "contact_pressure".into(),
            data: FieldData::Scalar(pressure),
        },
        Field {
            name: "contact_status".into(),
            data: FieldData::Codes {
                values: status,
                meanings,
            },
        },
    ];
    for (k, tool) in model.tools.iter().enumerate() {
        let gaps = state
            .positions
            .iter()
            .map(|x| {
                tool.gap(
                    &(x - state.tool_translations[k]),
                    model.tool_contact(k).offset,
                )
            })
            .collect();
        fields.push(Field {
            name: format!("gap_{}", tool.name.replace(' ', "_")),
            data: FieldData::Scalar(gaps),
        });
    }
    fields
}
