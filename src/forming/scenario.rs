//! The scenario file of a forming run: blank, tools, process and outputs, read from TOML and
//! checked. Unknown keys and inconsistent values are errors that name the key; any scalar can
//! be overridden from the command line (`--set process.temperature=310`).

use crate::io::describe_toml_error;
use crate::mesh::DiagonalPattern;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A scenario read and checked; paths resolved against the scenario's folder.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    pub origin: String,
    pub blank: Blank,
    pub tools: Tools,
    pub process: Process,
    pub output: Output,
}

/// The blank: a rectangular ply of one material card.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Blank {
    /// Material card (TOML), relative to the scenario file.
    pub card: PathBuf,
    /// Size along x and y (mm), centred on the punch axis.
    pub width: f64,
    pub length: f64,
    /// Target element size (mm).
    pub element_size: f64,
    /// Warp angle from x (degrees).
    #[serde(default)]
    pub ply_angle: f64,
    /// Cell pattern; single diagonals by default (bending is accurate on them, see
    /// `element::bending_triangle`).
    #[serde(default = "default_pattern")]
    pub pattern: DiagonalPattern,
}

fn default_pattern() -> DiagonalPattern {
    DiagonalPattern::Right
}

/// The tool set: a hemispherical (or double-dome) punch, a die with a round (or stadium-shaped)
/// opening and a flat blank holder around it (`contact::tools`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tools {
    /// "hemisphere" or "double-dome".
    pub shape: String,
    /// Double dome only: half-length of the punch's ridge along x (mm). Every radius of the
    /// tool set is then a distance from the ridge segment `|x| <= half_length`.
    pub half_length: Option<f64>,
    pub punch_radius: f64,
    pub die_opening_radius: f64,
    pub die_fillet_radius: f64,
    /// Inner radius of the blank holder (default: the die opening plus its fillet).
    pub holder_inner_radius: Option<f64>,
    /// Target edge length of the tool meshes (mm).
    pub resolution: f64,
}

/// Forming temperature, punch travel, blank-holder force, friction, scaling.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Process {
    /// Isothermal forming temperature (°C).
    pub temperature: f64,
    /// Punch travel (mm) and physical punch speed (mm/s).
    pub stroke: f64,
    pub punch_speed: f64,
    /// Blank-holder force (N): the holder pushes the flange against the die with it, free to
    /// move along the stroke. 0 (the default) leaves the holder out, unless a gap is given.
    #[serde(default)]
    pub blank_holder_force: f64,
    /// Instead of a force, the holder fixed at this gap (mm) below the blank's lower face: the
    /// die and the holder `thickness + gap` apart.
    pub blank_holder_gap: Option<f64>,
    /// Coulomb friction between the blank and each tool.
    pub friction: Friction,
    /// Time scaling: the stroke runs this many times faster, eta1 divided by it.
    #[serde(default = "one")]
    pub time_scaling: f64,
    /// Mass scaling to this time step (s).
    pub target_time_step: Option<f64>,
}

fn one() -> f64 {
    1.0
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    pub punch: f64,
    pub die: f64,
    pub holder: f64,
}

/// What to write.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// Output folder, relative to the working directory.
    #[serde(default = "default_folder")]
    pub folder: PathBuf,
    /// ParaView frames over the stroke (0: none) and rows of the CSV history.
    #[serde(default = "default_frames")]
    pub frames: usize,
    #[serde(default = "default_history")]
    pub history_points: usize,
    /// Locking angle of the fabric (degrees), marked on the shear-angle map; cells beyond it
    /// are flagged. `None`: no mark.
    pub locking_angle: Option<f64>,
}

impl Default for Output {
    fn default() -> Self {
        Self {
            folder: default_folder(),
            frames: default_frames(),
            history_points: default_history(),
            locking_angle: None,
        }
    }
}

fn default_folder() -> PathBuf {
    PathBuf::from("results")
}

fn default_frames() -> usize {
    20
}

fn default_history() -> usize {
    100
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    blank: Blank,
    tools: Tools,
    process: Process,
    #[serde(default)]
    output: Output,
}

/// Why a scenario cannot be used: the file and what is wrong (with the key or the line).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{origin}: {message}")]
pub struct ScenarioError {
    pub origin: String,
    pub message: String,
}

impl Scenario {
    /// Reads `path`, applies the `key=value` overrides, and checks it.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Self, ScenarioError> {
        let origin = path.display().to_string();
        let error = |message: String| ScenarioError {
            origin: origin.clone(),
            message,
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| error(format!("cannot read the scenario: {e}")))?;
        let file: ScenarioFile = if overrides.is_empty() {
            toml::from_str(&text).map_err(|e| error(describe_toml_error(&text, &e)))?
        } else {
            let mut table: toml::Table =
                toml::from_str(&text).map_err(|e| error(describe_toml_error(&text, &e)))?;
            for o in overrides {
                apply_override(&mut table, o).map_err(error)?;
            }
            toml::Value::Table(table)
                .try_into()
                .map_err(|e: toml::de::Error| error(e.message().trim().replace('\n', " ")))?
        };
        let folder = path.parent().unwrap_or(Path::new("."));
        let scenario = Scenario {
            origin: origin.clone(),
            blank: Blank {
                card: folder.join(&file.blank.card),
                ..file.blank
            },
            tools: file.tools,
            process: file.process,
            output: file.output,
        };
        scenario.check().map_err(error)?;
        Ok(scenario)
    }

    /// Half-length of the punch's ridge (mm): 0 for the hemisphere.
    pub fn ridge_half_length(&self) -> f64 {
        self.tools.half_length.unwrap_or(0.0)
    }

    /// Distance (mm) of `(x, y)` from the punch's axis (hemisphere) or ridge (double dome):
    /// the radius that every size of the tool set is measured along.
    pub fn distance_from_ridge(&self, x: f64, y: f64) -> f64 {
        crate::contact::distance_from_ridge(self.ridge_half_length(), x, y)
    }

    /// The holder's inner radius.
    pub fn holder_inner_radius(&self) -> f64 {
        self.tools
            .holder_inner_radius
            .unwrap_or(self.tools.die_opening_radius + self.tools.die_fillet_radius)
    }

    /// Consistency: sizes positive, the punch passes through the die opening, the blank
    /// reaches over the holder, the stroke stays within the die.
    fn check(&self) -> Result<(), String> {
        let (b, t, p) = (&self.blank, &self.tools, &self.process);
        for (key, value) in [
            ("blank.width", b.width),
            ("blank.length", b.length),
            ("blank.element_size", b.element_size),
            ("tools.punch_radius", t.punch_radius),
            ("tools.die_opening_radius", t.die_opening_radius),
            ("tools.die_fillet_radius", t.die_fillet_radius),
            ("tools.resolution", t.resolution),
            ("process.stroke", p.stroke),
            ("process.punch_speed", p.punch_speed),
        ] {
            positive(key, value)?;
        }
        self.check_shape()?;
        if !(p.temperature.is_finite()) {
            return Err("process.temperature must be a number".into());
        }
        if !(p.blank_holder_force.is_finite() && p.blank_holder_force >= 0.0) {
            return Err(format!(
                "process.blank_holder_force = {} must be >= 0 (N)",
                p.blank_holder_force
            ));
        }
        if let Some(gap) = p.blank_holder_gap {
            if !(gap.is_finite() && gap >= 0.0) {
                return Err(format!(
                    "process.blank_holder_gap = {gap} must be >= 0 (mm)"
                ));
            }
            if p.blank_holder_force > 0.0 {
                return Err(
                    "process.blank_holder_force and process.blank_holder_gap are two ways to \
                     drive the holder: give one of them"
                        .into(),
                );
            }
        }
        for (key, mu) in [
            ("process.friction.punch", p.friction.punch),
            ("process.friction.die", p.friction.die),
            ("process.friction.holder", p.friction.holder),
        ] {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(format!("{key} = {mu} must be >= 0"));
            }
        }
        if !(p.time_scaling.is_finite() && p.time_scaling >= 1.0) {
            return Err(format!(
                "process.time_scaling = {} must be >= 1",
                p.time_scaling
            ));
        }
        if let Some(dt) = p.target_time_step {
            positive("process.target_time_step", dt)?;
        }
        if t.die_opening_radius <= t.punch_radius {
            return Err(format!(
                "tools.die_opening_radius = {} must exceed tools.punch_radius = {} (plus the \
                 blank's thickness) for the punch to pass",
                t.die_opening_radius, t.punch_radius
            ));
        }
        if p.stroke > 2.0 * t.punch_radius {
            return Err(format!(
                "process.stroke = {} goes beyond the punch (radius {} with a skirt as tall)",
                p.stroke, t.punch_radius
            ));
        }
        let holder = self.holder_inner_radius();
        positive("tools.holder_inner_radius", holder)?;
        if holder <= t.punch_radius {
            return Err(format!(
                "tools.holder_inner_radius = {holder} must exceed tools.punch_radius = {}",
                t.punch_radius
            ));
        }
        let half_side = (0.5 * b.width - self.ridge_half_length()).min(0.5 * b.length);
        if (p.blank_holder_force > 0.0 || p.blank_holder_gap.is_some()) && half_side <= holder {
            return Err(format!(
                "the blank ({} x {} mm) does not reach the blank holder (inner radius {holder} \
                 mm): it cannot be held",
                b.width, b.length
            ));
        }
        if b.element_size > 0.25 * t.punch_radius {
            return Err(format!(
                "blank.element_size = {} is too coarse for a punch of radius {}: at least four \
                 elements across the punch radius are needed",
                b.element_size, t.punch_radius
            ));
        }
        if let Some(angle) = self.output.locking_angle {
            if !(angle.is_finite() && angle > 0.0 && angle < 90.0) {
                return Err(format!(
                    "output.locking_angle = {angle} must lie between 0 and 90 degrees"
                ));
            }
        }
        if self.output.history_points == 0 {
            return Err("output.history_points must be at least 1".into());
        }
        Ok(())
    }
}

impl Scenario {
    /// The shape is known, and the ridge's half-length given exactly when it has one.
    fn check_shape(&self) -> Result<(), String> {
        match (self.tools.shape.as_str(), self.tools.half_length) {
            ("hemisphere", None) => Ok(()),
            ("hemisphere", Some(_)) => Err(
                "tools.half_length is for tools.shape = \"double-dome\"; a hemisphere has none"
                    .into(),
            ),
            ("double-dome", Some(l)) => positive("tools.half_length", l),
            ("double-dome", None) => Err(
                "tools.half_length (the half-length of the ridge, mm) is needed for tools.shape \
                 = \"double-dome\""
                    .into(),
            ),
            (other, _) => Err(format!(
                "tools.shape = \"{other}\": the tool sets available are \"hemisphere\" and \
                 \"double-dome\""
            )),
        }
    }
}

fn positive(key: &str, value: f64) -> Result<(), String> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(format!("{key} = {value} must be a positive number"))
    }
}

/// `section.key=value` (any depth): sets an existing or new scalar; the value is read as TOML
/// (a number, a quoted string, true/false), a bare word as a string.
fn apply_override(table: &mut toml::Table, assignment: &str) -> Result<(), String> {
    let (path, raw) = assignment
        .split_once('=')
        .ok_or_else(|| format!("--set {assignment}: expected key=value"))?;
    let keys: Vec<&str> = path.trim().split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!("--set {assignment}: empty key in '{path}'"));
    }
    let mut value = parse_scalar(raw.trim());
    let (last, parents) = keys.split_last().unwrap_or((&"", &[]));
    let mut here = table;
    for key in parents {
        here = here
            .entry(key.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or_else(|| format!("--set {assignment}: '{key}' is not a section"))?;
    }
    // `--set process.temperature=310` on a float key means 310.0
    if let (Some(toml::Value::Float(_)), toml::Value::Integer(i)) = (here.get(*last), &value) {
        value = toml::Value::Float(*i as f64);
    }
    if matches!(here.get(*last), Some(toml::Value::Table(_))) {
        return Err(format!(
            "--set {assignment}: '{path}' is a section, not a value"
        ));
    }
    here.insert(last.to_string(), value);
    Ok(())
}

fn parse_scalar(raw: &str) -> toml::Value {
    let wrapped = format!("v = {raw}");
    toml::from_str::<toml::Table>(&wrapped)
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(raw.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_set_nested_scalars_and_refuse_sections() {
        let mut table: toml::Table = toml::from_str("[process]\ntemperature = 300.0\n").unwrap();
        apply_override(&mut table, "process.temperature=310").unwrap();
        assert_eq!(table["process"]["temperature"], toml::Value::Float(310.0));
        apply_override(&mut table, "output.folder=out").unwrap();
        assert_eq!(table["output"]["folder"], toml::Value::String("out".into()));
        assert!(apply_override(&mut table, "process=3").is_err());
        assert!(apply_override(&mut table, "process.temperature").is_err());
        assert!(apply_override(&mut table, "process..x=1").is_err());
    }
}
