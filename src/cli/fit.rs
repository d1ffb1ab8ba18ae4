//! `thermostamp fit ...`: parameter identification from test curves (docs/model.md §5):
//! `fit matrix` and `fit shear` here, `fit fabric-tension` in `fit_fabric_tension.rs`.

use crate::experiment::virtual_test::cli_names;
use crate::fit::commands::{
    fit_matrix_card, fit_shear_card, CurveSource, MatrixCurves, MatrixShare, ShearCardFit,
    ShearOptions,
};
use crate::fit::least_squares::MAX_POWER;
use crate::fit::matrix::{Eta1, TemperatureFit};
use crate::fit::shear::ShearFit;
use crate::fit::shear_fe::{refine_shear_fe, FeRun, RefineSettings, ShearFeFit, Stop};
use crate::io::plot::write_png;
use crate::limits::{
    ranges_help, BULK_MODULUS, FRICTION_ONSET, LENGTH, SHEAR_ANGLE, SPEED, TEMPERATURE,
};
use crate::material::fabric::ShearTerm;
use crate::material::fabric_shear::DEFAULT_FRICTION_ONSET_DEG;
use anyhow::Context;
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Subcommand, Debug)]
pub enum FitCommand {
    /// C10(T), eta1(T) (and D1) of the matrix law from neat-resin uniaxial tension curves.
    Matrix(MatrixArgs),
    /// Yarn tension coefficients A_k of [fabric] from strip tension tests along warp / weft.
    FabricTension(super::fit_fabric_tension::FabricTensionArgs),
    /// Shear law of [fabric] (polynomial c_k, friction-like, locking terms) from a bias-extension
    /// or picture-frame curve.
    Shear(ShearArgs),
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShearTestKind {
    BiasExtension,
    PictureFrame,
}

#[derive(clap::Args, Debug)]
#[command(after_help = format!(
    "{}\n\n{}\n  --terms: powers 1 to {MAX_POWER}",
    "CSV columns: displacement_mm (crosshead, mm, increasing) and force_N (N, >= 0), or\n\
    displacement and force as `thermostamp test bias-extension` and `picture-frame` write\n\
    them; other columns are ignored.\n\
    Bias extension (default): --width W --length H (free length, H/W >= 2); the normalised\n\
    shear force of Cao et al. 2008 is solved recursively from small angles (docs/model.md §5).\n\
    Picture frame: --frame-side L (pin to pin) [--fabric-side, default L].\n\
    Model: F_sh(gamma) = 2 t_B sin(gamma) W_s'(sin^2 gamma), W_s(I10) a sum of the --terms:\n\
    k = c_k I10^k; friction = k_0 (sqrt(I10 + eps^2) - eps), eps = sin(--friction-onset), a\n\
    nearly constant shear force t_B k_0 from the first degrees; locking = (k_l/3)\n\
    <I10 - sin^2(--locking-angle)>^3 (docs/model.md §3). A fit whose force falls as the shear\n\
    grows within the fitted range, or with a negative friction or locking coefficient, is\n\
    refused; so is one with a coefficient the data do not determine (its standard error\n\
    larger than it, moving the fit by more than 5 %).\n\
    A card with matrix layers (a prepreg) needs --temperature and --speed of the test: the\n\
    layers' force, driven through the test's pin-jointed kinematics, is subtracted first.\n\
    --refine-fe (bias extension): starting from that fit, runs the FE bias-extension test\n\
    with the card (W/6 crossed cells) in a Gauss-Newton loop on the measured force curve;\n\
    each iteration is one FE run (seconds to minutes).",
    ranges_help(&[
        ("--width, --length, --frame-side, --fabric-side, --fe-element-size", LENGTH),
        ("--temperature", TEMPERATURE),
        ("--speed", SPEED),
        ("--max-shear, --locking-angle", SHEAR_ANGLE),
        ("--friction-onset", FRICTION_ONSET),
    ])
))]
pub struct ShearArgs {
    /// Force–displacement curve (CSV).
    #[arg(long)]
    data: PathBuf,
    /// The test the curve comes from.
    #[arg(long, value_enum, default_value = "bias-extension")]
    test: ShearTestKind,
    /// Bias extension: specimen width W (mm); no default, required for a bias extension.
    #[arg(long, allow_negative_numbers = true)]
    width: Option<f64>,
    /// Bias extension: free length H between the clamps (mm); no default, required for a bias
    /// extension.
    #[arg(long, allow_negative_numbers = true)]
    length: Option<f64>,
    /// Picture frame: frame side, pin to pin (mm); no default, required for a picture frame.
    #[arg(long, allow_negative_numbers = true)]
    frame_side: Option<f64>,
    /// Picture frame: side of the sheared fabric square (mm); default the frame side.
    #[arg(long, allow_negative_numbers = true)]
    fabric_side: Option<f64>,
    /// Material card whose [fabric] shear is replaced (everything else is kept as it is).
    #[arg(long)]
    card: PathBuf,
    /// Where to write the card (may be the same file as --card).
    #[arg(long)]
    output: PathBuf,
    /// Temperature of the test (°C); no default: needed when the card has matrix layers.
    #[arg(long, allow_negative_numbers = true)]
    temperature: Option<f64>,
    /// Crosshead speed of the test (mm/s); no default: needed when the card has matrix layers.
    #[arg(long, allow_negative_numbers = true)]
    speed: Option<f64>,
    /// Terms of W_s to fit, comma-separated: `friction`, `locking` and powers `k` of c_k I10^k
    /// (e.g. `friction,1,2,3`); a single number m alone means c_1..c_m.
    #[arg(long, default_value = "3")]
    terms: String,
    /// Onset of the friction-like term (degrees): eps = sin(onset); its force is 71 % of its
    /// plateau there.
    #[arg(long, allow_negative_numbers = true, default_value_t = DEFAULT_FRICTION_ONSET_DEG)]
    friction_onset: f64,
    /// Locking angle of the locking term (degrees); no default, needed with `locking` in
    /// --terms.
    #[arg(long, allow_negative_numbers = true)]
    locking_angle: Option<f64>,
    /// Largest shear angle fitted (degrees).
    #[arg(long, allow_negative_numbers = true, default_value_t = 50.0)]
    max_shear: f64,
    /// PNG of the normalised shear force vs shear angle: data (dots) and model (line); with
    /// --refine-fe, of the crosshead force: data (dots) and the final FE run (line). Default:
    /// no plot.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Refine the coefficients by running the FE bias-extension test inside the fit loop, on
    /// the measured force curve (bias extension only; default: off, the analytic fit).
    #[arg(long)]
    refine_fe: bool,
    /// --refine-fe: cell size of the FE specimen (mm); default W/6.
    #[arg(long, allow_negative_numbers = true, requires = "refine_fe")]
    fe_element_size: Option<f64>,
    /// --refine-fe: Gauss-Newton iterations at most (one FE run each, more when a step is
    /// halved).
    #[arg(long, default_value_t = 6, requires = "refine_fe")]
    fe_iterations: usize,
}

#[derive(clap::Args, Debug)]
#[command(after_help = format!(
    "{}\n\n{}",
    "Manifest (TOML, paths relative to it), one [[curve]] per CSV file:\n  \
    [[curve]]\n  \
    file = \"pps-280C-1.csv\"\n  \
    temperature = 280.0       # °C\n  \
    strain_rate = 1.0         # 1/s, or crosshead_speed (mm/s) and gauge_length (mm)\n\
    CSV columns: strain or stretch, and stress (true, MPa) or nominal_stress (MPa).\n\
    D1: --bulk-modulus K gives D1 = 2/K; --poisson nu gives K = 2G(1+nu)/(3(1-2nu)) with\n\
    G = 2 C10(T); with neither, D1 is kept from --card.",
    ranges_help(&[("--bulk-modulus", BULK_MODULUS)])
))]
pub struct MatrixArgs {
    /// TOML manifest listing the curves with their temperature and strain rate.
    #[arg(long)]
    manifest: PathBuf,
    /// Material card whose [matrix] section is replaced (the rest is kept as it is); without
    /// it (the default) the output holds the [matrix] section only.
    #[arg(long)]
    card: Option<PathBuf>,
    /// Where to write the card (may be the same file as --card).
    #[arg(long)]
    output: PathBuf,
    /// Bulk modulus K of the resin (MPa): D1 = 2/K at every temperature. Default, with neither
    /// this nor --poisson: D1 kept from --card.
    #[arg(long, allow_negative_numbers = true, conflicts_with = "poisson")]
    bulk_modulus: Option<f64>,
    /// Poisson ratio of the resin: D1 from K = 2 G (1 + nu) / (3 (1 - 2 nu)), G = 2 C10(T).
    /// Default, with neither this nor --bulk-modulus: D1 kept from --card.
    #[arg(long, allow_negative_numbers = true)]
    poisson: Option<f64>,
    /// PNG comparing the data with the fitted model (default: no plot).
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(command: &FitCommand) -> anyhow::Result<()> {
    match command {
        FitCommand::Matrix(args) => run_matrix(args),
        FitCommand::FabricTension(args) => super::fit_fabric_tension::run(args),
        FitCommand::Shear(args) => run_shear(args),
    }
}

impl ShearArgs {
    /// The options as the library takes them.
    fn options(&self) -> ShearOptions {
        ShearOptions {
            bias_extension: self.test == ShearTestKind::BiasExtension,
            width: self.width,
            length: self.length,
            frame_side: self.frame_side,
            fabric_side: self.fabric_side,
            temperature: self.temperature,
            speed: self.speed,
            terms: self.terms.clone(),
            friction_onset: self.friction_onset,
            locking_angle: self.locking_angle,
            max_shear: self.max_shear,
            refine_fe: self.refine_fe,
            fe_element_size: self.fe_element_size,
        }
    }
}

fn run_shear(args: &ShearArgs) -> anyhow::Result<()> {
    let data = CurveSource::File(args.data.clone());
    let fitted = fit_shear_card(&args.card, &data, &args.options(), cli_names, &mut |line| {
        eprintln!("{line}")
    })?;
    let fit = &fitted.fit;
    // the analytic fit before the FE loop starts (it takes minutes); without one, the card
    // is written first, so that a reader closing the output early does not lose it
    let refined = if args.refine_fe {
        print_shear_table(fit, fitted.matrix.as_ref());
        Some(refine(args, &fitted)?)
    } else {
        None
    };
    let (law, provenance) = match &refined {
        Some(r) => (r.law(), refined_provenance(args, r)),
        None => (fit.law(), Vec::new()),
    };
    let origin = args.output.display().to_string();
    let written = fitted.card_with(&law, provenance, &origin)?;
    std::fs::write(&args.output, &written).with_context(|| format!("cannot write {origin}"))?;
    if !args.refine_fe {
        print_shear_table(fit, fitted.matrix.as_ref());
    }
    if let Some(png) = &args.plot {
        write_png(png, &fitted.plot(refined.as_ref())?, 900, 600)?;
    }
    Ok(())
}

/// `--refine-fe`: the FE bias-extension test in the loop, from the analytic fit, on the
/// measured (not matrix-subtracted: the FE has the matrix layers) curve.
fn refine(args: &ShearArgs, fitted: &ShearCardFit) -> anyhow::Result<ShearFeFit> {
    let fit = &fitted.fit;
    let (Some(width), Some(length)) = (args.width, args.length) else {
        anyhow::bail!("--refine-fe needs the bias-extension specimen's --width and --length");
    };
    let mut settings = RefineSettings::new(width, length, args.max_shear.to_radians());
    if let Some(size) = args.fe_element_size {
        settings.fe.element_size = size;
    }
    settings.max_iterations = args.fe_iterations;
    settings.fe.test_speed = args.speed;
    if let Some(t) = args.temperature {
        settings.fe.temperature = t;
    }
    println!(
        "refining by the FE bias-extension test ({:.1} mm crossed cells, {} iterations at most):",
        settings.fe.element_size, settings.max_iterations
    );
    println!(
        "{:>4}  {:>6}  {:>8}  {:>34}  {:>10}  {:>8}  {:>9}  {:>6}  {:>7}",
        "it",
        "step",
        "",
        names_of(&fit.terms),
        "RMS (N)",
        "% range",
        "per point",
        "KE/IE",
        "wall"
    );
    let mut report = |r: &FeRun| {
        let c: Vec<String> = r.coefficients.iter().map(|c| format!("{c:.4e}")).collect();
        println!(
            "{:>4}  {:>6.3}  {:>8}  {:>34}  {:>10.4}  {:>8.2}  {:>8.1}%  {:>6.3}  {:>6.1}s",
            r.iteration,
            r.step_fraction,
            if r.accepted { "accepted" } else { "rejected" },
            c.join(", "),
            r.rms_force,
            100.0 * r.rms_of_range,
            100.0 * r.per_point_rms,
            r.kinetic_ratio,
            r.wall_seconds
        );
    };
    let refined = refine_shear_fe(
        &fitted.measured,
        &fitted.card,
        &fit.law(),
        &settings,
        &mut report,
    )?;
    if refined.stop == Stop::NoDescent {
        eprintln!(
            "warning: no step along the analytic model's direction lowered the FE misfit; the \
             best coefficients found are kept"
        );
    }
    print_coefficients(
        "refined c_k (MPa)",
        &refined.terms,
        &refined.coefficients,
        &refined.standard_errors,
    );
    Ok(refined)
}

/// Comment lines about the FE refinement, after the analytic fit's.
fn refined_provenance(args: &ShearArgs, refined: &ShearFeFit) -> Vec<String> {
    let errors: Vec<String> = refined
        .standard_errors
        .iter()
        .map(|e| format!("{e:.2e}"))
        .collect();
    let misfit = refined.best().map_or(String::new(), |b| {
        format!(
            ": FE misfit RMS {:.3e} N ({:.2} % of the force range, {:.1} % per point)",
            b.rms_force,
            100.0 * b.rms_of_range,
            100.0 * b.per_point_rms
        )
    });
    vec![format!(
        "Then refined by the FE bias-extension test in the loop (--refine-fe{}, {} FE runs){misfit}; \
         standard errors [{}] MPa.",
        args.fe_element_size
            .map_or(String::new(), |h| format!(" --fe-element-size {h}")),
        refined.runs.len(),
        errors.join(", ")
    )]
}

/// The names of the terms' coefficients, for a table header (MPa).
fn names_of(terms: &[ShearTerm]) -> String {
    let names: Vec<String> = terms.iter().map(ShearTerm::name).collect();
    format!("{} (MPa)", names.join(", "))
}

/// The shear coefficients with their standard errors, one row each (the term's name first)
/// under `header`.
fn print_coefficients(
    header: &str,
    terms: &[ShearTerm],
    coefficients: &[f64],
    standard_errors: &[f64],
) {
    println!("{:>8}  {:>24}", "term", header);
    for ((term, c), e) in terms.iter().zip(coefficients).zip(standard_errors) {
        println!("{:>8}  {:>24}", term.name(), format!("{c:.4e} ± {e:.2e}"));
    }
}

/// The fit's coefficients, its misfit (RMS over the mean and over the range of the data's
/// `F_sh`), and each point's residual.
fn print_shear_table(fit: &ShearFit, matrix: Option<&MatrixShare>) {
    print_coefficients(
        "c_k (MPa)",
        &fit.terms,
        &fit.result.parameters,
        &fit.result.standard_errors,
    );
    println!(
        "points: {}; RMS residual of the {}: {:.3e} ({:.3} relative; {:.2} % of the mean, \
         {:.2} % of the range)",
        fit.points.len(),
        fit.quantity,
        fit.rms,
        fit.result.rms_residual,
        100.0 * fit.rms_of_mean,
        100.0 * fit.rms_of_range
    );
    println!(
        "{:>6}  {:>9}  {:>12}  {:>12}  {:>9}   ({})",
        "line", "shear (°)", "data", "model", "residual", fit.quantity
    );
    for p in &fit.fitted {
        let relative = if p.data != 0.0 {
            format!("{:+.1} %", 100.0 * (p.model - p.data) / p.data)
        } else {
            "-".into()
        };
        println!(
            "{:>6}  {:>9.2}  {:>12.4e}  {:>12.4e}  {:>9}",
            p.line,
            p.gamma.to_degrees(),
            p.data,
            p.model,
            relative
        );
    }
    if let (Some(m), Some(last)) = (matrix, fit.points.last()) {
        let i = m.fabric.lines.iter().position(|&l| l == last.line);
        if let Some(i) = i {
            let total = m.fabric.force[i] + m.force[i];
            println!(
                "matrix layers at {} °C, {} mm/s: {:.3} N of the {:.3} N measured at the last \
                 fitted point (line {}), subtracted",
                m.conditions.temperature, m.conditions.speed, m.force[i], total, last.line
            );
        }
    }
}

fn run_matrix(args: &MatrixArgs) -> anyhow::Result<()> {
    let origin = args.output.display().to_string();
    let fitted = fit_matrix_card(
        args.card.as_deref(),
        &MatrixCurves::Manifest(args.manifest.clone()),
        (args.bulk_modulus, args.poisson),
        &origin,
        cli_names,
    )?;
    std::fs::write(&args.output, &fitted.card).with_context(|| format!("cannot write {origin}"))?;
    print_table(&fitted.fits);
    if let Some(png) = &args.plot {
        write_png(png, &fitted.plot(), 900, 600)?;
    }
    Ok(())
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
