//! Material cards: a TOML file describing one prepreg ply (layers, matrix, fabric), read and
//! checked into ready-to-use laws. Unknown keys and out-of-range values are errors that name
//! the file and the key.

use super::fabric::{ShearInteraction, ShearTerm, YarnTension};
use super::fabric_shear::DEFAULT_FRICTION_ONSET_DEG;
use super::{
    Laminate, Layer, MaterialError, MaterialLaw, TemperatureTable, ViscoHyperelasticMatrix,
    WovenFabric,
};
use crate::element::BendingRigidity;
use crate::io::from_toml_text;
use crate::limits::{
    between, shown, shown_apart, Range, BENDING_RIGIDITY, COMPLIANCE, DENSITY, FRACTION,
    FRICTION_ONSET, SHEAR_ANGLE, STIFFNESS, TEMPERATURE, THICKNESS, VISCOSITY,
};
use crate::thermal::properties::{ThermalProperties, ThermalSection};
use serde::Deserialize;
use std::path::Path;
use std::sync::Arc;

/// A material card that was read and checked.
#[derive(Clone, Debug)]
pub struct MaterialCard {
    pub name: String,
    /// Density of the ply, tonne/mm^3.
    pub density: f64,
    /// The matrix law; absent for a dry fabric whose stack has no matrix layer.
    pub matrix: Option<Arc<ViscoHyperelasticMatrix>>,
    pub fabric: Arc<WovenFabric>,
    pub laminate: Laminate,
    /// Bending rigidity of the ply per unit width (docs/model.md §4), constant or a table in
    /// temperature; absent: a membrane.
    pub bending: Option<BendingCard>,
    /// The ply's thermal properties (`[thermal]`, docs/model.md §9), which a non-isothermal
    /// run needs; absent: the card serves isothermal runs only.
    pub thermal: Option<ThermalProperties>,
}

/// The card's `[bending]`: rigidities per unit width (N·mm), constant or given at temperatures
/// and interpolated as the matrix's tables are (docs/model.md §4).
#[derive(Clone, Debug, PartialEq)]
pub enum BendingCard {
    Constant(BendingRigidity),
    Table {
        warp: TemperatureTable,
        weft: TemperatureTable,
    },
}

impl BendingCard {
    /// The rigidities at `temperature` (°C); outside a table an error.
    pub fn at(&self, temperature: f64) -> Result<BendingRigidity, MaterialError> {
        match self {
            Self::Constant(r) => Ok(*r),
            Self::Table { warp, weft } => Ok(BendingRigidity {
                warp: warp.at(temperature)?,
                weft: weft.at(temperature)?,
            }),
        }
    }

    /// The temperatures the table covers; `None` for constant rigidities.
    pub fn range(&self) -> Option<(f64, f64)> {
        match self {
            Self::Constant(_) => None,
            Self::Table { warp, .. } => Some(warp.range()),
        }
    }
}

/// What is wrong with a material card, and in which file.
#[derive(Debug, thiserror::Error)]
#[error("{origin}: {message}")]
pub struct CardError {
    pub origin: String,
    pub message: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CardFile {
    name: String,
    density: f64,
    layers: LayersSection,
    matrix: Option<MatrixSection>,
    fabric: FabricSection,
    bending: Option<BendingSection>,
    thermal: Option<ThermalSection>,
}

/// `[bending]`: rigidities per unit width (N·mm) for curvature along warp and weft, as from
/// cantilever (Peirce) tests of the prepreg at the forming temperature: numbers, or lists at
/// the temperatures of `temperature`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BendingSection {
    temperature: Option<Vec<f64>>,
    warp: NumberOrList,
    weft: NumberOrList,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum NumberOrList {
    Number(f64),
    List(Vec<f64>),
}

impl BendingSection {
    fn check(self) -> Result<BendingCard, String> {
        let key = |name: &str| format!("[bending] {name}");
        match (self.temperature, self.warp, self.weft) {
            (None, NumberOrList::Number(warp), NumberOrList::Number(weft)) => {
                BENDING_RIGIDITY.check("[bending] warp", warp)?;
                BENDING_RIGIDITY.check("[bending] weft", weft)?;
                Ok(BendingCard::Constant(BendingRigidity { warp, weft }))
            }
            (Some(temperatures), NumberOrList::List(warp), NumberOrList::List(weft)) => {
                TEMPERATURE.check_each("[bending] temperature", &temperatures)?;
                BENDING_RIGIDITY.check_each("[bending] warp", &warp)?;
                BENDING_RIGIDITY.check_each("[bending] weft", &weft)?;
                Ok(BendingCard::Table {
                    warp: TemperatureTable::new(key("warp"), temperatures.clone(), warp)?,
                    weft: TemperatureTable::new(key("weft"), temperatures, weft)?,
                })
            }
            (None, _, _) => Err(
                "[bending] warp and weft are numbers (N·mm), or lists with a temperature list"
                    .into(),
            ),
            (Some(_), _, _) => Err(
                "[bending] with a temperature list, warp and weft are lists of the rigidity at \
                 each temperature"
                    .into(),
            ),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LayersSection {
    matrix_thickness: Option<f64>,
    fabric_thickness: f64,
    #[serde(default = "default_stack")]
    stack: Vec<LayerKind>,
}

#[derive(Deserialize, Clone, Copy, PartialEq, Eq, Debug)]
#[serde(rename_all = "lowercase")]
enum LayerKind {
    Matrix,
    Fabric,
}

fn default_stack() -> Vec<LayerKind> {
    vec![LayerKind::Matrix, LayerKind::Fabric, LayerKind::Matrix]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MatrixSection {
    temperature: Vec<f64>,
    c10: Vec<f64>,
    d1: Vec<f64>,
    eta1: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FabricSection {
    warp_tension: Vec<f64>,
    weft_tension: Vec<f64>,
    #[serde(default = "default_compression_fraction")]
    compression_fraction: f64,
    /// Polynomial `c_1, c_2, ...` of `W_s` (MPa); may be empty with another shear term.
    #[serde(default)]
    shear: Vec<f64>,
    /// Friction-like term `k_0` (MPa, docs/model.md §3).
    shear_friction: Option<f64>,
    /// Its onset angle (degrees): `eps = sin(onset)`.
    shear_friction_onset: Option<f64>,
    /// Locking term `k_l` (MPa) and its angle (degrees).
    shear_locking: Option<f64>,
    shear_locking_angle: Option<f64>,
}

/// docs/model.md §3: yarn compression stiffness defaults to 1e-3 of the initial tensile one.
fn default_compression_fraction() -> f64 {
    1e-3
}

/// Largest shear angle at which the shear energy must still be non-decreasing (degrees): a card
/// is checked at every whole degree up to it, and so is every trial law of the FE refinement
/// (`fit::shear_fe`), so that a refined law can be written to a card that loads.
pub(crate) const SHEAR_CHECK_LIMIT_DEG: u32 = 75;
/// Yarn strain up to which the tension must stay non-negative.
const TENSION_CHECK_STRAIN: f64 = 0.05;

impl MaterialCard {
    /// Reads and checks the card at `path`.
    pub fn load(path: &Path) -> Result<Self, CardError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| CardError {
            origin: origin.clone(),
            message: format!("cannot read the material card: {e}"),
        })?;
        Self::from_toml(&text, &origin)
    }

    /// The temperatures over which the card's tables are defined (all of them at once);
    /// `None` for a card with nothing tabulated (a dry fabric), which holds at any temperature.
    pub fn temperature_range(&self) -> Option<(f64, f64)> {
        let matrix = self.matrix.as_ref().map(|m| m.parameters_range());
        let bending = self.bending.as_ref().and_then(BendingCard::range);
        match (matrix, bending) {
            (Some((a, b)), Some((c, d))) => Some((a.max(c), b.min(d))),
            (one, other) => one.or(other),
        }
    }

    /// Whether the card's tables cover `temperature` (°C), which `key` (a scenario key or a
    /// command-line option) gave: the run is refused before it starts rather than stopped by
    /// its first element. A temperature within a rounding error of a table's end is at the end
    /// (`limits::ROUNDING`), as the tables themselves take it.
    pub fn check_temperature(&self, key: &str, temperature: f64) -> Result<(), String> {
        match self.temperature_range() {
            Some((lo, hi)) if !between(temperature, lo, hi) => {
                let nearest = if temperature < lo { lo } else { hi };
                Err(format!(
                    "{key} = {} °C is outside the card's tables ({}): choose a temperature \
                     inside them, or extend the tables of the card",
                    shown_apart(temperature, nearest),
                    describe_tables(self.matrix.as_deref(), self.bending.as_ref())
                ))
            }
            _ => Ok(()),
        }
    }

    /// Reads and checks a card from TOML text; `origin` names it in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, CardError> {
        let error = |message: String| CardError {
            origin: origin.to_string(),
            message,
        };
        let file: CardFile = from_toml_text(text).map_err(error)?;
        file.check().map_err(error)
    }
}

/// The temperatures each of the card's tables covers, for messages: `[matrix] temperature
/// 280 to 320 °C and [bending] temperature 250 °C`.
fn describe_tables(
    matrix: Option<&ViscoHyperelasticMatrix>,
    bending: Option<&BendingCard>,
) -> String {
    let span = |(lo, hi): (f64, f64)| {
        if lo == hi {
            format!("{} °C", shown(lo))
        } else {
            format!("{} to {} °C", shown(lo), shown(hi))
        }
    };
    let tables: Vec<String> = [
        (
            "[matrix]",
            matrix.map(ViscoHyperelasticMatrix::parameters_range),
        ),
        ("[bending]", bending.and_then(BendingCard::range)),
    ]
    .into_iter()
    .filter_map(|(section, range)| Some(format!("{section} temperature {}", span(range?))))
    .collect();
    tables.join(" and ")
}

/// The matrix's and the bending's tables must share a temperature, or the card holds at none.
fn check_tables_overlap(
    matrix: Option<&ViscoHyperelasticMatrix>,
    bending: Option<&BendingCard>,
) -> Result<(), String> {
    let (Some((a, b)), Some((c, d))) = (
        matrix.map(ViscoHyperelasticMatrix::parameters_range),
        bending.and_then(BendingCard::range),
    ) else {
        return Ok(());
    };
    let (lo, hi) = (a.max(c), b.min(d));
    if lo <= hi || between(lo, hi, hi) {
        return Ok(());
    }
    Err(format!(
        "the tables do not overlap ({}): the card holds at no temperature; give [bending] \
         rigidities at temperatures of the [matrix] table",
        describe_tables(matrix, bending)
    ))
}

fn all_finite(key: &str, values: &[f64]) -> Result<(), String> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(format!("{key}[{i}] is not a finite number")),
        None => Ok(()),
    }
}

impl CardFile {
    fn check(self) -> Result<MaterialCard, String> {
        if self.name.trim().is_empty() {
            return Err("name must not be empty".into());
        }
        DENSITY.check("density", self.density)?;
        let matrix = self
            .matrix
            .map(MatrixSection::check)
            .transpose()?
            .map(Arc::new);
        let fabric = Arc::new(self.fabric.check()?);
        let laminate = self.layers.check(matrix.clone(), fabric.clone())?;
        let bending = self.bending.map(BendingSection::check).transpose()?;
        check_tables_overlap(matrix.as_deref(), bending.as_ref())?;
        let thermal = self.thermal.map(ThermalSection::check).transpose()?;
        Ok(MaterialCard {
            name: self.name,
            density: self.density,
            matrix,
            fabric,
            laminate,
            bending,
            thermal,
        })
    }
}

impl LayersSection {
    fn check(
        &self,
        matrix: Option<Arc<ViscoHyperelasticMatrix>>,
        fabric: Arc<WovenFabric>,
    ) -> Result<Laminate, String> {
        let t_b = self.fabric_thickness;
        THICKNESS.check("[layers] fabric_thickness", t_b)?;
        if !self.stack.contains(&LayerKind::Fabric) {
            return Err("[layers] stack must contain at least one \"fabric\" layer".into());
        }
        let matrix_layer = match (self.stack.contains(&LayerKind::Matrix), matrix) {
            (false, _) => None,
            (true, None) => {
                return Err(
                    "the stack has matrix layers but the card has no [matrix] section".into(),
                )
            }
            (true, Some(law)) => {
                let thickness = self
                    .matrix_thickness
                    .ok_or("[layers] matrix_thickness is missing")?;
                THICKNESS.check("[layers] matrix_thickness", thickness)?;
                Some(Layer {
                    law: law as Arc<dyn MaterialLaw>,
                    thickness,
                })
            }
        };
        let layers = self
            .stack
            .iter()
            .map(|kind| match (kind, &matrix_layer) {
                (LayerKind::Matrix, Some(layer)) => layer.clone(),
                _ => Layer {
                    law: fabric.clone() as Arc<dyn MaterialLaw>,
                    thickness: t_b,
                },
            })
            .collect();
        Laminate::new(layers).map_err(|e| format!("[layers]: {e}"))
    }
}

impl MatrixSection {
    fn check(self) -> Result<ViscoHyperelasticMatrix, String> {
        let table = |key: &str, values: Vec<f64>| {
            TemperatureTable::new(key, self.temperature.clone(), values)
                .map_err(|e| format!("[matrix]: {e}"))
        };
        let c10 = table("c10", self.c10)?;
        let d1 = table("d1", self.d1)?;
        let eta1 = table("eta1", self.eta1)?;
        TEMPERATURE.check_each("[matrix] temperature", &self.temperature)?;
        STIFFNESS.check_each("[matrix] c10", c10.values())?;
        COMPLIANCE.check_each("[matrix] d1", d1.values())?;
        VISCOSITY.check_each("[matrix] eta1", eta1.values())?;
        Ok(ViscoHyperelasticMatrix::new(c10, d1, eta1))
    }
}

impl FabricSection {
    fn check(self) -> Result<WovenFabric, String> {
        let f = self.compression_fraction;
        FRACTION.check("[fabric] compression_fraction", f)?;
        let shear = self.shear_law()?;
        let warp = yarn("[fabric] warp_tension", self.warp_tension, f)?;
        let weft = yarn("[fabric] weft_tension", self.weft_tension, f)?;
        check_shear_stress(&shear)?;
        Ok(WovenFabric::new(warp, weft, shear))
    }
}

/// The shear law's stress `W_s'(I10)` at every whole degree up to [`SHEAR_CHECK_LIMIT_DEG`],
/// as far as a forming run shears: never negative (a falling shear energy is a negative shear
/// stiffness, unstable in any solver) and never beyond [`STIFFNESS`] (a high power fitted to
/// a few points can reach 1e18 MPa there).
fn check_shear_stress(shear: &ShearInteraction) -> Result<(), String> {
    for deg in (0..=SHEAR_CHECK_LIMIT_DEG).map(f64::from) {
        let stress = shear.derivative(deg.to_radians().sin().powi(2));
        if stress < 0.0 {
            return Err(format!(
                "[fabric] shear: the shear energy decreases at {deg}° of shear (W_s'(I10) < 0; \
                 a card's law is checked up to {SHEAR_CHECK_LIMIT_DEG}°): the coefficients give a \
                 negative shear stiffness"
            ));
        }
        let key = format!("[fabric] shear: W_s'(I10) at {deg}° of shear");
        STIFFNESS.from_zero().check(&key, stress)?;
    }
    Ok(())
}

impl FabricSection {
    /// `W_s` from `shear`, `shear_friction` (and its onset) and `shear_locking` (and its angle),
    /// docs/model.md §3: at least one term; coefficients finite, the friction and locking ones
    /// non-negative; angles inside their ranges.
    fn shear_law(&self) -> Result<ShearInteraction, String> {
        all_finite("[fabric] shear", &self.shear)?;
        let mut terms: Vec<(ShearTerm, f64)> =
            ShearInteraction::new(self.shear.clone()).terms().to_vec();
        let non_negative = |key: &str, v: f64| {
            STIFFNESS.from_zero().check(&format!("[fabric] {key}"), v)?;
            Ok::<_, String>(v)
        };
        let angle = |key: &str, v: f64, range: Range| {
            range.check(&format!("[fabric] {key}"), v)?;
            Ok::<_, String>(v.to_radians())
        };
        match (self.shear_friction, self.shear_friction_onset) {
            (Some(k0), onset) => {
                let onset = onset.unwrap_or(DEFAULT_FRICTION_ONSET_DEG);
                terms.push((
                    ShearTerm::Friction {
                        onset: angle("shear_friction_onset", onset, FRICTION_ONSET)?,
                    },
                    non_negative("shear_friction", k0)?,
                ));
            }
            (None, Some(_)) => {
                return Err("[fabric] shear_friction_onset is given without shear_friction".into())
            }
            (None, None) => {}
        }
        match (self.shear_locking, self.shear_locking_angle) {
            (Some(kl), Some(a)) => terms.push((
                ShearTerm::Locking {
                    angle: angle("shear_locking_angle", a, SHEAR_ANGLE)?,
                },
                non_negative("shear_locking", kl)?,
            )),
            (Some(_), None) => {
                return Err(
                    "[fabric] shear_locking needs shear_locking_angle (degrees), where it begins"
                        .into(),
                )
            }
            (None, Some(_)) => {
                return Err("[fabric] shear_locking_angle is given without shear_locking".into())
            }
            (None, None) => {}
        }
        if terms.is_empty() {
            return Err(
                "[fabric] shear needs at least one term: coefficients c1, c2, ... or shear_friction"
                    .into(),
            );
        }
        Ok(ShearInteraction::from_terms(terms))
    }
}

fn yarn(
    key: &str,
    coefficients: Vec<f64>,
    compression_fraction: f64,
) -> Result<YarnTension, String> {
    all_finite(key, &coefficients)?;
    let Some(&a2) = coefficients.first() else {
        return Err(format!("{key} needs at least one coefficient A2"));
    };
    // A2 is the yarns' initial tensile modulus
    STIFFNESS.check(&format!("{key}[0] (A2)"), a2)?;
    let tension = YarnTension::new(coefficients, compression_fraction);
    for i in 1..=50 {
        let stretch = 1.0 + TENSION_CHECK_STRAIN * f64::from(i) / 50.0;
        if tension.tension(stretch) < 0.0 {
            return Err(format!(
                "{key}: the yarn tension is negative at {:.1} % strain; check the signs of A_k",
                100.0 * (stretch - 1.0)
            ));
        }
    }
    // the higher A_k, small strains' coefficients, are bounded through the modulus they give
    let stretch = 1.0 + TENSION_CHECK_STRAIN;
    let secant = format!(
        "{key}: the yarns' secant modulus at {} % strain",
        100.0 * TENSION_CHECK_STRAIN
    );
    STIFFNESS
        .from_zero()
        .check(&secant, tension.tension(stretch) / TENSION_CHECK_STRAIN)?;
    Ok(tension)
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALID: &str = r#"
name = "test"
density = 1.5e-9
[layers]
matrix_thickness = 0.04
fabric_thickness = 0.23
[matrix]
temperature = [280.0, 320.0]
c10 = [0.05, 0.02]
d1 = [1e-3, 1e-3]
eta1 = [1e-3, 5e-4]
[fabric]
warp_tension = [4e4, 2e6]
weft_tension = [4e4, 2e6]
shear = [0.25, 0.0, 2.0]
"#;

    fn error_of(text: &str) -> String {
        MaterialCard::from_toml(text, "card.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn reads_a_valid_card_into_an_aba_laminate() {
        let card = MaterialCard::from_toml(VALID, "card.toml").unwrap();
        let names: Vec<_> = card
            .laminate
            .layers()
            .iter()
            .map(|l| l.law.name())
            .collect();
        assert_eq!(names, ["matrix", "fabric", "matrix"]);
        assert!((card.laminate.reference_thickness() - 0.31).abs() < 1e-12);
        assert_eq!(card.fabric.warp.tension(1.0), 0.0);
    }

    #[test]
    fn unknown_key_is_named_with_its_line() {
        let text = VALID.replace("shear = [", "sheer = 1\nshear = [");
        let e = error_of(&text);
        assert!(e.starts_with("card.toml: line 15, column 1"), "{e}");
        assert!(e.contains("sheer"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }

    #[test]
    fn bad_values_name_their_key() {
        let cases = [
            (
                "matrix_thickness = 0.04",
                "matrix_thickness = -0.04",
                "[layers] matrix_thickness",
            ),
            ("c10 = [0.05, 0.02]", "c10 = [0.05]", "c10 has 1 values"),
            ("d1 = [1e-3, 1e-3]", "d1 = [1e-3, 0.0]", "[matrix] d1[1]"),
            (
                "warp_tension = [4e4, 2e6]",
                "warp_tension = [0.0, 2e6]",
                "warp_tension[0] (A2)",
            ),
            (
                "weft_tension = [4e4, 2e6]",
                "weft_tension = [4e4, -1e8]",
                "weft_tension: the yarn tension is negative",
            ),
            (
                "shear = [0.25, 0.0, 2.0]",
                "shear = [0.25, -1.0]",
                "shear energy decreases",
            ),
            ("density = 1.5e-9", "density = 0.0", "density = 0"),
            (
                "temperature = [280.0, 320.0]",
                "temperature = [320.0, 280.0]",
                "increase strictly",
            ),
        ];
        for (from, to, expected) in cases {
            let e = error_of(&VALID.replace(from, to));
            assert!(e.contains(expected), "{to}: {e}");
        }
    }

    /// The friction-like and locking terms of `W_s`: read with their angles, the onset's
    /// default 1°, and refused when half given, negative or out of range, naming the key.
    #[test]
    fn shear_friction_and_locking_terms_are_read_and_checked() {
        let with = VALID.replace(
            "shear = [0.25, 0.0, 2.0]",
            "shear = [0.25]\nshear_friction = 0.05\nshear_locking = 3.0\nshear_locking_angle = 45.0",
        );
        let card = MaterialCard::from_toml(&with, "card.toml").unwrap();
        let shear = &card.fabric.shear;
        assert_eq!(shear.coefficients(), vec![0.25]);
        assert_eq!(shear.friction(), Some((0.05, 1f64.to_radians())));
        assert_eq!(shear.locking(), Some((3.0, 45f64.to_radians())));
        let friction_only = VALID.replace(
            "shear = [0.25, 0.0, 2.0]",
            "shear_friction = 0.05\nshear_friction_onset = 2.0",
        );
        let card = MaterialCard::from_toml(&friction_only, "card.toml").unwrap();
        assert_eq!(
            card.fabric.shear.friction(),
            Some((0.05, 2f64.to_radians()))
        );
        let cases = [
            (
                "shear_friction = 0.05",
                "shear_friction = -0.05",
                "shear_friction = -0.05",
            ),
            (
                "shear_locking_angle = 45.0",
                "shear_locking_angle = 95.0",
                "shear_locking_angle = 95",
            ),
            (
                "shear_locking_angle = 45.0",
                "",
                "needs shear_locking_angle",
            ),
            (
                "shear_friction = 0.05",
                "shear_friction_onset = 1.0",
                "without shear_friction",
            ),
            (
                "shear_friction = 0.05",
                "shear_friction_onset = 20.0\nshear_friction = 0.05",
                "shear_friction_onset = 20",
            ),
        ];
        for (from, to, expected) in cases {
            let e = error_of(&with.replace(from, to));
            assert!(e.contains(expected), "{to}: {e}");
        }
        let none = VALID.replace("shear = [0.25, 0.0, 2.0]", "shear = []");
        assert!(
            error_of(&none).contains("at least one term"),
            "{}",
            error_of(&none)
        );
    }

    #[test]
    fn bending_section_is_optional_and_checked() {
        assert!(MaterialCard::from_toml(VALID, "card.toml")
            .unwrap()
            .bending
            .is_none());
        let with = format!("{VALID}\n[bending]\nwarp = 2.0\nweft = 0.5\n");
        let card = MaterialCard::from_toml(&with, "card.toml").unwrap();
        assert_eq!(
            card.bending,
            Some(BendingCard::Constant(BendingRigidity {
                warp: 2.0,
                weft: 0.5
            }))
        );
        let negative = with.replace("weft = 0.5", "weft = -0.5");
        assert!(error_of(&negative).contains("[bending] weft = -0.5 N·mm"));
        let unknown = with.replace("weft = 0.5", "weft = 0.5\ntwist = 1.0");
        assert!(error_of(&unknown).contains("twist"));
    }

    /// Rigidities given at temperatures: interpolated, the card's range narrowed to the table's,
    /// and a table that does not match its temperatures or mixes numbers and lists refused.
    #[test]
    fn bending_rigidity_may_be_a_temperature_table() {
        let with = format!(
            "{VALID}\n[bending]\ntemperature = [290.0, 310.0]\nwarp = [2.0, 1.0]\nweft = [1.0, 0.5]\n"
        );
        let card = MaterialCard::from_toml(&with, "card.toml").unwrap();
        let bending = card.bending.as_ref().unwrap();
        let at = bending.at(300.0).unwrap();
        assert!((at.warp - 1.5).abs() < 1e-12 && (at.weft - 0.75).abs() < 1e-12);
        assert_eq!(card.temperature_range(), Some((290.0, 310.0)));
        assert!(card
            .check_temperature("process.temperature", 285.0)
            .is_err());
        assert!(bending.at(315.0).is_err());
        for (from, to, expected) in [
            ("warp = [2.0, 1.0]", "warp = [2.0]", "has 1 values"),
            ("warp = [2.0, 1.0]", "warp = 2.0", "lists of the rigidity"),
            (
                "warp = [2.0, 1.0]",
                "warp = [2.0, -1.0]",
                "[bending] warp[1] = -1 N·mm",
            ),
            (
                "temperature = [290.0, 310.0]\n",
                "",
                "with a temperature list",
            ),
        ] {
            let e = error_of(&with.replace(from, to));
            assert!(e.contains(expected), "{to}: {e}");
        }
    }

    /// A bending table that shares no temperature with the matrix's is refused when the card is
    /// read, naming both tables, instead of a range printed backwards ("280 to 250 °C") when
    /// the card is used.
    #[test]
    fn tables_that_do_not_overlap_are_refused_naming_both() {
        let with =
            format!("{VALID}\n[bending]\ntemperature = [250.0]\nwarp = [2.0]\nweft = [1.0]\n");
        let e = error_of(&with);
        assert!(e.starts_with("card.toml: the tables do not overlap"), "{e}");
        assert!(
            e.contains("[matrix] temperature 280 to 320 °C and [bending] temperature 250 °C"),
            "{e}"
        );
        let touching = with.replace("[250.0]", "[320.0]");
        assert!(MaterialCard::from_toml(&touching, "card.toml").is_ok());
    }

    /// A temperature a rounding error past a table's end is at the end; one further out is
    /// refused with the digits that show it, and the tables' ranges.
    #[test]
    fn temperatures_at_the_tables_ends_hold_within_rounding() {
        let card = MaterialCard::from_toml(VALID, "card.toml").unwrap();
        card.check_temperature("process.temperature", 320.000_000_000_1)
            .unwrap();
        let e = card
            .check_temperature("process.temperature", 320.000_000_412_345_7)
            .unwrap_err();
        assert!(
            e.starts_with(
                "process.temperature = 320.0000004 °C is outside the card's tables \
                 ([matrix] temperature 280 to 320 °C)"
            ),
            "{e}"
        );
    }

    /// Every number of a card within its quantity's range (`crate::limits`), named by its key.
    #[test]
    fn values_nobody_means_are_refused_naming_the_key() {
        for (from, to, expected) in [
            (
                "density = 1.5e-9",
                "density = 1.5e300",
                "density = 1.5e300 tonne/mm^3",
            ),
            (
                "fabric_thickness = 0.23",
                "fabric_thickness = 1e9",
                "[layers] fabric_thickness",
            ),
            (
                "temperature = [280.0, 320.0]",
                "temperature = [280.0, 1e300]",
                "[matrix] temperature[1]",
            ),
            (
                "c10 = [0.05, 0.02]",
                "c10 = [0.05, 1e300]",
                "[matrix] c10[1]",
            ),
            (
                "eta1 = [1e-3, 5e-4]",
                "eta1 = [1e-3, 1e300]",
                "[matrix] eta1[1]",
            ),
            (
                "warp_tension = [4e4, 2e6]",
                "warp_tension = [4e300, 2e6]",
                "warp_tension[0] (A2) = 4e300 MPa",
            ),
            (
                "weft_tension = [4e4, 2e6]",
                "weft_tension = [4e4, 2e12]",
                "weft_tension: the yarns' secant modulus at 5 % strain",
            ),
            (
                "shear = [0.25, 0.0, 2.0]",
                "shear = [0.25, 0.0, 2e20]",
                "W_s'(I10) at 1° of shear",
            ),
            (
                "shear = [0.25, 0.0, 2.0]",
                "shear = [0.25]\ncompression_fraction = 2.0",
                "compression_fraction = 2",
            ),
        ] {
            let e = error_of(&VALID.replace(from, to));
            assert!(e.contains(expected), "{to}: {e}");
            assert!(e.contains("out of range"), "{to}: {e}");
        }
    }

    #[test]
    fn missing_section_is_an_error() {
        let text = VALID.split("[fabric]").next().unwrap();
        assert!(error_of(text).contains("fabric"));
    }

    #[test]
    fn dry_fabric_needs_no_matrix() {
        let fabric_only = VALID.split("[matrix]").next().unwrap().to_string()
            + "[fabric]"
            + VALID.split("[fabric]").nth(1).unwrap();
        let text = fabric_only
            .replace("matrix_thickness = 0.04\n", "")
            .replace(
                "fabric_thickness = 0.23",
                "fabric_thickness = 0.23\nstack = [\"fabric\"]",
            );
        let card = MaterialCard::from_toml(&text, "dry.toml").unwrap();
        assert!(card.matrix.is_none());
        assert_eq!(card.laminate.layers().len(), 1);
        let missing = fabric_only.replace("matrix_thickness = 0.04\n", "");
        assert!(
            error_of(&missing).contains("no [matrix] section"),
            "{}",
            error_of(&missing)
        );
    }

    #[test]
    fn custom_stack_of_layers() {
        let text = VALID.replace(
            "fabric_thickness = 0.23",
            "fabric_thickness = 0.23\nstack = [\"matrix\", \"fabric\", \"matrix\", \"fabric\", \"matrix\"]",
        );
        let card = MaterialCard::from_toml(&text, "card.toml").unwrap();
        assert_eq!(card.laminate.layers().len(), 5);
        assert!((card.laminate.reference_thickness() - 0.58).abs() < 1e-12);
    }
}
