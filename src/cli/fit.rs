//! `thermostamp fit ...`: parameter identification from test curves (docs/model.md §5):
//! `fit matrix` and `fit shear` here, `fit fabric-tension` in `fit_fabric_tension.rs`.

use crate::fit::card_key::{remove_key, replace_key, toml_array, toml_float, FIT_MARKER};
use crate::fit::card_section::{matrix_section, replace_matrix_section};
use crate::fit::least_squares::{Determination, MAX_POWER};
use crate::fit::matrix::{fit_matrix, uniaxial_stress, BulkRule, Eta1, TemperatureFit};
use crate::fit::shear::{
    fit_shear, read_force_curve, shear_points, ForceCurve, ShearFit, ShearPoint, ShearTest,
};
use crate::fit::shear_fe::{refine_shear_fe, FeRun, RefineSettings, ShearFeFit, Stop};
use crate::fit::shear_matrix::{matrix_layers, subtract_matrix, TestConditions};
use crate::fit::tension_data::{read_manifest, TensionCurve};
use crate::io::plot::{write_png, LinePlot, LineStyle, Series};
use crate::limits::{
    check_given, ranges_help, shown, BULK_MODULUS, FRICTION_ONSET, LENGTH, SHEAR_ANGLE, SPEED,
    TEMPERATURE,
};
use crate::material::fabric::{ShearInteraction, ShearTerm};
use crate::material::fabric_shear::DEFAULT_FRICTION_ONSET_DEG;
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

fn run_shear(args: &ShearArgs) -> anyhow::Result<()> {
    check_shear_numbers(args)?;
    let terms = shear_terms(args)?;
    let test = shear_test(args)?;
    if args.refine_fe && args.test == ShearTestKind::PictureFrame {
        anyhow::bail!(
            "--refine-fe runs the FE bias-extension test: it needs a bias-extension curve; a \
             picture frame shears homogeneously, so its analytic fit is already what the FE gives"
        );
    }
    let (text, card) = read_card(&args.card)?;
    let thickness = fabric_thickness(&card, &args.card)?;
    let measured = read_force_curve(&args.data)?;
    let matrix = matrix_share(args, &card, &measured, &test)?;
    let curve = matrix.as_ref().map_or(&measured, |m| &m.fabric);
    let fit = fit_shear(curve, &test, thickness, &terms, args.max_shear.to_radians())?;
    let names: Vec<String> = terms.iter().map(ShearTerm::name).collect();
    let coefficients = Coefficients {
        names: &names,
        values: &fit.result.parameters,
        errors: &fit.result.standard_errors,
        unit: "MPa",
    };
    check_determined(
        &args.data.display().to_string(),
        &format!("--terms {}", args.terms),
        &coefficients,
        &fit.result.determination(),
    )?;
    // the analytic fit before the FE loop starts (it takes minutes); without one, the card
    // is written first, so that a reader closing the output early does not lose it
    let refined = if args.refine_fe {
        print_shear_table(&fit, matrix.as_ref());
        Some(refine(args, &card, &measured, &fit)?)
    } else {
        None
    };
    let (law, mut provenance) = match &refined {
        Some(r) => (r.law(), refined_provenance(args, r)),
        None => (fit.law(), Vec::new()),
    };
    provenance.splice(0..0, shear_provenance(args, &fit, matrix.as_ref()));
    let origin = args.output.display().to_string();
    let written = write_shear_law(&text, &law, &provenance)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.card.display()))?;
    fitted_card_loads(&written, &args.output, &args.data.display().to_string())?;
    std::fs::write(&args.output, &written).with_context(|| format!("cannot write {origin}"))?;
    if !args.refine_fe {
        print_shear_table(&fit, matrix.as_ref());
    }
    if let Some(png) = &args.plot {
        let plot = match &refined {
            Some(r) => refined_plot(r),
            None => {
                let matrix_points = match &matrix {
                    Some(m) => matrix_points(&measured, m, &test, args.max_shear.to_radians())?,
                    None => Vec::new(),
                };
                shear_plot(&fit, &matrix_points, thickness, args.max_shear)
            }
        };
        write_png(png, &plot, 900, 600)?;
    }
    Ok(())
}

/// The numbers of `fit shear`'s options inside their ranges (`crate::limits`), before any
/// file is read.
fn check_shear_numbers(args: &ShearArgs) -> anyhow::Result<()> {
    check_given([
        ("--width", args.width, LENGTH),
        ("--length", args.length, LENGTH),
        ("--frame-side", args.frame_side, LENGTH),
        ("--fabric-side", args.fabric_side, LENGTH),
        ("--temperature", args.temperature, TEMPERATURE),
        ("--speed", args.speed, SPEED),
        ("--max-shear", Some(args.max_shear), SHEAR_ANGLE),
        ("--fe-element-size", args.fe_element_size, LENGTH),
    ])
    .map_err(anyhow::Error::msg)
}

/// The terms `--terms` names (module doc of `fit::shear`), with `--friction-onset` and
/// `--locking-angle`: each once, powers from 1 to [`MAX_POWER`] (checked before any term is
/// made: `--terms 4294967295` would be 4294967295 of them), `locking` only with its angle.
fn shear_terms(args: &ShearArgs) -> anyhow::Result<Vec<ShearTerm>> {
    let bad = |why: String| anyhow::anyhow!("--terms {}: {why}", args.terms);
    let beyond = |k: &str| {
        bad(format!(
            "power {k} is beyond {MAX_POWER}, the highest a fit determines (a higher power of \
             I10 is flat over all but the last points of a curve)"
        ))
    };
    // a power: digits only, however many (too many for any integer type is still a power)
    let power = |token: &str| match token.parse::<u32>() {
        Ok(k) if k <= MAX_POWER => Ok(Some(k)),
        _ if !token.is_empty() && token.bytes().all(|b| b.is_ascii_digit()) => Err(beyond(token)),
        _ => Ok(None),
    };
    let tokens: Vec<&str> = args.terms.split(',').map(str::trim).collect();
    if let [single] = tokens.as_slice() {
        match power(single)? {
            Some(0) => return Err(bad("at least one term is needed".into())),
            Some(m) => return Ok(crate::fit::shear::polynomial_terms(m)),
            None => {}
        }
    }
    let mut terms = Vec::new();
    for token in tokens {
        let term = match token {
            "friction" => {
                let onset = args.friction_onset;
                FRICTION_ONSET
                    .check("--friction-onset", onset)
                    .map_err(anyhow::Error::msg)?;
                ShearTerm::Friction {
                    onset: onset.to_radians(),
                }
            }
            "locking" => match args.locking_angle {
                Some(a) => {
                    SHEAR_ANGLE
                        .check("--locking-angle", a)
                        .map_err(anyhow::Error::msg)?;
                    ShearTerm::Locking {
                        angle: a.to_radians(),
                    }
                }
                None => anyhow::bail!(
                    "--terms {}: the locking term needs --locking-angle (degrees), where the \
                     yarns begin to jam",
                    args.terms
                ),
            },
            other => match power(other)? {
                Some(k) if k >= 1 => ShearTerm::Power(k),
                _ => {
                    return Err(bad(format!(
                        "'{other}' is not a term: friction, locking or a power 1, 2, ..."
                    )))
                }
            },
        };
        if terms.iter().any(|t: &ShearTerm| t.name() == term.name()) {
            return Err(bad(format!("'{token}' is named twice")));
        }
        terms.push(term);
    }
    Ok(terms)
}

/// A fit's coefficients as its table prints them: names, values, standard errors, unit.
pub(super) struct Coefficients<'a> {
    pub names: &'a [String],
    pub values: &'a [f64],
    pub errors: &'a [f64],
    pub unit: &'a str,
}

/// Refuses a fit with a coefficient that the data (`data`) do not determine
/// ([`Determination::undetermined`]), naming it and `option`, which chose the terms; notes
/// on standard error the terms the fit does not need.
pub(super) fn check_determined(
    data: &str,
    option: &str,
    c: &Coefficients,
    determination: &Determination,
) -> anyhow::Result<()> {
    let describe = |i: usize| {
        format!(
            "{} = {} ± {} {}",
            c.names[i],
            shown(c.values[i]),
            shown(c.errors[i]),
            c.unit
        )
    };
    if let Some(i) = determination.undetermined {
        anyhow::bail!(
            "{data}: the data do not determine {}: its standard error exceeds it and moves the \
             fit by more than 5 %; fit fewer or other terms ({option})",
            describe(i)
        );
    }
    for &i in &determination.not_needed {
        eprintln!(
            "note: {data}: {} is not determined by the data (its standard error exceeds it), \
             but moves the fit by less than 5 %: the fit does not need the term ({option})",
            describe(i)
        );
    }
    Ok(())
}

/// The card a fit is about to write must load. The rest of it loaded as the input card, so
/// when it does not the fitted coefficients are the cause: the message names the data they
/// were fitted to (`data`), and `output` is not written.
pub(super) fn fitted_card_loads(text: &str, output: &Path, data: &str) -> anyhow::Result<()> {
    match MaterialCard::from_toml(text, &output.display().to_string()) {
        Ok(_) => Ok(()),
        Err(e) => anyhow::bail!(
            "{data}: the coefficients fitted to it make a card that does not load, so {} is not \
             written: {}; fit fewer or other terms, or over another range",
            output.display(),
            e.message
        ),
    }
}

/// `card` with its `[fabric]` shear law set to `law`: `shear` (the polynomial, with
/// `provenance` above it), `shear_friction` and `shear_friction_onset`, `shear_locking` and
/// `shear_locking_angle`, each written when the law has the term and removed when not.
fn write_shear_law(
    card: &str,
    law: &ShearInteraction,
    provenance: &[String],
) -> Result<String, String> {
    let mut text = replace_key(
        card,
        "fabric",
        "shear",
        &toml_array(&law.coefficients()),
        provenance,
    )?;
    let mut set = |key: &str, value: Option<f64>| -> Result<(), String> {
        text = match value {
            Some(v) => replace_key(&text, "fabric", key, &toml_float(v), &[])?,
            None => remove_key(&text, "fabric", key)?,
        };
        Ok(())
    };
    let friction = law.friction();
    set("shear_friction", friction.map(|f| f.0))?;
    set("shear_friction_onset", friction.map(|f| f.1.to_degrees()))?;
    let locking = law.locking();
    set("shear_locking", locking.map(|l| l.0))?;
    set("shear_locking_angle", locking.map(|l| l.1.to_degrees()))?;
    Ok(text)
}

/// `--refine-fe`: the FE bias-extension test in the loop, from the analytic fit, on the
/// measured (not matrix-subtracted: the FE has the matrix layers) curve.
fn refine(
    args: &ShearArgs,
    card: &MaterialCard,
    measured: &ForceCurve,
    fit: &ShearFit,
) -> anyhow::Result<ShearFeFit> {
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
    let refined = refine_shear_fe(measured, card, &fit.law(), &settings, &mut report)?;
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

/// Crosshead force against displacement: the data and the final FE run.
fn refined_plot(refined: &ShearFeFit) -> LinePlot {
    let data = refined
        .points
        .iter()
        .map(|p| (p.displacement, p.data))
        .collect();
    let fe = refined
        .points
        .iter()
        .map(|p| (p.displacement, p.fe))
        .collect();
    LinePlot {
        title: "fit shear --refine-fe: data (dots), FE bias-extension test (line)".into(),
        x_label: "crosshead displacement (mm)".into(),
        y_label: "force (N)".into(),
        series: vec![
            Series::new("data", data, LineStyle::Markers).with_colour(0),
            Series::new("FE, refined card", fe, LineStyle::Solid).with_colour(1),
        ],
    }
}

/// The fabric's part of a prepreg's curve and the matrix layers' part (docs/model.md §5).
struct MatrixShare {
    fabric: ForceCurve,
    force: Vec<f64>,
    conditions: TestConditions,
}

/// The matrix layers' share of the measured force, for a card that has matrix layers; `None`
/// for a dry fabric.
fn matrix_share(
    args: &ShearArgs,
    card: &MaterialCard,
    measured: &ForceCurve,
    test: &ShearTest,
) -> anyhow::Result<Option<MatrixShare>> {
    let Some(layers) = matrix_layers(&card.laminate) else {
        return Ok(None);
    };
    let (Some(temperature), Some(speed)) = (args.temperature, args.speed) else {
        anyhow::bail!(
            "{}: the card has matrix layers; their share of the force is subtracted at the \
             test's temperature and crosshead speed: give --temperature (°C) and --speed (mm/s)",
            args.card.display()
        );
    };
    let conditions = TestConditions { temperature, speed };
    let (fabric, force) = subtract_matrix(measured, &layers, test, conditions).map_err(|e| {
        anyhow::anyhow!(
            "{}: the matrix layers at {temperature} °C: {e}",
            args.card.display()
        )
    })?;
    Ok(Some(MatrixShare {
        fabric,
        force,
        conditions,
    }))
}

/// The matrix layers' force normalised like the data, up to `max_shear` (for the plot).
fn matrix_points(
    measured: &ForceCurve,
    matrix: &MatrixShare,
    test: &ShearTest,
    max_shear: f64,
) -> anyhow::Result<Vec<ShearPoint>> {
    let curve = ForceCurve {
        force: matrix.force.clone(),
        ..measured.clone()
    };
    Ok(shear_points(&curve, test)?
        .into_iter()
        .filter(|p| p.gamma <= max_shear)
        .collect())
}

fn shear_test(args: &ShearArgs) -> anyhow::Result<ShearTest> {
    let test = match args.test {
        ShearTestKind::BiasExtension => match (args.width, args.length) {
            (Some(width), Some(length)) => ShearTest::BiasExtension { width, length },
            _ => anyhow::bail!("a bias-extension curve needs --width and --length (mm)"),
        },
        ShearTestKind::PictureFrame => match args.frame_side {
            Some(frame_side) => ShearTest::PictureFrame {
                frame_side,
                fabric_side: args.fabric_side.unwrap_or(frame_side),
            },
            None => anyhow::bail!("a picture-frame curve needs --frame-side (mm)"),
        },
    };
    test.validate().map_err(anyhow::Error::msg)?;
    Ok(test)
}

/// The fabric layer's thickness t_B: the card's stack must have exactly one fabric layer.
fn fabric_thickness(card: &MaterialCard, path: &Path) -> anyhow::Result<f64> {
    let fabric: Vec<f64> = card
        .laminate
        .layers()
        .iter()
        .filter(|l| l.law.name() == "fabric")
        .map(|l| l.thickness)
        .collect();
    match fabric[..] {
        [thickness] => Ok(thickness),
        _ => anyhow::bail!(
            "{}: the stack has {} fabric layers; the shear fit needs exactly one",
            path.display(),
            fabric.len()
        ),
    }
}

/// Comment lines above the written `shear` key: what it was fitted from and how; the first
/// starts with [`FIT_MARKER`] so that a re-fit replaces them.
fn shear_provenance(args: &ShearArgs, fit: &ShearFit, matrix: Option<&MatrixShare>) -> Vec<String> {
    let test = match args.test {
        ShearTestKind::BiasExtension => format!(
            "bias extension {} x {} mm",
            args.width.unwrap_or(f64::NAN),
            args.length.unwrap_or(f64::NAN)
        ),
        ShearTestKind::PictureFrame => format!(
            "picture frame, frame side {} mm",
            args.frame_side.unwrap_or(f64::NAN)
        ),
    };
    let errors: Vec<String> = fit
        .result
        .standard_errors
        .iter()
        .map(|e| format!("{e:.2e}"))
        .collect();
    let mut lines = vec![format!(
        "{FIT_MARKER} shear` (docs/model.md §5) to {} ({test}), {} points up to {}° of shear.",
        args.data.display(),
        fit.points.len(),
        args.max_shear
    )];
    if let Some(m) = matrix {
        lines.push(format!(
            "The matrix layers' force at {} °C and {} mm/s was subtracted first.",
            m.conditions.temperature, m.conditions.speed
        ));
    }
    lines.push(format!(
        "Standard errors [{}] MPa (terms {}); RMS misfit of the {} {:.3e} ({:.1} % of the \
         mean, {:.1} % of the range).",
        errors.join(", "),
        args.terms,
        fit.quantity,
        fit.rms,
        100.0 * fit.rms_of_mean,
        100.0 * fit.rms_of_range
    ));
    lines
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

/// Normalised shear force vs shear angle: data as dots, the fitted law as a line, and the
/// subtracted matrix layers' share (if any) dashed.
fn shear_plot(
    fit: &ShearFit,
    matrix: &[ShearPoint],
    thickness: f64,
    max_shear_deg: f64,
) -> LinePlot {
    let data = fit
        .points
        .iter()
        .map(|p| (p.gamma.to_degrees(), p.force))
        .collect();
    let law = fit.law();
    let model = (0..=100)
        .map(|k| {
            let g = max_shear_deg * f64::from(k) / 100.0;
            (g, law.normalised_shear_force(thickness, g.to_radians()))
        })
        .collect();
    let label = if matrix.is_empty() {
        "data"
    } else {
        "data less the matrix layers"
    };
    let mut series = vec![
        Series::new(label, data, LineStyle::Markers).with_colour(0),
        Series::new("model", model, LineStyle::Solid).with_colour(1),
    ];
    if !matrix.is_empty() {
        let share = matrix
            .iter()
            .map(|p| (p.gamma.to_degrees(), p.force))
            .collect();
        series.push(
            Series::new("matrix layers (subtracted)", share, LineStyle::Dashed).with_colour(2),
        );
    }
    LinePlot {
        title: "fit shear: data (dots), F_sh = 2 t sin(g) W_s'(sin^2 g) (line)".into(),
        x_label: "shear angle (°)".into(),
        y_label: "normalised shear force (N/mm)".into(),
        series,
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
        fitted_card_loads(&text, &args.output, &args.manifest.display().to_string())?;
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
            "Fitted by `thermostamp fit matrix` (docs/model.md §5) to {} curves of {}.",
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
        title: "fit matrix: data (dots), model of docs/model.md §5 (lines)".into(),
        x_label: "stretch".into(),
        y_label: "true stress (MPa)".into(),
        series,
    }
}
