//! The pictures of a forming run (docs/forming.md, "Pictures"): the forces and draw-in
//! against the stroke, the shear angle on the formed part (iso view) and on the flat blank,
//! the flange's gap to the die, the thickness change, and for a layup the slip between plies.
//! Each map names the run in its title, shows the tools' outlines and marks its extreme.

use crate::contact::ply_contact::InterplyNode;
use crate::contact::TriangleSurface;
use crate::forming::run::{die_gap, shear_angles};
use crate::forming::{FormingModel, FormingRecord, FormingRun, Scenario};
use crate::io::plot::{
    write_map_png, write_twin_png, LegendCell, Limit, LinePlot, LineStyle, MapFrame, MapLine,
    MapPlot, Marker, Series, TwinPlot, MISSING_COLOUR,
};
use crate::solver::State;
use nalgebra::Vector3;
use plotters::style::RGBColor;
use std::path::{Path, PathBuf};

pub const FORCE_PLOT: &str = "forming-punch-force.png";
pub const SHEAR_MAP: &str = "forming-shear-map.png";
pub const SHEAR_BLANK: &str = "forming-shear-blank.png";
pub const WRINKLE_MAP: &str = "forming-wrinkle-map.png";
pub const THICKNESS_MAP: &str = "forming-thickness-map.png";
pub const SLIP_MAP: &str = "forming-slip-map.png";
pub const TEMPERATURE_MAP: &str = "forming-temperature-map.png";

/// Every picture a run may write, by which a later run into the folder finds and clears them.
pub const PICTURES: [&str; 7] = [
    FORCE_PLOT,
    SHEAR_MAP,
    SHEAR_BLANK,
    WRINKLE_MAP,
    THICKNESS_MAP,
    SLIP_MAP,
    TEMPERATURE_MAP,
];

/// Size of the maps and of the force plot (pixels).
pub const MAP_SIZE: (u32, u32) = (1000, 760);
pub const PLOT_SIZE: (u32, u32) = (1000, 620);

/// A picture written: its file and, for a map, the map and where its plotting area lies in
/// the picture (what the picture tests read).
pub struct Picture {
    pub path: PathBuf,
    pub map: Option<(MapPlot, MapFrame)>,
}

/// Writes the run's pictures into `dir`: the force plot, and where the run has a part to show
/// ([`FormingRun::formed_state`]) the maps of it.
pub fn write_pictures(
    dir: &Path,
    scenario: &Scenario,
    forming: &FormingModel,
    result: &FormingRun,
) -> anyhow::Result<Vec<Picture>> {
    let stopped = result.outcome.is_err();
    let reached = result.records.last().map_or(0.0, |r| r.stroke);
    let run = run_line(scenario, forming, reached, stopped);
    let mut pictures = vec![write_force_plot(dir, &run, &result.records)?];
    let Some(state) = result.formed_state() else {
        return Ok(pictures);
    };
    let run = run_line(scenario, forming, forming.punch_travel(state.time), stopped);
    let outlines = tool_outlines(forming, state);
    let locking = scenario.output.locking_angle;
    let mut maps = vec![
        (
            SHEAR_MAP,
            shear_map(forming, state, &outlines, &run, locking),
        ),
        (
            SHEAR_BLANK,
            shear_blank(forming, state, &outlines, &run, locking),
        ),
        (
            THICKNESS_MAP,
            thickness_map(forming, state, &outlines, &run),
        ),
    ];
    if let Some(map) = wrinkle_map(forming, state, &outlines, &run) {
        maps.push((WRINKLE_MAP, map));
    }
    if forming.model.plies.len() > 1 {
        maps.push((SLIP_MAP, slip_map(forming, state, &run)));
    }
    if let Some(map) = temperature_map(forming, state, &outlines, &run) {
        maps.push((TEMPERATURE_MAP, map));
    }
    for (name, map) in maps {
        let path = dir.join(name);
        let frame = write_map_png(&path, &map, MAP_SIZE.0, MAP_SIZE.1)?;
        pictures.push(Picture {
            path,
            map: Some((map, frame)),
        });
    }
    Ok(pictures)
}

/// The run in a line, for the titles: card, temperature, holder, stroke reached, solver.
pub fn run_line(
    scenario: &Scenario,
    forming: &FormingModel,
    reached: f64,
    stopped: bool,
) -> String {
    let p = &scenario.process;
    let holder = match (p.blank_holder_gap, forming.holder_tool) {
        (Some(gap), _) => format!("holder gap {gap} mm"),
        (None, Some(_)) => format!("holder {} N", p.blank_holder_force),
        (None, None) => "no holder".to_string(),
    };
    let stroke = if stopped {
        format!("stroke {reached:.2} of {} mm (stopped)", forming.stroke)
    } else {
        format!("stroke {reached:.1} mm")
    };
    // the card's name without its parenthesised remarks, which would not fit a title
    let card = forming.card.name.split(" (").next().unwrap_or_default();
    let temperature = match &scenario.heat {
        Some(h) => format!(
            "blank {} °C, {} s in air, punch {} °C",
            h.blank_temperature, h.transfer_time, h.punch
        ),
        None => format!("{} °C", p.temperature),
    };
    format!(
        "{card}, {temperature}, {holder}, {stroke}, {}",
        forming.solver.name()
    )
}

/// `forming-punch-force.png`: punch and holder forces on the left axis, the edge's draw-in
/// on the right one, against the punch's stroke.
fn write_force_plot(dir: &Path, run: &str, records: &[FormingRecord]) -> anyhow::Result<Picture> {
    let path = dir.join(FORCE_PLOT);
    let curve = |f: fn(&FormingRecord) -> f64| records.iter().map(|r| (r.stroke, f(r))).collect();
    let plot = TwinPlot {
        plot: LinePlot {
            title: format!("Punch and holder forces, draw-in\n{run}"),
            x_label: "punch stroke (mm)".into(),
            y_label: "force (N)".into(),
            series: vec![
                Series::new("punch force", curve(|r| r.punch_force), LineStyle::Solid),
                Series::new("holder force", curve(|r| r.holder_force), LineStyle::Solid),
            ],
        },
        right_label: "draw-in of the edge (mm)".into(),
        right: vec![Series::new(
            "draw-in (right axis)",
            curve(|r| r.draw_in),
            LineStyle::Dashed,
        )],
    };
    write_twin_png(&path, &plot, PLOT_SIZE.0, PLOT_SIZE.1)?;
    Ok(Picture { path, map: None })
}

/// `forming-shear-map.png`: the formed part in an iso view, coloured by |shear angle|, the
/// largest marked, the locking angle marked on the scale and cells beyond it flagged.
fn shear_map(
    forming: &FormingModel,
    state: &State,
    outlines: &[Outline],
    run: &str,
    locking: Option<f64>,
) -> MapPlot {
    let view = View::iso(stroke_axis(forming));
    let title = format!("Shear angle on the formed part (iso view)\n{run}");
    let mut map = part_map(
        forming,
        (&state.positions, &view),
        outlines,
        (title, shear_values(forming, state), shear_label(locking)),
    );
    mark_shear(&mut map, locking);
    map
}

/// `forming-shear-blank.png`: the shear angle of each cell drawn where it lay on the flat
/// blank, with the tools' outlines over it: where on the blank to expect the shear.
fn shear_blank(
    forming: &FormingModel,
    state: &State,
    outlines: &[Outline],
    run: &str,
    locking: Option<f64>,
) -> MapPlot {
    let title = format!("Shear angle on the flat blank (top view)\n{run}");
    let mut map = part_map(
        forming,
        (&forming.model.mesh.nodes, &View::top()),
        outlines,
        (title, shear_values(forming, state), shear_label(locking)),
    );
    mark_shear(&mut map, locking);
    map
}

fn shear_values(forming: &FormingModel, state: &State) -> Vec<f64> {
    shear_angles(&forming.model, state)
        .into_iter()
        .map(f64::abs)
        .collect()
}

fn shear_label(locking: Option<f64>) -> String {
    match locking {
        Some(_) => "|shear angle| (°); beyond locking magenta".into(),
        None => "|shear angle| (°)".into(),
    }
}

/// The largest shear marked on the part, the locking angle on the scale.
fn mark_shear(map: &mut MapPlot, locking: Option<f64>) {
    map.limit = locking.map(|value| Limit {
        value,
        label: format!("locking {value}°"),
        flags_cells: true,
    });
    mark_cell(map, largest, |v| format!("max {v:.1}°"));
}

/// `forming-temperature-map.png` of a non-isothermal run: each cell's temperature through its
/// thickness (the layers' mean, weighted by their thickness) on the formed part, iso view, at
/// the end of the stroke, the coldest marked. `None` for an isothermal run.
fn temperature_map(
    forming: &FormingModel,
    state: &State,
    outlines: &[Outline],
    run: &str,
) -> Option<MapPlot> {
    let (heat, thermal) = (forming.model.heat.as_ref()?, state.thermal.as_ref()?);
    let blank = &heat.blank;
    let layers = blank.layers();
    let shares = blank.layer_thickness_shares();
    let temperatures = blank.element_layer_temperatures(thermal);
    let values: Vec<f64> = (0..forming.model.elements.len())
        .map(|k| {
            let share = &shares[blank.ply_of_element(k)];
            (0..layers)
                .map(|l| share[l] * temperatures[k * layers + l])
                .sum()
        })
        .collect();
    let view = View::iso(stroke_axis(forming));
    let title = format!("Temperature at the end (iso view)\n{run}");
    let mut map = part_map(
        forming,
        (&state.positions, &view),
        outlines,
        (
            title,
            values,
            "temperature, mean through the ply (°C)".into(),
        ),
    );
    let (low, high) = span(&map.values);
    map.scale = Some((low, high));
    mark_cell(&mut map, smallest, |v| format!("coldest {v:.1} °C"));
    Some(map)
}

/// `forming-thickness-map.png`: the thickness change `t / t0 - 1` of each cell (the
/// membrane's thickness, docs/model.md §3) on the formed part, iso view, the thinnest marked.
fn thickness_map(
    forming: &FormingModel,
    state: &State,
    outlines: &[Outline],
    run: &str,
) -> MapPlot {
    let model = &forming.model;
    let change: Vec<f64> = state
        .membrane
        .iter()
        .enumerate()
        .map(|(k, m)| 100.0 * (m.thickness / model.thickness(k) - 1.0))
        .collect();
    let view = View::iso(stroke_axis(forming));
    let title = format!("Thickness change t / t0 - 1 (iso view)\n{run}");
    let mut map = part_map(
        forming,
        (&state.positions, &view),
        outlines,
        (title, change, "thickness change (%)".into()),
    );
    // thinning and thickening both matter: the scale spans the values, not from 0
    let (low, high) = span(&map.values);
    map.scale = Some((low, high));
    mark_cell(&mut map, farthest_from_zero, |v| {
        format!("largest {v:+.1} %")
    });
    map
}

/// `forming-wrinkle-map.png`: each flange cell's gap to the die (the mean of its corners',
/// as the flange measures take it, `run::die_gap`), top view, the rest grey, half the ply's
/// thickness (where the flange counts as lifted) marked on the scale. `None` without flange
/// measures (tools from files without `tools.flange_radius`).
fn wrinkle_map(
    forming: &FormingModel,
    state: &State,
    outlines: &[Outline],
    run: &str,
) -> Option<MapPlot> {
    if !forming.measures_flange() {
        return None;
    }
    let model = &forming.model;
    let x = &state.positions;
    let gaps: Vec<f64> = model
        .mesh
        .cells
        .iter()
        .enumerate()
        .map(|(k, cell)| {
            let ply = model.ply_index(k);
            let nodes = cell.nodes();
            if nodes.iter().all(|&n| forming.in_flange(&x[n])) {
                let sum: f64 = nodes
                    .iter()
                    .map(|&n| die_gap(forming, state, ply, &x[n]))
                    .sum();
                sum / nodes.len() as f64
            } else {
                f64::NAN
            }
        })
        .collect();
    if !gaps.iter().any(|g| g.is_finite()) {
        return None;
    }
    let title = format!("Flange wrinkles: gap to the die (top view)\n{run}");
    let mut map = part_map(
        forming,
        (x, &View::top()),
        outlines,
        (title, gaps, "gap to the die (mm)".into()),
    );
    let half = 0.5
        * model.plies[model.plies.len() - 1]
            .laminate
            .reference_thickness();
    map.limit = Some(Limit {
        value: half,
        label: "half ply".into(),
        flags_cells: false,
    });
    let RGBColor(r, g, b) = MISSING_COLOUR;
    map.legend.push(LegendCell {
        label: "not flange".into(),
        fill: Some((r, g, b)),
        outlined: false,
    });
    mark_cell(&mut map, largest, |v| format!("max {v:.2} mm"));
    Some(map)
}

/// `forming-slip-map.png` of a layup: how far each ply slid over its neighbours, each cell
/// coloured by the mean of its corners' `interply_slip` (the larger of a node's two sides),
/// top view, the plies side by side on one scale.
fn slip_map(forming: &FormingModel, state: &State, run: &str) -> MapPlot {
    let slip: Vec<f64> = state.interply.iter().map(InterplyNode::slip).collect();
    let values = forming
        .model
        .mesh
        .cells
        .iter()
        .map(|c| c.nodes().iter().map(|&n| slip[n]).sum::<f64>() / c.nodes().len() as f64)
        .collect();
    let title = format!("Interply slip (top view)\n{run}");
    let mut map = part_map(
        forming,
        (&state.positions, &View::top()),
        &[],
        (title, values, "interply slip (mm)".into()),
    );
    mark_cell(&mut map, largest, |v| format!("max {v:.2} mm"));
    map
}

/// An orthographic view: screen axes `right` and `up`, and `toward` the viewer.
struct View {
    right: Vector3<f64>,
    up: Vector3<f64>,
    toward: Vector3<f64>,
    /// Whether cells are shaded by how squarely they face the viewer (a projected 3D part).
    shaded: bool,
}

impl View {
    /// From above, x to the right and y up.
    fn top() -> Self {
        Self {
            right: Vector3::x(),
            up: Vector3::y(),
            toward: Vector3::z(),
            shaded: false,
        }
    }

    /// An iso view from 30° above the blank's plane on the side the part is drawn to
    /// (`axis`, the punch's travel, up on the screen), turned 60° from x about it, so that
    /// the part's wall shows instead of collapsing into a ring as from above.
    fn iso(axis: Vector3<f64>) -> Self {
        let (elevation, azimuth) = (30f64.to_radians(), (-60f64).to_radians());
        let toward = (elevation.cos()
            * (azimuth.cos() * Vector3::x() + azimuth.sin() * Vector3::y())
            + elevation.sin() * axis)
            .normalize();
        let right = axis.cross(&toward).normalize();
        Self {
            up: toward.cross(&right),
            right,
            toward,
            shaded: true,
        }
    }

    fn project(&self, p: &Vector3<f64>) -> (f64, f64) {
        (p.dot(&self.right), p.dot(&self.up))
    }
}

/// The direction the punch travels: from the punch towards the die.
fn stroke_axis(forming: &FormingModel) -> Vector3<f64> {
    let tools = &forming.model.tools;
    let mean_z = |t: usize| {
        let v = &tools[t].surface.vertices;
        v.iter().map(|p| p.z).sum::<f64>() / v.len().max(1) as f64
    };
    if mean_z(forming.punch_tool) <= mean_z(forming.die_tool) {
        Vector3::z()
    } else {
        -Vector3::z()
    }
}

/// A tool's outline: segments in space, drawn in both views with a legend entry.
struct Outline {
    label: &'static str,
    /// Whether the line lies inside the formed part (the punch's section), where an iso view
    /// of the part cannot show it.
    inside_part: bool,
    colour: (u8, u8, u8),
    segments: Vec<[Vector3<f64>; 2]>,
}

/// The tools' outlines where they stand in `state`: the die's opening (where its flat face
/// ends), the punch's section in the die's face at the stroke reached, and the holder's inner
/// edge. An outline the tool does not have (no holder) is left out.
fn tool_outlines(forming: &FormingModel, state: &State) -> Vec<Outline> {
    let axis = stroke_axis(forming);
    let placed = |t: usize| -> Vec<Vector3<f64>> {
        forming.model.tools[t]
            .vertices_at(state.tool_translations[t])
            .collect()
    };
    let levels = |v: &[Vector3<f64>]| {
        v.iter()
            .map(|p| p.dot(&axis))
            .fold((f64::MAX, f64::MIN), |(lo, hi), h| (lo.min(h), hi.max(h)))
    };
    let mut outlines = Vec::new();
    let die = placed(forming.die_tool);
    let (face, back) = levels(&die);
    // just into the opening: the contour where the flat face turns into the fillet
    let into = (0.01 * (back - face)).min(0.1);
    outlines.push(Outline {
        label: "die opening",
        inside_part: false,
        colour: (120, 60, 0),
        segments: contour(
            &die,
            &forming.model.tools[forming.die_tool].surface,
            axis,
            face + into,
        ),
    });
    let punch = placed(forming.punch_tool);
    let (bottom, nose) = levels(&punch);
    let travel = forming.punch_travel(state.time);
    outlines.push(Outline {
        label: "punch in the die face",
        inside_part: true,
        colour: (0, 0, 0),
        segments: contour(
            &punch,
            &forming.model.tools[forming.punch_tool].surface,
            axis,
            nose - travel.min(0.98 * (nose - bottom)),
        ),
    });
    if let Some(h) = forming.holder_tool {
        outlines.push(Outline {
            label: "holder inner edge",
            inside_part: false,
            colour: (110, 110, 110),
            segments: inner_edge(forming, &placed(h), &forming.model.tools[h].surface),
        });
    }
    outlines.retain(|o| !o.segments.is_empty());
    outlines
}

/// Where the surface crosses the plane `x . axis = level`: a segment per triangle it cuts.
fn contour(
    vertices: &[Vector3<f64>],
    surface: &TriangleSurface,
    axis: Vector3<f64>,
    level: f64,
) -> Vec<[Vector3<f64>; 2]> {
    let height = |v: usize| vertices[v].dot(&axis) - level;
    surface
        .triangles
        .iter()
        .filter_map(|t| {
            let crossings: Vec<Vector3<f64>> = [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])]
                .into_iter()
                .filter(|&(a, b)| (height(a) < 0.0) != (height(b) < 0.0))
                .map(|(a, b)| {
                    let w = height(a) / (height(a) - height(b));
                    vertices[a] + w * (vertices[b] - vertices[a])
                })
                .collect();
            (crossings.len() == 2).then(|| [crossings[0], crossings[1]])
        })
        .collect()
}

/// The holder's inner edge: the edges of its surface that belong to one triangle and lie
/// nearer the punch's axis (ridge) than halfway to its outer edge.
fn inner_edge(
    forming: &FormingModel,
    vertices: &[Vector3<f64>],
    surface: &TriangleSurface,
) -> Vec<[Vector3<f64>; 2]> {
    let mut count = std::collections::HashMap::new();
    for t in &surface.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *count.entry((a.min(b), a.max(b))).or_insert(0usize) += 1;
        }
    }
    let edges: Vec<([Vector3<f64>; 2], f64)> = count
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .map(|((a, b), _)| {
            let middle = 0.5 * (vertices[a] + vertices[b]);
            (
                [vertices[a], vertices[b]],
                forming.distance_from_ridge(&middle),
            )
        })
        .collect();
    let (near, far) = edges.iter().fold((f64::MAX, f64::MIN), |(lo, hi), e| {
        (lo.min(e.1), hi.max(e.1))
    });
    let halfway = 0.5 * (near + far);
    edges
        .into_iter()
        .filter(|e| e.1 < halfway)
        .map(|e| e.0)
        .collect()
}

/// A map of the part as `view` sees `points` (a position per node), a value per cell, the
/// tools' outlines over it; a layup's plies side by side in a grid ([`panels`]). Cells are
/// drawn far to near (painter's algorithm), so that the near side of a deep part covers its
/// far side; in a shaded view each cell's colour is dimmed as it turns from the viewer.
fn part_map(
    forming: &FormingModel,
    (points, view): (&[Vector3<f64>], &View),
    outlines: &[Outline],
    (title, values, value_label): (String, Vec<f64>, String),
) -> MapPlot {
    let model = &forming.model;
    let flat: Vec<(f64, f64)> = points.iter().map(|p| view.project(p)).collect();
    let plies = model.plies.len();
    let offset = panels(&flat, plies);
    let cells = &model.mesh.cells;
    let mut order: Vec<usize> = (0..cells.len()).collect();
    let depth = |k: usize| {
        let nodes = cells[k].nodes();
        nodes
            .iter()
            .map(|&n| points[n].dot(&view.toward))
            .sum::<f64>()
            / nodes.len() as f64
    };
    let depths: Vec<f64> = (0..cells.len()).map(depth).collect();
    order.sort_by(|&a, &b| depths[a].total_cmp(&depths[b]));
    let polygon = |k: usize| {
        let (dx, dy) = offset(model.ply_index(k));
        cells[k]
            .nodes()
            .iter()
            .map(|&n| (flat[n].0 + dx, flat[n].1 + dy))
            .collect()
    };
    let shade = |k: usize| {
        let n = cells[k].nodes();
        let (a, b, c) = (points[n[0]], points[n[1]], points[n[2]]);
        // a quad's normal from its diagonals, a triangle's from two sides
        let normal = match n.get(3) {
            Some(&d) => (c - a).cross(&(points[d] - b)),
            None => (b - a).cross(&(c - a)),
        };
        let facing = normal.normalize().dot(&view.toward).abs();
        0.55 + 0.45 * if facing.is_finite() { facing } else { 1.0 }
    };
    let mut map = MapPlot::new(
        title,
        value_label,
        order.iter().map(|&k| polygon(k)).collect(),
        order.iter().map(|&k| values[k]).collect(),
    );
    if view.shaded {
        map.shade = order.iter().map(|&k| shade(k)).collect();
    } else if plies == 1 {
        // a layup's panels are offset from each other: their coordinates are not the part's
        map.axes = Some(("x (mm)".into(), "y (mm)".into()));
    }
    if plies > 1 {
        map.title = map.title.replacen(
            '\n',
            &format!("; plies 1 to {plies} from the punch's side, in reading order\n"),
            1,
        );
    }
    // a projected part hides the tools' lines behind it (a ply's own cells); a tolerance of a
    // quarter cell keeps those that lie on the part (the die's opening under the flange)
    let hidden = |at: (f64, f64), depth: f64, ply: usize| {
        view.shaded
            && (0..cells.len()).any(|k| {
                model.ply_index(k) == ply
                    && depth_at(cells[k].nodes(), points, view, at)
                        > depth + 0.25 * forming.element_size
                    && inside(&polygon_at(cells[k].nodes(), &flat), at)
            })
    };
    map.lines = outlines
        .iter()
        .filter(|o| !(view.shaded && o.inside_part))
        .map(|o| MapLine {
            label: o.label.to_string(),
            colour: o.colour,
            segments: (0..plies)
                .flat_map(|ply| {
                    let (dx, dy) = offset(ply);
                    o.segments.iter().filter_map(move |s| {
                        let middle = 0.5 * (s[0] + s[1]);
                        let ends = s.map(|p| {
                            let (x, y) = view.project(&p);
                            (x + dx, y + dy)
                        });
                        let seen = !hidden(view.project(&middle), middle.dot(&view.toward), ply);
                        seen.then_some(ends)
                    })
                })
                .collect(),
        })
        .collect();
    map
}

/// Where each ply's panel goes (an offset in the picture's plane): one panel for a single
/// ply, a layup's in a grid of about as many columns as rows, ply 1 (the punch's side) top
/// left, in reading order.
fn panels(flat: &[(f64, f64)], plies: usize) -> impl Fn(usize) -> (f64, f64) {
    let (x0, x1, y0, y1) = flat.iter().fold(
        (f64::MAX, f64::MIN, f64::MAX, f64::MIN),
        |(x0, x1, y0, y1), p| (x0.min(p.0), x1.max(p.0), y0.min(p.1), y1.max(p.1)),
    );
    let columns = (plies as f64).sqrt().ceil().max(1.0) as usize;
    let (width, height) = (1.1 * (x1 - x0), 1.1 * (y1 - y0));
    move |ply| {
        let (row, column) = (ply / columns, ply % columns);
        (width * column as f64, -height * row as f64)
    }
}

/// The projected corners of a cell, unshifted.
fn polygon_at(nodes: &[usize], flat: &[(f64, f64)]) -> Vec<(f64, f64)> {
    nodes.iter().map(|&n| flat[n]).collect()
}

/// The depth (towards the viewer) of the cell of `nodes` at the screen point `(x, y)`: on the
/// plane through its centre normal to its diagonals; seen edge on, its centre's depth.
fn depth_at(nodes: &[usize], points: &[Vector3<f64>], view: &View, (x, y): (f64, f64)) -> f64 {
    let centre = nodes.iter().map(|&n| points[n]).sum::<Vector3<f64>>() / nodes.len() as f64;
    let (a, c) = (points[nodes[0]], points[nodes[2]]);
    let (b, d) = (points[nodes[1]], points[nodes[nodes.len() - 1]]);
    let normal = (c - a).cross(&(d - b));
    let facing = view.toward.dot(&normal);
    if facing.abs() < 1e-6 * normal.norm() {
        return centre.dot(&view.toward);
    }
    // the point x right + y up + t toward on the plane: (p - centre) . normal = 0
    (centre.dot(&normal) - x * view.right.dot(&normal) - y * view.up.dot(&normal)) / facing
}

/// Whether `p` lies inside the polygon `corners` (crossing number, any polygon).
fn inside(corners: &[(f64, f64)], (x, y): (f64, f64)) -> bool {
    let n = corners.len();
    (0..n)
        .filter(|&i| {
            let ((x0, y0), (x1, y1)) = (corners[i], corners[(i + 1) % n]);
            (y0 > y) != (y1 > y) && x < x0 + (y - y0) / (y1 - y0) * (x1 - x0)
        })
        .count()
        % 2
        == 1
}

/// Marks the cell `pick` chooses (if any) at its centre with `label` of its value.
fn mark_cell(map: &mut MapPlot, pick: fn(&[f64]) -> Option<usize>, label: impl Fn(f64) -> String) {
    map.marker = pick(&map.values).map(|k| {
        let corners = &map.cells[k];
        let n = corners.len() as f64;
        let at = corners
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.0 / n, y + p.1 / n));
        Marker {
            at,
            label: label(map.values[k]),
        }
    });
}

/// The index of the largest finite value.
fn largest(values: &[f64]) -> Option<usize> {
    (0..values.len())
        .filter(|&k| values[k].is_finite())
        .max_by(|&a, &b| values[a].total_cmp(&values[b]))
}

/// The index of the smallest finite value.
fn smallest(values: &[f64]) -> Option<usize> {
    (0..values.len())
        .filter(|&k| values[k].is_finite())
        .min_by(|&a, &b| values[a].total_cmp(&values[b]))
}

/// The index of the finite value farthest from zero.
fn farthest_from_zero(values: &[f64]) -> Option<usize> {
    (0..values.len())
        .filter(|&k| values[k].is_finite())
        .max_by(|&a, &b| values[a].abs().total_cmp(&values[b].abs()))
}

/// The smallest and largest finite value.
fn span(values: &[f64]) -> (f64, f64) {
    values
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)))
}
