//! The values each number a user gives may take — scenario keys, command-line options, material
//! cards — and how a number is shown in a message.
//!
//! Every quantity has a range beyond which no one means the value: a blank-holder force of
//! 1e300 N, a ply turned by 1e300°, a density of 1e6 tonne/mm^3. Such a value is refused, naming
//! its key or option (exit code 2), instead of being run to an arbitrary result (an angle taken
//! modulo a turn after losing every digit, a force bound that overflows to `inf`). The ranges are
//! wide on purpose: they refuse what is absurd, not what is unusual. They are listed for users in
//! docs/guide/scenario.md, docs/guide/materials.md ("Material cards") and each command's
//! `--help`.
//!
//! **Choice:** a value within [`ROUNDING`] (relative) of a closed end counts as at that end: a
//! number written with a digit too many (`320.0000000001` for a table ending at 320 °C) is not
//! refused for a difference nobody sees. A value refused is shown with as many digits as it
//! takes to tell it from the end it passed ([`shown_apart`]), never rounded onto it.

/// Relative distance from a closed end within which a value counts as at that end.
pub const ROUNDING: f64 = 1e-9;

/// Significant digits of a number in a message, unless more are needed to tell it from the
/// bound it is compared with ([`shown_apart`]).
pub const SHOWN_DIGITS: usize = 6;

/// The values a quantity may take, its unit, and why the range ends where it does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub low: f64,
    pub high: f64,
    /// Whether `low` itself is allowed.
    pub low_allowed: bool,
    /// Whether `high` itself is allowed.
    pub high_allowed: bool,
    /// The unit written after a number (`""` for a pure number).
    pub unit: &'static str,
    /// Why the range ends there, said with a refusal.
    pub why: &'static str,
}

impl Range {
    /// From `low` to `high`, both allowed.
    pub const fn closed(low: f64, high: f64, unit: &'static str, why: &'static str) -> Self {
        Self {
            low,
            high,
            low_allowed: true,
            high_allowed: true,
            unit,
            why,
        }
    }

    /// Strictly between `low` and `high`.
    pub const fn open(low: f64, high: f64, unit: &'static str, why: &'static str) -> Self {
        Self {
            low_allowed: false,
            high_allowed: false,
            ..Self::closed(low, high, unit, why)
        }
    }

    /// Above `low` (not allowed) and up to `high` (allowed).
    pub const fn above(low: f64, high: f64, unit: &'static str, why: &'static str) -> Self {
        Self {
            low_allowed: false,
            ..Self::closed(low, high, unit, why)
        }
    }

    /// The same range from 0 on, 0 allowed: a coefficient that may be left at zero.
    pub const fn from_zero(self) -> Self {
        Self {
            low: 0.0,
            low_allowed: true,
            ..self
        }
    }

    /// Whether `value` lies in the range (a closed end within [`ROUNDING`]).
    pub fn contains(&self, value: f64) -> bool {
        let at = |end: f64| (value - end).abs() <= ROUNDING * end.abs();
        let above_low = value > self.low || (self.low_allowed && at(self.low));
        let below_high = value < self.high || (self.high_allowed && at(self.high));
        above_low && below_high
    }

    /// `Ok` for a value in the range; else a message naming `key` (a scenario or card key,
    /// written `key = value`, or a command-line option, written `--option value`), the value,
    /// the range and why.
    pub fn check(&self, key: &str, value: f64) -> Result<(), String> {
        if self.contains(value) {
            return Ok(());
        }
        let nearest = if value < self.low {
            self.low
        } else {
            self.high
        };
        let given = if value.is_finite() {
            self.with_unit(&shown_apart(value, nearest))
        } else {
            format!("{value}")
        };
        let assignment = if key.starts_with("--") { " " } else { " = " };
        Err(format!(
            "{key}{assignment}{given} is out of range: it must lie {} ({})",
            self.describe(),
            self.why
        ))
    }

    /// [`Self::check`] of every value of a list, the first one refused named `key[i]`.
    pub fn check_each(&self, key: &str, values: &[f64]) -> Result<(), String> {
        values
            .iter()
            .enumerate()
            .try_for_each(|(i, &v)| self.check(&format!("{key}[{i}]"), v))
    }

    /// `from 0.001 to 10000 mm`, `strictly between 0 and 90°`, ...
    pub fn describe(&self) -> String {
        let (low, high) = (shown(self.low), self.with_unit(&shown(self.high)));
        match (self.low_allowed, self.high_allowed) {
            (true, true) => format!("from {low} to {high}"),
            (false, false) => format!("strictly between {low} and {high}"),
            (false, true) => format!("above {low} and at most {high}"),
            (true, false) => format!("at least {low} and below {high}"),
        }
    }

    fn with_unit(&self, number: &str) -> String {
        match self.unit {
            "" => number.to_string(),
            "°" => format!("{number}°"),
            unit => format!("{number} {unit}"),
        }
    }
}

/// The `--help` section on the ranges of a command's `options`, one line each.
pub fn ranges_help(options: &[(&str, Range)]) -> String {
    let lines: Vec<String> = options
        .iter()
        .map(|(option, range)| format!("  {option}: {}", range.describe()))
        .collect();
    format!(
        "Ranges (a value outside is refused, naming its option):\n{}",
        lines.join("\n")
    )
}

/// [`Range::check`] of each `(key, value, range)` whose value is given, in order: the first
/// refusal.
pub fn check_given<'a>(
    given: impl IntoIterator<Item = (&'a str, Option<f64>, Range)>,
) -> Result<(), String> {
    given
        .into_iter()
        .try_for_each(|(key, value, range)| value.map_or(Ok(()), |v| range.check(key, v)))
}

/// Whether `value` lies from `low` to `high`, an end within [`ROUNDING`]: the test of a range
/// whose ends are data (the temperatures of a card's tables) rather than a quantity's.
pub fn between(value: f64, low: f64, high: f64) -> bool {
    Range::closed(low, high, "", "").contains(value)
}

/// Lengths: the blank's sides and element size, the tools' radii and resolution, the stroke,
/// the specimens of the virtual tests and fits (mm).
pub const LENGTH: Range = Range::closed(
    1e-3,
    1e4,
    "mm",
    "a micrometre to ten metres: beyond any ply, tool or press",
);
/// The blank holder's gap below the blank (mm).
pub const GAP: Range = Range::closed(
    0.0,
    1e4,
    "mm",
    "ten metres is beyond any press, and the holder touches nothing",
);
/// Orientations: ply angle, warp angle of the drape preview, fibre angle of a material point
/// and of a strip test (degrees).
pub const ANGLE: Range =
    Range::closed(-360.0, 360.0, "°", "one turn either way; nobody means more");
/// Shear angles of the fabric: locking angle, largest shear fitted (degrees).
pub const SHEAR_ANGLE: Range = Range::open(
    0.0,
    90.0,
    "°",
    "the yarns of a woven fabric shear by less than 90°",
);
/// Onset of the friction-like shear term (degrees).
pub const FRICTION_ONSET: Range = Range::open(
    0.0,
    15.0,
    "°",
    "the friction-like term sets in within the first degrees of shear",
);
/// Temperatures (°C).
pub const TEMPERATURE: Range = Range::closed(
    -273.15,
    1000.0,
    "°C",
    "absolute zero to 1000 °C, past which every thermoplastic has decomposed",
);
/// Punch and crosshead speeds (mm/s).
pub const SPEED: Range = Range::closed(
    1e-4,
    1e4,
    "mm/s",
    "6 µm/min to 10 m/s: slower than any creep test, faster than any press",
);
/// Forces: the blank holder's (N).
pub const FORCE: Range = Range::closed(0.0, 1e7, "N", "10 MN is a 1000-tonne press");
/// Mean pressure of the blank holder over the blank's area (MPa).
pub const HOLDER_PRESSURE: Range = Range::closed(
    0.0,
    50.0,
    "MPa",
    "thermoplastic composites are formed and consolidated at a few MPa",
);
/// Coulomb friction coefficients between the blank and a tool.
pub const FRICTION: Range = Range::closed(
    0.0,
    5.0,
    "",
    "measured coefficients between a ply and a tool lie below 1",
);
/// Time scaling of the explicit solver.
pub const TIME_SCALING: Range = Range::closed(
    1.0,
    1e6,
    "",
    "a million times faster is past any quasi-static run",
);
/// The step mass scaling brings the elements up to (s).
pub const TIME_STEP: Range = Range::closed(
    1e-12,
    1.0,
    "s",
    "a picosecond to a second: beyond any stable step of a ply",
);
/// Mass-proportional damping of the virtual tests (1/s).
pub const DAMPING: Range = Range::closed(
    0.0,
    1e6,
    "1/s",
    "a million per second damps any motion within a microsecond",
);
/// Rows of a CSV history.
pub const HISTORY_POINTS: Range =
    Range::closed(1.0, 1e6, "", "a million rows is more than anyone reads");
/// ParaView frames.
pub const FRAMES: Range =
    Range::closed(0.0, 1e4, "", "ten thousand files is more than anyone opens");
/// Density of a ply (tonne/mm^3).
pub const DENSITY: Range = Range::closed(
    1e-12,
    1e-7,
    "tonne/mm^3",
    "0.001 to 100 g/cm^3: from aerogel to past the densest metal",
);
/// Thickness of a layer of a ply (mm).
pub const THICKNESS: Range = Range::closed(
    1e-3,
    100.0,
    "mm",
    "a micrometre to 100 mm: a ply, not a block",
);
/// Moduli and stiffness coefficients of a card (MPa): `C10`, the yarns' `A2` and their secant
/// modulus, the shear law's stress `W_s'`, its friction-like and locking coefficients; the bulk
/// modulus of `fit matrix`.
pub const STIFFNESS: Range = Range::above(0.0, 1e6, "MPa", "1000 GPa is stiffer than any fibre");
/// The resin's bulk modulus `K` of `fit matrix` (MPa), [`COMPLIANCE`]'s range of `2/K`.
pub const BULK_MODULUS: Range = Range::closed(
    1e-3,
    1e6,
    "MPa",
    "1 kPa to 1000 GPa: from a foam to past any solid",
);
/// `D1 = 2/K` of the matrix (1/MPa).
pub const COMPLIANCE: Range = Range::closed(
    2e-6,
    2e3,
    "1/MPa",
    "D1 = 2/K for a bulk modulus K from 1 kPa to 1000 GPa",
);
/// `eta1` of the matrix (MPa·s).
pub const VISCOSITY: Range = Range::closed(0.0, 1e9, "MPa·s", "1e15 Pa·s is a glass, not a melt");
/// Viscosity of the molten film between two plies (Pa·s).
pub const FILM_VISCOSITY: Range = Range::closed(
    0.0,
    1e8,
    "Pa·s",
    "thermoplastic melts flow at 10 to 1e5 Pa·s",
);
/// Yield stress of the film between two plies (MPa).
pub const FILM_YIELD: Range = Range::above(
    0.0,
    1e3,
    "MPa",
    "a molten film yields far below the 1 GPa of a solid polymer",
);
/// Thickness of the molten film between two plies (mm).
pub const FILM_THICKNESS: Range = Range::above(
    0.0,
    100.0,
    "mm",
    "a film between two plies is thinner than any ply",
);
/// Consistency `K` of a power-law film (Pa·s^n).
pub const FILM_CONSISTENCY: Range = Range::above(
    0.0,
    1e8,
    "Pa·s^n",
    "1e8 Pa·s^n is beyond any melt a ply is formed in",
);
/// Power-law index `n` of a shear-thinning film.
pub const FILM_INDEX: Range = Range::above(
    0.0,
    1.0,
    "",
    "a melt thins with the shear rate (n < 1) or not (n = 1), never thickens",
);
/// Lowest shear rate of a power-law film (1/s).
pub const FILM_CUTOFF_RATE: Range = Range::above(
    0.0,
    1e6,
    "1/s",
    "a million per second is past any rheometer and any press",
);
/// Stress at which a Cross film turns from Newtonian to thinning (MPa).
pub const FILM_TRANSITION_STRESS: Range =
    Range::above(0.0, 1e3, "MPa", "1 GPa is beyond any stress a melt carries");
/// Bending rigidity per unit width (N·mm).
pub const BENDING_RIGIDITY: Range = Range::closed(
    0.0,
    1e8,
    "N·mm",
    "a 10 mm plate of 1000 GPa bends with 8e7 N·mm",
);
/// Thermal conductivities (W/(m·K)).
pub const CONDUCTIVITY: Range = Range::above(
    0.0,
    1000.0,
    "W/(m·K)",
    "copper conducts 400 W/(m·K); a polymer 0.2, a carbon fibre up to 100 along its axis",
);
/// Heat-transfer coefficients of a face: to the air, to a tool, between plies (W/(m²·K)).
pub const HEAT_TRANSFER: Range = Range::closed(
    0.0,
    1e6,
    "W/(m²·K)",
    "still air gives 5-25, a prepreg pressed on a steel tool some hundreds to thousands",
);
/// Specific heats (J/(kg·K)).
pub const SPECIFIC_HEAT: Range = Range::above(
    0.0,
    1e5,
    "J/(kg·K)",
    "water's 4186 J/(kg·K) is among the highest of all materials",
);
/// Latent heats of crystallisation (J/g of laminate).
pub const LATENT_HEAT: Range = Range::closed(
    0.0,
    500.0,
    "J/g",
    "a fully crystalline polyethylene releases 293 J/g",
);
/// Emissivities of a surface.
pub const EMISSIVITY: Range = Range::closed(0.0, 1.0, "", "a black body has 1");
/// Times (s) of a process step: the transfer from the oven to the press.
pub const PROCESS_TIME: Range = Range::closed(
    0.0,
    3600.0,
    "s",
    "an hour in air leaves any ply at room temperature",
);
/// The step of the heat equation (s of process time).
pub const THERMAL_STEP: Range = Range::above(
    0.0,
    10.0,
    "s",
    "a ply on a tool cools through its thickness within a second",
);
/// Avrami exponents.
pub const AVRAMI_EXPONENT: Range = Range::closed(
    1.0,
    4.0,
    "",
    "Avrami's n lies between 1 (rods, instantaneous nuclei) and 4 (spheres, sporadic nuclei)",
);
/// Crystallisation rates of Nakamura's law (1/s).
pub const CRYSTALLISATION_RATE: Range = Range::above(
    0.0,
    1e6,
    "1/s",
    "a polymer crystallises within a millisecond at the fastest",
);
/// Contact pressures (MPa).
pub const PRESSURE: Range = Range::closed(
    0.0,
    1000.0,
    "MPa",
    "thermoplastic composites are formed at a few MPa",
);
/// A share, from none to all: the yarns' compression stiffness over their tensile one.
pub const FRACTION: Range = Range::closed(0.0, 1.0, "", "a share of the tensile stiffness");

/// `x` to [`SHOWN_DIGITS`] significant digits, plainly between 1e-4 and 1e7 (`0.3`,
/// `12345.7`), else as `1.5e300`.
pub fn shown(x: f64) -> String {
    shown_to(x, SHOWN_DIGITS)
}

/// `x` with [`SHOWN_DIGITS`] significant digits, or as many more as it takes to tell it from
/// `other` (the end of a range it passed): `360.0001` against 360, never `360`.
pub fn shown_apart(x: f64, other: f64) -> String {
    (SHOWN_DIGITS..=17)
        .map(|digits| (shown_to(x, digits), shown_to(other, digits)))
        .find(|(a, b)| a != b)
        .map_or_else(|| shown_to(x, 17), |(a, _)| a)
}

fn shown_to(x: f64, digits: usize) -> String {
    let r: f64 = format!("{x:.*e}", digits - 1).parse().unwrap_or(x);
    if r == 0.0 || (1e-4..1e7).contains(&r.abs()) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_outside_are_refused_naming_the_key_the_range_and_why() {
        let e = FORCE
            .check("process.blank_holder_force", 1e300)
            .unwrap_err();
        assert_eq!(
            e,
            "process.blank_holder_force = 1e300 N is out of range: it must lie from 0 to 1e7 N \
             (10 MN is a 1000-tonne press)"
        );
        let e = ANGLE.check("--warp-angle", -1e300).unwrap_err();
        assert!(e.starts_with("--warp-angle -1e300° is out of range"), "{e}");
        let e = SHEAR_ANGLE.check("output.locking_angle", 90.0).unwrap_err();
        assert!(e.contains("strictly between 0 and 90°"), "{e}");
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let e = LENGTH.check("blank.width", bad).unwrap_err();
            assert!(e.starts_with(&format!("blank.width = {bad} is out")), "{e}");
        }
        assert!(STIFFNESS.check("c10", 0.0).is_err());
        assert!(STIFFNESS.from_zero().check("shear_friction", 0.0).is_ok());
        let e = STIFFNESS
            .check_each("[matrix] c10", &[0.2, 2e6])
            .unwrap_err();
        assert!(e.starts_with("[matrix] c10[1] = 2000000 MPa"), "{e}");
    }

    /// A closed end is reached within a rounding error and no further; a value past it is shown
    /// with the digits that tell it from the end.
    #[test]
    fn ends_hold_within_rounding_and_refusals_show_the_difference() {
        assert!(ANGLE.contains(360.0 + 1e-8));
        assert!(!ANGLE.contains(360.0 + 1e-6));
        assert!(TIME_STEP.contains(1e-12 * (1.0 - 1e-10)));
        assert!(
            !TIME_STEP.contains(0.0),
            "an absolute tolerance would let 0 through"
        );
        assert!(SHEAR_ANGLE.contains(89.999) && !SHEAR_ANGLE.contains(90.0));
        let e = ANGLE.check("blank.ply_angle", 360.000_000_4).unwrap_err();
        assert!(e.contains("= 360.0000004°"), "{e}");
        assert_eq!(shown_apart(320.000_000_412_345_7, 320.0), "320.0000004");
        assert_eq!(shown_apart(1.0e-7, 1e-4), "1e-7");
        assert_eq!(shown(12345.678), "12345.7");
        assert_eq!(shown(1e300), "1e300");
    }

    #[test]
    fn ranges_describe_their_ends() {
        assert_eq!(LENGTH.describe(), "from 0.001 to 10000 mm");
        assert_eq!(STIFFNESS.describe(), "above 0 and at most 1000000 MPa");
        assert_eq!(FRICTION_ONSET.describe(), "strictly between 0 and 15°");
    }
}
