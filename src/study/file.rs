//! The study file: a base forming scenario, the parameters to vary (any scalar of the scenario,
//! as lists or ranges), its design (the full factorial of the values, or cases sampled from
//! them: [`super::design`]), and where the cases go (docs/study.md). Reading it checks the file,
//! the base scenario and the first case (so that a key the scenario does not know stops the
//! study at once); the cases are made one at a time from their number, never all held at
//! once, and each case's own scenario is checked before it runs ([`Study::check_case`]).

use super::design::{Design, DesignSection, Method};
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
    /// The varied parameters, in the file's order: the first two span the charts.
    pub parameters: Vec<Parameter>,
    /// Which cases run: every combination of the values, or a sample of them.
    pub design: Design,
    /// Where the case folders and the summary go (absolute path; given relative to the folder
    /// the sweep runs in, as a scenario's `output.folder` is).
    pub folder: PathBuf,
    /// Waviness above which a case counts as wrinkled (mm).
    pub wrinkle_threshold: f64,
    /// Worker threads of each case; the cases run side by side on the remaining cores.
    pub threads_per_case: usize,
    /// Number of cases: the product of the parameters' counts, or the samples of a sampled
    /// design; at most [`MAX_CASES`].
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
    /// `count` values evenly from `from` to `to`, both included (the full factorial).
    Range {
        from: f64,
        to: f64,
        count: usize,
    },
    /// Any value from `from` to `to` (a sampled design): no list of values, so
    /// [`Self::count`] is 0; [`Self::at`] gives them.
    Interval {
        from: f64,
        to: f64,
    },
}

impl Values {
    /// How many values: at least one for a list or a counted range, 0 for an interval (whose
    /// values are not counted).
    pub fn count(&self) -> usize {
        match self {
            Values::List(values) => values.len(),
            Values::Range { count, .. } => *count,
            Values::Interval { .. } => 0,
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
            Values::Range { .. } | Values::Interval { .. } => None,
        }
    }

    /// The value at `u` in [0, 1] of a sampled design's coordinate: for an interval the point
    /// that far from `from` to `to` (a TOML float), for a list or a counted range value
    /// `floor(u * count)` (each value an equal share of [0, 1)).
    pub fn at(&self, u: f64) -> Option<toml::Value> {
        match self {
            Values::Interval { from, to } => Some(toml::Value::Float(from + u * (to - from))),
            _ => {
                let n = self.count();
                self.get(((u * n as f64).floor() as usize).min(n.saturating_sub(1)))
            }
        }
    }

    /// The smallest and largest numbers among the values (the span of a chart's axis);
    /// `None` where a value is not a number.
    pub fn span(&self) -> Option<(f64, f64)> {
        let numbers: Option<Vec<f64>> = match self {
            Values::Interval { from, to } => Some(vec![*from, *to]),
            _ => self.iter().map(|v| number(&v)).collect(),
        };
        let numbers = numbers?;
        let low = numbers.iter().copied().reduce(f64::min)?;
        let high = numbers.iter().copied().reduce(f64::max)?;
        Some((low, high))
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
            Values::Interval { from, to } => {
                let mut table = toml::Table::new();
                table.insert("from".into(), toml::Value::Float(*from));
                table.insert("to".into(), toml::Value::Float(*to));
                toml::Value::Table(table)
            }
        }
    }

    /// The same values in the same order, however written (a list or a range); an interval
    /// is the same as the same interval only.
    pub fn same_as(&self, other: &Values) -> bool {
        match (self, other) {
            (Values::Interval { .. }, _) | (_, Values::Interval { .. }) => self == other,
            _ => self.count() == other.count() && self.iter().eq(other.iter()),
        }
    }
}

/// A TOML number as a float; `None` for a string or a boolean.
pub fn number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(f) => Some(*f),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
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
    design: DesignSection,
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
    /// Reads and checks the study at `path`: its `base` relative to the study file's folder,
    /// its `output.folder` relative to the current directory ([`Self::from_text`]).
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| StudyError {
            origin: origin.clone(),
            message: format!("cannot read the study file: {e}"),
        })?;
        let run_dir = std::env::current_dir().map_err(|e| StudyError {
            origin: origin.clone(),
            message: format!("cannot tell the current directory: {e}"),
        })?;
        Self::from_text(&text, &origin, study_folder(path), &run_dir)
    }

    /// Reads and checks a study from the text of a study file (one that a program wrote, say),
    /// named `origin` in messages (its file stem names the default `output.folder`, as a study
    /// file's does): `base` is resolved against `base_dir`, `output.folder` against `run_dir`.
    /// Checks that the base scenario loads, every parameter has at least one value and is
    /// given once, the design holds, the cases number [`MAX_CASES`] at most, and the first
    /// case's scenario loads (so that a key the scenario does not know is an error naming
    /// it). The other cases are checked by [`Self::check_case`].
    pub fn from_text(
        text: &str,
        origin: &str,
        base_dir: &Path,
        run_dir: &Path,
    ) -> Result<Self, StudyError> {
        let error = |message: String| StudyError {
            origin: origin.to_string(),
            message,
        };
        let file: StudyFile = from_toml_text(text).map_err(error)?;
        let folder = std::path::absolute(base_dir).map_err(|e| error(e.to_string()))?;
        let base = folder.join(&file.base);
        let method = file.design.method().map_err(error)?;
        let parameters = parameters(&file.parameters, method).map_err(error)?;
        let design = file.design.design(parameters.len()).map_err(error)?;
        let cases_count = match &design {
            Design::FullFactorial => cases_count(&parameters).map_err(error)?,
            Design::Sampled(s) => s.samples,
        };
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
            .unwrap_or_else(|| PathBuf::from(default_folder(Path::new(origin))));
        let study = Self {
            origin: origin.to_string(),
            base,
            parameters,
            design,
            folder: std::path::absolute(run_dir.join(&output)).map_err(|e| error(e.to_string()))?,
            wrinkle_threshold,
            threads_per_case,
            cases_count,
        };
        if let Some(first) = study.case(1) {
            study.check_case(&first)?;
        }
        Ok(study)
    }

    /// Case `number` (from 1): of the full factorial of the parameters' values, the last
    /// parameter varying fastest, or the sampled design's point `number - 1` mapped onto the
    /// parameters' values ([`Values::at`]); `None` beyond the last case.
    pub fn case(&self, number: usize) -> Option<Case> {
        if number == 0 || number > self.cases_count {
            return None;
        }
        if let Design::Sampled(sampling) = &self.design {
            let point = sampling.point(number - 1)?;
            let values = self
                .parameters
                .iter()
                .zip(point)
                .map(|(p, &u)| p.values.at(u))
                .collect::<Option<Vec<_>>>()?;
            return Some(Case { number, values });
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

/// The parameters of the study file's `[parameters]` table, each given once; ranges as the
/// design `method` takes them (counted for the full factorial, continuous for a sampled one).
pub fn parameters(table: &toml::Table, method: Method) -> Result<Vec<Parameter>, String> {
    let mut out = Vec::new();
    let mut spellings = Vec::new();
    flatten(("", ""), table, method, &mut out, &mut spellings)?;
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
    method: Method,
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
            toml::Value::Table(t) if t.contains_key("from") && method.sampled() => {
                interval(&key, t, method)?
            }
            toml::Value::Table(t) if t.contains_key("from") => range(&key, t)?,
            toml::Value::Table(t) => {
                flatten((&key, &spelling), t, method, out, spellings)?;
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
    let (from, to) = ends(key, table, "from, to and count")?;
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

/// A sampled design's range `{ from = a, to = b }`: finite ends, any value between them; a
/// `count` is refused, since the design, not a list of evenly spaced values, picks them.
fn interval(key: &str, table: &toml::Table, method: Method) -> Result<Values, String> {
    if table.contains_key("count") {
        return Err(format!(
            "parameters.{key}.count: a {} design draws each case's value from anywhere between              from and to, so a range has no count; give {{ from = a, to = b }}, or a list of              the values to pick from",
            method.name()
        ));
    }
    if let Some(unknown) = table.keys().find(|k| !["from", "to"].contains(&k.as_str())) {
        return Err(format!(
            "parameters.{key}.{unknown}: a range of a {} design has from and to only",
            method.name()
        ));
    }
    let (from, to) = ends(key, table, "from and to")?;
    Ok(Values::Interval { from, to })
}

/// The `from` and `to` of a range, finite numbers; `needs` says what a range has, for the
/// message when one is missing.
fn ends(key: &str, table: &toml::Table, needs: &str) -> Result<(f64, f64), String> {
    let number = |name: &str| match table.get(name) {
        Some(toml::Value::Float(x)) if x.is_finite() => Ok(*x),
        Some(toml::Value::Integer(i)) => Ok(*i as f64),
        Some(other) => Err(format!(
            "parameters.{key}.{name} = {other}: must be a finite number"
        )),
        None => Err(format!(
            "parameters.{key}: a range needs {needs}; {name} is missing"
        )),
    };
    Ok((number("from")?, number("to")?))
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
        parameters(&toml::from_str(text).unwrap(), Method::FullFactorial)
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

    /// A study on the hemisphere example, from text, with `design` and `parameters` lines.
    fn sampled_study(design: &str, parameters: &str) -> Result<Study, StudyError> {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
        let text = format!(
            "base = \"examples/hemisphere.toml\"\n[design]\n{design}\n[parameters]\n{parameters}\n\
             [output]\nfolder = \"out\"\n"
        );
        Study::from_text(&text, "sampled.toml", repo, Path::new("/tmp/runs"))
    }

    const TWO_RANGES_AND_A_LIST: &str = "process.temperature = { from = 280.0, to = 320.0 }\n\
        process.blank_holder_force = { from = 0.0, to = 300.0 }\n\
        process.punch_speed = [5.0, 10.0, 20.0]";

    fn column(study: &Study, j: usize) -> Vec<f64> {
        study
            .cases()
            .map(|c| number(&c.values[j]).unwrap())
            .collect()
    }

    /// The stratum of each value among `n` equal strata of [from, to].
    fn strata(values: &[f64], (from, to): (f64, f64), n: usize) -> Vec<usize> {
        let mut s: Vec<usize> = values
            .iter()
            .map(|v| (((v - from) / (to - from) * n as f64).floor() as usize).min(n - 1))
            .collect();
        s.sort_unstable();
        s
    }

    /// `from_text` resolves the base against its folder and the output against the run's.
    #[test]
    fn a_study_from_text_resolves_its_paths() {
        let study = sampled_study("", "process.temperature = [300.0]").unwrap();
        assert_eq!(
            study.base,
            Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/hemisphere.toml")
        );
        assert_eq!(study.folder, Path::new("/tmp/runs/out"));
        assert_eq!(study.design, Design::FullFactorial);
    }

    /// A Latin hypercube of 16 cases: each range's 16 equal strata hold one case each, the
    /// values are floats within the range, and the list's values are the only ones taken,
    /// each about a third of the time (16 strata over 3 values: 4 to 6 cases each).
    #[test]
    fn a_latin_hypercube_study_stratifies_its_ranges() {
        let study = sampled_study(
            "method = \"latin-hypercube\"\nsamples = 16\nseed = 7",
            TWO_RANGES_AND_A_LIST,
        )
        .unwrap();
        assert_eq!(study.cases_count(), 16);
        assert_eq!(study.case(17), None);
        let all: Vec<usize> = (0..16).collect();
        for (j, span) in [(0, (280.0, 320.0)), (1, (0.0, 300.0))] {
            let values = column(&study, j);
            assert!(
                values.iter().all(|v| (span.0..=span.1).contains(v)),
                "{values:?}"
            );
            assert_eq!(strata(&values, span, 16), all, "parameter {j}: {values:?}");
        }
        assert!(study.cases().all(|c| c.values[0].is_float()));
        let speeds = column(&study, 2);
        for listed in [5.0, 10.0, 20.0] {
            let n = speeds.iter().filter(|v| **v == listed).count();
            assert!((4..=6).contains(&n), "{listed}: {speeds:?}");
        }
    }

    /// The same seed gives the same cases from two loads; another seed, other cases.
    #[test]
    fn the_seed_decides_the_cases() {
        for method in ["latin-hypercube", "sobol"] {
            let design = |seed: u64| format!("method = \"{method}\"\nsamples = 8\nseed = {seed}");
            let cases = |seed| {
                sampled_study(&design(seed), TWO_RANGES_AND_A_LIST)
                    .unwrap()
                    .cases()
                    .collect::<Vec<_>>()
            };
            assert_eq!(cases(7), cases(7), "{method}");
            assert_ne!(cases(7), cases(8), "{method}");
        }
    }

    /// A Sobol study's values lie in their ranges, and its first 2^k cases put one value in
    /// each of 2^k equal intervals of each range.
    #[test]
    fn a_sobol_study_stratifies_its_prefixes() {
        let study = sampled_study(
            "method = \"sobol\"\nsamples = 32\nseed = 3",
            TWO_RANGES_AND_A_LIST,
        )
        .unwrap();
        for (j, span) in [(0, (280.0, 320.0)), (1, (0.0, 300.0))] {
            let values = column(&study, j);
            assert!(
                values.iter().all(|v| (span.0..span.1).contains(v)),
                "{values:?}"
            );
            for k in 0..=5 {
                let n = 1 << k;
                let expected: Vec<usize> = (0..n).collect();
                assert_eq!(
                    strata(&values[..n], span, n),
                    expected,
                    "2^{k}, parameter {j}"
                );
            }
        }
        assert!(column(&study, 2)
            .iter()
            .all(|v| [5.0, 10.0, 20.0].contains(v)));
    }

    /// A sampled design refuses a counted range, naming the key and saying why; the full
    /// factorial refuses samples.
    #[test]
    fn designs_refuse_what_they_do_not_take() {
        let e = sampled_study(
            "method = \"sobol\"\nsamples = 8",
            "process.temperature = { from = 280.0, to = 320.0, count = 3 }",
        )
        .unwrap_err();
        assert!(
            e.message.contains("parameters.process.temperature.count")
                && e.message.contains("no count"),
            "{e}"
        );
        let e = sampled_study("samples = 8", "process.temperature = [300.0]").unwrap_err();
        assert!(e.message.contains("design.samples"), "{e}");
        let e = sampled_study("method = \"sobol\"", "process.temperature = [300.0]").unwrap_err();
        assert!(e.message.contains("design.samples is missing"), "{e}");
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
