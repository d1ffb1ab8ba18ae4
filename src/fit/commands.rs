//! The `thermostamp fit ...` commands after their arguments are read, for every front end
//! (the command line, the Python package): each reads the card and the curves, fits, checks
//! the fit as the command line checks it and returns the fit with the card text it makes (and
//! the plot the command line draws); the front end writes and prints them. Curves come from
//! the files the command line reads or from CSV text a program made ([`CurveSource`]);
//! messages name the options through an [`OptionNames`].

use crate::experiment::virtual_test::OptionNames;
use crate::fit::card_key::{remove_key, replace_key, toml_array, toml_float, FIT_MARKER};
use crate::fit::card_section::{matrix_section, replace_matrix_section};
use crate::fit::fabric_tension::{
    check_terms, fit_yarn_tension, strip_force_per_width, TensionFit,
};
use crate::fit::least_squares::{Determination, MAX_POWER};
use crate::fit::matrix::{fit_matrix, uniaxial_stress, BulkRule, TemperatureFit};
use crate::fit::shear::{
    fit_shear, parse_force_curve, shear_points, ForceCurve, ShearFit, ShearPoint, ShearTest,
};
use crate::fit::shear_fe::ShearFeFit;
use crate::fit::shear_matrix::{matrix_layers, subtract_matrix, TestConditions};
use crate::fit::strip_data::{parse_strip_curve, StripCurve};
use crate::fit::tension_data::{
    manifest_curve, parse_curve, read_manifest, CurveSpec, TensionCurve,
};
use crate::io::plot::{LinePlot, LineStyle, Series};
use crate::io::xy_curve::read_curve_text;
use crate::io::InputError;
use crate::limits::{check_given, shown, FRICTION_ONSET, LENGTH, SHEAR_ANGLE, SPEED, TEMPERATURE};
use crate::material::fabric::{ShearInteraction, ShearTerm};
use crate::material::fabric_shear::DEFAULT_FRICTION_ONSET_DEG;
use crate::material::{MaterialCard, TemperatureTable};
use anyhow::Context;
use std::path::{Path, PathBuf};

/// Where a curve comes from: the CSV file the command line reads, or CSV text a program made
/// (`origin` names it in messages).
#[derive(Clone, Debug, PartialEq)]
pub enum CurveSource {
    File(PathBuf),
    Text { origin: String, text: String },
}

impl CurveSource {
    /// The curve's name in messages and its CSV text.
    pub fn read(&self) -> Result<(String, String), InputError> {
        match self {
            Self::File(path) => read_curve_text(path),
            Self::Text { origin, text } => Ok((origin.clone(), text.clone())),
        }
    }

    /// The curve's name in messages.
    pub fn origin(&self) -> String {
        match self {
            Self::File(path) => path.display().to_string(),
            Self::Text { origin, .. } => origin.clone(),
        }
    }
}

/// A material card's text and the card it loads as.
pub fn read_card(path: &Path) -> anyhow::Result<(String, MaterialCard)> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the material card", path.display()))?;
    let card = MaterialCard::from_toml(&text, &path.display().to_string())?;
    Ok((text, card))
}

/// A fit's coefficients as its table prints them: names, values, standard errors, unit.
pub struct Coefficients<'a> {
    pub names: &'a [String],
    pub values: &'a [f64],
    pub errors: &'a [f64],
    pub unit: &'a str,
}

/// Refuses a fit with a coefficient that the data (`data`) do not determine
/// ([`Determination::undetermined`]), naming it and `option`, which chose the terms; `say`
/// gets a note on the terms the fit does not need.
pub fn check_determined(
    data: &str,
    option: &str,
    c: &Coefficients,
    determination: &Determination,
    say: &mut dyn FnMut(String),
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
        say(format!(
            "note: {data}: {} is not determined by the data (its standard error exceeds it), \
             but moves the fit by less than 5 %: the fit does not need the term ({option})",
            describe(i)
        ));
    }
    Ok(())
}

/// The card a fit is about to write must load. The rest of it loaded as the input card, so
/// when it does not the fitted coefficients are the cause: the message names the data they
/// were fitted to (`data`), and `output` (the card's name) is not written.
pub fn fitted_card_loads(text: &str, output: &str, data: &str) -> anyhow::Result<()> {
    match MaterialCard::from_toml(text, output) {
        Ok(_) => Ok(()),
        Err(e) => anyhow::bail!(
            "{data}: the coefficients fitted to it make a card that does not load, so {output} \
             is not written: {}; fit fewer or other terms, or over another range",
            e.message
        ),
    }
}

// --- fit fabric-tension ---------------------------------------------------------------------

/// One direction of `fit fabric-tension`: its card key, curve and fit.
pub struct DirectionFit {
    pub key: &'static str,
    pub curve: StripCurve,
    pub fit: TensionFit,
}

/// What `fit fabric-tension` fitted: the fabric layer's thickness `t_B` (mm), a fit per
/// direction given, and the card with them.
pub struct FabricTensionFit {
    pub thickness: f64,
    pub fits: Vec<DirectionFit>,
    pub card: String,
}

/// `thermostamp fit fabric-tension`: the yarn tension coefficients of the card at `card` from
/// the `warp` and `weft` strip curves (at least one), `terms` of them (default as many as
/// the card has), `width` converting a force column. `output` names the card written in
/// messages.
pub fn fit_fabric_tension_card(
    card: &Path,
    (warp, weft): (Option<&CurveSource>, Option<&CurveSource>),
    (terms, width): (Option<usize>, Option<f64>),
    output: &str,
    names: OptionNames,
    say: &mut dyn FnMut(String),
) -> anyhow::Result<FabricTensionFit> {
    let terms_option = names("terms");
    if let Some(terms) = terms {
        check_terms(terms).map_err(|why| anyhow::anyhow!("{terms_option} {terms}: {why}"))?;
    }
    if let Some(width) = width {
        LENGTH
            .check(&names("width"), width)
            .map_err(anyhow::Error::msg)?;
    }
    let (text, material) = read_card(card)?;
    let thickness = material
        .laminate
        .layers()
        .iter()
        .find(|l| l.law.name() == "fabric")
        .map(|l| l.thickness)
        .context("the card's laminate has no fabric layer")?;
    let mut fits = Vec::new();
    for (key, source, law) in [
        ("warp_tension", warp, &material.fabric.warp),
        ("weft_tension", weft, &material.fabric.weft),
    ] {
        let Some(source) = source else { continue };
        let (origin, csv) = source.read()?;
        let curve = parse_strip_curve(&csv, &origin, width)?;
        let n = terms.unwrap_or(law.coefficients().len());
        let fit = fit_yarn_tension(&curve, thickness, n)?;
        let coefficient_names: Vec<String> = (0..n).map(|i| format!("A{}", i + 2)).collect();
        let coefficients = Coefficients {
            names: &coefficient_names,
            values: &fit.coefficients,
            errors: &fit.standard_errors,
            unit: "MPa",
        };
        let option = match terms {
            Some(n) => format!("{terms_option} {n}"),
            None => format!("{terms_option}, by default the card's {n}"),
        };
        check_determined(
            &curve.origin,
            &option,
            &coefficients,
            &fit.determination,
            say,
        )?;
        fits.push(DirectionFit { key, curve, fit });
    }
    let mut written = text.clone();
    for d in &fits {
        let comment = tension_provenance(d, thickness);
        written = replace_key(
            &written,
            "fabric",
            d.key,
            &toml_array(&d.fit.coefficients),
            &comment,
        )
        .map_err(|e| anyhow::anyhow!("{}: {e}", card.display()))?;
    }
    let data: Vec<String> = fits.iter().map(|d| d.curve.origin.clone()).collect();
    fitted_card_loads(&written, output, &data.join(" and "))?;
    Ok(FabricTensionFit {
        thickness,
        fits,
        card: written,
    })
}

/// Comment line above the written key; it starts with [`FIT_MARKER`] so that a re-fit
/// replaces it.
fn tension_provenance(d: &DirectionFit, thickness: f64) -> Vec<String> {
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

impl FabricTensionFit {
    /// The command line's plot: data as dots and the fitted model as a line per direction.
    pub fn plot(&self) -> LinePlot {
        tension_plot(&self.fits, self.thickness)
    }
}

/// Data as dots and the fitted model as a line, one colour per direction.
fn tension_plot(fits: &[DirectionFit], thickness: f64) -> LinePlot {
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

// --- fit matrix -----------------------------------------------------------------------------

/// The curves of `fit matrix`: a manifest file, or curves with their conditions, `origin`
/// naming them together in messages (as the manifest's file would).
pub enum MatrixCurves {
    Manifest(PathBuf),
    Given {
        origin: String,
        curves: Vec<(CurveSource, CurveSpec)>,
    },
}

impl MatrixCurves {
    /// The name of the curves together, in messages and in the card's comment.
    pub fn origin(&self) -> String {
        match self {
            Self::Manifest(path) => path.display().to_string(),
            Self::Given { origin, .. } => origin.clone(),
        }
    }

    /// Every curve, checked.
    pub fn read(&self) -> Result<Vec<TensionCurve>, InputError> {
        match self {
            Self::Manifest(path) => read_manifest(path),
            Self::Given { origin, curves } => {
                if curves.is_empty() {
                    return Err(InputError::in_file(origin, "no curve is given"));
                }
                curves
                    .iter()
                    .enumerate()
                    .map(|(i, (source, spec))| {
                        let label = source.origin();
                        manifest_curve(origin, (i + 1, &label), spec, |t, rate| {
                            let (name, text) = source.read()?;
                            parse_curve(&text, &name, t, rate)
                        })
                    })
                    .collect()
            }
        }
    }
}

/// What `fit matrix` fitted: the curves, a fit per temperature, and the card (the `[matrix]`
/// section alone without an input card).
pub struct MatrixCardFit {
    pub curves: Vec<TensionCurve>,
    pub fits: Vec<TemperatureFit>,
    pub card: String,
}

/// `thermostamp fit matrix`: `C10(T)`, `eta1(T)` and `D1` from `curves`, into the `[matrix]`
/// section of the card at `card` (kept as it is otherwise) or alone; `D1` from
/// `bulk_modulus`, or `poisson`, or the input card's table. `output` names the card written
/// in messages.
pub fn fit_matrix_card(
    card: Option<&Path>,
    curves: &MatrixCurves,
    (bulk_modulus, poisson): (Option<f64>, Option<f64>),
    output: &str,
    names: OptionNames,
) -> anyhow::Result<MatrixCardFit> {
    let card = card.map(read_card).transpose()?;
    let matrix = card.as_ref().and_then(|(_, c)| c.matrix.clone());
    let bulk = bulk_rule(
        (bulk_modulus, poisson),
        matrix.as_deref().map(|m| m.d1_table()),
        names,
    )?;
    let read = curves.read()?;
    let fits = fit_matrix(&read, &bulk, matrix.as_deref().map(|m| m.eta1_table()))?;
    let section = matrix_section(&fits, &matrix_provenance(&curves.origin(), &read, &bulk));
    let text = match &card {
        Some((text, _)) => replace_matrix_section(text, &section),
        None => section,
    };
    if card.is_some() {
        fitted_card_loads(&text, output, &curves.origin())?;
    }
    Ok(MatrixCardFit {
        curves: read,
        fits,
        card: text,
    })
}

fn bulk_rule(
    (bulk_modulus, poisson): (Option<f64>, Option<f64>),
    card_d1: Option<&TemperatureTable>,
    names: OptionNames,
) -> anyhow::Result<BulkRule> {
    let rule = match (bulk_modulus, poisson, card_d1) {
        (Some(k), _, _) => BulkRule::BulkModulus(k),
        (None, Some(nu), _) => BulkRule::Poisson(nu),
        (None, None, Some(table)) => BulkRule::Table(table.clone()),
        (None, None, None) => anyhow::bail!(
            "D1 needs {} K or {} nu (or a {} whose [matrix] d1 is kept)",
            names("bulk-modulus"),
            names("poisson"),
            names("card")
        ),
    };
    rule.validate().map_err(anyhow::Error::msg)?;
    Ok(rule)
}

/// Comment lines of the written section: what it was fitted from and how.
fn matrix_provenance(origin: &str, curves: &[TensionCurve], bulk: &BulkRule) -> Vec<String> {
    let d1 = match bulk {
        BulkRule::BulkModulus(k) => format!("D1 = 2/K with K = {k} MPa"),
        BulkRule::Poisson(nu) => {
            format!("D1 = 2/K with K = 2G(1+nu)/(3(1-2nu)), G = 2 C10(T), nu = {nu}")
        }
        BulkRule::Table(_) => "D1 interpolated in the input card's table".into(),
    };
    vec![
        format!(
            "Fitted by `thermostamp fit matrix` (docs/model.md §5) to {} curves of {origin}.",
            curves.len(),
        ),
        format!("{d1}."),
    ]
}

impl MatrixCardFit {
    /// The command line's plot: data as dots and the fitted model as lines, a colour per
    /// curve.
    pub fn plot(&self) -> LinePlot {
        matrix_plot(&self.curves, &self.fits)
    }
}

/// Data as dots and the fitted model as lines, one colour per curve.
fn matrix_plot(curves: &[TensionCurve], fits: &[TemperatureFit]) -> LinePlot {
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

// --- fit shear ------------------------------------------------------------------------------

/// The options of `fit shear` (the command line's, without the files).
#[derive(Clone, Debug, PartialEq)]
pub struct ShearOptions {
    /// Which test the curve comes from: a bias extension (`true`) or a picture frame.
    pub bias_extension: bool,
    pub width: Option<f64>,
    pub length: Option<f64>,
    pub frame_side: Option<f64>,
    pub fabric_side: Option<f64>,
    pub temperature: Option<f64>,
    pub speed: Option<f64>,
    pub terms: String,
    pub friction_onset: f64,
    pub locking_angle: Option<f64>,
    pub max_shear: f64,
    pub refine_fe: bool,
    pub fe_element_size: Option<f64>,
}

impl Default for ShearOptions {
    /// The command line's defaults.
    fn default() -> Self {
        Self {
            bias_extension: true,
            width: None,
            length: None,
            frame_side: None,
            fabric_side: None,
            temperature: None,
            speed: None,
            terms: "3".into(),
            friction_onset: DEFAULT_FRICTION_ONSET_DEG,
            locking_angle: None,
            max_shear: 50.0,
            refine_fe: false,
            fe_element_size: None,
        }
    }
}

/// The fabric's part of a prepreg's curve and the matrix layers' part (docs/model.md §5).
pub struct MatrixShare {
    pub fabric: ForceCurve,
    pub force: Vec<f64>,
    pub conditions: TestConditions,
}

/// What `fit shear` fitted analytically, with what the card, the refinement and the plot
/// need.
pub struct ShearCardFit {
    pub fit: ShearFit,
    pub matrix: Option<MatrixShare>,
    /// The curve as measured (the matrix layers' share not subtracted).
    pub measured: ForceCurve,
    pub test: ShearTest,
    /// The fabric layer's thickness `t_B` (mm).
    pub thickness: f64,
    /// The input card and its text.
    pub card: MaterialCard,
    pub card_text: String,
    card_origin: String,
    options: ShearOptions,
}

/// `thermostamp fit shear` up to the analytic fit, checked: the options, the card at `card`,
/// the curve `data`, the matrix layers' share subtracted for a prepreg.
pub fn fit_shear_card(
    card: &Path,
    data: &CurveSource,
    options: &ShearOptions,
    names: OptionNames,
    say: &mut dyn FnMut(String),
) -> anyhow::Result<ShearCardFit> {
    check_shear_numbers(options, names)?;
    let terms = shear_terms(options, names)?;
    let test = shear_test(options, names)?;
    if options.refine_fe && !options.bias_extension {
        anyhow::bail!(
            "{} runs the FE bias-extension test: it needs a bias-extension curve; a \
             picture frame shears homogeneously, so its analytic fit is already what the FE gives",
            names("refine-fe")
        );
    }
    let (text, material) = read_card(card)?;
    let card_origin = card.display().to_string();
    let thickness = fabric_thickness(&material, &card_origin)?;
    let (origin, csv) = data.read()?;
    let measured = parse_force_curve(&csv, &origin)?;
    let matrix = matrix_share(options, &material, &card_origin, &measured, &test, names)?;
    let curve = matrix.as_ref().map_or(&measured, |m| &m.fabric);
    let fit = fit_shear(
        curve,
        &test,
        thickness,
        &terms,
        options.max_shear.to_radians(),
    )?;
    let term_names: Vec<String> = terms.iter().map(ShearTerm::name).collect();
    let coefficients = Coefficients {
        names: &term_names,
        values: &fit.result.parameters,
        errors: &fit.result.standard_errors,
        unit: "MPa",
    };
    check_determined(
        &origin,
        &format!("{} {}", names("terms"), options.terms),
        &coefficients,
        &fit.result.determination(),
        say,
    )?;
    Ok(ShearCardFit {
        fit,
        matrix,
        measured,
        test,
        thickness,
        card: material,
        card_text: text,
        card_origin,
        options: options.clone(),
    })
}

impl ShearCardFit {
    /// The card with its `[fabric]` shear law set to `law` (the analytic fit's, or a
    /// refinement's with `more` comment lines on it), checked to load; `output` names it in
    /// messages.
    pub fn card_with(
        &self,
        law: &ShearInteraction,
        more: Vec<String>,
        output: &str,
    ) -> anyhow::Result<String> {
        let mut provenance = more;
        provenance.splice(0..0, self.provenance());
        let written = write_shear_law(&self.card_text, law, &provenance)
            .map_err(|e| anyhow::anyhow!("{}: {e}", self.card_origin))?;
        fitted_card_loads(&written, output, &self.measured.origin)?;
        Ok(written)
    }

    /// The command line's plot: with a refinement, the crosshead force of the data and of
    /// the final FE run; else the normalised shear force of the data and the fitted law, and
    /// the subtracted matrix layers' share.
    pub fn plot(&self, refined: Option<&ShearFeFit>) -> anyhow::Result<LinePlot> {
        Ok(match refined {
            Some(r) => refined_plot(r),
            None => {
                let max_shear = self.options.max_shear;
                let matrix_points = match &self.matrix {
                    Some(m) => {
                        matrix_points(&self.measured, m, &self.test, max_shear.to_radians())?
                    }
                    None => Vec::new(),
                };
                shear_plot(&self.fit, &matrix_points, self.thickness, max_shear)
            }
        })
    }

    /// Comment lines above the written `shear` key: what it was fitted from and how; the
    /// first starts with [`FIT_MARKER`] so that a re-fit replaces them.
    fn provenance(&self) -> Vec<String> {
        let o = &self.options;
        let fit = &self.fit;
        let test = if o.bias_extension {
            format!(
                "bias extension {} x {} mm",
                o.width.unwrap_or(f64::NAN),
                o.length.unwrap_or(f64::NAN)
            )
        } else {
            format!(
                "picture frame, frame side {} mm",
                o.frame_side.unwrap_or(f64::NAN)
            )
        };
        let errors: Vec<String> = fit
            .result
            .standard_errors
            .iter()
            .map(|e| format!("{e:.2e}"))
            .collect();
        let mut lines = vec![format!(
            "{FIT_MARKER} shear` (docs/model.md §5) to {} ({test}), {} points up to {}° of shear.",
            self.measured.origin,
            fit.points.len(),
            o.max_shear
        )];
        if let Some(m) = &self.matrix {
            lines.push(format!(
                "The matrix layers' force at {} °C and {} mm/s was subtracted first.",
                m.conditions.temperature, m.conditions.speed
            ));
        }
        lines.push(format!(
            "Standard errors [{}] MPa (terms {}); RMS misfit of the {} {:.3e} ({:.1} % of the \
             mean, {:.1} % of the range).",
            errors.join(", "),
            o.terms,
            fit.quantity,
            fit.rms,
            100.0 * fit.rms_of_mean,
            100.0 * fit.rms_of_range
        ));
        lines
    }
}

/// The numbers of `fit shear`'s options inside their ranges (`crate::limits`), before any
/// file is read.
fn check_shear_numbers(o: &ShearOptions, names: OptionNames) -> anyhow::Result<()> {
    let n = |o: &str| names(o);
    check_given([
        (n("width").as_str(), o.width, LENGTH),
        (n("length").as_str(), o.length, LENGTH),
        (n("frame-side").as_str(), o.frame_side, LENGTH),
        (n("fabric-side").as_str(), o.fabric_side, LENGTH),
        (n("temperature").as_str(), o.temperature, TEMPERATURE),
        (n("speed").as_str(), o.speed, SPEED),
        (n("max-shear").as_str(), Some(o.max_shear), SHEAR_ANGLE),
        (n("fe-element-size").as_str(), o.fe_element_size, LENGTH),
    ])
    .map_err(anyhow::Error::msg)
}

/// The terms the terms option names (module doc of `fit::shear`), with the friction onset
/// and the locking angle: each once, powers from 1 to [`MAX_POWER`] (checked before any term
/// is made: `4294967295` would be 4294967295 of them), `locking` only with its angle.
fn shear_terms(o: &ShearOptions, names: OptionNames) -> anyhow::Result<Vec<ShearTerm>> {
    let option = names("terms");
    let bad = |why: String| anyhow::anyhow!("{option} {}: {why}", o.terms);
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
    let tokens: Vec<&str> = o.terms.split(',').map(str::trim).collect();
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
                let onset = o.friction_onset;
                FRICTION_ONSET
                    .check(&names("friction-onset"), onset)
                    .map_err(anyhow::Error::msg)?;
                ShearTerm::Friction {
                    onset: onset.to_radians(),
                }
            }
            "locking" => match o.locking_angle {
                Some(a) => {
                    SHEAR_ANGLE
                        .check(&names("locking-angle"), a)
                        .map_err(anyhow::Error::msg)?;
                    ShearTerm::Locking {
                        angle: a.to_radians(),
                    }
                }
                None => anyhow::bail!(
                    "{option} {}: the locking term needs {} (degrees), where the yarns begin to \
                     jam",
                    o.terms,
                    names("locking-angle")
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

/// The matrix layers' share of the measured force, for a card that has matrix layers; `None`
/// for a dry fabric.
fn matrix_share(
    o: &ShearOptions,
    card: &MaterialCard,
    card_origin: &str,
    measured: &ForceCurve,
    test: &ShearTest,
    names: OptionNames,
) -> anyhow::Result<Option<MatrixShare>> {
    let Some(layers) = matrix_layers(&card.laminate) else {
        return Ok(None);
    };
    let (Some(temperature), Some(speed)) = (o.temperature, o.speed) else {
        anyhow::bail!(
            "{card_origin}: the card has matrix layers; their share of the force is subtracted \
             at the test's temperature and crosshead speed: give {} (°C) and {} (mm/s)",
            names("temperature"),
            names("speed")
        );
    };
    let conditions = TestConditions { temperature, speed };
    let (fabric, force) = subtract_matrix(measured, &layers, test, conditions).map_err(|e| {
        anyhow::anyhow!("{card_origin}: the matrix layers at {temperature} °C: {e}")
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

fn shear_test(o: &ShearOptions, names: OptionNames) -> anyhow::Result<ShearTest> {
    let test = if o.bias_extension {
        match (o.width, o.length) {
            (Some(width), Some(length)) => ShearTest::BiasExtension { width, length },
            _ => anyhow::bail!(
                "a bias-extension curve needs {} and {} (mm)",
                names("width"),
                names("length")
            ),
        }
    } else {
        match o.frame_side {
            Some(frame_side) => ShearTest::PictureFrame {
                frame_side,
                fabric_side: o.fabric_side.unwrap_or(frame_side),
            },
            None => anyhow::bail!("a picture-frame curve needs {} (mm)", names("frame-side")),
        }
    };
    test.validate().map_err(anyhow::Error::msg)?;
    Ok(test)
}

/// The fabric layer's thickness t_B: the card's stack must have exactly one fabric layer.
fn fabric_thickness(card: &MaterialCard, origin: &str) -> anyhow::Result<f64> {
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
            "{origin}: the stack has {} fabric layers; the shear fit needs exactly one",
            fabric.len()
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
