//! `thermostamp fit fabric-tension`: the yarn tension coefficients `A_k` of a card's `[fabric]`
//! from strip tension tests along warp and weft (docs/model.md §3, §5).

use crate::experiment::virtual_test::cli_names;
use crate::fit::commands::{fit_fabric_tension_card, CurveSource, DirectionFit};
use crate::fit::least_squares::MAX_POWER;
use crate::io::plot::write_png;
use crate::limits::{ranges_help, LENGTH};
use anyhow::Context;
use std::path::PathBuf;

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

pub fn run(args: &FabricTensionArgs) -> anyhow::Result<()> {
    let warp = args.warp.clone().map(CurveSource::File);
    let weft = args.weft.clone().map(CurveSource::File);
    let origin = args.output.display().to_string();
    let fitted = fit_fabric_tension_card(
        &args.card,
        (warp.as_ref(), weft.as_ref()),
        (args.terms, args.width),
        &origin,
        cli_names,
        &mut |line| eprintln!("{line}"),
    )?;
    std::fs::write(&args.output, &fitted.card).with_context(|| format!("cannot write {origin}"))?;
    print_table(&fitted.fits);
    if let Some(png) = &args.plot {
        write_png(png, &fitted.plot(), 900, 600)?;
    }
    Ok(())
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
