//! `thermostamp fit ...`: parameter identification from test curves (MODEL.md §5): `fit matrix`
//! here, `fit fabric-tension` in `fit_fabric_tension.rs`; `fit shear` will join them.

use crate::fit::card_section::{matrix_section, replace_matrix_section};
use crate::fit::matrix::{fit_matrix, uniaxial_stress, BulkRule, Eta1, TemperatureFit};
use crate::fit::tension_data::{read_manifest, TensionCurve};
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::material::{MaterialCard, TemperatureTable};
use anyhow::Context;
use clap::Subcommand;
use std::path::{Path, PathBuf};

#[derive(Subcommand, Debug)]
pub enum FitCommand {
    /// C10(T), eta1(T) (and D1) of the matrix law from neat-resin uniaxial tension curves.
    Matrix(MatrixArgs),
    /// Yarn tension coefficients A_k of [fabric] from strip tension tests along warp / weft.
    FabricTension(super::fit_fabric_tension::FabricTensionArgs),
}

#[derive(clap::Args, Debug)]
#[command(
    after_help = "Manifest (TOML, paths relative to it), one [[curve]] per CSV file:\n  \
    [[curve]]\n  \
    file = \"pps-280C-1.csv\"\n  \
    temperature = 280.0       # °C\n  \
    strain_rate = 1.0         # 1/s, or crosshead_speed (mm/s) and gauge_length (mm)\n\
    CSV columns: strain or stretch, and stress (true, MPa) or nominal_stress (MPa).\n\
    D1: --bulk-modulus K gives D1 = 2/K; --poisson nu gives K = 2G(1+nu)/(3(1-2nu)) with\n\
    G = 2 C10(T); with neither, D1 is kept from --card."
)]
pub struct MatrixArgs {
    /// TOML manifest listing the curves with their temperature and strain rate.
    #[arg(long)]
    manifest: PathBuf,
    /// Material card whose [matrix] section is replaced (the rest is kept as it is); without
    /// it the output holds the [matrix] section only.
    #[arg(long)]
    card: Option<PathBuf>,
    /// Where to write the card (may be the same file as --card).
    #[arg(long)]
    output: PathBuf,
    /// Bulk modulus K of the resin (MPa): D1 = 2/K at every temperature.
    #[arg(long, conflicts_with = "poisson")]
    bulk_modulus: Option<f64>,
    /// Poisson ratio of the resin: D1 from K = 2 G (1 + nu) / (3 (1 - 2 nu)), G = 2 C10(T).
    #[arg(long, allow_negative_numbers = true)]
    poisson: Option<f64>,
    /// PNG comparing the data with the fitted model.
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(command: &FitCommand) -> anyhow::Result<()> {
    match command {
        FitCommand::Matrix(args) => run_matrix(args),
        FitCommand::FabricTension(args) => super::fit_fabric_tension::run(args),
    }
}

fn run_matrix(args: &MatrixArgs) -> anyhow::Result<()> {
    let card = args.card.as_ref().map(|path| read_card(path)).transpose()?;
    let matrix = card.as_ref().and_then(|(_, c)| c.matrix.clone());
    let bulk = bulk_rule(args, matrix.as_deref().map(|m| m.d1_table()))?;
    let curves = read_manifest(&args.manifest)?;
    let fits = fit_matrix(&curves, &bulk, matrix.as_deref().map(|m| m.eta1_table()))?;

    let section = matrix_section(&fits, &provenance(args, &curves, &bulk));
    let text = match &card {
        Some((text, _)) => replace_matrix_section(text, &section),
        None => section,
    };
    let origin = args.output.display().to_string();
    if card.is_some() {
        // The card must still load; anything else is a bug here, caught before writing.
        MaterialCard::from_toml(&text, &origin)?;
    }
    std::fs::write(&args.output, &text).with_context(|| format!("cannot write {origin}"))?;
    print_table(&fits);
    if let Some(png) = &args.plot {
        write_png(png, &comparison_plot(&curves, &fits), 900, 600)?;
    }
    Ok(())
}

fn read_card(path: &Path) -> anyhow::Result<(String, MaterialCard)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the material card", path.display()))?;
    let card = MaterialCard::from_toml(&text, &path.display().to_string())?;
    Ok((text, card))
}

fn bulk_rule(args: &MatrixArgs, card_d1: Option<&TemperatureTable>) -> anyhow::Result<BulkRule> {
    let rule = match (args.bulk_modulus, args.poisson, card_d1) {
        (Some(k), _, _) => BulkRule::BulkModulus(k),
        (None, Some(nu), _) => BulkRule::Poisson(nu),
        (None, None, Some(table)) => BulkRule::Table(table.clone()),
        (None, None, None) => anyhow::bail!(
            "D1 needs --bulk-modulus K or --poisson nu (or a --card whose [matrix] d1 is kept)"
        ),
    };
    rule.validate().map_err(anyhow::Error::msg)?;
    Ok(rule)
}

/// Comment lines of the written section: what it was fitted from and how.
fn provenance(args: &MatrixArgs, curves: &[TensionCurve], bulk: &BulkRule) -> Vec<String> {
    let d1 = match bulk {
        BulkRule::BulkModulus(k) => format!("D1 = 2/K with K = {k} MPa"),
        BulkRule::Poisson(nu) => {
            format!("D1 = 2/K with K = 2G(1+nu)/(3(1-2nu)), G = 2 C10(T), nu = {nu}")
        }
        BulkRule::Table(_) => "D1 interpolated in the input card's table".into(),
    };
    vec![
        format!(
            "Fitted by `thermostamp fit matrix` (MODEL.md §5) to {} curves of {}.",
            curves.len(),
            args.manifest.display()
        ),
        format!("{d1}."),
    ]
}

fn print_table(fits: &[TemperatureFit]) {
    println!(
        "{:>8}  {:>6}  {:>6}  {:>22}  {:>24}  {:>10}  {:>12}",
        "T (°C)", "curves", "points", "C10 (MPa)", "eta1 (MPa·s)", "D1 (1/MPa)", "RMS res (MPa)"
    );
    for f in fits {
        let eta1 = match f.eta1 {
            Eta1::Fitted {
                value,
                standard_error,
            } => format!("{value:.4e} ± {standard_error:.2e}"),
            Eta1::FromCard { value } => format!("{value:.4e} (card)"),
        };
        println!(
            "{:>8}  {:>6}  {:>6}  {:>22}  {:>24}  {:>10.4e}  {:>12.3e}",
            f.temperature,
            f.curves.len(),
            f.points,
            format!("{:.4e} ± {:.2e}", f.c10, f.c10_standard_error),
            eta1,
            f.d1,
            f.rms_residual
        );
    }
}

/// Data as dots and the fitted model as lines, one colour per curve.
fn comparison_plot(curves: &[TensionCurve], fits: &[TemperatureFit]) -> LinePlot {
    let mut series = Vec::new();
    let mut colour = 0;
    for fit in fits {
        for &i in &fit.curves {
            let curve = &curves[i];
            let data = curve
                .stretch
                .iter()
                .copied()
                .zip(curve.stress.iter().copied());
            series.push(Series::new("", data.collect(), LineStyle::Markers).with_colour(colour));
            let (first, last) = (curve.stretch[0], curve.stretch[curve.stretch.len() - 1]);
            let model = (0..=100)
                .map(|k| {
                    let l = first + (last - first) * f64::from(k) / 100.0;
                    let sigma = uniaxial_stress(fit.c10, fit.eta1.value(), l, curve.strain_rate);
                    (l, sigma)
                })
                .collect();
            let label = format!("{} °C, {} /s", fit.temperature, curve.strain_rate);
            series.push(Series::new(label, model, LineStyle::Solid).with_colour(colour));
            colour += 1;
        }
    }
    LinePlot {
        title: "fit matrix: data (dots), model of MODEL.md §5 (lines)".into(),
        x_label: "stretch".into(),
        y_label: "true stress (MPa)".into(),
        series,
    }
}
