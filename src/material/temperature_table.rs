//! Temperature-dependent parameters as piecewise-linear tables (docs/model.md §2, (choice)).

use super::MaterialError;
use crate::limits::between;

/// A parameter given at increasing temperatures, interpolated linearly in between.
///
/// A temperature outside the table is an error, never a silent extrapolation. A table of one
/// entry is valid at that temperature only.
#[derive(Clone, Debug, PartialEq)]
pub struct TemperatureTable {
    quantity: String,
    temperatures: Vec<f64>,
    values: Vec<f64>,
}

impl TemperatureTable {
    /// Builds the table of `quantity` (its name in messages) or says what is wrong with it.
    pub fn new(
        quantity: impl Into<String>,
        temperatures: Vec<f64>,
        values: Vec<f64>,
    ) -> Result<Self, String> {
        let quantity = quantity.into();
        if temperatures.is_empty() {
            return Err(format!("the temperature table of {quantity} is empty"));
        }
        if temperatures.len() != values.len() {
            return Err(format!(
                "{quantity} has {} values but there are {} temperatures",
                values.len(),
                temperatures.len()
            ));
        }
        if let Some(i) = temperatures.iter().position(|t| !t.is_finite()) {
            return Err(format!(
                "temperature #{} of {quantity} is not finite",
                i + 1
            ));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("value #{} of {quantity} is not finite", i + 1));
        }
        if let Some(i) = temperatures.windows(2).position(|w| w[1] <= w[0]) {
            return Err(format!(
                "temperatures of {quantity} must increase strictly: {} is followed by {}",
                temperatures[i],
                temperatures[i + 1]
            ));
        }
        Ok(Self {
            quantity,
            temperatures,
            values,
        })
    }

    /// The same table with every value multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            values: self.values.iter().map(|v| v * factor).collect(),
            ..self.clone()
        }
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Lowest and highest temperature of the table.
    pub fn range(&self) -> (f64, f64) {
        (
            self.temperatures[0],
            *self.temperatures.last().unwrap_or(&f64::NAN),
        )
    }

    /// The value at `temperature`, interpolated linearly between table points; a temperature
    /// within a rounding error of an end (`limits::ROUNDING`, relative) is at the end, so that
    /// one printed with a digit too many still hits the end value.
    pub fn at(&self, temperature: f64) -> Result<f64, MaterialError> {
        let (lo, hi) = self.range();
        if !between(temperature, lo, hi) {
            return Err(self.out_of_range(temperature));
        }
        if self.temperatures.len() == 1 {
            return Ok(self.values[0]);
        }
        let t = temperature.clamp(lo, hi);
        let upper = self
            .temperatures
            .partition_point(|&ti| ti < t)
            .clamp(1, self.temperatures.len() - 1);
        let (t0, t1) = (self.temperatures[upper - 1], self.temperatures[upper]);
        let (v0, v1) = (self.values[upper - 1], self.values[upper]);
        let w = (t - t0) / (t1 - t0);
        Ok(v0 + w * (v1 - v0))
    }

    fn out_of_range(&self, temperature: f64) -> MaterialError {
        let (min, max) = self.range();
        MaterialError::TemperatureOutOfRange {
            quantity: self.quantity.clone(),
            temperature,
            min,
            max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table() -> TemperatureTable {
        TemperatureTable::new("c10", vec![280.0, 300.0, 320.0], vec![3.0, 2.0, 0.5]).unwrap()
    }

    #[test]
    fn reproduces_table_points_and_interpolates_linearly() {
        let t = table();
        assert_eq!(t.at(280.0).unwrap(), 3.0);
        assert_eq!(t.at(300.0).unwrap(), 2.0);
        assert_eq!(t.at(320.0).unwrap(), 0.5);
        assert!((t.at(290.0).unwrap() - 2.5).abs() < 1e-15);
        assert!((t.at(315.0).unwrap() - 0.875).abs() < 1e-15);
    }

    #[test]
    fn refuses_temperatures_outside_the_table() {
        let t = table();
        for temp in [279.0, 320.5, 320.000_001, f64::NAN] {
            let err = t.at(temp).unwrap_err();
            assert!(matches!(err, MaterialError::TemperatureOutOfRange { .. }));
            assert!(err.to_string().contains("c10"), "{err}");
        }
    }

    /// 320.0000000001 °C is the table's end written with a digit too many: at the end, not
    /// outside; a refusal shows the digits that put a temperature outside.
    #[test]
    fn ends_hold_within_a_rounding_error_and_refusals_show_why() {
        let t = table();
        assert_eq!(t.at(320.000_000_000_1).unwrap(), 0.5);
        assert_eq!(t.at(279.999_999_999_9).unwrap(), 3.0);
        let e = t.at(320.000_000_412_345_7).unwrap_err().to_string();
        assert!(
            e.starts_with("temperature 320.0000004 °C is outside"),
            "{e}"
        );
        assert!(e.contains("(280 to 320 °C)"), "{e}");
    }

    #[test]
    fn single_point_table_is_valid_only_at_its_temperature() {
        let t = TemperatureTable::new("eta1", vec![300.0], vec![1e-3]).unwrap();
        assert_eq!(t.at(300.0).unwrap(), 1e-3);
        assert!(t.at(301.0).is_err());
    }

    #[test]
    fn rejects_malformed_tables() {
        let mismatch = TemperatureTable::new("d1", vec![1.0, 2.0], vec![1.0]).unwrap_err();
        assert!(mismatch.contains("1 values but there are 2"), "{mismatch}");
        let unordered = TemperatureTable::new("d1", vec![2.0, 1.0], vec![1.0, 1.0]).unwrap_err();
        assert!(unordered.contains("increase strictly"), "{unordered}");
        assert!(TemperatureTable::new("d1", vec![], vec![]).is_err());
    }
}
