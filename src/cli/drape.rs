//! `thermostamp drape scenario.toml`: the kinematic draping preview of a forming scenario, with
//! a CSV of the cells, a ParaView file of the net and the largest shear angle.

use super::shared::ScenarioArgs;
use crate::drape::DrapeResult;
use crate::forming::drape_preview::drape_preview;
use crate::io::vtk::{write_vtu, Field, FieldData, VtuFrame};
use crate::io::write_csv;
use anyhow::Context;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    scenario: ScenarioArgs,
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    let (scenario, dir) = args.scenario.load()?;
    let net = drape_preview(&scenario).map_err(|e| anyhow::anyhow!("drape: {e}"))?;
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("cannot create the output folder {}", dir.display()))?;
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
    let file = std::fs::File::create(&path)
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

/// `drape.vtu`: each cell of the net as two triangles carrying its shear angle.
fn write_net(dir: &Path, net: &DrapeResult) -> anyhow::Result<PathBuf> {
    let mut points = Vec::new();
    let mut triangles = Vec::new();
    let mut shear = Vec::new();
    for c in net.cells() {
        let corners = [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(a, b)| net.node(c.i + a, c.j + b));
        if let [Some(p0), Some(p1), Some(p2), Some(p3)] = corners {
            let base = points.len();
            points.extend([p0, p1, p2, p3]);
            triangles.push([base, base + 1, base + 2]);
            triangles.push([base, base + 2, base + 3]);
            shear.extend([c.shear_deg, c.shear_deg]);
        }
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
            triangles: &triangles,
            point_data: &[],
            cell_data: &cell_data,
        },
    )?;
    Ok(path)
}
