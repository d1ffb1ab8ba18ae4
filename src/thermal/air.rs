//! Heat lost by a free face to the room: natural convection and radiation (docs/model.md
//! Eq. (H5)).
//!
//! Between the oven and the press a hot ply loses on the order of 100 K in a few seconds, half
//! of it by radiation at 300 °C, so radiation cannot be left out. It enters the column as a
//! linearised face coefficient evaluated at the start of the step, which keeps the column's
//! system linear; the step is short against the cooling time (seconds), so the lag is small.

use super::column::FaceExchange;

/// Stefan–Boltzmann constant in N/(mm s K^4): 5.670374419e-8 W/(m^2 K^4) x 1e-3.
pub const STEFAN_BOLTZMANN: f64 = 5.670374419e-11;

/// Kelvin at 0 °C; used for radiation only, every other temperature stays in °C.
const ZERO_CELSIUS: f64 = 273.15;

/// A face in still air.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AirExchange {
    /// Natural-convection coefficient, N/(mm s K) (1e-3 x W/(m^2 K)).
    pub convection: f64,
    /// Emissivity of the surface, 0 to 1.
    pub emissivity: f64,
    /// Temperature of the air and of the surroundings the face radiates to, °C.
    pub room_temperature: f64,
}

impl AirExchange {
    /// Says which quantity is out of range, if one is.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.convection.is_finite() && self.convection >= 0.0) {
            return Err(format!(
                "the convection coefficient in air must be zero or positive and finite, not {}",
                self.convection
            ));
        }
        if !(0.0..=1.0).contains(&self.emissivity) {
            return Err(format!(
                "the emissivity must be between 0 and 1, not {}",
                self.emissivity
            ));
        }
        if !(self.room_temperature.is_finite() && self.room_temperature > -ZERO_CELSIUS) {
            return Err(format!(
                "the room temperature must be finite and above absolute zero, not {} °C",
                self.room_temperature
            ));
        }
        Ok(())
    }

    /// The face seen by a column whose surface is at `surface_temperature` (°C, that of the
    /// start of the step): `h = h_conv + h_rad` to the room temperature, with
    /// `h_rad = eps sigma (T^2 + Tr^2)(T + Tr)` in kelvin (docs/model.md Eq. (H5)), so that
    /// `h_rad (T - Tr) = eps sigma (T^4 - Tr^4)` exactly at that temperature.
    pub fn face(&self, surface_temperature: f64) -> FaceExchange {
        FaceExchange {
            conductance: self.convection + self.radiation(surface_temperature),
            temperature: self.room_temperature,
        }
    }

    /// `h_rad` of docs/model.md Eq. (H5), N/(mm s K).
    fn radiation(&self, surface_temperature: f64) -> f64 {
        let t = surface_temperature + ZERO_CELSIUS;
        let room = self.room_temperature + ZERO_CELSIUS;
        self.emissivity * STEFAN_BOLTZMANN * (t * t + room * room) * (t + room)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::thermal::column::{step_column, ColumnGrid, ColumnLayer, ColumnScratch, ColumnStep};

    /// 10 W/(m^2 K), emissivity 0.9, room at 25 °C.
    const AIR: AirExchange = AirExchange {
        convection: 0.01,
        emissivity: 0.9,
        room_temperature: 25.0,
    };
    const RHO_C: f64 = 1.872;
    const PLY: f64 = 0.31;

    /// Right-hand side of the lumped ODE `rho c t dT/dt = -2 [h (T - Tr) + eps sigma (T^4 -
    /// Tr^4)]`, written with the fourth powers (not with `face`) so that it checks them.
    fn lumped_rate(t: f64) -> f64 {
        let (tk, rk) = (t + 273.15, AIR.room_temperature + 273.15);
        let flux = AIR.convection * (t - AIR.room_temperature)
            + AIR.emissivity * 5.670374419e-11 * (tk.powi(4) - rk.powi(4));
        -2.0 * flux / (RHO_C * PLY)
    }

    fn rk4(mut t: f64, duration: f64, steps: usize) -> f64 {
        let h = duration / steps as f64;
        for _ in 0..steps {
            let k1 = lumped_rate(t);
            let k2 = lumped_rate(t + 0.5 * h * k1);
            let k3 = lumped_rate(t + 0.5 * h * k2);
            let k4 = lumped_rate(t + h * k3);
            t += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        t
    }

    /// A single ply from 320 °C, both faces in air for 5 s, against the lumped ODE.
    #[test]
    fn ply_in_air_cools_like_the_lumped_ode() {
        let (t0, dt, duration): (f64, f64, f64) = (320.0, 0.01, 5.0);
        let layers = [0.04, 0.23, 0.04].map(|thickness| ColumnLayer {
            thickness,
            conductivity: 0.3,
        });
        let grid = ColumnGrid::new(&layers, 4).unwrap();
        let n = grid.cells();
        let caps: Vec<f64> = (0..n).map(|c| RHO_C * grid.cell_thickness(c)).collect();
        let sources = vec![0.0; n];
        let mut temps = vec![t0; n];
        let mut scratch = ColumnScratch::default();
        let steps = (duration / dt).round() as usize;
        for _ in 0..steps {
            let step = ColumnStep {
                capacities: &caps,
                thickness_stretch: &[1.0; 3],
                area_ratio: 1.0,
                faces: [AIR.face(temps[0]), AIR.face(temps[n - 1])],
                sources: &sources,
                dt,
            };
            step_column(&grid, &step, &mut temps, &mut scratch);
        }
        let mean = temps.iter().sum::<f64>() / n as f64;
        let reference = rk4(t0, duration, 50_000);
        let drop = t0 - reference;
        let error = (mean - reference).abs() / drop;
        eprintln!(
            "drop {drop:.2} K, column {mean:.3} °C, ODE {reference:.3} °C, error {error:.2e}"
        );
        assert!(
            drop > 100.0,
            "a single ply loses more than 100 K in 5 s: {drop}"
        );
        assert!(error < 0.01, "{error}");
    }

    #[test]
    fn radiation_coefficient_gives_the_fourth_power_law() {
        let face = AIR.face(300.0);
        let (t, r) = (573.15_f64, 298.15_f64);
        let exact = 0.01 * 275.0 + 0.9 * 5.670374419e-11 * (t.powi(4) - r.powi(4));
        assert!((face.conductance * 275.0 - exact).abs() < 1e-12 * exact);
        assert_eq!(face.temperature, 25.0);
    }

    #[test]
    fn validation_names_the_quantity() {
        assert!(AIR.validate().is_ok());
        let e = AirExchange {
            emissivity: 1.2,
            ..AIR
        };
        assert!(e.validate().unwrap_err().contains("emissivity"));
        let e = AirExchange {
            convection: -0.01,
            ..AIR
        };
        assert!(e.validate().unwrap_err().contains("convection"));
        let e = AirExchange {
            room_temperature: f64::NAN,
            ..AIR
        };
        assert!(e.validate().unwrap_err().contains("room temperature"));
        let e = AirExchange {
            emissivity: f64::NAN,
            ..AIR
        };
        assert!(e.validate().is_err());
    }
}
