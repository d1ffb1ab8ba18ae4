//! The study's design (docs/study.md, "Designs"): which cases a study runs. The full factorial
//! runs every combination of the parameters' values; a Latin hypercube or a Sobol sequence
//! runs a chosen number of cases spread over the parameters' ranges, for studies with more
//! parameters than a factorial can afford (5 parameters at 4 values are 1024 runs; 32 sampled
//! cases already map the same space). A sampled design is a point of the unit cube per case,
//! one coordinate per parameter, made once when the study is read, from a seed, so that the
//! same study file gives the same cases on any machine.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

use super::file::MAX_CASES;

/// The most parameters a Sobol design takes: the dimensions of `sobol_burley`'s sequence.
pub const SOBOL_MAX_PARAMETERS: usize = sobol_burley::NUM_DIMENSIONS as usize;
/// The most cases a Sobol design takes: the length of `sobol_burley`'s sequence (2^16).
pub const SOBOL_MAX_SAMPLES: usize = 1 << 16;
/// The most coordinates a sampled design holds (samples x parameters, 8 bytes each: 400 MB),
/// so that a study file cannot exhaust the memory before anything runs.
pub const MAX_SAMPLED_VALUES: usize = 50_000_000;

/// How the cases are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Every combination of the parameters' values, the last parameter varying fastest.
    FullFactorial,
    /// One case in each of `samples` equal strata of every parameter, the strata paired at
    /// random (McKay et al., 1979).
    LatinHypercube,
    /// The first `samples` points of an Owen-scrambled Sobol sequence (Burley, 2020): evenly
    /// spread in every projection, and a prefix of 2^k points stratified in 2^k intervals.
    Sobol,
}

impl Method {
    pub const ALL: [Method; 3] = [Self::FullFactorial, Self::LatinHypercube, Self::Sobol];

    /// The name the study file gives it.
    pub fn name(self) -> &'static str {
        match self {
            Self::FullFactorial => "full-factorial",
            Self::LatinHypercube => "latin-hypercube",
            Self::Sobol => "sobol",
        }
    }

    /// Whether the cases are sampled (their number given), rather than every combination.
    pub fn sampled(self) -> bool {
        self != Self::FullFactorial
    }
}

/// The cases a study runs.
#[derive(Clone, Debug, PartialEq)]
pub enum Design {
    /// Every combination of the parameters' values.
    FullFactorial,
    /// A number of cases sampled from the parameters' ranges and lists.
    Sampled(Sampling),
}

/// A sampled design: its method, number of cases, seed, and the points of the unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampling {
    pub method: Method,
    pub samples: usize,
    pub seed: u64,
    /// Coordinates in [0, 1], one per parameter, case after case.
    unit: Vec<f64>,
    parameters: usize,
}

impl Sampling {
    /// Makes the `samples` points of `method` (sampled) over `parameters` dimensions.
    fn new(method: Method, samples: usize, seed: u64, parameters: usize) -> Self {
        let unit = match method {
            Method::Sobol => sobol(samples, parameters, seed),
            _ => latin_hypercube(samples, parameters, seed),
        };
        Self {
            method,
            samples,
            seed,
            unit,
            parameters,
        }
    }

    /// The point of case `index` (from 0): a coordinate in [0, 1] per parameter.
    pub fn point(&self, index: usize) -> Option<&[f64]> {
        let start = index.checked_mul(self.parameters)?;
        self.unit.get(start..start + self.parameters)
    }
}

impl Design {
    pub fn method(&self) -> Method {
        match self {
            Self::FullFactorial => Method::FullFactorial,
            Self::Sampled(s) => s.method,
        }
    }

    /// The design as the study file writes it, for the record of the study a folder holds;
    /// `None` for the full factorial, which writes none (so that the record of a factorial
    /// study is what it was before designs existed).
    pub fn as_written(&self) -> Option<toml::Table> {
        let Self::Sampled(s) = self else {
            return None;
        };
        let mut table = toml::Table::new();
        table.insert("method".into(), toml::Value::String(s.method.name().into()));
        table.insert("samples".into(), toml::Value::Integer(s.samples as i64));
        table.insert("seed".into(), toml::Value::Integer(s.seed as i64));
        Some(table)
    }
}

/// The study file's `[design]`.
#[derive(Deserialize, Default, Clone, Debug)]
#[serde(deny_unknown_fields)]
pub struct DesignSection {
    method: Option<String>,
    samples: Option<i64>,
    seed: Option<i64>,
}

impl DesignSection {
    /// Reads a `[design]` table (as the record of a study folder holds it).
    pub fn from_table(table: &toml::Table) -> Result<Self, String> {
        crate::io::from_toml_value(toml::Value::Table(table.clone()))
    }

    /// The method named, full factorial where none is.
    pub fn method(&self) -> Result<Method, String> {
        let Some(name) = &self.method else {
            return Ok(Method::FullFactorial);
        };
        Method::ALL
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                let names: Vec<String> = Method::ALL
                    .iter()
                    .map(|m| format!("\"{}\"", m.name()))
                    .collect();
                format!(
                    "design.method = \"{name}\": unknown; one of {}",
                    names.join(", ")
                )
            })
    }

    /// The design over `parameters` varied parameters: for a sampled method, `samples` from 1
    /// to [`MAX_CASES`] (and what the Sobol sequence has) and a seed from 0; for the full
    /// factorial, neither.
    pub fn design(&self, parameters: usize) -> Result<Design, String> {
        let method = self.method()?;
        if !method.sampled() {
            if let Some(key) = [("samples", self.samples), ("seed", self.seed)]
                .iter()
                .find_map(|(k, v)| v.map(|_| *k))
            {
                return Err(format!(
                    "design.{key}: a full-factorial design runs every combination of the \
                     parameters' values; samples and seed are for method = \"latin-hypercube\" \
                     or \"sobol\""
                ));
            }
            return Ok(Design::FullFactorial);
        }
        let name = method.name();
        let samples = match self.samples {
            Some(n) if (1..=MAX_CASES as i64).contains(&n) => n as usize,
            Some(n) => {
                return Err(format!(
                    "design.samples = {n}: must be a whole number of cases from 1 to {MAX_CASES}"
                ))
            }
            None => {
                return Err(format!(
                    "design.samples is missing: a {name} design runs the number of cases it \
                     gives (1 to {MAX_CASES})"
                ))
            }
        };
        let seed = match self.seed {
            None => 0,
            Some(s) if s >= 0 => s as u64,
            Some(s) => {
                return Err(format!(
                    "design.seed = {s}: must be a whole number from 0 (the same seed gives the \
                     same cases)"
                ))
            }
        };
        if method == Method::Sobol {
            sobol_limits(samples, seed, parameters)?;
        }
        if samples.saturating_mul(parameters) > MAX_SAMPLED_VALUES {
            return Err(format!(
                "design.samples = {samples} over {parameters} parameters: {} coordinates, more \
                 than the {MAX_SAMPLED_VALUES} a study holds; give fewer samples or parameters",
                samples.saturating_mul(parameters)
            ));
        }
        Ok(Design::Sampled(Sampling::new(
            method, samples, seed, parameters,
        )))
    }
}

/// What `sobol_burley`'s sequence supports: [`SOBOL_MAX_SAMPLES`] points of
/// [`SOBOL_MAX_PARAMETERS`] dimensions, and a 32-bit seed.
fn sobol_limits(samples: usize, seed: u64, parameters: usize) -> Result<(), String> {
    if samples > SOBOL_MAX_SAMPLES {
        return Err(format!(
            "design.samples = {samples}: a sobol design has at most {SOBOL_MAX_SAMPLES} cases \
             (the length of its sequence); use method = \"latin-hypercube\" for more"
        ));
    }
    if parameters > SOBOL_MAX_PARAMETERS {
        return Err(format!(
            "[parameters] has {parameters} parameters: a sobol design takes at most \
             {SOBOL_MAX_PARAMETERS} (the dimensions of its sequence); use method = \
             \"latin-hypercube\" for more"
        ));
    }
    if seed > u64::from(u32::MAX) {
        return Err(format!(
            "design.seed = {seed}: a sobol design's seed is at most {}",
            u32::MAX
        ));
    }
    Ok(())
}

/// A Latin hypercube of `samples` points over `parameters` dimensions: for each dimension an
/// independent random permutation of the strata 0..samples and an independent place within
/// each stratum, u = (stratum + U[0, 1)) / samples, drawn from ChaCha8 seeded with `seed`
/// (a generator whose stream is the same on every platform).
fn latin_hypercube(samples: usize, parameters: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut unit = vec![0.0; samples * parameters];
    for j in 0..parameters {
        let strata = permutation(&mut rng, samples);
        for (i, stratum) in strata.into_iter().enumerate() {
            let jitter: f64 = rng.random();
            // (N - 1 + U) / N may round up to 1 for large N: the coordinate stays within [0, 1]
            unit[i * parameters + j] = ((stratum as f64 + jitter) / samples as f64).min(1.0);
        }
    }
    unit
}

/// A uniformly random permutation of 0..n (Fisher–Yates, on 64-bit draws whatever the
/// platform's word).
fn permutation(rng: &mut ChaCha8Rng, n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let k = rng.random_range(0..=i as u64) as usize;
        order.swap(i, k);
    }
    order
}

/// The first `samples` points of the Owen-scrambled Sobol sequence of `sobol_burley`, each
/// parameter a dimension, scrambled by `seed` (at most 32 bits, checked by [`sobol_limits`]).
fn sobol(samples: usize, parameters: usize, seed: u64) -> Vec<f64> {
    let mut unit = Vec::with_capacity(samples * parameters);
    for i in 0..samples {
        for j in 0..parameters {
            unit.push(f64::from(sobol_burley::sample(
                i as u32,
                j as u32,
                seed as u32,
            )));
        }
    }
    unit
}

#[cfg(test)]
mod tests {
    use super::*;

    fn section(method: &str, samples: Option<i64>, seed: Option<i64>) -> DesignSection {
        DesignSection {
            method: Some(method.into()),
            samples,
            seed,
        }
    }

    fn sampled(method: &str, samples: i64, seed: i64, parameters: usize) -> Sampling {
        match section(method, Some(samples), Some(seed))
            .design(parameters)
            .unwrap()
        {
            Design::Sampled(s) => s,
            Design::FullFactorial => panic!("{method} is not sampled"),
        }
    }

    /// The stratum of each case's coordinate `j` among `n` equal strata of [0, 1].
    fn strata(s: &Sampling, j: usize, n: usize) -> Vec<usize> {
        (0..n)
            .map(|i| (s.point(i).unwrap()[j] * n as f64).floor() as usize)
            .collect()
    }

    fn each_once(mut strata: Vec<usize>, n: usize) -> bool {
        strata.sort_unstable();
        strata == (0..n).collect::<Vec<_>>()
    }

    /// Every parameter of a Latin hypercube has one case in each of its N strata, and the
    /// parameters are paired differently (not all on the diagonal).
    #[test]
    fn a_latin_hypercube_has_one_case_per_stratum() {
        for (n, d, seed) in [(1, 1, 0), (7, 3, 0), (16, 5, 42), (1000, 2, 7)] {
            let s = sampled("latin-hypercube", n as i64, seed, d);
            for j in 0..d {
                assert!(each_once(strata(&s, j, n), n), "n = {n}, parameter {j}");
            }
            if n > 2 && d > 1 {
                assert_ne!(strata(&s, 0, n), strata(&s, 1, n));
            }
        }
    }

    /// The first 2^k points of the Sobol sequence put one case in each of 2^k equal
    /// intervals of every parameter, for every prefix length 2^k of the design.
    #[test]
    fn a_sobol_prefix_of_two_to_the_k_is_stratified() {
        let s = sampled("sobol", 64, 3, 6);
        for k in 0..=6 {
            let n = 1 << k;
            for j in 0..6 {
                assert!(
                    each_once(strata(&s, j, n), n),
                    "2^{k} points, parameter {j}"
                );
            }
        }
    }

    /// The seed makes the cases: the same seed gives the same points, another seed others.
    #[test]
    fn the_seed_decides_the_points() {
        for method in ["latin-hypercube", "sobol"] {
            let a = sampled(method, 20, 7, 3);
            assert_eq!(a, sampled(method, 20, 7, 3), "{method}");
            assert_ne!(a.unit, sampled(method, 20, 8, 3).unit, "{method}");
            assert!(a.unit.iter().all(|u| (0.0..1.0).contains(u)), "{method}");
        }
    }

    /// Refused designs name the key and say why.
    #[test]
    fn bad_designs_name_the_key() {
        let cases = [
            (
                section("latin-hypercube", None, None),
                2,
                "design.samples is missing",
            ),
            (section("sobol", Some(0), None), 2, "design.samples = 0"),
            (section("sobol", Some(1 << 17), None), 2, "at most 65536"),
            (section("sobol", Some(8), None), 300, "at most 256"),
            (section("sobol", Some(8), Some(1 << 40)), 2, "design.seed"),
            (
                section("latin-hypercube", Some(8), Some(-1)),
                2,
                "design.seed = -1",
            ),
            (
                section("full-factorial", Some(8), None),
                2,
                "design.samples:",
            ),
            (section("full-factorial", None, Some(1)), 2, "design.seed:"),
            (
                section("random", Some(8), None),
                2,
                "design.method = \"random\"",
            ),
            (
                section("latin-hypercube", Some(1_000_000), None),
                51,
                "coordinates",
            ),
        ];
        for (s, parameters, expected) in cases {
            let e = s.design(parameters).unwrap_err();
            assert!(e.contains(expected), "{s:?}: {e}");
        }
        assert_eq!(
            DesignSection::default().design(3),
            Ok(Design::FullFactorial)
        );
    }
}
