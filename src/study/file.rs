//! The study file: a base forming scenario, the parameters to vary (any scalar of the scenario,
//! as lists or ranges), and where the cases go (docs/study.md). Reading it checks the file,
//! the base scenario and the first case (so that a key the scenario does not know stops the
//! study at once); the cases are made one at a time from their number, never all held at
//! once, and each case's own scenario is checked before it runs ([`Study::check_case`]).

use crate::forming::Scenario;
use crate::io::from_toml_text;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The most cases a study may have: a million forming runs is a campaign for a cluster; more
/// is a mistake in the file (a `count` a thousand times too large), refused before anything
/// is made.
pub const MAX_CASES: usize = 1_000_000;

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
    /// Number of cases: the product of the parameters' counts, at most [`MAX_CASES`].
    cases_count: usize,
}

/// One varied scenario key and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    pub key: String,
    pub values: Values,
}

/// The values of a parameter, each a TOML scalar: a list as written, or a range, whose values
/// are computed when asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    List(Vec<toml::Value>),
    /// `count` values evenly from `from` to `to`, both included.
    Range {
        from: f64,
        to: f64,
        count: usize,
    },
}

impl Values {
    /// How many values (at least one).
    pub fn count(&self) -> usize {
        match self {
            Values::List(values) => values.len(),
            Values::Range { count, .. } => *count,
        }
    }

    /// Value `i` (from 0), `i` below [`Self::count`].
    pub fn get(&self, i: usize) -> Option<toml::Value> {
        match self {
            Values::List(values) => values.get(i).cloned(),
            Values::Range { from, to, count } if i < *count => {
                let t = if *count == 1 {
                    0.0
                } else {
                    i as f64 / (*count - 1) as f64
                };
                Some(toml::Value::Float(from + t * (to - from)))
            }
            Values::Range { .. } => None,
        }
    }

    /// The values in order.
    pub fn iter(&self) -> impl Iterator<Item = toml::Value> + '_ {
        (0..self.count()).filter_map(|i| self.get(i))
    }

    /// The values as the study file gives them: the list, or the range's table.
    pub fn as_written(&self) -> toml::Value {
        match self {
            Values::List(values) => toml::Value::Array(values.clone()),
            Values::Range { from, to, count } => {
                let mut table = toml::Table::new();
                table.insert("from".into(), toml::Value::Float(*from));
                table.insert("to".into(), toml::Value::Float(*to));
                table.insert("count".into(), toml::Value::Integer(*count as i64));
                toml::Value::Table(table)
            }
        }
    }

    /// The same values in the same order, however written (a list or a range).
    pub fn same_as(&self, other: &Values) -> bool {
        self.count() == other.count() && self.iter().eq(other.iter())
    }
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

impl Study {
    /// Reads and checks the study at `path`: the base scenario loads, every parameter has at
    /// least one value and is given once, the cases number [`MAX_CASES`] at most, and the
    /// first case's scenario loads (so that a key the scenario does not know is an error
    /// naming it). The other cases are checked by [`Self::check_case`].
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        let origin = path.display().to_string();
        let error = |message: String| StudyError {
            origin: origin.clone(),
            message,
        };
        let text = std::fs::read_to_string(path)
            .map_err(|e| error(format!("cannot read the study file: {e}")))?;
        let file: StudyFile = from_toml_text(&text).map_err(error)?;
        let folder = std::path::absolute(study_folder(path)).map_err(|e| error(e.to_string()))?;
        let base = folder.join(&file.base);
        let parameters = parameters(&file.parameters).map_err(error)?;
        let cases_count = cases_count(&parameters).map_err(error)?;
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
        let output = file
            .output
            .folder
            .unwrap_or_else(|| PathBuf::from(default_folder(path)));
        let study = Self {
            origin: origin.clone(),
            base,
            parameters,
            folder: std::path::absolute(&output).map_err(|e| error(e.to_string()))?,
            wrinkle_threshold,
            threads_per_case,
            cases_count,
        };
        if let Some(first) = study.case(1) {
            study.check_case(&first)?;
        }
        Ok(study)
    }

    /// Case `number` (from 1) of the full factorial of the parameters' values, the last
    /// parameter varying fastest; `None` beyond the last case.
    pub fn case(&self, number: usize) -> Option<Case> {
        if number == 0 || number > self.cases_count {
            return None;
        }
        let mut rest = number - 1;
        let mut values = Vec::with_capacity(self.parameters.len());
        for p in self.parameters.iter().rev() {
            let n = p.values.count();
            values.push(p.values.get(rest % n)?);
            rest /= n;
        }
        values.reverse();
        Some(Case { number, values })
    }

    /// Every case in order, made as it is asked for.
    pub fn cases(&self) -> impl Iterator<Item = Case> + '_ {
        (1..=self.cases_count).filter_map(|n| self.case(n))
    }

    /// `key=value` overrides of the base scenario for `case`.
    pub fn overrides(&self, case: &Case) -> Vec<String> {
        self.parameters
            .iter()
            .zip(&case.values)
            .map(|(p, v)| format!("{}={v}", p.key))
            .collect()
    }

    /// The folder of case `number`: `case-001`, ... under the study's folder.
    pub fn case_folder(&self, number: usize) -> PathBuf {
        let width = self.cases_count.to_string().len().max(3);
        self.folder.join(format!("case-{number:0width$}"))
    }

    /// Number of cases.
    pub fn cases_count(&self) -> usize {
        self.cases_count
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
    /// case, its keys and values. What only the run's pre-flight finds (a stroke in too few
    /// steps, not enough memory) fails the case when it runs, recorded with its reason.
    pub fn check_case(&self, case: &Case) -> Result<(), StudyError> {
        let named = |e: String| StudyError {
            origin: self.origin.clone(),
            message: format!("case {} ({}): {e}", case.number, self.describe(case)),
        };
        let scenario =
            Scenario::load(&self.base, &self.overrides(case)).map_err(|e| named(e.to_string()))?;
        let card = crate::material::MaterialCard::load(&scenario.blank.card)
            .map_err(|e| named(e.to_string()))?;
        card.check_temperature("process.temperature", scenario.process.temperature)
            .map_err(named)
    }
}

/// The folder the study file is in (`.` for a bare file name).
fn study_folder(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    }
}

/// The parameters of the study file's `[parameters]` table, each given once.
pub fn parameters(table: &toml::Table) -> Result<Vec<Parameter>, String> {
    let mut out = Vec::new();
    let mut spellings = Vec::new();
    flatten(("", ""), table, &mut out, &mut spellings)?;
    if out.is_empty() {
        return Err("[parameters] is empty: name at least one scenario key to vary".into());
    }
    Ok(out)
}

/// The parameters of `table` under `prefix` (the key so far, and as the file spells it),
/// keys joined by dots (`process.temperature` may be written as a quoted key or as a nested
/// table, which makes it the same key: given both ways, it is refused, since the two could
/// differ); a value is a list of scalars or a range table. `spellings` holds how each key of
/// `out` was written.
fn flatten(
    prefix: (&str, &str),
    table: &toml::Table,
    out: &mut Vec<Parameter>,
    spellings: &mut Vec<String>,
) -> Result<(), String> {
    for (name, value) in table {
        let joined = |a: &str, b: &str| {
            if a.is_empty() {
                b.to_string()
            } else {
                format!("{a}.{b}")
            }
        };
        let key = joined(prefix.0, name);
        let spelling = joined(prefix.1, &spelled(name));
        let values = match value {
            toml::Value::Array(values) => list(&key, values)?,
            toml::Value::Table(t) if t.contains_key("from") => range(&key, t)?,
            toml::Value::Table(t) => {
                flatten((&key, &spelling), t, out, spellings)?;
                continue;
            }
            other => {
                return Err(format!(
                    "parameters.{key} = {other}: give a list of values, [a, b, ...], or a range, \
                     {{ from = a, to = b, count = n }}"
                ))
            }
        };
        if let Some(i) = out.iter().position(|p| p.key == key) {
            return Err(format!(
                "parameters.{key} is given twice, as {} and as {spelling}: give each key once",
                spellings[i]
            ));
        }
        out.push(Parameter { key, values });
        spellings.push(spelling);
    }
    Ok(())
}

/// A key as TOML writes it: bare when it can be, else quoted.
fn spelled(name: &str) -> String {
    let bare = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        name.to_string()
    } else {
        toml::Value::String(name.to_string()).to_string()
    }
}

/// A list of scalars, at least one.
fn list(key: &str, values: &[toml::Value]) -> Result<Values, String> {
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
    Ok(Values::List(values.to_vec()))
}

/// A range `{ from = a, to = b, count = n }`: finite ends, a whole count from 1 to
/// [`MAX_CASES`] (checked before any value is made), two values or more between different
/// ends.
fn range(key: &str, table: &toml::Table) -> Result<Values, String> {
    if let Some(unknown) = table
        .keys()
        .find(|k| !["from", "to", "count"].contains(&k.as_str()))
    {
        return Err(format!(
            "parameters.{key}.{unknown}: a range has from, to and count only"
        ));
    }
    let number = |name: &str| match table.get(name) {
        Some(toml::Value::Float(x)) if x.is_finite() => Ok(*x),
        Some(toml::Value::Integer(i)) => Ok(*i as f64),
        Some(other) => Err(format!(
            "parameters.{key}.{name} = {other}: must be a finite number"
        )),
        None => Err(format!(
            "parameters.{key}: a range needs from, to and count; {name} is missing"
        )),
    };
    let (from, to) = (number("from")?, number("to")?);
    let count = match table.get("count") {
        Some(toml::Value::Integer(n)) if (1..=MAX_CASES as i64).contains(n) => *n as usize,
        Some(other) => {
            return Err(format!(
                "parameters.{key}.count = {other}: must be a whole number of values from 1 to \
                 {MAX_CASES}"
            ))
        }
        None => {
            return Err(format!(
                "parameters.{key}: a range needs from, to and count; count is missing"
            ))
        }
    };
    if count == 1 && from != to {
        return Err(format!(
            "parameters.{key}: count = 1 with from = {from} and to = {to}: give two values or more"
        ));
    }
    Ok(Values::Range { from, to, count })
}

/// The number of cases, the product of the parameters' counts, refused above [`MAX_CASES`]
/// (computed in floating point, so that no product overflows).
fn cases_count(parameters: &[Parameter]) -> Result<usize, String> {
    let product: f64 = parameters.iter().map(|p| p.values.count() as f64).product();
    if product <= MAX_CASES as f64 {
        return Ok(product as usize);
    }
    let counts: Vec<String> = parameters
        .iter()
        .map(|p| format!("parameters.{}: {}", p.key, p.values.count()))
        .collect();
    let total = if product < 1e15 {
        format!("{product:.0}")
    } else {
        format!("{product:e}")
    };
    Err(format!(
        "the study has {total} cases ({}), more than {MAX_CASES}: give fewer values, or split \
         it into several studies",
        counts.join(" x ")
    ))
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

    fn parsed(text: &str) -> Result<Vec<Parameter>, String> {
        parameters(&toml::from_str(text).unwrap())
    }

    /// Ranges include both ends; lists keep their order; nested and quoted keys are the same.
    #[test]
    fn parameters_flatten_to_dotted_keys() {
        let out =
            parsed("a.b = [1.0, 2.0]\n\"c.d\" = { from = 0.0, to = 300.0, count = 4 }\n").unwrap();
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
            "x = { from = 0.0, to = 1.0, count = 1e12 }",
            "x = { from = 0.0, to = 1.0, count = 9223372036854775807 }",
            "x = { from = 0.0, to = 1.0, count = 4, step = 2 }",
            "x = { from = nan, to = 1.0, count = 4 }",
        ] {
            assert!(parsed(bad).is_err(), "{bad}");
        }
    }

    /// A key given as a quoted dotted key and as a nested table is refused, naming both.
    #[test]
    fn a_key_given_twice_is_refused() {
        let e = parsed("\"process.temperature\" = [280.0]\nprocess.temperature = [320.0]\n")
            .unwrap_err();
        assert!(
            e.contains("parameters.process.temperature is given twice")
                && e.contains("\"process.temperature\"")
                && e.contains(" process.temperature:"),
            "{e}"
        );
    }

    /// Counts beyond the cap are refused from their product, however large, before any value
    /// is made; at the cap they are accepted.
    #[test]
    fn the_number_of_cases_is_capped() {
        let range = |count: usize| Parameter {
            key: "k".into(),
            values: Values::Range {
                from: 0.0,
                to: 1.0,
                count,
            },
        };
        assert_eq!(cases_count(&[range(1000), range(1000)]), Ok(MAX_CASES));
        let e = cases_count(&[range(1000), range(1001)]).unwrap_err();
        assert!(e.contains("1001000 cases"), "{e}");
        let e = cases_count(&vec![range(MAX_CASES); 5]).unwrap_err();
        assert!(e.contains("1e30 cases"), "{e}");
    }

    /// A range and the list of its values are the same values.
    #[test]
    fn a_range_and_its_list_are_the_same_values() {
        let range = Values::Range {
            from: 0.0,
            to: 300.0,
            count: 4,
        };
        let list = Values::List([0.0, 100.0, 200.0, 300.0].map(toml::Value::Float).to_vec());
        assert!(range.same_as(&list));
        assert!(!range.same_as(&Values::List(vec![toml::Value::Float(0.0)])));
        assert_eq!(range.get(4), None);
    }
}
