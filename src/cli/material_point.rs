//! `thermostamp material-point`: the single-element test of the material models.

use crate::experiment::material_point::{material_point, PointLayer};
use crate::io::{read_csv_table, write_csv};
use crate::material::MaterialCard;
use anyhow::Context;
use clap::ValueEnum;
use std::io::Write;
use std::path::PathBuf;

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

impl From<LayerChoice> for PointLayer {
    fn from(choice: LayerChoice) -> Self {
        match choice {
            LayerChoice::Matrix => Self::Matrix,
            LayerChoice::Fabric => Self::Fabric,
            LayerChoice::Laminate => Self::Laminate,
        }
    }
}

pub fn run(args: &Args) -> anyhow::Result<()> {
    crate::limits::ANGLE
        .check("--angle", args.angle)
        .map_err(anyhow::Error::msg)?;
    let card = MaterialCard::load(&args.card)?;
    let layer = PointLayer::from(args.layer);
    let history = read_csv_table(&args.history, layer.history_columns())?;
    let table = material_point(
        &card,
        &args.card.display().to_string(),
        layer,
        args.angle,
        &history,
    )?;
    write_output(args.output.as_ref(), table.header, &table.rows)
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
