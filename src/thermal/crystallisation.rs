//! Crystallisation of the matrix while it cools: Nakamura kinetics per material point
//! (docs/model.md Eqs. (H7), (H8)).
//!
//! The state of a point is the integral `theta = int K(T) dt`; the crystalline fraction
//! (relative to the final one) is `X = 1 - exp(-theta^n)`. Integrating `theta` rather than
//! `X` avoids the start of the differential form, `dX/dt ~ X^((n-1)/n)`, whose right-hand
//! side vanishes at `X = 0` and whose solution from `X = 0` is not unique.

use std::fmt;

/// Nakamura kinetics: an Avrami exponent and the rate `K(T)` (1/s) as a table.
#[derive(Clone, Debug, PartialEq)]
pub struct Nakamura {
    exponent: f64,
    temperatures: Vec<f64>,
    rates: Vec<f64>,
}

/// A temperature below the lowest of the rate table: the kinetics there are unknown and a
/// guess would set how much crystallises.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateError {
    /// The temperature asked for, °C.
    pub temperature: f64,
    /// Lowest and highest temperature of the table, °C.
    pub range: (f64, f64),
}

impl fmt::Display for RateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "temperature {} °C is below the crystallisation table (from {} °C)",
            self.temperature, self.range.0
        )
    }
}

impl std::error::Error for RateError {}

impl Nakamura {
    /// Builds the kinetics or says what is wrong: the exponent must lie in [1, 4] (the
    /// physical Avrami exponents), the temperatures increase strictly and the rates be
    /// positive and finite (their logarithms are interpolated).
    pub fn new(exponent: f64, temperatures: Vec<f64>, rates: Vec<f64>) -> Result<Self, String> {
        if !(1.0..=4.0).contains(&exponent) {
            return Err(format!(
                "the Avrami exponent must be between 1 and 4, not {exponent}"
            ));
        }
        if temperatures.is_empty() {
            return Err("the crystallisation rate table is empty".into());
        }
        if temperatures.len() != rates.len() {
            return Err(format!(
                "the crystallisation table has {} rates but {} temperatures",
                rates.len(),
                temperatures.len()
            ));
        }
        if let Some(i) = temperatures.iter().position(|t| !t.is_finite()) {
            return Err(format!(
                "temperature #{} of the crystallisation table is not finite",
                i + 1
            ));
        }
        if let Some(i) = temperatures.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "temperatures of the crystallisation table must increase strictly: {} is \
                 followed by {}",
                temperatures[i],
                temperatures[i + 1]
            ));
        }
        if let Some(i) = rates.iter().position(|k| !(k.is_finite() && *k > 0.0)) {
            return Err(format!(
                "crystallisation rate #{} must be positive and finite, not {}",
                i + 1,
                rates[i]
            ));
        }
        Ok(Self {
            exponent,
            temperatures,
            rates,
        })
    }

    /// The Avrami exponent `n`.
    pub fn exponent(&self) -> f64 {
        self.exponent
    }

    /// The highest temperature of the table, °C: above it the melt does not crystallise.
    pub fn melt_onset(&self) -> f64 {
        *self.temperatures.last().unwrap_or(&f64::NAN)
    }

    /// `K(T)` in 1/s: `ln K` linear in `T` between table points, because the rate changes by
    /// orders of magnitude over a few tens of kelvin and a linear interpolation of `K` would
    /// overestimate it badly between points. Zero above the table (the melt), an error below
    /// it (and for a temperature that is not a number).
    pub fn rate(&self, temperature: f64) -> Result<f64, RateError> {
        let last = self.temperatures.len() - 1;
        if temperature > self.temperatures[last] {
            return Ok(0.0);
        }
        if temperature.is_nan() || temperature < self.temperatures[0] {
            return Err(RateError {
                temperature,
                range: (self.temperatures[0], self.temperatures[last]),
            });
        }
        if last == 0 {
            return Ok(self.rates[0]);
        }
        let upper = self
            .temperatures
            .partition_point(|&t| t < temperature)
            .clamp(1, last);
        let (t0, t1) = (self.temperatures[upper - 1], self.temperatures[upper]);
        let (k0, k1) = (self.rates[upper - 1], self.rates[upper]);
        let w = (temperature - t0) / (t1 - t0);
        // K0 (K1/K0)^w rather than exp(ln K0 + ...): exact at the table points.
        Ok(k0 * (k1 / k0).powf(w))
    }

    /// `X = 1 - exp(-theta^n)` (docs/model.md Eq. (H7)), the fraction of the final
    /// crystallinity; `-expm1` keeps its digits when it is small.
    pub fn fraction(&self, theta: f64) -> f64 {
        -(-theta.powf(self.exponent)).exp_m1()
    }

    /// `theta` at the end of a step of `dt` seconds over which the temperature went from
    /// `t_start` to `t_end`: the trapezoid `theta + dt (K(t_start) + K(t_end)) / 2`, exact
    /// for a constant temperature.
    pub fn advance(&self, theta: f64, t_start: f64, t_end: f64, dt: f64) -> Result<f64, RateError> {
        Ok(theta + 0.5 * dt * (self.rate(t_start)? + self.rate(t_end)?))
    }
}

/// Heat released per unit volume (N/mm^2 = MJ/m^3) when the crystalline fraction goes from
/// `x_old` to `x_new` (docs/model.md Eq. (H8)): `rho L (x_new - x_old)`, with `rho` the
/// density (tonne/mm^3) and `latent_heat` the heat of crystallisation at the final
/// crystallinity per unit mass (mm^2/s^2 = 1e-6 J/kg) — of the laminate if `rho` is the
/// laminate's. A column's source is this times the cell's reference thickness.
pub fn latent_heat_release(rho: f64, latent_heat: f64, x_old: f64, x_new: f64) -> f64 {
    rho * latent_heat * (x_new - x_old)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PPS-like table (test data, not the shipped card): the rate peaks at low temperature
    /// and falls by orders of magnitude towards the melt.
    fn kinetics() -> Nakamura {
        Nakamura::new(
            3.0,
            vec![170.0, 190.0, 210.0, 230.0, 250.0, 270.0, 280.0],
            vec![0.5, 0.3, 0.12, 0.04, 0.008, 5e-4, 1e-5],
        )
        .unwrap()
    }

    /// At a constant temperature the rate is constant and the trapezoid exact: repeated
    /// steps give Avrami's `X = 1 - exp(-k t^n)` with `k = K^n`.
    #[test]
    fn isothermal_hold_follows_avrami() {
        let nak = kinetics();
        let temperature = 235.0;
        let k_rate = nak.rate(temperature).unwrap();
        let k_avrami = k_rate.powf(3.0);
        let (mut theta, dt) = (0.0, 0.1);
        for i in 1..=1000 {
            theta = nak.advance(theta, temperature, temperature, dt).unwrap();
            let t = i as f64 * dt;
            let avrami = 1.0 - (-k_avrami * t.powi(3)).exp();
            assert!((nak.fraction(theta) - avrami).abs() < 1e-12, "t = {t}");
        }
        assert!(nak.fraction(theta) > 0.999, "the hold reaches the end");
    }

    /// `dX/dt = n K (1 - X) (-ln(1 - X))^((n-1)/n)` of docs/model.md Eq. (H7).
    fn differential(nak: &Nakamura, temperature: f64, x: f64) -> f64 {
        let n = nak.exponent();
        let k = nak.rate(temperature).unwrap();
        n * k * (1.0 - x) * (-(-x).ln_1p()).powf((n - 1.0) / n)
    }

    /// Cooling at a constant rate from 270 °C: `theta` stepped with `advance` (dt = 0.05 s)
    /// against RK4 on the differential form (dt = 1e-3 s). The differential form cannot start
    /// at `X = 0` (its right-hand side vanishes there and `X = 0` is a solution), so both
    /// start from the same state `X0 = 1e-12` at 270 °C: `advance` from the `theta0` of
    /// `X0`, RK4 from `X0`. Both then solve the same initial-value problem, whose solution is
    /// unique, and differ only by their discretisation.
    #[test]
    fn constant_cooling_matches_the_differential_form() {
        let nak = kinetics();
        let x0: f64 = 1e-12;
        let theta0 = (-(-x0).ln_1p()).powf(1.0 / nak.exponent());
        for kelvin_per_minute in [10.0, 50.0] {
            let rate = kelvin_per_minute / 60.0;
            let temperature = |t: f64| 270.0 - rate * t;
            let duration = 95.0 / rate;
            let (coarse, fine): (f64, f64) = (0.05, 1e-3);
            let per_coarse = (coarse / fine).round() as usize;
            let mut theta = theta0;
            let mut x = x0;
            let mut worst: f64 = 0.0;
            let mut crossed = [false; 3];
            let steps = (duration / coarse).round() as usize;
            for i in 0..steps {
                let t = i as f64 * coarse;
                theta = nak
                    .advance(theta, temperature(t), temperature(t + coarse), coarse)
                    .unwrap();
                for j in 0..per_coarse {
                    let s = t + j as f64 * fine;
                    let k1 = differential(&nak, temperature(s), x);
                    let k2 = differential(&nak, temperature(s + 0.5 * fine), x + 0.5 * fine * k1);
                    let k3 = differential(&nak, temperature(s + 0.5 * fine), x + 0.5 * fine * k2);
                    let k4 = differential(&nak, temperature(s + fine), x + fine * k3);
                    x += fine / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
                }
                worst = worst.max((nak.fraction(theta) - x).abs());
                for (c, level) in crossed.iter_mut().zip([0.1, 0.5, 0.9]) {
                    *c |= x > level;
                }
            }
            eprintln!("{kelvin_per_minute} K/min: largest difference in X {worst:.2e}");
            assert!(
                crossed.iter().all(|&c| c),
                "the run crosses X = 0.1, 0.5, 0.9"
            );
            // Measured 6.8e-8 (10 K/min) and 9.3e-7 (50 K/min); 1e-4 still tells the trapezoid
            // from a rectangle rule on either end of the step.
            assert!(worst < 1e-4, "{kelvin_per_minute} K/min: {worst}");
        }
    }

    #[test]
    fn rate_table_interpolates_logarithms_and_stops_at_its_ends() {
        let nak = kinetics();
        assert_eq!(nak.rate(230.0).unwrap(), 0.04);
        assert_eq!(nak.rate(280.0).unwrap(), 1e-5);
        let geometric = (0.04_f64 * 0.008).sqrt();
        assert!((nak.rate(240.0).unwrap() - geometric).abs() < 1e-15 * geometric);
        assert_eq!(nak.rate(280.001).unwrap(), 0.0);
        assert_eq!(nak.melt_onset(), 280.0);
        let e = nak.rate(169.5).unwrap_err();
        assert_eq!(e.range, (170.0, 280.0));
        assert_eq!(
            e.to_string(),
            "temperature 169.5 °C is below the crystallisation table (from 170 °C)"
        );
        assert!(nak.rate(f64::NAN).is_err());
        assert!(nak.advance(0.0, 200.0, 160.0, 0.1).is_err());
    }

    #[test]
    fn rejects_malformed_kinetics() {
        let t = || vec![200.0, 250.0];
        assert!(Nakamura::new(0.5, t(), vec![1.0, 0.1])
            .unwrap_err()
            .contains("exponent"));
        assert!(Nakamura::new(3.0, t(), vec![1.0, 0.0])
            .unwrap_err()
            .contains("rate #2"));
        assert!(Nakamura::new(3.0, vec![250.0, 200.0], vec![1.0, 0.1])
            .unwrap_err()
            .contains("increase"));
        assert!(Nakamura::new(3.0, t(), vec![1.0]).is_err());
        assert!(Nakamura::new(3.0, vec![], vec![]).is_err());
    }

    #[test]
    fn latent_heat_is_released_with_the_fraction() {
        // PPS laminate, 1.6e-9 tonne/mm^3, 17.5 J/g = 1.75e10 mm^2/s^2: 28 MJ/m^3 in full.
        let q = latent_heat_release(1.6e-9, 1.75e10, 0.2, 0.7);
        assert!((q - 14.0).abs() < 1e-12);
    }
}
