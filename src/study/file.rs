//! The study file: a base forming scenario, the parameters to vary (any scalar of the scenario,
//! as lists or ranges), and where the cases go (docs/study.md). Every case's scenario is built
//! and checked when the file is read, so that a bad value stops the study before any case runs.

use crate::forming::Scenario;
use crate::io::from_toml_text;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A study that was read and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    pub origin: String,
    /// The base scenario (absolute path).
    pub base: PathBuf,
    /// The varied parameters, in the file's order: the first two span the heat maps.
    pub parameters: Vec<Parameter>,
    /// Where the case folders and the summary go (absolute path; given relative to the folder
    /// the sweep runs in, as a scenario's `output.folder` is).
    pub folder: PathBuf,
    /// Waviness above which a case counts as wrinkled (mm).
    pub wrinkle_threshold: f64,
    /// Worker threads of each case; the cases run side by side on the remaining cores.
    pub threads_per_case: usize,
}

/// One varied scenario key and its values, each a TOML scalar.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub key: String,
    pub values: Vec<toml::Value>,
}

/// One case: its number (from 1) and the value of each parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct Case {
    pub number: usize,
    pub values: Vec<toml::Value>,
}

/// What is wrong with a study file, and in which file.
#[derive(Debug, thiserror::Error)]
#[error("{origin}: {message}")]
pub struct StudyError {
    pub origin: String,
    pub message: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StudyFile {
    base: PathBuf,
    parameters: toml::Table,
    #[serde(default)]
    output: OutputSection,
    #[serde(default)]
    run: RunSection,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct OutputSection {
    folder: Option<PathBuf>,
    wrinkle_threshold: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RunSection {
    threads_per_case: Option<usize>,
}

/// A range of values: `count` values evenly from `from` to `to`, both included.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Range {
    from: f64,
    to: f64,
    count: usize,
}

impl Study {
    /// Reads and checks the study at `path`: the base scenario loads, every parameter has at
    /// least one value, and the scenario of every case loads (so a key the scenario does not
    /// know, or a value it refuses, is an error naming the key and the value).
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        let origin = path.display().to_string();
        let error = |message: String| StudyError {
            origin: origin.clone(),
            message,
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| error(format!("cannot read the study file: {e}")))?;
        let file: StudyFile = from_toml_text(&text).map_err(error)?;
        let folder = std::path::absolute(path.parent().unwrap_or(Path::new(".")))
            .map_err(|e| error(e.to_string()))?;
        let base = folder.join(&file.base);
        let mut parameters = Vec::new();
        flatten("", &file.parameters, &mut parameters).map_err(error)?;
        if parameters.is_empty() {
            return Err(error(
                "[parameters] is empty: name at least one scenario key to vary".into(),
            ));
        }
        let base_scenario = Scenario::load(&base, &[])
            .map_err(|e| error(format!("base = {}: {e}", file.base.display())))?;
        let half_ply = 0.5 * ply_thickness(&base_scenario).map_err(error)?;
        let wrinkle_threshold = file.output.wrinkle_threshold.unwrap_or(half_ply);
        if !(wrinkle_threshold.is_finite() && wrinkle_threshold > 0.0) {
            return Err(error(format!(
                "output.wrinkle_threshold = {wrinkle_threshold}: must be a positive length (mm)"
            )));
        }
        let threads_per_case = file.run.threads_per_case.unwrap_or(1);
        if threads_per_case == 0 {
            return Err(error(
                "run.threads_per_case = 0: at least one thread".into(),
            ));
        }
        let study_folder = file
            .output
            .folder
            .unwrap_or_else(|| PathBuf::from(default_folder(path)));
        let study = Self {
            origin: origin.clone(),
            base,
            parameters,
            folder: std::path::absolute(&study_folder).map_err(|e| error(e.to_string()))?,
            wrinkle_threshold,
            threads_per_case,
        };
        for case in study.cases() {
            study.check_case(&case).map_err(error)?;
        }
        Ok(study)
    }

    /// The full factorial of the parameters' values, the last parameter varying fastest.
    pub fn cases(&self) -> Vec<Case> {
        let mut cases: Vec<Vec<toml::Value>> = vec![Vec::new()];
        for p in &self.parameters {
            cases = cases
                .into_iter()
                .flat_map(|head| {
                    p.values.iter().map(move |v| {
                        let mut values = head.clone();
                        values.push(v.clone());
                        values
                    })
                })
                .collect();
        }
        cases
            .into_iter()
            .enumerate()
            .map(|(i, values)| Case {
                number: i + 1,
                values,
            })
            .collect()
    }

    /// `key=value` overrides of the base scenario for `case`.
    pub fn overrides(&self, case: &Case) -> Vec<String> {
        self.parameters
            .iter()
            .zip(&case.values)
            .map(|(p, v)| format!("{}={v}", p.key))
            .collect()
    }

    /// The case's folder: `case-001`, ... under the study's folder.
    pub fn case_folder(&self, case: &Case) -> PathBuf {
        let width = self.cases_count().to_string().len().max(3);
        self.folder.join(format!("case-{:0width$}", case.number))
    }

    /// Number of cases.
    pub fn cases_count(&self) -> usize {
        self.parameters.iter().map(|p| p.values.len()).product()
    }

    /// `key = value, ...` of the case, for lists and progress lines.
    pub fn describe(&self, case: &Case) -> String {
        self.parameters
            .iter()
            .zip(&case.values)
            .map(|(p, v)| format!("{} = {v}", p.key))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The case's scenario loads and its card holds at its temperature: the message names the
    /// keys and values of the case. What only the run's pre-flight finds (a stroke in too few
    /// steps, not enough memory) fails the case when it runs, recorded with its reason.
    fn check_case(&self, case: &Case) -> Result<(), String> {
        let named = |e: String| format!("case {} ({}): {e}", case.number, self.describe(case));
        let scenario =
            Scenario::load(&self.base, &self.overrides(case)).map_err(|e| named(e.to_string()))?;
        let card = crate::material::MaterialCard::load(&scenario.blank.card)
            .map_err(|e| named(e.to_string()))?;
        card.check_temperature("process.temperature", scenario.process.temperature)
            .map_err(named)
    }
}

/// The parameters of `table`, keys joined by dots (`process.temperature` may be written as a
/// quoted key or as a nested table); a value is a list of scalars or a range table.
fn flatten(prefix: &str, table: &toml::Table, out: &mut Vec<Parameter>) -> Result<(), String> {
    for (key, value) in table {
        let key = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        match value {
            toml::Value::Array(values) => {
                if values.is_empty() {
                    return Err(format!("parameters.{key} = []: give at least one value"));
                }
                if let Some(v) = values
                    .iter()
                    .find(|v| matches!(v, toml::Value::Array(_) | toml::Value::Table(_)))
                {
                    return Err(format!(
                        "parameters.{key}: {v} is not a scalar (a number, a string, true or false)"
                    ));
                }
                out.push(Parameter {
                    key,
                    values: values.clone(),
                });
            }
            toml::Value::Table(t) if t.contains_key("from") => {
                let range: Range = toml::Value::Table(t.clone())
                    .try_into()
                    .map_err(|e| format!("parameters.{key}: {e}"))?;
                out.push(Parameter {
                    values: range_values(&key, &range)?,
                    key,
                });
            }
            toml::Value::Table(t) => flatten(&key, t, out)?,
            other => {
                return Err(format!(
                    "parameters.{key} = {other}: give a list of values, [a, b, ...], or a range, \
                     {{ from = a, to = b, count = n }}"
                ))
            }
        }
    }
    Ok(())
}

/// `count` values from `from` to `to`, both included.
fn range_values(key: &str, r: &Range) -> Result<Vec<toml::Value>, String> {
    if !(r.from.is_finite() && r.to.is_finite()) || r.count == 0 {
        return Err(format!(
            "parameters.{key}: from = {}, to = {}, count = {}: finite ends and at least one value",
            r.from, r.to, r.count
        ));
    }
    if r.count == 1 && r.from != r.to {
        return Err(format!(
            "parameters.{key}: count = 1 with from = {} and to = {}: give two values or more",
            r.from, r.to
        ));
    }
    Ok((0..r.count)
        .map(|i| {
            let t = if r.count == 1 {
                0.0
            } else {
                i as f64 / (r.count - 1) as f64
            };
            toml::Value::Float(r.from + t * (r.to - r.from))
        })
        .collect())
}

/// The ply's thickness of the base scenario's card (mm).
fn ply_thickness(scenario: &Scenario) -> Result<f64, String> {
    crate::material::MaterialCard::load(&scenario.blank.card)
        .map(|card| card.laminate.reference_thickness())
        .map_err(|e| e.to_string())
}

/// `name-results` for a study file `name.toml`.
fn default_folder(path: &Path) -> String {
    let stem = path
        .file_stem()
        .map_or("study".into(), |s| s.to_string_lossy().into_owned());
    format!("{stem}-results")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ranges include both ends; lists keep their order; nested and quoted keys are the same.
    #[test]
    fn parameters_flatten_to_dotted_keys() {
        let table: toml::Table =
            toml::from_str("a.b = [1.0, 2.0]\n\"c.d\" = { from = 0.0, to = 300.0, count = 4 }\n")
                .unwrap();
        let mut out = Vec::new();
        flatten("", &table, &mut out).unwrap();
        assert_eq!(out[0].key, "a.b");
        assert_eq!(out[1].key, "c.d");
        let values: Vec<f64> = out[1]
            .values
            .iter()
            .map(|v| v.as_float().unwrap())
            .collect();
        assert_eq!(values, vec![0.0, 100.0, 200.0, 300.0]);
        for bad in [
            "x = []",
            "x = 3.0",
            "x = [[1.0]]",
            "x = { from = 0.0, to = 1.0, count = 0 }",
        ] {
            let table: toml::Table = toml::from_str(bad).unwrap();
            assert!(flatten("", &table, &mut Vec::new()).is_err(), "{bad}");
        }
    }
}
