//! The lamination model A:B:A (docs/model.md §4): perfectly bonded layers sharing the in-plane
//! deformation, each in plane stress, summed into the membrane resultant `N = sum_k t_k S2_k`.
//!
//! State variables, per layer `k`: the thickness stretch `lambda3_k` and its rate at the end of
//! the last converged step ([`LaminateState`]); the viscous matrix needs the rate because its
//! through-thickness stress depends on `Cdot33 = 2 lambda3 lambda3dot`.

use super::stress_free_stretch::{find_stress_free_stretch_probed, Evaluation, StressSample};
use super::{
    FibreDirections, MaterialError, MaterialLaw, PointKinematics, StepModuli, ThicknessRule,
    ThroughThicknessTangent,
};
use nalgebra::{Matrix2, Matrix3, Matrix3x2};
use std::sync::Arc;

/// Plane-stress iterations stop when `|S33|` is below this fraction of the in-plane stress.
const PLANE_STRESS_TOLERANCE: f64 = 1e-12;

/// One layer of the stack: its law and reference thickness (mm).
#[derive(Clone, Debug)]
pub struct Layer {
    pub law: Arc<dyn MaterialLaw>,
    pub thickness: f64,
}

/// A stack of perfectly bonded layers, by default matrix : fabric : matrix.
#[derive(Clone, Debug)]
pub struct Laminate {
    layers: Vec<Layer>,
    /// Indices of the layers that share one law object, in stack order. Layers of a group that
    /// start a step in the same state end it in the same state (the law sees no thickness), so
    /// the plane-stress solve is done once per group: the two skins of A:B:A cost one.
    groups: Vec<Vec<usize>>,
}

/// A layer's thickness stretch, its rate and its stress after a step.
struct LayerSolution {
    lambda3: f64,
    rate: f64,
    s: Matrix3<f64>,
}

/// The most layers a laminate may have where each layer has its own temperature.
pub const MAX_LAYERS: usize = 8;

/// The temperature of each layer of the stack at one point (°C): one for the whole stack (an
/// isothermal run), or each layer its own (a non-isothermal run, docs/model.md §9: a matrix
/// skin on a cold tool is colder than the fabric under it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerTemperatures {
    values: [f64; MAX_LAYERS],
    /// 0 for one temperature for every layer, `values[0]`.
    len: usize,
}

impl LayerTemperatures {
    /// Every layer at `temperature`.
    pub fn uniform(temperature: f64) -> Self {
        Self {
            values: [temperature; MAX_LAYERS],
            len: 0,
        }
    }

    /// Layer `k` at `values[k]`; at most [`MAX_LAYERS`] layers (a longer list is an error).
    pub fn per_layer(values: &[f64]) -> Result<Self, String> {
        if values.is_empty() || values.len() > MAX_LAYERS {
            return Err(format!(
                "a temperature per layer needs 1 to {MAX_LAYERS} layers, not {}",
                values.len()
            ));
        }
        let mut all = [values[0]; MAX_LAYERS];
        all[..values.len()].copy_from_slice(values);
        Ok(Self {
            values: all,
            len: values.len(),
        })
    }

    /// The temperature of layer `k`.
    pub fn layer(&self, k: usize) -> f64 {
        match self.len {
            0 => self.values[0],
            _ => self.values[k],
        }
    }
}

impl From<f64> for LayerTemperatures {
    fn from(temperature: f64) -> Self {
        Self::uniform(temperature)
    }
}

/// In-plane kinematics of the sheet in an orthonormal local basis `(e1, e2)` of the reference
/// tangent plane (docs/model.md §1).
#[derive(Clone, Copy, Debug)]
pub struct MembraneKinematics {
    /// `C2 = F^T F` (2x2).
    pub c: Matrix2<f64>,
    /// `C2dot = Fdot^T F + F^T Fdot` (2x2).
    pub c_dot: Matrix2<f64>,
    /// Temperature of each layer, °C.
    pub temperature: LayerTemperatures,
    /// Warp and weft in the local basis (third components zero).
    pub fibres: FibreDirections,
}

impl MembraneKinematics {
    /// From the in-plane deformation gradient `F` (3x2: local reference coordinates to current
    /// 3D positions) and its rate.
    pub fn from_deformation(
        f: &Matrix3x2<f64>,
        f_dot: &Matrix3x2<f64>,
        temperature: impl Into<LayerTemperatures>,
        fibres: FibreDirections,
    ) -> Self {
        Self {
            c: f.transpose() * f,
            c_dot: f_dot.transpose() * f + f.transpose() * f_dot,
            temperature: temperature.into(),
            fibres,
        }
    }

    /// Layer `k`'s 3D kinematics, `C = diag-block(C2, lambda3^2)` (docs/model.md §1), at its
    /// temperature.
    pub fn layer_point(&self, k: usize, lambda3: f64, lambda3_rate: f64) -> PointKinematics {
        let mut c = Matrix3::zeros();
        let mut c_dot = Matrix3::zeros();
        c.fixed_view_mut::<2, 2>(0, 0).copy_from(&self.c);
        c_dot.fixed_view_mut::<2, 2>(0, 0).copy_from(&self.c_dot);
        c[(2, 2)] = lambda3 * lambda3;
        c_dot[(2, 2)] = 2.0 * lambda3 * lambda3_rate;
        PointKinematics {
            c,
            c_dot,
            temperature: self.temperature.layer(k),
            fibres: self.fibres,
        }
    }
}

/// One backward-Euler step of an element's in-plane kinematics: `C` at its end, `C` at its
/// start, its duration (s), the temperature and the yarns.
#[derive(Clone, Copy, Debug)]
pub struct BackwardEulerStep {
    pub c: Matrix2<f64>,
    pub c_start: Matrix2<f64>,
    pub dt: f64,
    pub temperature: LayerTemperatures,
    pub fibres: FibreDirections,
}

impl BackwardEulerStep {
    /// The kinematics at `c`, with the rate `(c - C_start) / dt`.
    pub fn kinematics(&self, c: &Matrix2<f64>) -> MembraneKinematics {
        MembraneKinematics {
            c: *c,
            c_dot: (c - self.c_start) / self.dt,
            temperature: self.temperature,
            fibres: self.fibres,
        }
    }
}

/// Step in the Green strain of the central differences of
/// [`Laminate::differenced_step_tangent`], 1e-5: the plane-stress solve's tolerance (1e-12 of
/// the stress) over `h` sets its error, which at 1e-6 reached 1e-5 of the tangent on a nearly
/// incompressible melt; the truncation error `h^2` stays far below.
const TANGENT_STEP: f64 = 1e-5;

/// The changes of the in-plane `C` of a unit change of each Voigt strain `(E11, E22, 2 E12)`.
const STRAIN_UNITS: [Matrix2<f64>; 3] = [
    Matrix2::new(2.0, 0.0, 0.0, 0.0),
    Matrix2::new(0.0, 0.0, 0.0, 2.0),
    Matrix2::new(0.0, 1.0, 1.0, 0.0),
];

/// The laminate's state variables at one point: per layer, `lambda3` and `dlambda3/dt`.
#[derive(Clone, Debug, PartialEq)]
pub struct LaminateState {
    pub thickness_stretch: Vec<f64>,
    pub thickness_stretch_rate: Vec<f64>,
}

/// Membrane response of the laminate at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MembraneResponse {
    /// 2nd Piola–Kirchhoff membrane resultant per unit reference width (N/mm), docs/model.md §4.
    pub n: Matrix2<f64>,
    /// Current thickness `t = sum_k t_k lambda3_k` (mm).
    pub thickness: f64,
}

impl Laminate {
    /// A stack of `layers`, each with a positive finite thickness.
    pub fn new(layers: Vec<Layer>) -> Result<Self, String> {
        if layers.is_empty() {
            return Err("a laminate needs at least one layer".into());
        }
        if let Some((k, layer)) = layers
            .iter()
            .enumerate()
            .find(|(_, l)| !(l.thickness.is_finite() && l.thickness > 0.0))
        {
            return Err(format!(
                "layer {k} ({}) has thickness {} mm; it must be > 0",
                layer.law.name(),
                layer.thickness
            ));
        }
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for (k, layer) in layers.iter().enumerate() {
            match groups
                .iter_mut()
                .find(|g| Arc::ptr_eq(&layers[g[0]].law, &layer.law))
            {
                Some(group) => group.push(k),
                None => groups.push(vec![k]),
            }
        }
        Ok(Self { layers, groups })
    }

    /// The A:B:A stack of the lamination model: `matrix (t_A) : fabric (t_B) : matrix (t_A)`.
    pub fn matrix_fabric_matrix(
        matrix: Arc<dyn MaterialLaw>,
        matrix_thickness: f64,
        fabric: Arc<dyn MaterialLaw>,
        fabric_thickness: f64,
    ) -> Result<Self, String> {
        Self::new(vec![
            Layer {
                law: matrix.clone(),
                thickness: matrix_thickness,
            },
            Layer {
                law: fabric,
                thickness: fabric_thickness,
            },
            Layer {
                law: matrix,
                thickness: matrix_thickness,
            },
        ])
    }

    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// Sum of the layers' reference thicknesses (mm).
    pub fn reference_thickness(&self) -> f64 {
        self.layers.iter().map(|l| l.thickness).sum()
    }

    /// The undeformed state: every `lambda3 = 1`, at rest.
    pub fn initial_state(&self) -> LaminateState {
        LaminateState {
            thickness_stretch: vec![1.0; self.layers.len()],
            thickness_stretch_rate: vec![0.0; self.layers.len()],
        }
    }

    /// Advances `state` to the kinematics `kin`, reached `dt` seconds after the state's, and
    /// returns the membrane resultant and thickness (docs/model.md §4).
    ///
    /// Each layer's thickness stretch follows its [`ThicknessRule`]; with `dt = 0` the
    /// thickness rate is taken as zero.
    pub fn membrane_response(
        &self,
        kin: &MembraneKinematics,
        dt: f64,
        state: &mut LaminateState,
    ) -> Result<MembraneResponse, MaterialError> {
        self.groups
            .iter()
            .try_fold(MembraneResponse::default(), |sum, group| {
                let part = self.advance_group(group, kin, dt, state)?;
                Ok(MembraneResponse {
                    n: sum.n + part.n,
                    thickness: sum.thickness + part.thickness,
                })
            })
    }

    /// [`Self::membrane_response`] of the layers of one group: they share a law, and a solve
    /// where they share the state too.
    fn advance_group(
        &self,
        group: &[usize],
        kin: &MembraneKinematics,
        dt: f64,
        state: &mut LaminateState,
    ) -> Result<MembraneResponse, MaterialError> {
        let mut response = MembraneResponse::default();
        let previous = state.thickness_stretch[group[0]];
        let shared = self.solve_layer(group[0], kin, previous, dt)?;
        for &k in group {
            let own;
            let solution = if state.thickness_stretch[k] == previous
                && kin.temperature.layer(k) == kin.temperature.layer(group[0])
            {
                &shared
            } else {
                own = self.solve_layer(k, kin, state.thickness_stretch[k], dt)?;
                &own
            };
            state.thickness_stretch[k] = solution.lambda3;
            state.thickness_stretch_rate[k] = solution.rate;
            let t_k = self.layers[k].thickness;
            response.n += solution.s.fixed_view::<2, 2>(0, 0) * t_k;
            response.thickness += t_k * solution.lambda3;
        }
        Ok(response)
    }

    /// The membrane resultant after a backward-Euler step (docs/solver.md, "Implicit"): the
    /// in-plane `C` reached `dt` after `c_start`, the rate `Cdot = (C - C_start) / dt`, each
    /// layer's thickness advanced from `start`. Returns the response, the advanced state and
    /// the tangent `D = dN/dE` in the order `(E11, E22, 2 E12)` (N/mm), from each layer's
    /// stress derivatives with its thickness stretch following its rule
    /// ([`Self::layer_tangent`]); by central differences of the response
    /// ([`Self::differenced_step_tangent`]) for a law that has none.
    pub fn step_tangent(
        &self,
        step: &BackwardEulerStep,
        start: &LaminateState,
    ) -> Result<(MembraneResponse, LaminateState, Matrix3<f64>), MaterialError> {
        let mut state = start.clone();
        let kin = step.kinematics(&step.c);
        let response = self.membrane_response(&kin, step.dt, &mut state)?;
        let d = self.advanced_step_tangent(step, start, &state)?;
        Ok((response, state, d))
    }

    /// The tangent of [`Self::step_tangent`] where the step's response is known: `state` is
    /// `start` advanced over `step`.
    pub fn advanced_step_tangent(
        &self,
        step: &BackwardEulerStep,
        start: &LaminateState,
        state: &LaminateState,
    ) -> Result<Matrix3<f64>, MaterialError> {
        let kin = step.kinematics(&step.c);
        let mut d = Matrix3::zeros();
        for group in &self.groups {
            d += match self.group_tangent(group, &kin, step.dt, state)? {
                Some(tangent) => tangent,
                None => self.differenced_group_tangent(group, step, start)?,
            };
        }
        Ok(d)
    }

    /// `dN/dE` of one group's layers from [`Self::layer_tangent`], computed once for the
    /// layers that share a state; `None` if a layer has none.
    fn group_tangent(
        &self,
        group: &[usize],
        kin: &MembraneKinematics,
        dt: f64,
        state: &LaminateState,
    ) -> Result<Option<Matrix3<f64>>, MaterialError> {
        let mut d = Matrix3::zeros();
        let mut last: Option<(usize, Matrix3<f64>)> = None;
        for &k in group {
            let shares_state = |j: usize| shares_point(kin, state, j, k);
            let tangent = match last.filter(|(j, _)| shares_state(*j)) {
                Some((_, tangent)) => tangent,
                None => match self.layer_tangent(k, kin, dt, state)? {
                    Some(tangent) => tangent,
                    None => return Ok(None),
                },
            };
            d += tangent * self.layers[k].thickness;
            last = Some((k, tangent));
        }
        Ok(Some(d))
    }

    /// `dS/dE` of layer `k`'s in-plane stress `(S11, S22, S12)` in `(E11, E22, 2 E12)` (MPa)
    /// in a state advanced to `kin` (docs/solver.md, "Laminate tangent"): the law's stress
    /// derivatives along each in-plane strain (its rate `dC / dt` with it) and along the
    /// thickness stretch (`dC33 = 2 lambda3`, `dCdot33 = 2 rate + 2 lambda3 / dt`), the
    /// stretch following its rule: `dlambda3 = -dS33 / (dS33/dlambda3)` in plane stress (the
    /// static condensation of `S33 = 0`), `-lambda3 tr(C2^-1 dC2) / 2` for a layer that keeps
    /// its volume. `None` where the law has no derivatives or its `S33` does not move with the
    /// thickness.
    fn layer_tangent(
        &self,
        k: usize,
        kin: &MembraneKinematics,
        dt: f64,
        state: &LaminateState,
    ) -> Result<Option<Matrix3<f64>>, MaterialError> {
        let (lambda3, rate) = (state.thickness_stretch[k], state.thickness_stretch_rate[k]);
        let point = kin.layer_point(k, lambda3, rate);
        let per_second = if dt > 0.0 { dt.recip() } else { 0.0 };
        let in_plane = |c2: Matrix2<f64>| {
            let mut dc = Matrix3::zeros();
            dc.fixed_view_mut::<2, 2>(0, 0).copy_from(&c2);
            (dc, dc * per_second)
        };
        let through = |value: f64| Matrix3::from_diagonal(&nalgebra::Vector3::new(0.0, 0.0, value));
        let thickness_rate_slope = if dt > 0.0 {
            2.0 * rate + 2.0 * lambda3 / dt
        } else {
            0.0
        };
        let directions = [
            in_plane(STRAIN_UNITS[0]),
            in_plane(STRAIN_UNITS[1]),
            in_plane(STRAIN_UNITS[2]),
            (through(2.0 * lambda3), through(thickness_rate_slope)),
        ];
        let mut ds = [Matrix3::zeros(); 4];
        let law = &self.layers[k].law;
        if !law.stress_derivatives(&point, &directions, &mut ds)? {
            return Ok(None);
        }
        let stretch_change: [f64; 3] = match law.thickness_rule() {
            ThicknessRule::PlaneStress => {
                let slope = ds[3][(2, 2)];
                if !(slope.is_finite() && slope != 0.0) {
                    return Ok(None);
                }
                std::array::from_fn(|j| -ds[j][(2, 2)] / slope)
            }
            ThicknessRule::VolumeConserving => {
                let c2_inv = kin.c.try_inverse().unwrap_or_else(Matrix2::zeros);
                STRAIN_UNITS.map(|u| -0.5 * lambda3 * (c2_inv * u).trace())
            }
        };
        let columns: [nalgebra::Vector3<f64>; 3] = std::array::from_fn(|j| {
            let total = ds[j] + ds[3] * stretch_change[j];
            nalgebra::Vector3::new(total[(0, 0)], total[(1, 1)], total[(0, 1)])
        });
        Ok(Some(Matrix3::from_columns(&columns)))
    }

    /// [`Self::step_tangent`] with every group's tangent by central differences of its
    /// response in `E` (step [`TANGENT_STEP`]): the reference its derivatives are checked
    /// against, and the tangent of laws without derivatives.
    pub fn differenced_step_tangent(
        &self,
        step: &BackwardEulerStep,
        start: &LaminateState,
    ) -> Result<Matrix3<f64>, MaterialError> {
        self.groups.iter().try_fold(Matrix3::zeros(), |d, group| {
            Ok(d + self.differenced_group_tangent(group, step, start)?)
        })
    }

    /// `dN/dE` of one group's layers by central differences of their response (step
    /// [`TANGENT_STEP`]), each probe advanced from `start`.
    fn differenced_group_tangent(
        &self,
        group: &[usize],
        step: &BackwardEulerStep,
        start: &LaminateState,
    ) -> Result<Matrix3<f64>, MaterialError> {
        let mut d = Matrix3::zeros();
        for (column, unit) in STRAIN_UNITS.iter().enumerate() {
            let at = |sign: f64| {
                let c = step.c + unit * (sign * TANGENT_STEP);
                let mut probe = start.clone();
                self.advance_group(group, &step.kinematics(&c), step.dt, &mut probe)
                    .map(|r| r.n)
            };
            let difference = (at(1.0)? - at(-1.0)?) / (2.0 * TANGENT_STEP);
            d.set_column(
                column,
                &nalgebra::Vector3::new(
                    difference[(0, 0)],
                    difference[(1, 1)],
                    0.5 * (difference[(0, 1)] + difference[(1, 0)]),
                ),
            );
        }
        Ok(d)
    }

    /// Thickness-weighted mean of the layers' wave moduli (MPa) in an advanced state: with the
    /// ply's density it gives the membrane wave speed that sets the stable time step.
    pub fn wave_modulus(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<f64, MaterialError> {
        let [wave] =
            self.thickness_mean(kin, state, |law, point| Ok([law.wave_modulus(point)?]))?;
        Ok(wave)
    }

    /// Thickness-weighted mean of the layers' viscous moduli (MPa·s) in an advanced state:
    /// with the wave modulus it gives the damping of the element's highest mode.
    pub fn viscous_modulus(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<f64, MaterialError> {
        let [viscous] =
            self.thickness_mean(kin, state, |law, point| Ok([law.viscous_modulus(point)?]))?;
        Ok(viscous)
    }

    /// [`Self::wave_modulus`] and [`Self::viscous_modulus`] in one pass over the layers, the
    /// same numbers: the explicit solver needs both for every element at every step.
    pub fn step_moduli(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<StepModuli, MaterialError> {
        let [wave, viscous] = self.thickness_mean(kin, state, |law, point| {
            let moduli = law.step_moduli(point)?;
            Ok([moduli.wave, moduli.viscous])
        })?;
        Ok(StepModuli { wave, viscous })
    }

    /// `sum_k t_k f(law_k, point_k) / t0`, evaluated once for the layers of a group that share
    /// their state and temperature.
    fn thickness_mean<const N: usize>(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
        f: impl Fn(&dyn MaterialLaw, &PointKinematics) -> Result<[f64; N], MaterialError>,
    ) -> Result<[f64; N], MaterialError> {
        let mut sum = [0.0; N];
        for group in &self.groups {
            let mut last: Option<(usize, [f64; N])> = None;
            for &k in group {
                let value = match last.filter(|(j, _)| shares_point(kin, state, *j, k)) {
                    Some((_, value)) => value,
                    None => {
                        let point = kin.layer_point(
                            k,
                            state.thickness_stretch[k],
                            state.thickness_stretch_rate[k],
                        );
                        f(self.layers[k].law.as_ref(), &point)?
                    }
                };
                for (s, v) in sum.iter_mut().zip(value) {
                    *s += self.layers[k].thickness * v;
                }
                last = Some((k, value));
            }
        }
        let t0 = self.reference_thickness();
        Ok(sum.map(|s| s / t0))
    }

    /// Initial in-plane shear modulus (MPa) in the frame of the yarns: the secant of a simple
    /// shear of 1e-3 rad, `N12 / (t0 gamma)`, rates zero. With the density it gives the slowest
    /// wave of a sheet at rest, `sqrt(G / rho)`, the speed a quasi-static test must stay far
    /// below.
    pub fn shear_modulus(&self, temperature: f64) -> Result<f64, MaterialError> {
        const GAMMA: f64 = 1e-3;
        let f = Matrix3x2::new(1.0, GAMMA, 0.0, 1.0, 0.0, 0.0);
        let kin = MembraneKinematics::from_deformation(
            &f,
            &Matrix3x2::zeros(),
            temperature,
            FibreDirections::default(),
        );
        let response = self.membrane_response(&kin, 0.0, &mut self.initial_state())?;
        Ok(response.n[(0, 1)] / (self.reference_thickness() * GAMMA))
    }

    /// The laminate for a process run `speed_up` times faster (docs/model.md §6): every law
    /// time-scaled, layers that shared a law still sharing one.
    pub fn time_scaled(&self, speed_up: f64) -> Self {
        self.with_laws(|law| law.time_scaled(speed_up))
    }

    /// The laminate for an isothermal run at `temperature` (see
    /// [`MaterialLaw::at_temperature`]): the same numbers at that temperature, computed without
    /// interpolating the parameter tables at every point; other temperatures work as before.
    pub fn at_temperature(&self, temperature: f64) -> Self {
        self.with_laws(|law| {
            law.at_temperature(temperature)
                .unwrap_or_else(|| Arc::clone(law))
        })
    }

    /// Every group's law replaced by `replace(law)`, layers that shared a law still sharing one.
    fn with_laws(&self, replace: impl Fn(&Arc<dyn MaterialLaw>) -> Arc<dyn MaterialLaw>) -> Self {
        let mut layers = self.layers.clone();
        for group in &self.groups {
            let replaced = replace(&self.layers[group[0]].law);
            for &k in group {
                layers[k].law = replaced.clone();
            }
        }
        Self {
            layers,
            groups: self.groups.clone(),
        }
    }

    /// 3D stress `S` of layer `k` for the kinematics and a state already advanced to them.
    /// The yarn tensions of the sheet, warp and weft (N/mm: force per unit reference width
    /// across the yarns), the sum over the layers with yarns of their reference thickness times
    /// [`MaterialLaw::yarn_tensions`] (docs/model.md §4).
    pub fn yarn_tensions(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<[f64; 2], MaterialError> {
        let mut sum = [0.0; 2];
        for (k, layer) in self.layers.iter().enumerate() {
            let point = kin.layer_point(
                k,
                state.thickness_stretch[k],
                state.thickness_stretch_rate[k],
            );
            if let Some(t) = layer.law.yarn_tensions(&point)? {
                sum[0] += layer.thickness * t[0];
                sum[1] += layer.thickness * t[1];
            }
        }
        Ok(sum)
    }

    pub fn layer_stress(
        &self,
        k: usize,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<Matrix3<f64>, MaterialError> {
        let point = kin.layer_point(
            k,
            state.thickness_stretch[k],
            state.thickness_stretch_rate[k],
        );
        self.layers[k].law.second_piola_kirchhoff(&point)
    }

    /// The incremental potential of a backward-Euler step of `dt` per unit reference area,
    /// `sum_k t_k (W_k + dt psi_k)` (N/mm), in a state advanced to `kin`: its derivative in `C`
    /// is half the membrane resultant, what the implicit solver's line search lowers.
    pub fn incremental_potential(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
        dt: f64,
    ) -> Result<f64, MaterialError> {
        self.layer_sum(kin, state, |law, point| {
            Ok(law.strain_energy(point)? + dt * law.viscous_potential(point)?)
        })
    }

    /// Stored energy per unit reference area, `sum_k t_k W_k` (N/mm), in an advanced state.
    pub fn stored_energy(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
    ) -> Result<f64, MaterialError> {
        self.layer_sum(kin, state, |law, point| law.strain_energy(point))
    }

    /// `sum_k t_k f(law_k, point_k)` over every layer in an advanced state.
    fn layer_sum(
        &self,
        kin: &MembraneKinematics,
        state: &LaminateState,
        f: impl Fn(&dyn MaterialLaw, &PointKinematics) -> Result<f64, MaterialError>,
    ) -> Result<f64, MaterialError> {
        self.layers
            .iter()
            .enumerate()
            .try_fold(0.0, |sum, (k, layer)| {
                let point = kin.layer_point(
                    k,
                    state.thickness_stretch[k],
                    state.thickness_stretch_rate[k],
                );
                Ok(sum + layer.thickness * f(layer.law.as_ref(), &point)?)
            })
    }

    /// Thickness stretch of layer `k` by its [`ThicknessRule`], with the stress it gives.
    fn solve_layer(
        &self,
        k: usize,
        kin: &MembraneKinematics,
        previous: f64,
        dt: f64,
    ) -> Result<LayerSolution, MaterialError> {
        let det_c2 = kin.c.determinant();
        if det_c2.is_nan() || det_c2 <= 0.0 {
            return Err(MaterialError::NonPositiveVolume { det_c: det_c2 });
        }
        let law = &self.layers[k].law;
        let stress_at = |lambda3: f64| {
            let rate = thickness_rate(lambda3, previous, dt);
            let s = law.second_piola_kirchhoff(&kin.layer_point(k, lambda3, rate))?;
            Ok(LayerSolution { lambda3, rate, s })
        };
        match law.thickness_rule() {
            ThicknessRule::VolumeConserving => stress_at(det_c2.sqrt().recip()),
            ThicknessRule::PlaneStress => {
                // The root is an iterate whose residual was evaluated, normally the last one.
                let mut last: Option<LayerSolution> = None;
                let s33 = |lambda3: f64, evaluation| match evaluation {
                    // The slope probe reads `S33` alone, which the law may compute cheaply.
                    Evaluation::SlopeProbe => {
                        let rate = thickness_rate(lambda3, previous, dt);
                        let point = kin.layer_point(k, lambda3, rate);
                        let sample = StressSample {
                            value: law.through_thickness_stress(&point)?,
                            scale: f64::NAN,
                        };
                        Ok((sample, None))
                    }
                    // With the law's tangent the slope is exact and no probe is needed.
                    Evaluation::Residual => {
                        let rate = thickness_rate(lambda3, previous, dt);
                        let (s, tangent) = law.stress_with_through_thickness_tangent(
                            &kin.layer_point(k, lambda3, rate),
                        )?;
                        let sample = StressSample {
                            value: s[(2, 2)],
                            scale: s.fixed_view::<2, 2>(0, 0).amax(),
                        };
                        let slope = tangent.map(|t| thickness_slope(&t, lambda3, rate, dt));
                        last = Some(LayerSolution { lambda3, rate, s });
                        Ok((sample, slope))
                    }
                };
                let lambda3 =
                    find_stress_free_stretch_probed(s33, previous, PLANE_STRESS_TOLERANCE)?
                        .map_err(|failure| MaterialError::PlaneStressNotConverged {
                            layer: k,
                            law: law.name(),
                            iterations: failure.iterations,
                            lambda3: failure.stretch,
                            s33: failure.residual,
                        })?;
                match last.filter(|s| s.lambda3 == lambda3) {
                    Some(solution) => Ok(solution),
                    None => stress_at(lambda3),
                }
            }
        }
    }
}

/// Whether layers `j` and `k` are at the same point: the same thickness stretch, rate and
/// temperature (layers of one law then have the same stress).
fn shares_point(kin: &MembraneKinematics, state: &LaminateState, j: usize, k: usize) -> bool {
    state.thickness_stretch[j] == state.thickness_stretch[k]
        && state.thickness_stretch_rate[j] == state.thickness_stretch_rate[k]
        && kin.temperature.layer(j) == kin.temperature.layer(k)
}

/// `dS33/dlambda3` along the layer's path: `C33 = lambda3^2` and, with the backward-difference
/// rate, `Cdot33 = 2 lambda3 (lambda3 - previous) / dt`, whose derivative is
/// `2 rate + 2 lambda3 / dt` (zero for a step of no duration, where the rate is held at zero).
fn thickness_slope(tangent: &ThroughThicknessTangent, lambda3: f64, rate: f64, dt: f64) -> f64 {
    let d_c_dot33 = if dt > 0.0 {
        2.0 * rate + 2.0 * lambda3 / dt
    } else {
        0.0
    };
    tangent.wrt_c33 * 2.0 * lambda3 + tangent.wrt_c_dot33 * d_c_dot33
}

/// Backward-difference thickness rate; zero for a step of no duration.
fn thickness_rate(lambda3: f64, previous: f64, dt: f64) -> f64 {
    if dt > 0.0 {
        (lambda3 - previous) / dt
    } else {
        0.0
    }
}
