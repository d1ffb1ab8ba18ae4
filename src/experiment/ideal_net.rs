//! Equilibrium of the bias-extension specimen as an ideal (inextensible) net with a shear
//! energy: the reference solution the finite-element bias test is checked against.
//!
//! The pin-jointed prediction of docs/model.md §5 assumes three zones of uniform shear. With
//! inextensible yarns, the deformed net is a Tchebychev net: the warp direction `alpha` can
//! only depend on the position `m = x + y` along the warp, the weft direction `beta` only on
//! the position `k = y - x` along the weft (compatibility of `r_m` and `r_k`). Yarn positions
//! whose warp or weft crosses a clamp keep their direction, so only the band `|m| < D/2`
//! (`D = length - width`) is free. The three-zone field is one member of this family: the
//! one with `alpha` uniform over the band. The equilibrium is the member that minimises the
//! shear energy at the imposed clamp displacement, and it is uniform only when the shear
//! force does not grow with the angle: for a fabric whose shear force rises with the angle,
//! the yarn positions crossing the long centre of zone C rotate less than those crossing its
//! short ends, and the centre shears less than the pin-jointed formula says.
//!
//! With the warp turned by `a(m)` and (by the mirror symmetry of the specimen) the weft by
//! `a(k)`, the shear angle is `a(m) + a(k)`, the clamp displacement is
//! `d = sqrt(2) * int_{|m|<D/2} [sin(pi/4 + a(m)) - sin(pi/4)] dm`, and the energy is the
//! integral of the areal shear energy over the specimen (`dx dy = dm dk / 2`). The band is cut
//! into cells of constant `a`; the energy is minimised at fixed `d` by Newton's method on the
//! Lagrangian.

use nalgebra::{DMatrix, DVector};
use std::f64::consts::{FRAC_PI_4, SQRT_2};

/// Areal shear energy of the net in trellis shear `gamma` and its first two derivatives with
/// respect to `gamma`: `[W, dW/dgamma, d2W/dgamma2]` per unit reference area.
pub trait TrellisEnergy {
    fn energy_and_derivatives(&self, gamma: f64) -> [f64; 3];
}

impl<F: Fn(f64) -> [f64; 3]> TrellisEnergy for F {
    fn energy_and_derivatives(&self, gamma: f64) -> [f64; 3] {
        self(gamma)
    }
}

/// The fabric's in-plane shear energy in trellis shear, `t W_s(sin^2 gamma)` (docs/model.md §3:
/// `I10 = sin^2 gamma`, yarns unstretched), with its derivatives in `gamma`.
pub fn fabric_trellis_energy(
    shear: &crate::material::fabric::ShearInteraction,
    thickness: f64,
) -> impl Fn(f64) -> [f64; 3] + '_ {
    move |gamma: f64| {
        let i10 = gamma.sin().powi(2);
        let di10 = (2.0 * gamma).sin();
        let d2i10 = 2.0 * (2.0 * gamma).cos();
        let (w1, w2) = (shear.derivative(i10), shear.second_derivative(i10));
        [
            thickness * shear.energy(i10),
            thickness * w1 * di10,
            thickness * (w2 * di10 * di10 + w1 * d2i10),
        ]
    }
}

/// The bias-extension specimen as an ideal net (free length `length`, `length >= 2 width`).
#[derive(Clone, Debug)]
pub struct IdealNetBias {
    pub width: f64,
    pub length: f64,
    /// Cells across the free band `|m| < D/2`; even, so that cell edges meet the specimen's
    /// free edges `|m - k| = width` on cell corners when `D / width` is a whole number.
    pub cells: usize,
}

/// The equilibrium at one clamp displacement.
#[derive(Clone, Debug)]
pub struct NetEquilibrium {
    pub displacement: f64,
    /// Yarn rotation `a` (radians) per cell of the free band, from `m = -D/2` up.
    pub rotation: Vec<f64>,
    /// Stored shear energy (per unit of the energy's area unit, e.g. N mm).
    pub energy: f64,
    /// Clamp force `dE/dd` (the Lagrange multiplier of the displacement constraint).
    pub force: f64,
    half_band: f64,
}

impl NetEquilibrium {
    /// Yarn rotation at position `s` along a yarn (`m` for the warp, `k` for the weft).
    fn rotation_at(&self, s: f64) -> f64 {
        if s.abs() >= self.half_band {
            return 0.0;
        }
        let h = 2.0 * self.half_band / self.rotation.len() as f64;
        let cell = ((s + self.half_band) / h).floor() as usize;
        self.rotation[cell.min(self.rotation.len() - 1)]
    }

    /// Shear angle (radians) at the reference point `(x, y)` of the specimen centred on the
    /// origin with the clamps at `y = -+length/2`.
    pub fn shear_angle(&self, x: f64, y: f64) -> f64 {
        self.rotation_at(x + y) + self.rotation_at(y - x)
    }
}

impl IdealNetBias {
    fn half_band(&self) -> f64 {
        0.5 * (self.length - self.width)
    }

    fn cell_size(&self) -> f64 {
        2.0 * self.half_band() / self.cells as f64
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(self.width > 0.0 && self.length >= 2.0 * self.width) {
            return Err(format!(
                "ideal net: need width > 0 and length >= 2 width, got {} x {}",
                self.width, self.length
            ));
        }
        if self.cells < 4 || !self.cells.is_multiple_of(2) {
            return Err(format!(
                "ideal net: cells must be even and >= 4, got {}",
                self.cells
            ));
        }
        Ok(())
    }

    /// Area weights of the cell pairs `(m_i, k_j)` of zone C (both yarns free) inside the
    /// specimen `|m - k| < width`, and of each free cell's zone-B part (its yarn crossing the
    /// fixed yarns). `dx dy = dm dk / 2`.
    fn zone_weights(&self) -> (DMatrix<f64>, DVector<f64>) {
        let (n, h, w) = (self.cells, self.cell_size(), self.width);
        let centre = |i: usize| -self.half_band() + (i as f64 + 0.5) * h;
        let overlap = |gap: f64| {
            // fraction of a cell pair whose centres are `gap` apart lying in |m - k| < w
            ((w - gap.abs()) / h + 0.5).clamp(0.0, 1.0)
        };
        let zone_c = DMatrix::from_fn(n, n, |i, j| 0.5 * h * h * overlap(centre(i) - centre(j)));
        let zone_b = DVector::from_fn(n, |i, _| {
            let along = 2.0 * w * h * 0.5;
            along - zone_c.row(i).sum()
        });
        (zone_c, zone_b)
    }

    fn displacement_of(&self, a: &DVector<f64>) -> f64 {
        let h = self.cell_size();
        SQRT_2
            * h
            * a.iter()
                .map(|&ai| (FRAC_PI_4 + ai).sin() - FRAC_PI_4.sin())
                .sum::<f64>()
    }

    /// Energy, gradient and Hessian of the net's shear energy in the cell rotations.
    fn energy(
        &self,
        law: &impl TrellisEnergy,
        a: &DVector<f64>,
        (zone_c, zone_b): &(DMatrix<f64>, DVector<f64>),
    ) -> (f64, DVector<f64>, DMatrix<f64>) {
        let n = a.len();
        let mut e = 0.0;
        let mut grad = DVector::zeros(n);
        let mut hess = DMatrix::zeros(n, n);
        for i in 0..n {
            // zone B: warp free, weft fixed, and its mirror image (weft free, warp fixed)
            let [w, w1, w2] = law.energy_and_derivatives(a[i]);
            e += 2.0 * zone_b[i] * w;
            grad[i] += 2.0 * zone_b[i] * w1;
            hess[(i, i)] += 2.0 * zone_b[i] * w2;
            for j in 0..n {
                let weight = zone_c[(i, j)];
                if weight == 0.0 {
                    continue;
                }
                let [w, w1, w2] = law.energy_and_derivatives(a[i] + a[j]);
                e += weight * w;
                grad[i] += 2.0 * weight * w1;
                hess[(i, j)] += 2.0 * weight * w2;
                hess[(i, i)] += 2.0 * weight * w2;
            }
        }
        (e, grad, hess)
    }

    /// Equilibria at the given clamp displacements (each `0 <= d < sqrt(2) D - D`), each
    /// started from the pin-jointed (uniform) field.
    pub fn solve(
        &self,
        law: &impl TrellisEnergy,
        displacements: &[f64],
    ) -> Result<Vec<NetEquilibrium>, String> {
        self.validate()?;
        let weights = self.zone_weights();
        displacements
            .iter()
            .map(|&d| self.solve_at(law, d, &weights))
            .collect()
    }

    fn solve_at(
        &self,
        law: &impl TrellisEnergy,
        d: f64,
        weights: &(DMatrix<f64>, DVector<f64>),
    ) -> Result<NetEquilibrium, String> {
        let big_d = self.length - self.width;
        if !(0.0..(SQRT_2 - 1.0) * big_d).contains(&d) {
            return Err(format!(
                "ideal net: displacement {d} outside [0, {:.3}) (the net locks at 90°)",
                (SQRT_2 - 1.0) * big_d
            ));
        }
        let n = self.cells;
        let uniform =
            0.5 * super::kinematics::bias_extension_shear_angle(self.width, self.length, d);
        let mut a = DVector::from_element(n, uniform);
        let mut lambda = 0.0;
        let h = self.cell_size();
        for _ in 0..100 {
            let (e, grad, hess) = self.energy(law, &a, weights);
            let dg = a.map(|ai| SQRT_2 * h * (FRAC_PI_4 + ai).cos());
            let residual = &grad - lambda * &dg;
            let gap = self.displacement_of(&a) - d;
            let scale = grad.amax().max(1e-300);
            if residual.amax() <= 1e-10 * scale && gap.abs() <= 1e-12 * big_d {
                return Ok(NetEquilibrium {
                    displacement: d,
                    rotation: a.iter().copied().collect(),
                    energy: e,
                    force: lambda,
                    half_band: self.half_band(),
                });
            }
            // KKT system of the Lagrangian E - lambda (g - d)
            let mut kkt = DMatrix::zeros(n + 1, n + 1);
            kkt.view_mut((0, 0), (n, n)).copy_from(&hess);
            for i in 0..n {
                kkt[(i, i)] += lambda * SQRT_2 * h * (FRAC_PI_4 + a[i]).sin();
                kkt[(i, n)] = -dg[i];
                kkt[(n, i)] = -dg[i];
            }
            let mut rhs = DVector::zeros(n + 1);
            rhs.rows_mut(0, n).copy_from(&(-residual));
            rhs[n] = gap;
            let step = kkt
                .lu()
                .solve(&rhs)
                .ok_or("ideal net: singular equilibrium equations (shear energy not convex?)")?;
            let max_turn = step.rows(0, n).amax();
            let damp = if max_turn > 0.1 { 0.1 / max_turn } else { 1.0 };
            a += damp * step.rows(0, n);
            lambda += damp * step[n];
        }
        Err(format!("ideal net: no equilibrium found at d = {d}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::kinematics::bias_extension_shear_angle;

    /// Shear force growing linearly with the angle: `W = k gamma^2 / 2`.
    fn linear(gamma: f64) -> [f64; 3] {
        let k = 0.02;
        [0.5 * k * gamma * gamma, k * gamma, k]
    }

    /// Shear force rising to a plateau within 1°: `W = tau eps ln cosh(gamma / eps)`.
    fn plateau(gamma: f64) -> [f64; 3] {
        let (tau, eps) = (0.01, 0.015);
        let x = gamma / eps;
        let log_cosh = x.abs() + (-2.0 * x.abs()).exp().ln_1p() - std::f64::consts::LN_2;
        [
            tau * eps * log_cosh,
            tau * x.tanh(),
            tau / eps / x.cosh().powi(2),
        ]
    }

    fn net(cells: usize) -> IdealNetBias {
        IdealNetBias {
            width: 150.0,
            length: 450.0,
            cells,
        }
    }

    #[test]
    fn constant_shear_force_gives_the_pin_jointed_three_zones() {
        let d = [30.0, 60.0, 90.0];
        for eq in net(60).solve(&plateau, &d).unwrap() {
            let pin = bias_extension_shear_angle(150.0, 450.0, eq.displacement);
            for (x, y) in [(0.0, 0.0), (50.0, 0.0), (0.0, 120.0)] {
                let got = eq.shear_angle(x, y);
                assert!(
                    (got - pin).abs().to_degrees() < 0.3,
                    "d {}: ({x},{y}) {:.2}° vs pin-jointed {:.2}°",
                    eq.displacement,
                    got.to_degrees(),
                    pin.to_degrees()
                );
            }
            assert!(eq.shear_angle(0.0, 200.0).abs() < 1e-12, "zone A sheared");
            let b = eq.shear_angle(60.0, 160.0);
            assert!((b - 0.5 * pin).abs().to_degrees() < 0.3, "zone B {b}");
        }
    }

    #[test]
    fn rising_shear_force_shears_the_centre_less_than_the_ends_of_zone_c() {
        let eq = &net(60).solve(&linear, &[90.0]).unwrap()[0];
        let pin = bias_extension_shear_angle(150.0, 450.0, 90.0);
        let centre = eq.shear_angle(0.0, 0.0);
        let apex = eq.shear_angle(0.0, 140.0);
        assert!(centre < pin - 2f64.to_radians(), "centre {centre} vs {pin}");
        assert!(apex > pin, "apex {apex} vs {pin}");
    }

    #[test]
    fn equilibrium_satisfies_the_constraint_and_beats_every_admissible_neighbour() {
        let netb = net(40);
        let weights = netb.zone_weights();
        let eq = &netb.solve(&linear, &[60.0]).unwrap()[0];
        let a = DVector::from_vec(eq.rotation.clone());
        assert!((netb.displacement_of(&a) - 60.0).abs() < 1e-9);
        // uniform field at the same displacement stores more energy
        let uniform =
            DVector::from_element(40, 0.5 * bias_extension_shear_angle(150.0, 450.0, 60.0));
        assert!(netb.energy(&linear, &uniform, &weights).0 > eq.energy);
        // any perturbation projected back on the constraint raises the energy
        for seed in 1..20u64 {
            let bump = DVector::from_fn(40, |i, _| {
                ((i as u64 * 7919 + seed * 104_729) % 97) as f64 / 97.0 - 0.5
            });
            let mut b = &a + 0.01 * bump;
            let shift = (60.0 - netb.displacement_of(&b))
                / b.iter()
                    .map(|&bi| SQRT_2 * netb.cell_size() * (FRAC_PI_4 + bi).cos())
                    .sum::<f64>();
            b.add_scalar_mut(shift);
            assert!((netb.displacement_of(&b) - 60.0).abs() < 1e-3);
            assert!(netb.energy(&linear, &b, &weights).0 > eq.energy);
        }
    }

    #[test]
    fn force_is_the_energy_rate_and_converges_with_cells() {
        let eqs = net(60).solve(&linear, &[59.5, 60.0, 60.5]).unwrap();
        let fd = (eqs[2].energy - eqs[0].energy) / 1.0;
        assert!(
            (eqs[1].force - fd).abs() < 1e-4 * fd,
            "{} vs {fd}",
            eqs[1].force
        );
        let fine = &net(120).solve(&linear, &[60.0]).unwrap()[0];
        let diff = (fine.shear_angle(0.0, 0.0) - eqs[1].shear_angle(0.0, 0.0)).abs();
        assert!(
            diff.to_degrees() < 0.1,
            "centre moved {}° on refinement",
            diff.to_degrees()
        );
    }

    #[test]
    fn bad_geometry_and_displacement_are_errors() {
        let short = IdealNetBias {
            width: 150.0,
            length: 250.0,
            cells: 20,
        };
        assert!(short.solve(&linear, &[10.0]).is_err());
        assert!(net(21).solve(&linear, &[10.0]).is_err());
        assert!(net(20)
            .solve(&linear, &[200.0])
            .unwrap_err()
            .contains("displacement"));
    }
}
