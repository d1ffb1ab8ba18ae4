//! `thermostamp material-point`: the single-element test of the material models.

use crate::experiment::material_point::{
    drive_laminate, drive_layer, LaminateResponse, MembraneSample, PointFailure, PointResponse,
    PointSample,
};
use crate::io::{check_finite_row, read_csv_table, write_csv, CsvTable, InputError};
use crate::material::{FibreDirections, MaterialCard, MaterialLaw};
use anyhow::Context;
use clap::ValueEnum;
use nalgebra::{Matrix2, Matrix3};
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(after_help = format!(
    "{}\n\n{}",
    "History columns:\n  \
        matrix, fabric: t,F11,F12,F13,F21,F22,F23,F31,F32,F33,T (full 3D F, T in °C)\n  \
        laminate:       t,F11,F12,F21,F22,T (in-plane F)\n\
        Output columns:\n  \
        matrix, fabric: t,S11,S22,S33,S12,S23,S13,sigma11,sigma22,sigma33,sigma12,sigma23,sigma13 (MPa)\n  \
        laminate:       t,N11,N22,N12,thickness (N/mm per unit reference width, mm)",
    crate::limits::ranges_help(&[("--angle", crate::limits::ANGLE)])
))]
pub struct Args {
    /// Material card (TOML), e.g. materials/t300-5hs-pps.toml.
    #[arg(long)]
    card: PathBuf,
    /// Which model to drive.
    #[arg(long, value_enum)]
    layer: LayerChoice,
    /// Deformation history (CSV).
    #[arg(long)]
    history: PathBuf,
    /// Warp direction, degrees from x in the x–y plane (weft 90° further on).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    angle: f64,
    /// Write the CSV here (default: standard output).
    #[arg(long)]
    output: Option<PathBuf>,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum LayerChoice {
    /// Layer A alone: visco-hyperelastic matrix (3D history).
    Matrix,
    /// Layer B alone: woven fabric (3D history).
    Fabric,
    /// The whole A:B:A ply in plane stress (in-plane history).
    Laminate,
}

const LAYER_COLUMNS: [&str; 11] = [
    "t", "F11", "F12", "F13", "F21", "F22", "F23", "F31", "F32", "F33", "T",
];
const LAYER_OUTPUT: [&str; 13] = [
    "t", "S11", "S22", "S33", "S12", "S23", "S13", "sigma11", "sigma22", "sigma33", "sigma12",
    "sigma23", "sigma13",
];
const LAMINATE_COLUMNS: [&str; 6] = ["t", "F11", "F12", "F21", "F22", "T"];
const LAMINATE_OUTPUT: [&str; 5] = ["t", "N11", "N22", "N12", "thickness"];

pub fn run(args: &Args) -> anyhow::Result<()> {
    crate::limits::ANGLE
        .check("--angle", args.angle)
        .map_err(anyhow::Error::msg)?;
    let card = MaterialCard::load(&args.card)?;
    let fibres = FibreDirections::in_plane(args.angle.to_radians());
    let (header, rows): (&[&str], Vec<Vec<f64>>) = match args.layer {
        LayerChoice::Matrix | LayerChoice::Fabric => {
            let table = read_csv_table(&args.history, &LAYER_COLUMNS)?;
            let history = point_history(&table)?;
            let law: &dyn MaterialLaw = match args.layer {
                LayerChoice::Matrix => card.matrix.as_deref().ok_or_else(|| {
                    anyhow::anyhow!("{}: the card has no [matrix] section", args.card.display())
                })?,
                _ => card.fabric.as_ref(),
            };
            let response =
                drive_layer(law, fibres, &history).map_err(|f| locate(&table, f, &args.card))?;
            (&LAYER_OUTPUT, response.iter().map(layer_row).collect())
        }
        LayerChoice::Laminate => {
            let table = read_csv_table(&args.history, &LAMINATE_COLUMNS)?;
            let history = membrane_history(&table)?;
            let response = drive_laminate(&card.laminate, fibres, &history)
                .map_err(|f| locate(&table, f, &args.card))?;
            (
                &LAMINATE_OUTPUT,
                response.iter().map(laminate_row).collect(),
            )
        }
    };
    check_response(args, header, &rows)?;
    write_output(args.output.as_ref(), header, &rows)
}

/// A response that is not a finite number comes from the card (a value the law cannot take,
/// such as 1e308 for a thickness) driven through the history: the error names both, as the
/// writer alone would name only a cell of an output nobody asked to read.
fn check_response(args: &Args, header: &[&str], rows: &[Vec<f64>]) -> anyhow::Result<()> {
    for (i, row) in rows.iter().enumerate() {
        check_finite_row(header, i + 1, row).map_err(|e| {
            anyhow::anyhow!(
                "{}: driven through {}, the response is not a finite number (output {e})",
                args.card.display(),
                args.history.display()
            )
        })?;
    }
    Ok(())
}

fn write_output(path: Option<&PathBuf>, header: &[&str], rows: &[Vec<f64>]) -> anyhow::Result<()> {
    match path {
        Some(path) => {
            let file = std::fs::File::create(path)
                .with_context(|| format!("cannot create {}", path.display()))?;
            write_csv(&mut std::io::BufWriter::new(file), header, rows)
                .with_context(|| format!("cannot write {}", path.display()))
        }
        None => {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            match write_csv(&mut out, header, rows).and_then(|_| out.flush()) {
                Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
                _ => Ok(()),
            }
        }
    }
}

/// Puts the history file and line on a failure of the material, and names the card whose law
/// failed there (a temperature outside its tables is the card's as much as the history's).
fn locate(table: &CsvTable, failure: PointFailure, card: &Path) -> InputError {
    InputError::at_line(
        &table.origin,
        table.lines[failure.index],
        format!("{} (material card {})", failure.error, card.display()),
    )
}

/// Checks times and volumes row by row, so that errors point at the line.
fn check_row(table: &CsvTable, i: usize, det_f: f64) -> Result<(), InputError> {
    let line = table.lines[i];
    if i > 0 && table.rows[i][0] <= table.rows[i - 1][0] {
        return Err(InputError::at_line(
            &table.origin,
            line,
            format!(
                "t = {} does not increase (previous t = {})",
                table.rows[i][0],
                table.rows[i - 1][0]
            ),
        ));
    }
    if det_f.is_nan() || det_f <= 0.0 {
        return Err(InputError::at_line(
            &table.origin,
            line,
            format!("det F = {det_f} <= 0: the deformation inverts or crushes the material"),
        ));
    }
    Ok(())
}

fn point_history(table: &CsvTable) -> Result<Vec<PointSample>, InputError> {
    table
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let f = Matrix3::new(r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8], r[9]);
            check_row(table, i, f.determinant())?;
            Ok(PointSample {
                t: r[0],
                f,
                temperature: r[10],
            })
        })
        .collect()
}

fn membrane_history(table: &CsvTable) -> Result<Vec<MembraneSample>, InputError> {
    table
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let f = Matrix2::new(r[1], r[2], r[3], r[4]);
            check_row(table, i, f.determinant())?;
            Ok(MembraneSample {
                t: r[0],
                f,
                temperature: r[5],
            })
        })
        .collect()
}

/// Voigt-like order of the output: 11, 22, 33, 12, 23, 13.
fn components(m: &Matrix3<f64>) -> [f64; 6] {
    [
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        m[(0, 1)],
        m[(1, 2)],
        m[(0, 2)],
    ]
}

fn layer_row(r: &PointResponse) -> Vec<f64> {
    std::iter::once(r.t)
        .chain(components(&r.s))
        .chain(components(&r.sigma))
        .collect()
}

fn laminate_row(r: &LaminateResponse) -> Vec<f64> {
    vec![r.t, r.n[(0, 0)], r.n[(1, 1)], r.n[(0, 1)], r.thickness]
}
