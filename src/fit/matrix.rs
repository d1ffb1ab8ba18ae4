//! Identification of the matrix law (docs/model.md §5): `C10(T)` and `eta1(T)` from neat-resin
//! uniaxial tension curves at several temperatures and strain rates, `D1(T)` from a bulk
//! modulus or a Poisson ratio.
//!
//! Model, docs/model.md §5, incompressible uniaxial tension at stretch `l` and constant rate
//! `ldot`: `sigma11 = 2 C10 (l^2 - 1/l) + 2 eta1 (l^2 + 2/l - 3) (2 l^3 + l^-3) ldot`.
//! It is what the law of `src/material/matrix.rs` (Eqs. 8–9 of Gong et al. 2018) gives for `F =
//! diag(l, l^-1/2, l^-1/2)` once the lateral stresses are removed (tested below against the law
//! itself, with the card's finite `D1` and the lateral stretch solved for zero lateral stress).
//!
//! Choices:
//! - Per temperature, `C10` and `eta1` are fitted jointly to every curve at that temperature
//!   (residuals: model minus measured true stress, MPa, unweighted). docs/model.md §5 identifies
//!   `eta1` from the difference between rates, so a temperature whose curves all share one
//!   rate fits `C10` alone, with `eta1` taken from a given card (`--card`) at that temperature;
//!   without one it is an error. The curve shape at one rate does separate the two terms in
//!   principle, but any misfit of the neo-Hookean elasticity would then be read as viscosity.
//! - `D1` plays no part in the fit (the resin is taken as incompressible). It is set from a
//!   bulk modulus `K` (`D1 = 2/K`, the same at every temperature), from a Poisson ratio `nu`
//!   (`K = 2 G (1 + nu) / (3 (1 - 2 nu))`, `G = 2 C10(T)`), or kept from the card.

use super::least_squares::{fit, FitError, FitResult, Residuals};
use super::tension_data::TensionCurve;
use crate::material::TemperatureTable;
use nalgebra::{DMatrix, DVector};

/// `d sigma11 / d C10`: `2 (l^2 - 1/l)`. docs/model.md §5.
pub fn elastic_shape(stretch: f64) -> f64 {
    2.0 * (stretch * stretch - 1.0 / stretch)
}

/// `d sigma11 / d eta1`: `2 (l^2 + 2/l - 3) (2 l^3 + l^-3) ldot`. docs/model.md §5.
pub fn viscous_shape(stretch: f64, strain_rate: f64) -> f64 {
    let l = stretch;
    2.0 * (l * l + 2.0 / l - 3.0) * (2.0 * l.powi(3) + l.powi(-3)) * strain_rate
}

/// True uniaxial stress of the incompressible resin, docs/model.md §5.
pub fn uniaxial_stress(c10: f64, eta1: f64, stretch: f64, strain_rate: f64) -> f64 {
    c10 * elastic_shape(stretch) + eta1 * viscous_shape(stretch, strain_rate)
}

/// Where `D1(T)` comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum BulkRule {
    /// `K` in MPa: `D1 = 2 / K` at every temperature.
    BulkModulus(f64),
    /// Poisson ratio: `D1 = 2 / K`, `K = 2 G (1 + nu) / (3 (1 - 2 nu))`, `G = 2 C10(T)`.
    Poisson(f64),
    /// Interpolated in an existing card's table.
    Table(TemperatureTable),
}

impl BulkRule {
    /// Checks the value given on the command line.
    pub fn validate(&self) -> Result<(), String> {
        match *self {
            BulkRule::BulkModulus(k) => crate::limits::BULK_MODULUS.check("--bulk-modulus", k),
            BulkRule::Poisson(nu) if !(nu.is_finite() && nu > -1.0 && nu < 0.5) => Err(format!(
                "--poisson {nu}: must lie in (-1, 0.5); 0.5 is incompressible, give a large \
                 --bulk-modulus instead"
            )),
            _ => Ok(()),
        }
    }

    /// `D1` at `temperature` for a fitted `c10`.
    pub fn d1(&self, temperature: f64, c10: f64) -> Result<f64, String> {
        match self {
            BulkRule::BulkModulus(k) => Ok(2.0 / k),
            BulkRule::Poisson(nu) => {
                let shear_modulus = 2.0 * c10;
                let bulk = 2.0 * shear_modulus * (1.0 + nu) / (3.0 * (1.0 - 2.0 * nu));
                Ok(2.0 / bulk)
            }
            BulkRule::Table(table) => table
                .at(temperature)
                .map_err(|e| format!("D1 from the card: {e}; give --bulk-modulus or --poisson")),
        }
    }
}

/// How `eta1` was obtained at one temperature.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Eta1 {
    Fitted {
        value: f64,
        standard_error: f64,
    },
    /// Taken from the card: the curves at this temperature share one rate.
    FromCard {
        value: f64,
    },
}

impl Eta1 {
    pub fn value(&self) -> f64 {
        match *self {
            Eta1::Fitted { value, .. } | Eta1::FromCard { value } => value,
        }
    }
}

/// The fit at one temperature.
#[derive(Clone, Debug, PartialEq)]
pub struct TemperatureFit {
    pub temperature: f64,
    pub c10: f64,
    pub c10_standard_error: f64,
    pub eta1: Eta1,
    pub d1: f64,
    /// RMS of model minus data over all points at this temperature, MPa.
    pub rms_residual: f64,
    pub points: usize,
    /// Indices of the curves (in the input order) fitted at this temperature.
    pub curves: Vec<usize>,
}

/// What went wrong at one temperature, naming the files there.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{temperature} °C ({files}): {message}")]
pub struct MatrixFitError {
    pub temperature: f64,
    pub files: String,
    pub message: String,
}

/// Rates closer than this (relative) count as the same rate.
const SAME_RATE: f64 = 1e-6;

/// Fits every temperature of `curves`, in increasing temperature. `card_eta1` gives `eta1`
/// where a temperature has a single rate (see the module notes).
pub fn fit_matrix(
    curves: &[TensionCurve],
    bulk: &BulkRule,
    card_eta1: Option<&TemperatureTable>,
) -> Result<Vec<TemperatureFit>, MatrixFitError> {
    group_by_temperature(curves)
        .into_iter()
        .map(|(temperature, indices)| {
            let group: Vec<&TensionCurve> = indices.iter().map(|&i| &curves[i]).collect();
            let error = |message: String| MatrixFitError {
                temperature,
                files: group
                    .iter()
                    .map(|c| c.origin.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                message,
            };
            let (c10, c10_se, eta1, rms_residual, result) =
                fit_one_temperature(&group, temperature, card_eta1).map_err(&error)?;
            check_physical(c10, c10_se, &eta1).map_err(&error)?;
            let d1 = bulk.d1(temperature, c10).map_err(&error)?;
            Ok(TemperatureFit {
                temperature,
                c10,
                c10_standard_error: c10_se,
                eta1,
                d1,
                rms_residual,
                points: result.observations,
                curves: indices,
            })
        })
        .collect()
}

/// The distinct temperatures, increasing, each with the indices of its curves.
fn group_by_temperature(curves: &[TensionCurve]) -> Vec<(f64, Vec<usize>)> {
    let mut temperatures: Vec<f64> = curves.iter().map(|c| c.temperature).collect();
    temperatures.sort_by(f64::total_cmp);
    temperatures.dedup();
    temperatures
        .into_iter()
        .map(|t| {
            let indices = (0..curves.len())
                .filter(|&i| curves[i].temperature == t)
                .collect();
            (t, indices)
        })
        .collect()
}

fn single_rate(group: &[&TensionCurve]) -> bool {
    let first = group[0].strain_rate;
    group
        .iter()
        .all(|c| (c.strain_rate - first).abs() <= SAME_RATE * first)
}

/// `C10`, its standard error, `eta1`, the unweighted RMS misfit (MPa) and the fit.
type OneTemperature = (f64, f64, Eta1, f64, FitResult);

fn fit_one_temperature(
    group: &[&TensionCurve],
    temperature: f64,
    card_eta1: Option<&TemperatureTable>,
) -> Result<OneTemperature, String> {
    let points = Points::of(group);
    if single_rate(group) {
        let eta1 = card_eta1
            .and_then(|table| table.at(temperature).ok())
            .ok_or_else(|| {
                format!(
                    "all curves share the strain rate {} 1/s, so eta1 cannot be identified \
                     (docs/model.md §5 takes it from the rate difference): add a curve at another \
                     rate, or give --card with an eta1 table covering {temperature} °C",
                    group[0].strain_rate
                )
            })?;
        let problem = ElasticOnly { points, eta1 };
        let result = fit(&problem, &[problem.points.c10_guess()]).map_err(describe)?;
        let misfit = problem.points.rms_misfit(result.parameters[0], eta1);
        Ok((
            result.parameters[0],
            result.standard_errors[0],
            Eta1::FromCard { value: eta1 },
            misfit,
            result,
        ))
    } else {
        let start = [points.c10_guess(), points.eta1_guess()];
        let result = fit(&points, &start).map_err(describe)?;
        let eta1 = Eta1::Fitted {
            value: result.parameters[1],
            standard_error: result.standard_errors[1],
        };
        let misfit = points.rms_misfit(result.parameters[0], result.parameters[1]);
        Ok((
            result.parameters[0],
            result.standard_errors[0],
            eta1,
            misfit,
            result,
        ))
    }
}

fn describe(e: FitError) -> String {
    e.to_string()
}

/// The card needs `C10 > 0` and `eta1 >= 0`; a fit outside says the data do not fit the law.
fn check_physical(c10: f64, c10_se: f64, eta1: &Eta1) -> Result<(), String> {
    if c10 <= 0.0 {
        return Err(format!(
            "fitted C10 = {c10:.4e} ± {c10_se:.1e} MPa is not positive: the curves do not \
             show the elastic stiffening of docs/model.md §5"
        ));
    }
    if let Eta1::Fitted {
        value,
        standard_error,
    } = *eta1
    {
        if value < 0.0 {
            return Err(format!(
                "fitted eta1 = {value:.4e} ± {standard_error:.1e} MPa·s is negative: the faster \
                 curves are not stiffer, or the rate effect is below the scatter"
            ));
        }
    }
    Ok(())
}

/// All points at one temperature: stretch, rate and measured true stress, and the weight
/// each residual is divided by.
///
/// Residuals are relative, `(model - data) / max(|data|, floor)` **(choice)**: tensile-test
/// noise grows with the load (a load cell's error is a share of its reading), and equal
/// weights would let the fast, high-stress curves decide the fit and make the standard errors
/// too small (unweighted, 84 % of fits over 50 seeds of 2 % relative noise fell within two
/// standard errors; weighted, the 95 % that the formula promises). The floor, 1 % of the
/// largest stress, keeps the points near zero strain from dominating.
struct Points {
    stretch: Vec<f64>,
    rate: Vec<f64>,
    stress: Vec<f64>,
    scale: Vec<f64>,
}

/// Share of the largest stress under which a point's residual is no longer relative.
const RELATIVE_FLOOR: f64 = 0.01;

impl Points {
    fn of(group: &[&TensionCurve]) -> Self {
        let mut points = Points {
            stretch: Vec::new(),
            rate: Vec::new(),
            stress: Vec::new(),
            scale: Vec::new(),
        };
        for curve in group {
            points.stretch.extend_from_slice(&curve.stretch);
            points.stress.extend_from_slice(&curve.stress);
            points
                .rate
                .extend(std::iter::repeat_n(curve.strain_rate, curve.stretch.len()));
        }
        let largest = points.stress.iter().copied().fold(0.0, f64::max);
        let floor = (RELATIVE_FLOOR * largest).max(f64::MIN_POSITIVE);
        points.scale = points.stress.iter().map(|s| s.abs().max(floor)).collect();
        points
    }

    /// RMS of model minus data (MPa), unweighted: what the table reports.
    fn rms_misfit(&self, c10: f64, eta1: f64) -> f64 {
        let ssr: f64 = (0..self.stretch.len())
            .map(|i| {
                (uniaxial_stress(c10, eta1, self.stretch[i], self.rate[i]) - self.stress[i]).powi(2)
            })
            .sum();
        (ssr / self.stretch.len() as f64).sqrt()
    }

    /// A start of the right order: all the stress read as elastic (or as viscous), halved.
    fn c10_guess(&self) -> f64 {
        0.5 * self.largest_ratio(|i| elastic_shape(self.stretch[i]))
    }

    fn eta1_guess(&self) -> f64 {
        0.5 * self.largest_ratio(|i| viscous_shape(self.stretch[i], self.rate[i]))
    }

    fn largest_ratio(&self, shape: impl Fn(usize) -> f64) -> f64 {
        let stress = self.stress.iter().copied().fold(0.0, f64::max);
        let shape = (0..self.stretch.len())
            .map(shape)
            .map(f64::abs)
            .fold(0.0, f64::max);
        if shape > 0.0 && stress > 0.0 {
            stress / shape
        } else {
            1.0
        }
    }
}

/// Both parameters, `[C10, eta1]`.
impl Residuals for Points {
    fn observations(&self) -> usize {
        self.stretch.len()
    }

    fn residuals(&self, p: &DVector<f64>) -> DVector<f64> {
        DVector::from_fn(self.stretch.len(), |i, _| {
            (uniaxial_stress(p[0], p[1], self.stretch[i], self.rate[i]) - self.stress[i])
                / self.scale[i]
        })
    }

    fn jacobian(&self, _: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(self.stretch.len(), 2, |i, j| {
            let shape = match j {
                0 => elastic_shape(self.stretch[i]),
                _ => viscous_shape(self.stretch[i], self.rate[i]),
            };
            shape / self.scale[i]
        })
    }
}

/// `C10` alone, `eta1` held.
struct ElasticOnly {
    points: Points,
    eta1: f64,
}

impl Residuals for ElasticOnly {
    fn observations(&self) -> usize {
        self.points.observations()
    }

    fn residuals(&self, p: &DVector<f64>) -> DVector<f64> {
        self.points
            .residuals(&DVector::from_column_slice(&[p[0], self.eta1]))
    }

    fn jacobian(&self, _: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_fn(self.points.observations(), 1, |i, _| {
            elastic_shape(self.points.stretch[i]) / self.points.scale[i]
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::synthetic::{tension_curve, Lcg};
    use crate::material::{FibreDirections, MaterialLaw, PointKinematics, ViscoHyperelasticMatrix};
    use nalgebra::Matrix3;

    /// The shipped T300/PPS card's matrix at 280, 300, 320 °C: (T, C10, eta1).
    const CARD: [(f64, f64, f64); 3] = [
        (280.0, 0.20, 2.94e-4),
        (300.0, 0.10, 1.86e-4),
        (320.0, 0.05, 1.22e-4),
    ];
    const RATES: [f64; 2] = [1.0, 30.0];

    fn curves(noise: f64, seed: u64) -> Vec<TensionCurve> {
        let mut rng = Lcg::new(seed);
        let mut out = Vec::new();
        for (t, c10, eta1) in CARD {
            for rate in RATES {
                out.push(tension_curve(
                    &format!("{t}C-{rate}.csv"),
                    t,
                    rate,
                    (c10, eta1),
                    (0.6, 31),
                    noise,
                    &mut rng,
                ));
            }
        }
        out
    }

    #[test]
    fn noiseless_round_trip_within_one_percent() {
        let fits = fit_matrix(&curves(0.0, 1), &BulkRule::BulkModulus(1500.0), None).unwrap();
        assert_eq!(fits.len(), 3);
        for (fit, (t, c10, eta1)) in fits.iter().zip(CARD) {
            assert_eq!(fit.temperature, t);
            assert!((fit.c10 / c10 - 1.0).abs() < 1e-6, "{fit:?}");
            assert!((fit.eta1.value() / eta1 - 1.0).abs() < 1e-6, "{fit:?}");
            assert!((fit.d1 - 2.0 / 1500.0).abs() < 1e-15);
            assert_eq!(fit.points, 62);
        }
    }

    #[test]
    fn noisy_round_trip_within_two_standard_errors() {
        let fits = fit_matrix(&curves(0.02, 7), &BulkRule::Poisson(0.45), None).unwrap();
        for (fit, (_, c10, eta1)) in fits.iter().zip(CARD) {
            let Eta1::Fitted {
                value,
                standard_error,
            } = fit.eta1
            else {
                panic!("two rates: eta1 is fitted")
            };
            assert!(
                (fit.c10 - c10).abs() < 2.0 * fit.c10_standard_error,
                "{fit:?}"
            );
            assert!((value - eta1).abs() < 2.0 * standard_error, "{fit:?}");
            // ... and the errors are a few percent, not a formality.
            assert!(fit.c10_standard_error < 0.1 * c10, "{fit:?}");
            assert!(standard_error < 0.1 * eta1, "{fit:?}");
            let k = 2.0 * 2.0 * fit.c10 * 1.45 / (3.0 * 0.1);
            assert!((fit.d1 - 2.0 / k).abs() < 1e-12 * fit.d1);
        }
    }

    /// The standard errors are what they claim: over many seeds, about 95 % of the fitted
    /// values lie within two of them of the truth (relative residuals match the relative
    /// noise: 284 of 300, 95 %; unweighted, only 84 % did).
    #[test]
    fn standard_errors_cover_the_truth_over_many_seeds() {
        let (mut inside, mut total) = (0, 0);
        for seed in 1..=50 {
            let fits =
                fit_matrix(&curves(0.02, seed), &BulkRule::BulkModulus(1500.0), None).unwrap();
            for (fit, (_, c10, eta1)) in fits.iter().zip(CARD) {
                let Eta1::Fitted {
                    value,
                    standard_error,
                } = fit.eta1
                else {
                    panic!()
                };
                inside += usize::from((fit.c10 - c10).abs() < 2.0 * fit.c10_standard_error);
                inside += usize::from((value - eta1).abs() < 2.0 * standard_error);
                total += 2;
            }
        }
        let share = inside as f64 / total as f64;
        eprintln!("{inside} of {total} within two standard errors");
        assert!(
            share > 0.9,
            "{inside} of {total} within two standard errors"
        );
    }

    #[test]
    fn single_rate_fits_c10_with_eta1_from_the_card() {
        let one: Vec<TensionCurve> = curves(0.0, 1).into_iter().step_by(2).collect();
        let e = fit_matrix(&one, &BulkRule::BulkModulus(1500.0), None).unwrap_err();
        assert!(e.message.contains("eta1 cannot be identified"), "{e}");
        assert!(e.to_string().starts_with("280 °C (280C-1.csv)"), "{e}");
        let eta1 = TemperatureTable::new(
            "eta1",
            CARD.iter().map(|c| c.0).collect(),
            CARD.iter().map(|c| c.2).collect(),
        )
        .unwrap();
        let fits = fit_matrix(&one, &BulkRule::BulkModulus(1500.0), Some(&eta1)).unwrap();
        for (fit, (_, c10, eta1)) in fits.iter().zip(CARD) {
            assert_eq!(fit.eta1, Eta1::FromCard { value: eta1 });
            assert!((fit.c10 / c10 - 1.0).abs() < 1e-6, "{fit:?}");
        }
    }

    #[test]
    fn too_few_points_and_unidentifiable_data_are_errors() {
        let mut few = curves(0.0, 1);
        few.truncate(2);
        for c in &mut few {
            c.stretch.truncate(1);
            c.stress.truncate(1);
        }
        let e = fit_matrix(&few, &BulkRule::BulkModulus(1500.0), None).unwrap_err();
        assert!(e.message.contains("2 data points for 2 parameters"), "{e}");
        // Unstretched points only: nothing to fit.
        for c in &mut few {
            c.stretch = vec![1.0; 3];
            c.stress = vec![0.0; 3];
        }
        let e = fit_matrix(&few, &BulkRule::BulkModulus(1500.0), None).unwrap_err();
        assert!(e.message.contains("singular"), "{e}");
    }

    /// The law of `src/material/matrix.rs` in uniaxial tension at a constant stretch rate,
    /// with the card's finite D1: the lateral stretch `m` of `F = diag(l, m, m)` is solved at
    /// each step so that the lateral Cauchy stress vanishes, with `Cdot` from a backward
    /// difference of `C` over the step.
    fn law_uniaxial_stress(law: &ViscoHyperelasticMatrix, rate: f64, stretch: f64) -> f64 {
        let steps = 4000;
        let dt = (stretch - 1.0) / rate / f64::from(steps);
        let c_of =
            |l: f64, m: f64| Matrix3::from_diagonal(&nalgebra::Vector3::new(l * l, m * m, m * m));
        let stress = |l: f64, m: f64, c_previous: &Matrix3<f64>| {
            let c = c_of(l, m);
            let point = PointKinematics {
                c,
                c_dot: (c - c_previous) / dt,
                temperature: 300.0,
                fibres: FibreDirections::in_plane(0.0),
            };
            let s = law.second_piola_kirchhoff(&point).unwrap();
            let j = l * m * m;
            (l * l * s[(0, 0)] / j, m * m * s[(1, 1)] / j)
        };
        let (mut l, mut m) = (1.0, 1.0);
        let mut sigma11 = 0.0;
        for _ in 0..steps {
            let c_previous = c_of(l, m);
            l += rate * dt;
            // Secant iteration on the lateral stress, from the incompressible guess.
            let (mut m0, mut m1) = (l.powf(-0.5), l.powf(-0.5) * (1.0 + 1e-7));
            let (mut f0, mut f1) = (stress(l, m0, &c_previous).1, stress(l, m1, &c_previous).1);
            for _ in 0..50 {
                if f1 == f0 {
                    break;
                }
                let m2 = m1 - f1 * (m1 - m0) / (f1 - f0);
                (m0, f0) = (m1, f1);
                m1 = m2;
                f1 = stress(l, m1, &c_previous).1;
                if f1.abs() < 1e-13 {
                    break;
                }
            }
            m = m1;
            sigma11 = stress(l, m, &c_previous).0;
        }
        sigma11
    }

    #[test]
    fn closed_form_is_what_the_implemented_law_gives() {
        // docs/model.md §5 against Eqs. (8)–(9) of Gong et al. 2018 as implemented, at 300 °C of
        // the shipped card.
        let (c10, eta1, d1) = (0.10, 1.86e-4, 1.3333e-3);
        let table = |v: f64| TemperatureTable::new("p", vec![300.0], vec![v]).unwrap();
        let law = ViscoHyperelasticMatrix::new(table(c10), table(d1), table(eta1));
        for rate in [0.01, 1.0, 10.0] {
            for stretch in [1.2, 1.6] {
                let law_stress = law_uniaxial_stress(&law, rate, stretch);
                let closed = uniaxial_stress(c10, eta1, stretch, rate);
                // The finite D1 (K = 1500 MPa against 2 C10 = 0.2 MPa) and the backward
                // difference in time leave differences far below 0.1 %.
                assert!(
                    (law_stress / closed - 1.0).abs() < 1e-3,
                    "rate {rate}, stretch {stretch}: law {law_stress}, closed form {closed}"
                );
            }
        }
    }
}
