//! Material-point driver: one point of a layer or of the laminate taken through a prescribed
//! deformation history, like a single-element test.
//!
//! Rates come from the history itself: `Cdot` by second-order finite differences in time
//! (three-point formulas, central inside, one-sided at the ends), so a history whose `F` is
//! linear in time gets the exact `Cdot`.

use crate::io::{check_finite_row, CsvTable, InputError};
use crate::material::stress_free_stretch::{find_stress_free_stretch, StressSample};
use crate::material::{
    cauchy_stress, FibreDirections, Laminate, MaterialCard, MaterialError, MaterialLaw,
    MembraneKinematics, PointKinematics, ViscoHyperelasticMatrix,
};
use nalgebra::{Matrix2, Matrix3};
use std::ops::{Add, Mul};

/// One instant of a 3D history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSample {
    pub t: f64,
    pub f: Matrix3<f64>,
    pub temperature: f64,
}

/// Response of a layer law at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointResponse {
    pub t: f64,
    /// Second Piola–Kirchhoff stress (MPa).
    pub s: Matrix3<f64>,
    /// Cauchy stress (MPa).
    pub sigma: Matrix3<f64>,
}

/// One instant of an in-plane (membrane) history.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MembraneSample {
    pub t: f64,
    /// In-plane deformation gradient in the sheet's x–y basis.
    pub f: Matrix2<f64>,
    pub temperature: f64,
}

/// Response of the laminate at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaminateResponse {
    pub t: f64,
    /// 2nd Piola–Kirchhoff membrane resultant per unit reference width (N/mm).
    pub n: Matrix2<f64>,
    /// Current thickness (mm).
    pub thickness: f64,
}

/// The material failed at sample `index` of the history.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("at t = {t}: {error}")]
pub struct PointFailure {
    pub index: usize,
    pub t: f64,
    pub error: MaterialError,
}

/// Time derivative of sampled `values` by three-point finite differences (exact for
/// quadratics, any spacing). One sample has rate zero; two give the secant.
pub fn time_derivative<M>(times: &[f64], values: &[M]) -> Vec<M>
where
    M: Copy + Add<Output = M> + Mul<f64, Output = M>,
{
    let n = values.len();
    match n {
        0 => Vec::new(),
        1 => vec![values[0] * 0.0],
        2 => {
            let d = (values[1] + values[0] * -1.0) * (1.0 / (times[1] - times[0]));
            vec![d, d]
        }
        _ => (0..n)
            .map(|i| {
                let j = i.clamp(1, n - 2); // centre of the three-point stencil
                let (t0, t1, t2) = (times[j - 1], times[j], times[j + 1]);
                let (w0, w1, w2) = lagrange_slope_weights(t0, t1, t2, times[i]);
                values[j - 1] * w0 + values[j] * w1 + values[j + 1] * w2
            })
            .collect(),
    }
}

/// Weights of the derivative at `t` of the parabola through `(t0, t1, t2)`.
fn lagrange_slope_weights(t0: f64, t1: f64, t2: f64, t: f64) -> (f64, f64, f64) {
    (
        ((t - t1) + (t - t2)) / ((t0 - t1) * (t0 - t2)),
        ((t - t0) + (t - t2)) / ((t1 - t0) * (t1 - t2)),
        ((t - t0) + (t - t1)) / ((t2 - t0) * (t2 - t1)),
    )
}

/// Drives one layer law through a 3D deformation history.
pub fn drive_layer(
    law: &dyn MaterialLaw,
    fibres: FibreDirections,
    history: &[PointSample],
) -> Result<Vec<PointResponse>, PointFailure> {
    let times: Vec<f64> = history.iter().map(|s| s.t).collect();
    let c: Vec<Matrix3<f64>> = history.iter().map(|s| s.f.transpose() * s.f).collect();
    let c_dot = time_derivative(&times, &c);
    history
        .iter()
        .enumerate()
        .map(|(i, sample)| {
            let point = PointKinematics {
                c: c[i],
                c_dot: c_dot[i],
                temperature: sample.temperature,
                fibres,
            };
            let s = law
                .second_piola_kirchhoff(&point)
                .map_err(|error| PointFailure {
                    index: i,
                    t: sample.t,
                    error,
                })?;
            Ok(PointResponse {
                t: sample.t,
                s,
                sigma: cauchy_stress(&sample.f, &s),
            })
        })
        .collect()
}

/// Drives the laminate through an in-plane deformation history (plane stress in every layer).
pub fn drive_laminate(
    laminate: &Laminate,
    fibres: FibreDirections,
    history: &[MembraneSample],
) -> Result<Vec<LaminateResponse>, PointFailure> {
    let times: Vec<f64> = history.iter().map(|s| s.t).collect();
    let c: Vec<Matrix2<f64>> = history.iter().map(|s| s.f.transpose() * s.f).collect();
    let c_dot = time_derivative(&times, &c);
    let mut state = laminate.initial_state();
    let mut previous_t = history.first().map_or(0.0, |s| s.t);
    history
        .iter()
        .enumerate()
        .map(|(i, sample)| {
            let kin = MembraneKinematics {
                c: c[i],
                c_dot: c_dot[i],
                temperature: sample.temperature.into(),
                fibres,
            };
            let dt = sample.t - previous_t;
            previous_t = sample.t;
            let r = laminate
                .membrane_response(&kin, dt, &mut state)
                .map_err(|error| PointFailure {
                    index: i,
                    t: sample.t,
                    error,
                })?;
            Ok(LaminateResponse {
                t: sample.t,
                n: r.n,
                thickness: r.thickness,
            })
        })
        .collect()
}

/// Uniaxial-stress test of the isotropic matrix along x: for each prescribed stretch
/// `lambda(t)`, the lateral stretch is solved so that `S22 = S33 = 0` (viscous part included,
/// lateral rate by backward difference). Returns `(lateral stretch, Cauchy sigma11)` per sample.
pub fn matrix_uniaxial_stress(
    matrix: &ViscoHyperelasticMatrix,
    times: &[f64],
    stretches: &[f64],
    temperature: f64,
) -> Result<Vec<(f64, f64)>, PointFailure> {
    let c11: Vec<f64> = stretches.iter().map(|l| l * l).collect();
    let c11_dot = time_derivative(times, &c11);
    let fibres = FibreDirections::default();
    let mut lateral = 1.0;
    let mut previous_t = times.first().copied().unwrap_or(0.0);
    let mut out = Vec::with_capacity(times.len());
    for (i, (&t, &stretch)) in times.iter().zip(stretches).enumerate() {
        let fail = |error| PointFailure { index: i, t, error };
        let dt = t - previous_t;
        let previous_lateral = lateral;
        let point_at = |mu: f64| {
            let mu_dot = if dt > 0.0 {
                (mu - previous_lateral) / dt
            } else {
                0.0
            };
            PointKinematics {
                c: Matrix3::from_diagonal(&nalgebra::Vector3::new(c11[i], mu * mu, mu * mu)),
                c_dot: Matrix3::from_diagonal(&nalgebra::Vector3::new(
                    c11_dot[i],
                    2.0 * mu * mu_dot,
                    2.0 * mu * mu_dot,
                )),
                temperature,
                fibres,
            }
        };
        let s22 = |mu: f64| {
            let s = matrix.second_piola_kirchhoff(&point_at(mu))?;
            Ok(StressSample {
                value: s[(1, 1)],
                scale: s[(0, 0)].abs(),
            })
        };
        lateral = find_stress_free_stretch(s22, lateral, 1e-13)
            .map_err(fail)?
            .map_err(|nc| {
                fail(MaterialError::PlaneStressNotConverged {
                    layer: 0,
                    law: "matrix",
                    iterations: nc.iterations,
                    lambda3: nc.stretch,
                    s33: nc.residual,
                })
            })?;
        let s = matrix
            .second_piola_kirchhoff(&point_at(lateral))
            .map_err(fail)?;
        let f = Matrix3::from_diagonal(&nalgebra::Vector3::new(stretch, lateral, lateral));
        out.push((lateral, cauchy_stress(&f, &s)[(0, 0)]));
        previous_t = t;
    }
    Ok(out)
}

/// Which model a material-point test drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointLayer {
    /// Layer A alone: visco-hyperelastic matrix (3D history).
    Matrix,
    /// Layer B alone: woven fabric (3D history).
    Fabric,
    /// The whole A:B:A ply in plane stress (in-plane history).
    Laminate,
}

/// History columns of a layer (matrix, fabric): time, the full 3D `F` by rows, temperature.
pub const LAYER_COLUMNS: [&str; 11] = [
    "t", "F11", "F12", "F13", "F21", "F22", "F23", "F31", "F32", "F33", "T",
];
/// Output columns of a layer: 2nd Piola–Kirchhoff and Cauchy stress (MPa).
pub const LAYER_OUTPUT: [&str; 13] = [
    "t", "S11", "S22", "S33", "S12", "S23", "S13", "sigma11", "sigma22", "sigma33", "sigma12",
    "sigma23", "sigma13",
];
/// History columns of the laminate: time, the in-plane `F` by rows, temperature.
pub const LAMINATE_COLUMNS: [&str; 6] = ["t", "F11", "F12", "F21", "F22", "T"];
/// Output columns of the laminate: membrane resultants (N/mm) and thickness (mm).
pub const LAMINATE_OUTPUT: [&str; 5] = ["t", "N11", "N22", "N12", "thickness"];

impl PointLayer {
    /// The columns its history must have, in this order.
    pub fn history_columns(self) -> &'static [&'static str] {
        match self {
            Self::Matrix | Self::Fabric => &LAYER_COLUMNS,
            Self::Laminate => &LAMINATE_COLUMNS,
        }
    }

    /// The columns of its response.
    pub fn output_columns(self) -> &'static [&'static str] {
        match self {
            Self::Matrix | Self::Fabric => &LAYER_OUTPUT,
            Self::Laminate => &LAMINATE_OUTPUT,
        }
    }
}

/// The response of a material-point test: one row of [`PointLayer::output_columns`] per row
/// of the history.
#[derive(Clone, Debug, PartialEq)]
pub struct PointTable {
    pub header: &'static [&'static str],
    pub rows: Vec<Vec<f64>>,
}

/// `thermostamp material-point` after its arguments are read: drives `layer` of `card` (read
/// from `card_origin`) with the warp at `angle` degrees from x through `history`, whose rows
/// are [`PointLayer::history_columns`]. A bad row (time not increasing, `det F <= 0`, the
/// material failing there) is an [`InputError`] at the table's line for the row.
pub fn material_point(
    card: &MaterialCard,
    card_origin: &str,
    layer: PointLayer,
    angle: f64,
    history: &CsvTable,
) -> anyhow::Result<PointTable> {
    let fibres = FibreDirections::in_plane(angle.to_radians());
    let locate = |failure: PointFailure| {
        InputError::at_line(
            &history.origin,
            history.lines[failure.index],
            format!("{} (material card {card_origin})", failure.error),
        )
    };
    let rows: Vec<Vec<f64>> = match layer {
        PointLayer::Matrix | PointLayer::Fabric => {
            let samples = point_history(history)?;
            let law: &dyn MaterialLaw = match layer {
                PointLayer::Matrix => card.matrix.as_deref().ok_or_else(|| {
                    anyhow::anyhow!("{card_origin}: the card has no [matrix] section")
                })?,
                _ => card.fabric.as_ref(),
            };
            let response = drive_layer(law, fibres, &samples).map_err(locate)?;
            response.iter().map(layer_row).collect()
        }
        PointLayer::Laminate => {
            let samples = membrane_history(history)?;
            let response = drive_laminate(&card.laminate, fibres, &samples).map_err(locate)?;
            response.iter().map(laminate_row).collect()
        }
    };
    let header = layer.output_columns();
    // a response that is not a finite number comes from the card (a value the law cannot
    // take, such as 1e308 for a thickness) driven through the history: the error names both,
    // as the writer alone would name only a cell of an output nobody asked to read
    for (i, row) in rows.iter().enumerate() {
        check_finite_row(header, i + 1, row).map_err(|e| {
            anyhow::anyhow!(
                "{card_origin}: driven through {}, the response is not a finite number (output \
                 {e})",
                history.origin
            )
        })?;
    }
    Ok(PointTable { header, rows })
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
