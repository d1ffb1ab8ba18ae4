//! The matrix layers' share of a shear test's crosshead force, to be subtracted before the
//! fabric's shear law is fitted (docs/model.md §5: "after subtracting the matrix layers'
//! contribution").
//!
//! The matrix layers are driven through the test's pin-jointed kinematics at the test's
//! temperature and crosshead speed, in plane stress like in the sheet (docs/model.md §2, §4). In
//! the pin-jointed shear of angle `gamma` with the pull along `y`, the yarns stay at
//! `±theta = ±(45° - gamma/2)` to `y` and keep their length, so
//! `F = diag(sqrt(2) sin(theta), sqrt(2) cos(theta))` and
//! `C2 = diag(2 sin^2(theta), 2 cos^2(theta))`, `C2dot = diag(-cos(gamma), cos(gamma)) gammadot`.
//! The stress power per unit reference area is `P = N : C2dot / 2` (docs/model.md §4), and the
//! crosshead force is the power of every zone over the crosshead speed:
//! - picture frame: the whole fabric square `L_fabric^2` at the frame's angle;
//! - bias extension (Cao et al. 2008): zone C of area `W (H - 3W/2)` at `gamma`, zone B of area
//!   `W^2` at `gamma/2` (and half its rate), zone A undeformed; the areas are the ones behind
//!   the normalisation of docs/model.md §5 (`experiment::kinematics::bias_extension_force`).
//!
//! The viscous matrix remembers its thickness rate, so each zone is followed from `d = 0` in
//! small steps of shear angle, not only at the data points.

use super::shear::{ForceCurve, ShearTest};
use crate::experiment::kinematics::{bias_extension_shear_angle, picture_frame_angles};
use crate::material::{
    FibreDirections, Laminate, LaminateState, Layer, MaterialError, MembraneKinematics,
};
use nalgebra::Matrix2;

/// Largest increment of shear angle between two states of a zone (radians): the plane-stress
/// thickness rate is a difference over one increment.
const MAX_ANGLE_STEP: f64 = 0.25 * std::f64::consts::PI / 180.0;

/// The matrix layers of a card's stack (every layer whose law is not the fabric), or `None`
/// for a dry fabric.
pub fn matrix_layers(laminate: &Laminate) -> Option<Laminate> {
    let layers: Vec<Layer> = laminate
        .layers()
        .iter()
        .filter(|l| l.law.name() != "fabric")
        .cloned()
        .collect();
    if layers.is_empty() {
        None
    } else {
        Laminate::new(layers).ok()
    }
}

/// Conditions of the test whose matrix share is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestConditions {
    /// Temperature of the specimen (°C).
    pub temperature: f64,
    /// Crosshead speed (mm/s) of the physical test.
    pub speed: f64,
}

/// One zone of the specimen that shears homogeneously: its reference area (mm²) and its shear
/// angle as a function of the crosshead displacement.
struct Zone {
    area: f64,
    angle: Box<dyn Fn(f64) -> f64>,
}

/// The homogeneously sheared zones of `test` (see the module notes).
fn zones(test: &ShearTest) -> Vec<Zone> {
    match *test {
        ShearTest::BiasExtension { width, length } => vec![
            Zone {
                area: width * (length - 1.5 * width),
                angle: Box::new(move |d| bias_extension_shear_angle(width, length, d)),
            },
            Zone {
                area: width * width,
                angle: Box::new(move |d| 0.5 * bias_extension_shear_angle(width, length, d)),
            },
        ],
        ShearTest::PictureFrame {
            frame_side,
            fabric_side,
        } => vec![Zone {
            area: fabric_side * fabric_side,
            angle: Box::new(move |d| picture_frame_angles(frame_side, d).1),
        }],
    }
}

/// Crosshead force (N) of the `matrix` layers at each of the increasing `displacements` (mm)
/// of `test`, pulled at `conditions.speed` at `conditions.temperature`.
pub fn matrix_force(
    matrix: &Laminate,
    test: &ShearTest,
    conditions: TestConditions,
    displacements: &[f64],
) -> Result<Vec<f64>, MaterialError> {
    let mut force = vec![0.0; displacements.len()];
    for zone in zones(test) {
        let power = zone_power(matrix, &zone, conditions, displacements)?;
        for (f, p) in force.iter_mut().zip(power) {
            *f += zone.area * p / conditions.speed;
        }
    }
    Ok(force)
}

/// Stress power per unit reference area (N/mm/s) of `matrix` in `zone` at each displacement,
/// following the zone from rest.
fn zone_power(
    matrix: &Laminate,
    zone: &Zone,
    conditions: TestConditions,
    displacements: &[f64],
) -> Result<Vec<f64>, MaterialError> {
    let mut state = matrix.initial_state();
    let mut reached = 0.0;
    let mut power = Vec::with_capacity(displacements.len());
    for &d in displacements {
        if d <= 0.0 {
            power.push(0.0);
            continue;
        }
        let steps = ((zone.angle)(d) - (zone.angle)(reached)).abs() / MAX_ANGLE_STEP;
        let steps = steps.ceil().max(1.0) as usize;
        let start = reached;
        let mut p = 0.0;
        for k in 1..=steps {
            let next = start + (d - start) * k as f64 / steps as f64;
            p = advance(matrix, zone, conditions, (reached, next), &mut state)?;
            reached = next;
        }
        power.push(p);
    }
    Ok(power)
}

/// Advances `state` from displacement `from` to `to` and returns the stress power per unit
/// reference area there, `P = N : C2dot / 2`.
fn advance(
    matrix: &Laminate,
    zone: &Zone,
    conditions: TestConditions,
    (from, to): (f64, f64),
    state: &mut LaminateState,
) -> Result<f64, MaterialError> {
    let gamma = (zone.angle)(to);
    let rate = angle_rate(zone, to) * conditions.speed;
    let kin = pin_jointed_kinematics(gamma, rate, conditions.temperature);
    let n = matrix
        .membrane_response(&kin, (to - from) / conditions.speed, state)?
        .n;
    Ok(0.5 * n.component_mul(&kin.c_dot).sum())
}

/// `curve` less the crosshead force of the `matrix` layers, and that force, point by point.
pub fn subtract_matrix(
    curve: &ForceCurve,
    matrix: &Laminate,
    test: &ShearTest,
    conditions: TestConditions,
) -> Result<(ForceCurve, Vec<f64>), MaterialError> {
    let share = matrix_force(matrix, test, conditions, &curve.displacement)?;
    let fabric = ForceCurve {
        force: curve.force.iter().zip(&share).map(|(f, m)| f - m).collect(),
        ..curve.clone()
    };
    Ok((fabric, share))
}

/// `dgamma/dd` of the zone by a central difference (the kinematics are smooth; the step is a
/// millionth of the displacement, at least 1e-9 mm).
fn angle_rate(zone: &Zone, d: f64) -> f64 {
    let h = (1e-6 * d).max(1e-9);
    ((zone.angle)(d + h) - (zone.angle)((d - h).max(0.0))) / (d + h - (d - h).max(0.0))
}

/// In-plane kinematics of pin-jointed shear by `gamma` at rate `gamma_rate`, pulled along `y`
/// (see the module notes); the reference yarns at ±45° to `y`.
pub fn pin_jointed_kinematics(gamma: f64, gamma_rate: f64, temperature: f64) -> MembraneKinematics {
    let theta = 0.25 * std::f64::consts::PI - 0.5 * gamma;
    let (s, c) = theta.sin_cos();
    let cos_gamma = gamma.cos();
    MembraneKinematics {
        c: Matrix2::new(2.0 * s * s, 0.0, 0.0, 2.0 * c * c),
        c_dot: Matrix2::new(-cos_gamma, 0.0, 0.0, cos_gamma) * gamma_rate,
        temperature: temperature.into(),
        fibres: FibreDirections::in_plane(std::f64::consts::FRAC_PI_4),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::kinematics::bias_extension_displacement;
    use crate::material::MaterialCard;

    /// A prepreg whose skins have the given `eta1` (MPa·s) at 300 °C.
    fn prepreg(eta1: f64) -> MaterialCard {
        let text = format!(
            "name = \"test\"\ndensity = 1.0e-9\n[layers]\nmatrix_thickness = 0.05\n\
             fabric_thickness = 0.3\n[matrix]\ntemperature = [300.0]\nc10 = [0.05]\n\
             d1 = [1.3333e-3]\neta1 = [{eta1:?}]\n[fabric]\nwarp_tension = [2.0e4]\n\
             weft_tension = [2.0e4]\nshear = [0.1, 0.0, 0.5]\n"
        );
        MaterialCard::from_toml(&text, "test card").unwrap()
    }

    const BIAS: ShearTest = ShearTest::BiasExtension {
        width: 50.0,
        length: 150.0,
    };
    const FRAME: ShearTest = ShearTest::PictureFrame {
        frame_side: 150.0,
        fabric_side: 130.0,
    };

    /// Stored energy (N·mm) of the matrix layers of every zone at displacement `d`.
    fn stored_energy(matrix: &Laminate, test: &ShearTest, d: f64) -> f64 {
        zones(test)
            .iter()
            .map(|zone| {
                let kin = pin_jointed_kinematics((zone.angle)(d), 0.0, 300.0);
                let mut state = matrix.initial_state();
                matrix.membrane_response(&kin, 0.0, &mut state).unwrap();
                zone.area * matrix.stored_energy(&kin, &state).unwrap()
            })
            .sum()
    }

    #[test]
    fn a_dry_fabric_has_no_matrix_layers_and_a_prepreg_two() {
        let card = prepreg(0.0);
        assert_eq!(matrix_layers(&card.laminate).unwrap().layers().len(), 2);
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("materials/twintex-plain-weave.toml");
        let twintex = MaterialCard::load(&path).unwrap();
        assert!(matrix_layers(&twintex.laminate).is_none());
    }

    #[test]
    fn pin_jointed_shear_keeps_the_yarn_lengths_and_gives_det_f_cos_gamma() {
        let gamma = 0.6;
        let kin = pin_jointed_kinematics(gamma, 0.0, 300.0);
        let yarn = nalgebra::Vector2::new(1.0, 1.0) / 2f64.sqrt();
        assert!(((yarn.transpose() * kin.c * yarn)[0] - 1.0).abs() < 1e-14);
        assert!((kin.c.determinant().sqrt() - gamma.cos()).abs() < 1e-14);
        let h = 1e-6;
        let difference = (pin_jointed_kinematics(gamma + h, 0.0, 300.0).c
            - pin_jointed_kinematics(gamma - h, 0.0, 300.0).c)
            / (2.0 * h);
        let rate = pin_jointed_kinematics(gamma, 1.0, 300.0).c_dot;
        assert!((difference - rate).norm() < 1e-8);
    }

    /// Without viscosity the crosshead force is the derivative of the stored energy.
    #[test]
    fn elastic_matrix_force_is_the_derivative_of_its_stored_energy() {
        let matrix = matrix_layers(&prepreg(0.0).laminate).unwrap();
        let conditions = TestConditions {
            temperature: 300.0,
            speed: 1.0,
        };
        for test in [BIAS, FRAME] {
            let d_max = match test {
                ShearTest::BiasExtension { width, length } => {
                    bias_extension_displacement(width, length, 50f64.to_radians())
                }
                ShearTest::PictureFrame { .. } => 60.0,
            };
            let d: Vec<f64> = (1..=10).map(|k| d_max * k as f64 / 10.0).collect();
            let force = matrix_force(&matrix, &test, conditions, &d).unwrap();
            for (&d, &f) in d.iter().zip(&force) {
                let h = 1e-4 * d;
                let derivative = (stored_energy(&matrix, &test, d + h)
                    - stored_energy(&matrix, &test, d - h))
                    / (2.0 * h);
                assert!(
                    (f - derivative).abs() < 1e-5 * derivative.abs(),
                    "{test:?} d = {d}: force {f} against dE/dd {derivative}"
                );
            }
        }
    }

    /// The viscous stress goes with the rate, so the force above the elastic one doubles when
    /// the crosshead is twice as fast (within the small change of the thickness rate).
    #[test]
    fn viscous_share_goes_with_the_crosshead_speed() {
        let viscous = matrix_layers(&prepreg(5.0).laminate).unwrap();
        let elastic = matrix_layers(&prepreg(0.0).laminate).unwrap();
        let d: Vec<f64> = (1..=8).map(|k| 5.0 * k as f64).collect();
        let at = |matrix: &Laminate, speed: f64| {
            let conditions = TestConditions {
                temperature: 300.0,
                speed,
            };
            matrix_force(matrix, &FRAME, conditions, &d).unwrap()
        };
        let base = at(&elastic, 1.0);
        let (slow, fast) = (at(&viscous, 0.5), at(&viscous, 1.0));
        for i in 0..d.len() {
            let (v1, v2) = (slow[i] - base[i], fast[i] - base[i]);
            assert!(v1 > 0.0);
            assert!(
                (v2 / v1 - 2.0).abs() < 0.01,
                "d = {}: viscous share {v1} N at 0.5 mm/s, {v2} N at 1 mm/s",
                d[i]
            );
        }
        let last = d.len() - 1;
        assert!(
            slow[last] - base[last] > 0.2 * base[last],
            "viscous share too small to test"
        );
    }
}
