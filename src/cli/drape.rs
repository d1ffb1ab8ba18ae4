//! `thermostamp drape scenario.toml`: the kinematic draping preview of a forming scenario, with
//! a CSV of the cells, a ParaView file of the net and the largest shear angle.

use super::shared::ScenarioArgs;
use crate::drape::DrapeResult;
use crate::forming::drape_preview::{drape_preview, Generators};
use crate::io::vtk::{write_vtu, Field, FieldData, VtuFrame};
use crate::io::write_csv;
use crate::limits::{ranges_help, ANGLE};
use crate::mesh::Cell;
use anyhow::Context;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(after_help = format!(
    "{}\n\n{}",
    super::shared::SCENARIO_REFERENCE,
    ranges_help(&[("--warp-angle", ANGLE)])
))]
pub struct Args {
    #[command(flatten)]
    scenario: ScenarioArgs,
    /// Start point of the net in plan, "x,y" in mm (default: the punch's apex, the middle of
    /// the double dome's ridge).
    #[arg(long, value_name = "X,Y", value_parser = parse_point)]
    start: Option<(f64, f64)>,
    /// Plan angle of the first generator, the warp, from x in degrees (default: the blank's
    /// ply angle); the weft is the second generator, at +90° in the tangent plane.
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_angle)]
    warp_angle: Option<f64>,
}

fn parse_point(text: &str) -> Result<(f64, f64), String> {
    let numbers: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("'{text}': {e}; expected x,y in mm"))?;
    match numbers[..] {
        [x, y] if x.is_finite() && y.is_finite() => Ok((x, y)),
        _ => Err(format!("'{text}': expected two numbers x,y in mm")),
    }
}

fn parse_angle(text: &str) -> Result<f64, String> {
    let angle = text
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("'{text}': expected an angle in degrees"))?;
    ANGLE.check("--warp-angle", angle)?;
    Ok(angle)
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (scenario, dir) = args.scenario.load()?;
    let generators = Generators {
        start: args.start.unwrap_or((0.0, 0.0)),
        warp_angle: args.warp_angle.unwrap_or(scenario.blank.ply_angle),
    };
    let net = drape_preview(&scenario, &generators).map_err(|e| match args.start {
        Some((x, y)) => anyhow::anyhow!("drape from --start {x},{y}: {e}"),
        None => anyhow::anyhow!("drape: {e}"),
    })?;
    crate::io::output_folder::create_folder(&dir)?;
    let csv = write_cells(&dir, &net)?;
    let vtu = write_net(&dir, &net)?;
    let report = net.report();
    match net.max_shear() {
        Some(m) => println!(
            "largest shear angle {:.1}° at cell ({}, {}), ({:.1}, {:.1}, {:.1}) mm",
            m.shear_deg.abs(),
            m.i,
            m.j,
            m.centre[0],
            m.centre[1],
            m.centre[2]
        ),
        None => println!("no cell could be draped"),
    }
    println!(
        "{} nodes placed, {} could not be (the edge of the formed part)",
        report.placed,
        report.failed()
    );
    println!("wrote {}", csv.display());
    println!("wrote {}", vtu.display());
    Ok(())
}

/// `drape.csv`: index, centre and shear angle of every cell.
fn write_cells(dir: &Path, net: &DrapeResult) -> anyhow::Result<PathBuf> {
    let path = dir.join("drape.csv");
    let file = crate::io::product_file::create(&path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    let rows = net.cells().into_iter().map(|c| {
        [
            c.i as f64,
            c.j as f64,
            c.centre[0],
            c.centre[1],
            c.centre[2],
            c.shear_deg,
        ]
    });
    write_csv(
        &mut std::io::BufWriter::new(file),
        &["i", "j", "x", "y", "z", "shear_angle_deg"],
        rows,
    )
    .with_context(|| format!("cannot write {}", path.display()))?;
    Ok(path)
}

/// `drape.vtu`: each cell of the net as a quadrilateral carrying its shear angle, on one point
/// per node of the net (neighbouring cells share their corners, as in the net).
fn write_net(dir: &Path, net: &DrapeResult) -> anyhow::Result<PathBuf> {
    let mut points = Vec::new();
    let mut point_of: HashMap<(i64, i64), usize> = HashMap::new();
    let mut cells = Vec::new();
    let mut shear = Vec::new();
    for c in net.cells() {
        let nodes = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(a, b)| (c.i + a, c.j + b));
        if nodes.iter().any(|&(i, j)| net.node(i, j).is_none()) {
            continue;
        }
        let [p0, p1, p2, p3] = nodes.map(|(i, j)| {
            *point_of.entry((i, j)).or_insert_with(|| {
                points.extend(net.node(i, j));
                points.len() - 1
            })
        });
        cells.push(Cell::Quad([p0, p1, p2, p3]));
        shear.push(c.shear_deg);
    }
    let path = dir.join("drape.vtu");
    let cell_data = [Field {
        name: "shear_angle_deg".into(),
        data: FieldData::Scalar(shear),
    }];
    write_vtu(
        &path,
        &VtuFrame {
            points: &points,
            cells: &cells,
            point_data: &[],
            cell_data: &cell_data,
        },
    )?;
    Ok(path)
}
