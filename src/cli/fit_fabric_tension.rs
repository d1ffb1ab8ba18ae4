//! `thermostamp fit fabric-tension`: the yarn tension coefficients `A_k` of a card's `[fabric]`
//! from strip tension tests along warp and weft (docs/model.md §3, §5).

use super::fit::{check_determined, fitted_card_loads, Coefficients};
use crate::fit::card_key::{replace_key, toml_array, FIT_MARKER};
use crate::fit::fabric_tension::{
    check_terms, fit_yarn_tension, strip_force_per_width, TensionFit,
};
use crate::fit::least_squares::MAX_POWER;
use crate::fit::strip_data::{read_strip_curve, StripCurve};
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::limits::{ranges_help, LENGTH};
use crate::material::MaterialCard;
use anyhow::Context;
use std::path::{Path, PathBuf};

#[derive(clap::Args, Debug)]
#[command(
    group = clap::ArgGroup::new("direction").required(true).multiple(true).args(["warp", "weft"]),
    after_help = format!(
        "CSV columns: strain (engineering) or stretch, and force_per_width (N/mm) or\n\
        force (N, divided by --width). Model (docs/model.md §5): force per width\n  \
        N(lambda) = t_B sum_{{k=2..n}} A_k (lambda - 1)^(k-1),\n\
        t_B the card's fabric_thickness; points with lambda <= 1 are not fitted.\n\n{}\n  \
        --terms: 1 to {MAX_POWER}",
        ranges_help(&[("--width", LENGTH)])
    )
)]
pub struct FabricTensionArgs {
    /// Strip test pulled along the warp (CSV); at least one of --warp, --weft is required, and
    /// a direction not given keeps its coefficients from the card (the default).
    #[arg(long)]
    warp: Option<PathBuf>,
    /// Strip test pulled along the weft (CSV); at least one of --warp, --weft is required, and
    /// a direction not given keeps its coefficients from the card (the default).
    #[arg(long)]
    weft: Option<PathBuf>,
    /// Material card whose [fabric] warp_tension / weft_tension are replaced (the rest is kept
    /// as it is); its fabric_thickness is t_B.
    #[arg(long)]
    card: PathBuf,
    /// Where to write the card (may be the same file as --card).
    #[arg(long)]
    output: PathBuf,
    /// Number of coefficients A_2.. to fit; default: as many as the card has.
    #[arg(long)]
    terms: Option<usize>,
    /// Specimen width (mm), for CSV files with a force column (N); no default: needed for such
    /// files only.
    #[arg(long, allow_negative_numbers = true)]
    width: Option<f64>,
    /// PNG comparing the data with the fitted model (default: no plot).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// One direction: its card key, curve and fit.
struct DirectionFit {
    key: &'static str,
    curve: StripCurve,
    fit: TensionFit,
}

pub fn run(args: &FabricTensionArgs) -> anyhow::Result<()> {
    if let Some(terms) = args.terms {
        check_terms(terms).map_err(|why| anyhow::anyhow!("--terms {terms}: {why}"))?;
    }
    if let Some(width) = args.width {
        LENGTH.check("--width", width).map_err(anyhow::Error::msg)?;
    }
    let text = std::fs::read_to_string(&args.card)
        .with_context(|| format!("{}: cannot read the material card", args.card.display()))?;
    let card = MaterialCard::from_toml(&text, &args.card.display().to_string())?;
    let thickness = fabric_thickness(&card)?;
    let mut fits = Vec::new();
    for (key, path, law) in [
        ("warp_tension", &args.warp, &card.fabric.warp),
        ("weft_tension", &args.weft, &card.fabric.weft),
    ] {
        let Some(path) = path else { continue };
        let curve = read_strip_curve(path, args.width)?;
        let terms = args.terms.unwrap_or(law.coefficients().len());
        let fit = fit_yarn_tension(&curve, thickness, terms)?;
        let names: Vec<String> = (0..terms).map(|i| format!("A{}", i + 2)).collect();
        let coefficients = Coefficients {
            names: &names,
            values: &fit.coefficients,
            errors: &fit.standard_errors,
            unit: "MPa",
        };
        let option = match args.terms {
            Some(n) => format!("--terms {n}"),
            None => format!("--terms, by default the card's {terms}"),
        };
        check_determined(&curve.origin, &option, &coefficients, &fit.determination)?;
        fits.push(DirectionFit { key, curve, fit });
    }

    let mut written = text.clone();
    for d in &fits {
        let comment = provenance(d, thickness);
        written = replace_key(
            &written,
            "fabric",
            d.key,
            &toml_array(&d.fit.coefficients),
            &comment,
        )
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.card.display()))?;
    }
    let origin = args.output.display().to_string();
    let data: Vec<String> = fits.iter().map(|d| d.curve.origin.clone()).collect();
    fitted_card_loads(&written, &args.output, &data.join(" and "))?;
    std::fs::write(&args.output, &written).with_context(|| format!("cannot write {origin}"))?;
    print_table(&fits);
    if let Some(png) = &args.plot {
        write_png(png, &comparison_plot(&fits, thickness), 900, 600)?;
    }
    Ok(())
}

/// `t_B`: the thickness of the card's fabric layer (mm).
fn fabric_thickness(card: &MaterialCard) -> anyhow::Result<f64> {
    card.laminate
        .layers()
        .iter()
        .find(|l| l.law.name() == "fabric")
        .map(|l| l.thickness)
        .context("the card's laminate has no fabric layer")
}

/// Comment line above the written key; it starts with [`FIT_MARKER`] so that a re-fit
/// replaces it.
fn provenance(d: &DirectionFit, thickness: f64) -> Vec<String> {
    vec![format!(
        "{FIT_MARKER} fabric-tension` (docs/model.md §5, t_B = {thickness} mm) to {} points of {}: \
         standard errors [{}] MPa, RMS residual {:.3e} N/mm.",
        d.fit.points,
        Path::new(&d.curve.origin).display(),
        d.fit
            .standard_errors
            .iter()
            .map(|s| format!("{s:.2e}"))
            .collect::<Vec<_>>()
            .join(", "),
        d.fit.rms_residual
    )]
}

fn print_table(fits: &[DirectionFit]) {
    println!(
        "{:>9}  {:>6}  {:>4}  {:>24}  {:>14}",
        "direction", "points", "k", "A_k (MPa)", "RMS res (N/mm)"
    );
    for d in fits {
        let direction = d.key.trim_end_matches("_tension");
        for (i, (a, se)) in d
            .fit
            .coefficients
            .iter()
            .zip(&d.fit.standard_errors)
            .enumerate()
        {
            let (name, points, rms) = if i == 0 {
                (
                    direction.to_string(),
                    d.fit.points.to_string(),
                    format!("{:.3e}", d.fit.rms_residual),
                )
            } else {
                Default::default()
            };
            println!(
                "{name:>9}  {points:>6}  {:>4}  {:>24}  {rms:>14}",
                i + 2,
                format!("{a:.4e} ± {se:.2e}")
            );
        }
    }
}

/// Data as dots and the fitted model as a line, one colour per direction.
fn comparison_plot(fits: &[DirectionFit], thickness: f64) -> LinePlot {
    let mut series = Vec::new();
    for (colour, d) in fits.iter().enumerate() {
        let data = d
            .curve
            .stretch
            .iter()
            .zip(&d.curve.force_per_width)
            .map(|(l, n)| (100.0 * (l - 1.0), *n));
        series.push(Series::new("", data.collect(), LineStyle::Markers).with_colour(colour));
        let last = d.curve.stretch[d.curve.stretch.len() - 1];
        let model = (0..=100)
            .map(|k| {
                let l = 1.0 + (last - 1.0) * f64::from(k) / 100.0;
                let n = strip_force_per_width(thickness, &d.fit.coefficients, l);
                (100.0 * (l - 1.0), n)
            })
            .collect();
        let label = d.key.trim_end_matches("_tension").to_string();
        series.push(Series::new(label, model, LineStyle::Solid).with_colour(colour));
    }
    LinePlot {
        title: "fit fabric-tension: data (dots), model of docs/model.md §5 (lines)".into(),
        x_label: "strain (%)".into(),
        y_label: "force per width (N/mm)".into(),
        series,
    }
}
