//! The harness of the adversarial tests: one invocation of the binary with the exit code it
//! must give and the pieces its one-line message must name (file and line, key or option),
//! and the scratch fixtures (the explicit hemisphere scenario and the T300/PPS card, with
//! absolute paths) the cases draw on.

use super::{repo_path, scratch_dir, thermostamp};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// One adversarial invocation.
pub struct Case {
    pub name: String,
    pub args: Vec<String>,
    pub code: i32,
    /// Pieces the message must contain (file, line, key or option).
    pub names: Vec<String>,
}

/// The fixtures every case draws on, in one scratch folder.
pub struct Fixtures {
    pub dir: PathBuf,
    /// The hemisphere example with the card's path made absolute.
    pub scenario: String,
    pub card: String,
}

impl Fixtures {
    /// The fixtures in the scratch folder `adversarial/<group>`: one group per test binary,
    /// since test binaries run side by side.
    pub fn new(group: &str) -> Self {
        let dir = scratch_dir("adversarial", group);
        let materials = repo_path("materials");
        let scenario = std::fs::read_to_string(repo_path("tests/data/hemisphere-explicit.toml"))
            .unwrap()
            .replace("../../materials/", &format!("{}/", materials.display()));
        let card = std::fs::read_to_string(repo_path("materials/t300-5hs-pps.toml")).unwrap();
        Self {
            dir,
            scenario,
            card,
        }
    }

    /// Writes `text` to `name` in the scratch folder and returns its path.
    pub fn file(&self, name: &str, text: &[u8]) -> String {
        let path = self.dir.join(name);
        std::fs::write(&path, text).unwrap();
        path.display().to_string()
    }

    /// The example scenario with `from` replaced by `to` (which must occur), written to `name`.
    pub fn scenario(&self, name: &str, from: &str, to: &str) -> String {
        assert!(
            self.scenario.contains(from),
            "{name}: '{from}' not in the example"
        );
        self.file(
            &format!("{name}.toml"),
            self.scenario.replace(from, to).as_bytes(),
        )
    }

    /// The T300/PPS card with `from` replaced by `to` (which must occur), written to `name`.
    pub fn card(&self, name: &str, from: &str, to: &str) -> String {
        assert!(self.card.contains(from), "{name}: '{from}' not in the card");
        self.file(
            &format!("{name}.toml"),
            self.card.replace(from, to).as_bytes(),
        )
    }

    /// The example scenario on the card file `card`.
    pub fn scenario_on_card(&self, name: &str, card: &str) -> String {
        let shipped = format!("{}", repo_path("materials/t300-5hs-pps.toml").display());
        self.scenario(name, &shipped, card)
    }

    /// The example scenario with its blank read from the mesh file `mesh`.
    pub fn file_blank(&self, name: &str, mesh: &str) -> String {
        let rectangle = ["width =", "length =", "element_size =", "pattern ="];
        let text: String = self
            .scenario
            .lines()
            .filter(|l| !rectangle.iter().any(|key| l.starts_with(key)))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
            .replace("[blank]\n", &format!("[blank]\nmesh = \"{mesh}\"\n"));
        self.file(&format!("{name}.toml"), text.as_bytes())
    }

    pub fn output(&self, name: &str) -> String {
        self.dir.join("out").join(name).display().to_string()
    }
}

pub fn case(name: &str, args: &[&str], code: i32, names: &[&str]) -> Case {
    Case {
        name: name.into(),
        args: args.iter().map(|s| s.to_string()).collect(),
        code,
        names: names.iter().map(|s| s.to_string()).collect(),
    }
}

pub fn repo(relative: &str) -> String {
    repo_path(relative).display().to_string()
}

pub fn args(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// Longest a refused invocation may take: it is refused before any step.
pub const REFUSAL_TIME: Duration = Duration::from_secs(30);

pub fn check(case: &Case) -> Result<(), String> {
    let args: Vec<&str> = case.args.iter().map(String::as_str).collect();
    let start = Instant::now();
    let out = thermostamp(&args);
    let elapsed = start.elapsed();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let code = out.status.code();
    let mut problems = Vec::new();
    if code != Some(case.code) {
        problems.push(format!("exit code {code:?}, expected {}", case.code));
    }
    if code == Some(101) || stderr.contains("panicked") {
        problems.push("panicked".into());
    }
    for piece in &case.names {
        if !stderr.contains(piece.as_str()) {
            problems.push(format!("'{piece}' not named"));
        }
    }
    let errors: Vec<&str> = stderr.lines().filter(|l| l.starts_with("error")).collect();
    if case.code == 2 && !case.args.is_empty() && errors.len() != 1 {
        problems.push(format!("{} error lines", errors.len()));
    }
    if stderr.chars().filter(char::is_ascii_digit).count() > 0 && has_long_number(&stderr) {
        problems.push("a number printed with too many digits".into());
    }
    if elapsed > REFUSAL_TIME {
        problems.push(format!("took {elapsed:?}"));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "{}: {}\n    {}",
            case.name,
            problems.join(", "),
            stderr.trim()
        ))
    }
}

/// A run of more than 20 digits (a float printed in full).
pub fn has_long_number(text: &str) -> bool {
    let mut run = 0;
    for c in text.chars() {
        run = if c.is_ascii_digit() { run + 1 } else { 0 };
        if run > 20 {
            return true;
        }
    }
    false
}

/// Every one of `cases` (at least `at_least` of them) gives its exit code and names what it
/// must; the failures listed together.
pub fn assert_all_pass(cases: &[Case], at_least: usize) {
    assert!(cases.len() >= at_least, "only {} cases", cases.len());
    let failures: Vec<String> = cases.iter().filter_map(|c| check(c).err()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}
