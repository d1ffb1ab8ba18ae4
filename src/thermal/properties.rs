//! The thermal properties of a ply, from the `[thermal]` section of its material card
//! (docs/model.md §9): specific heat, conductivities, emissivity and crystallisation.
//!
//! The card gives them in the units of data sheets (J/(kg·K), W/(m·K), J/g); they are kept here
//! in the program's mm–N–s–tonne system: a conductivity in N/(s·K) (the same number as in
//! W/(m·K)), a specific heat in mm²/(s²·K) (1 J/(kg·K) = 1e6 mm²/(s²·K)), a latent heat in
//! mm²/s² (1 J/g = 1e9 mm²/s²).

use super::crystallisation::Nakamura;
use crate::limits::{
    between, check_given, AVRAMI_EXPONENT, CONDUCTIVITY, CRYSTALLISATION_RATE, EMISSIVITY,
    FRACTION, LATENT_HEAT, SPECIFIC_HEAT, TEMPERATURE,
};
use serde::Deserialize;

/// J/(kg·K) in mm²/(s²·K).
pub const SPECIFIC_HEAT_UNIT: f64 = 1e6;
/// J/g in mm²/s².
pub const LATENT_HEAT_UNIT: f64 = 1e9;
/// W/(m²·K) in N/(mm·s·K).
pub const HEAT_TRANSFER_UNIT: f64 = 1e-3;

/// A quantity given at increasing temperatures, interpolated linearly; outside the table an
/// error naming it (never a silent extrapolation).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    quantity: String,
    temperatures: Vec<f64>,
    values: Vec<f64>,
}

/// A temperature outside a thermal table.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error(
    "temperature {temperature:.2} °C is outside the table of {quantity} ({low} to {high} °C); \
     extend the table in the material card"
)]
pub struct OutsideTable {
    pub quantity: String,
    pub temperature: f64,
    pub low: f64,
    pub high: f64,
}

impl Table {
    /// The table of `quantity` (its card key, for messages): temperatures strictly increasing.
    pub fn new(quantity: &str, temperatures: Vec<f64>, values: Vec<f64>) -> Result<Self, String> {
        if temperatures.is_empty() || temperatures.len() != values.len() {
            return Err(format!(
                "{quantity}: give one value at each of the {} temperatures",
                temperatures.len()
            ));
        }
        if let Some(i) = temperatures.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "{quantity}: the temperatures must increase strictly ({} is followed by {})",
                temperatures[i],
                temperatures[i + 1]
            ));
        }
        Ok(Self {
            quantity: quantity.to_string(),
            temperatures,
            values,
        })
    }

    /// A constant: one value at any temperature.
    pub fn constant(quantity: &str, value: f64) -> Self {
        Self {
            quantity: quantity.to_string(),
            temperatures: vec![-273.15, 1000.0],
            values: vec![value, value],
        }
    }

    /// The value at `temperature` (°C).
    pub fn at(&self, temperature: f64) -> Result<f64, OutsideTable> {
        let (low, high) = self.range();
        if !between(temperature, low, high) {
            return Err(OutsideTable {
                quantity: self.quantity.clone(),
                temperature,
                low,
                high,
            });
        }
        let t = temperature.clamp(low, high);
        let i = self
            .temperatures
            .windows(2)
            .position(|w| t <= w[1])
            .unwrap_or(0);
        if self.temperatures.len() == 1 {
            return Ok(self.values[0]);
        }
        let (t0, t1) = (self.temperatures[i], self.temperatures[i + 1]);
        let s = (t - t0) / (t1 - t0);
        Ok(self.values[i] + s * (self.values[i + 1] - self.values[i]))
    }

    /// The temperatures the table covers (°C).
    pub fn range(&self) -> (f64, f64) {
        (
            self.temperatures[0],
            *self.temperatures.last().unwrap_or(&0.0),
        )
    }
}

/// Crystallisation of the matrix: Nakamura's kinetics (docs/model.md Eq. (H7)), the heat it
/// releases (H8) and the crystallinity past which a layer counts as frozen.
#[derive(Clone, Debug)]
pub struct Crystallisation {
    pub kinetics: Nakamura,
    /// Heat released per unit mass of the ply by its full (relative) crystallisation, mm²/s².
    pub latent_heat: f64,
    /// Relative crystallinity `X` past which a layer no longer flows (the summary's frozen
    /// area).
    pub frozen_at: f64,
}

/// What the heat equation needs of one ply (docs/model.md §9).
#[derive(Clone, Debug)]
pub struct ThermalProperties {
    /// Specific heat of the ply (mm²/(s²·K)) against temperature.
    pub specific_heat: Table,
    /// Conductivities of the fabric layer (N/(s·K)): in the plane along the warp and the weft,
    /// and through the thickness.
    pub conductivity_warp: f64,
    pub conductivity_weft: f64,
    pub conductivity_through: f64,
    /// Conductivity of a matrix layer (N/(s·K)), the same in every direction.
    pub matrix_conductivity: f64,
    /// Emissivity of the ply's faces (radiation to the room, Eq. (H5)).
    pub emissivity: f64,
    pub crystallisation: Option<Crystallisation>,
}

/// The card's `[thermal]` section as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalSection {
    /// Temperatures (°C) of `specific_heat`, or none for a constant.
    temperature: Option<Vec<f64>>,
    /// J/(kg·K): a number, or a list at `temperature`.
    specific_heat: NumberOrList,
    /// W/(m·K).
    conductivity_warp: f64,
    conductivity_weft: f64,
    conductivity_through: f64,
    matrix_conductivity: f64,
    #[serde(default = "default_emissivity")]
    emissivity: f64,
    crystallisation: Option<CrystallisationSection>,
}

/// Emissivity of a ply whose faces are not given one: a dark polymer surface, 0.9
/// (an ESTIMATE: carbon/thermoplastic laminates are measured at 0.85-0.95).
fn default_emissivity() -> f64 {
    0.9
}

#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
enum NumberOrList {
    Number(f64),
    List(Vec<f64>),
}

/// `[thermal.crystallisation]` as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CrystallisationSection {
    /// Avrami's exponent `n`.
    exponent: f64,
    /// Temperatures (°C) of `rate`; the matrix does not crystallise above the last.
    temperature: Vec<f64>,
    /// Nakamura's rate `K(T)` (1/s).
    rate: Vec<f64>,
    /// J/g of ply.
    latent_heat: f64,
    #[serde(default = "default_frozen_at")]
    frozen_at: f64,
}

/// **(choice)** A layer is frozen when half its crystallinity has formed: the melt's viscosity
/// has then risen by orders of magnitude and it no longer flows at forming rates.
fn default_frozen_at() -> f64 {
    0.5
}

impl ThermalSection {
    /// The checked properties, each bad value named by its card key.
    pub fn check(self) -> Result<ThermalProperties, String> {
        check_given([
            (
                "[thermal] conductivity_warp",
                Some(self.conductivity_warp),
                CONDUCTIVITY,
            ),
            (
                "[thermal] conductivity_weft",
                Some(self.conductivity_weft),
                CONDUCTIVITY,
            ),
            (
                "[thermal] conductivity_through",
                Some(self.conductivity_through),
                CONDUCTIVITY,
            ),
            (
                "[thermal] matrix_conductivity",
                Some(self.matrix_conductivity),
                CONDUCTIVITY,
            ),
            ("[thermal] emissivity", Some(self.emissivity), EMISSIVITY),
        ])?;
        let specific_heat = specific_heat_table(self.temperature, self.specific_heat)?;
        let crystallisation = self.crystallisation.map(|c| c.check()).transpose()?;
        Ok(ThermalProperties {
            specific_heat,
            conductivity_warp: self.conductivity_warp,
            conductivity_weft: self.conductivity_weft,
            conductivity_through: self.conductivity_through,
            matrix_conductivity: self.matrix_conductivity,
            emissivity: self.emissivity,
            crystallisation,
        })
    }
}

/// `[thermal] specific_heat` in mm²/(s²·K): a constant, or a table at `temperature`.
fn specific_heat_table(
    temperatures: Option<Vec<f64>>,
    specific_heat: NumberOrList,
) -> Result<Table, String> {
    const KEY: &str = "[thermal] specific_heat";
    match (temperatures, specific_heat) {
        (None, NumberOrList::Number(c)) => {
            SPECIFIC_HEAT.check(KEY, c)?;
            Ok(Table::constant(KEY, c * SPECIFIC_HEAT_UNIT))
        }
        (Some(temperatures), NumberOrList::List(values)) => {
            TEMPERATURE.check_each("[thermal] temperature", &temperatures)?;
            SPECIFIC_HEAT.check_each(KEY, &values)?;
            let values = values.iter().map(|c| c * SPECIFIC_HEAT_UNIT).collect();
            Table::new(KEY, temperatures, values)
        }
        _ => Err(format!(
            "{KEY} is a number (J/(kg·K)), or a list with a [thermal] temperature list of the \
             same length"
        )),
    }
}

impl CrystallisationSection {
    fn check(self) -> Result<Crystallisation, String> {
        const KEY: &str = "[thermal.crystallisation]";
        AVRAMI_EXPONENT.check(&format!("{KEY} exponent"), self.exponent)?;
        TEMPERATURE.check_each(&format!("{KEY} temperature"), &self.temperature)?;
        CRYSTALLISATION_RATE.check_each(&format!("{KEY} rate"), &self.rate)?;
        LATENT_HEAT.check(&format!("{KEY} latent_heat"), self.latent_heat)?;
        FRACTION.check(&format!("{KEY} frozen_at"), self.frozen_at)?;
        let kinetics = Nakamura::new(self.exponent, self.temperature, self.rate)
            .map_err(|e| format!("{KEY}: {e}"))?;
        Ok(Crystallisation {
            kinetics,
            latent_heat: self.latent_heat * LATENT_HEAT_UNIT,
            frozen_at: self.frozen_at,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section(text: &str) -> Result<ThermalProperties, String> {
        let s: ThermalSection = toml::from_str(text).map_err(|e| e.to_string())?;
        s.check()
    }

    const VALID: &str = "specific_heat = 1200.0\nconductivity_warp = 3.0\n\
        conductivity_weft = 3.0\nconductivity_through = 0.4\nmatrix_conductivity = 0.3\n";

    /// Data-sheet units become the program's: 1200 J/(kg·K) is 1.2e9 mm²/(s²·K).
    #[test]
    fn units_of_data_sheets_are_converted() {
        let p = section(VALID).unwrap();
        assert_eq!(p.specific_heat.at(300.0).unwrap(), 1.2e9);
        assert_eq!(p.conductivity_through, 0.4);
        assert_eq!(p.emissivity, 0.9);
    }

    /// A negative conductivity is refused, naming the key.
    #[test]
    fn negative_conductivity_is_refused_by_key() {
        let e = section(&VALID.replace("conductivity_weft = 3.0", "conductivity_weft = -1.0"))
            .unwrap_err();
        assert!(e.contains("[thermal] conductivity_weft"), "{e}");
    }

    /// A table is interpolated linearly and refuses a temperature outside it.
    #[test]
    fn specific_heat_table_interpolates_and_refuses_outside() {
        let p = section(&VALID.replace(
            "specific_heat = 1200.0",
            "temperature = [100.0, 300.0]\nspecific_heat = [1000.0, 1400.0]",
        ))
        .unwrap();
        assert!((p.specific_heat.at(200.0).unwrap() - 1.2e9).abs() < 1e-3);
        let e = p.specific_heat.at(50.0).unwrap_err().to_string();
        assert!(
            e.contains("specific_heat") && e.contains("100 to 300"),
            "{e}"
        );
    }
}
