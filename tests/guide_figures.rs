//! The user guide's figures are the program's: the quick commands the guide shows are run as it
//! shows them, and the figures they print or write are compared with the figures the guide
//! states (docs/guide/*.md, README.md, docs/performance.md).
//!
//! A figure in the docs is marked by an HTML comment right after it, on the same line:
//! `peak punch force 71.3 N<!-- figure: hemisphere.peak_punch_force -->`. The test reads the
//! last number before the marker, so a change of the code that changes a figure needs only the
//! docs to be updated. A figure matches when it is the measured value rounded to the digits the
//! docs write (half a unit of the last digit written, plus 0.1 % for the last bit of rounding).
//! Timings are never marked: no test asserts a timing. Every marker must be known here, and
//! every figure named here must be marked in the docs.

mod common;

use common::{repo_path, scratch_dir, thermostamp};
use std::collections::BTreeMap;
use std::path::Path;

/// The files whose figures are checked.
const DOCS: [&str; 3] = ["README.md", "docs/guide", "docs/performance.md"];

/// A figure as the docs state it: its value, the digits after the point, and where.
#[derive(Debug, Clone)]
struct Stated {
    value: f64,
    decimals: i32,
    place: String,
}

fn doc_files() -> Vec<(String, String)> {
    let mut files = Vec::new();
    for doc in DOCS {
        let path = repo_path(doc);
        if path.is_dir() {
            let mut entries: Vec<_> = std::fs::read_dir(&path)
                .unwrap()
                .map(|e| e.unwrap().path())
                .filter(|p| p.extension().is_some_and(|e| e == "md"))
                .collect();
            entries.sort();
            for entry in entries {
                let name = entry
                    .strip_prefix(repo_path(""))
                    .unwrap()
                    .display()
                    .to_string();
                files.push((name, std::fs::read_to_string(&entry).unwrap()));
            }
        } else {
            files.push((doc.to_string(), std::fs::read_to_string(&path).unwrap()));
        }
    }
    files
}

/// The last number in `text`: digits with an optional sign, point, thousands commas and
/// exponent, e.g. `71.3`, `-0.5`, `1,200`, `3.9e-3`; its value and its digits after the point.
fn last_number(text: &str) -> Option<(f64, i32)> {
    let chars: Vec<char> = text.chars().collect();
    let mut end = chars.len();
    while end > 0 && !chars[end - 1].is_ascii_digit() {
        end -= 1;
    }
    if end == 0 {
        return None;
    }
    let mut start = end;
    while start > 0 {
        let c = chars[start - 1];
        let exponent = (c == 'e' || c == 'E')
            && start >= 2
            && chars[start - 2].is_ascii_digit()
            && start < chars.len()
            && (chars[start].is_ascii_digit() || chars[start] == '-');
        let sign_of_exponent = c == '-' && start >= 2 && matches!(chars[start - 2], 'e' | 'E');
        let inner = (c == '.' || c == ',')
            && start >= 2
            && chars[start - 2].is_ascii_digit()
            && chars[start].is_ascii_digit();
        if c.is_ascii_digit() || exponent || sign_of_exponent || inner {
            start -= 1;
        } else {
            break;
        }
    }
    if start > 0 && chars[start - 1] == '-' {
        start -= 1;
    }
    let token: String = chars[start..end].iter().filter(|c| **c != ',').collect();
    let mantissa = token.split(['e', 'E']).next().unwrap();
    let exponent: i32 = token
        .split(['e', 'E'])
        .nth(1)
        .map_or(0, |e| e.parse().unwrap());
    let decimals = mantissa.split('.').nth(1).map_or(0, |d| d.len() as i32) - exponent;
    Some((token.parse().ok()?, decimals))
}

/// Every marked figure of the docs, by name.
fn stated_figures() -> BTreeMap<String, Stated> {
    let mut found = BTreeMap::new();
    for (file, text) in doc_files() {
        for (n, line) in text.lines().enumerate() {
            let mut rest = line;
            let mut before = String::new();
            while let Some(at) = rest.find("<!-- figure: ") {
                before.push_str(&rest[..at]);
                let after = &rest[at + "<!-- figure: ".len()..];
                let close = after
                    .find("-->")
                    .expect("a figure marker is closed on its line");
                let name = after[..close].trim().to_string();
                let place = format!("{file}:{}", n + 1);
                let (value, decimals) = last_number(&before)
                    .unwrap_or_else(|| panic!("{place}: no number before the marker {name}"));
                let earlier = found.insert(
                    name.clone(),
                    Stated {
                        value,
                        decimals,
                        place: place.clone(),
                    },
                );
                if let Some(earlier) = earlier {
                    assert!(
                        (earlier.value - value).abs() <= 0.0,
                        "{name} is {} at {} and {value} at {place}",
                        earlier.value,
                        earlier.place
                    );
                }
                rest = &after[close + 3..];
            }
        }
    }
    found
}

/// The docs' text with line continuations joined and runs of blanks made one, so that a
/// command can be looked for whatever its line breaks.
fn joined_docs() -> String {
    let mut all = String::new();
    for (_, text) in doc_files() {
        all.push_str(&text.replace("\\\n", " "));
        all.push('\n');
    }
    all.split(' ')
        .filter(|w| !w.is_empty())
        .collect::<Vec<_>>()
        .join(" ")
}

/// Asserts that the docs show `thermostamp ARGS` (or `cargo run --release -- ARGS`).
fn shown(args: &[&str]) {
    let docs = joined_docs();
    let line = args.join(" ");
    assert!(
        docs.contains(&format!("thermostamp {line}"))
            || docs.contains(&format!("cargo run --release -- {line}")),
        "the docs do not show the command `thermostamp {line}`"
    );
}

/// Runs `thermostamp ARGS` as the docs show it, with `extra` arguments that only say where the
/// results go; returns its standard output and error.
fn run_shown(args: &[&str], extra: &[&str]) -> (String, String) {
    shown(args);
    let all: Vec<&str> = args.iter().chain(extra).copied().collect();
    let out = thermostamp(&all);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "{all:?} failed:\n{stderr}");
    (stdout, stderr)
}

/// Compares each measured figure with the docs' figure of that name.
fn compare(measured: &[(&str, f64)]) {
    let stated = stated_figures();
    let mut wrong = Vec::new();
    for &(name, value) in measured {
        let Some(s) = stated.get(name) else {
            wrong.push(format!("{name}: measured {value}, not marked in the docs"));
            continue;
        };
        let tolerance = 0.5 * 10f64.powi(-s.decimals) + 1e-3 * value.abs();
        if (s.value - value).abs() > tolerance {
            wrong.push(format!(
                "{name}: the docs say {} ({}), the command gives {value}",
                s.value, s.place
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "figures of the docs that are not true:\n{}",
        wrong.join("\n")
    );
}

/// A CSV file's column, by header name, as numbers (empty and quoted cells skipped).
fn csv_column(path: &Path, column: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().unwrap().split(',').map(str::trim).collect();
    let at = header
        .iter()
        .position(|h| *h == column)
        .unwrap_or_else(|| panic!("{}: no column {column} in {header:?}", path.display()));
    lines
        .filter_map(|l| {
            // a quoted first cell (the status) may hold commas: count cells from the right
            let cells: Vec<&str> = l.rsplitn(header.len(), ',').collect();
            cells[header.len() - 1 - at].trim().parse().ok()
        })
        .collect()
}

fn last(path: &Path, column: &str) -> f64 {
    *csv_column(path, column).last().expect("a row")
}

/// The number right after `label` in `text` (e.g. `largest shear angle 31.7°`).
fn after(text: &str, label: &str) -> f64 {
    let at = text
        .find(label)
        .unwrap_or_else(|| panic!("`{label}` not in:\n{text}"))
        + label.len();
    let number: String = text[at..]
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || "+-.eE".contains(*c))
        .collect();
    number
        .trim_end_matches(['e', 'E'])
        .parse()
        .unwrap_or_else(|_| panic!("no number after `{label}` in:\n{text}"))
}

#[test]
fn numbers_are_read_as_written() {
    assert_eq!(last_number("peak punch force 71.3 N"), Some((71.3, 1)));
    assert_eq!(last_number("gives 31.7°"), Some((31.7, 1)));
    assert_eq!(last_number("1,200 cells"), Some((1200.0, 0)));
    assert_eq!(last_number("k_0 = 3.886e-3"), Some((3.886e-3, 6)));
    assert_eq!(last_number("at -0.25 MPa"), Some((-0.25, 2)));
    assert_eq!(last_number("no figure"), None);
}

#[test]
fn every_marked_figure_is_checked() {
    let known: Vec<&str> = FIGURES.iter().map(|(name, _)| *name).collect();
    for (name, s) in stated_figures() {
        assert!(
            known.contains(&name.as_str()),
            "{}: figure {name} is marked but no test checks it",
            s.place
        );
    }
    let stated = stated_figures();
    for (name, _) in FIGURES {
        assert!(
            stated.contains_key(*name),
            "figure {name} is checked but not marked in the docs"
        );
    }
}

/// Every figure the docs mark, and the test that checks it.
const FIGURES: &[(&str, &str)] = &[
    ("hemisphere.peak_punch_force", "the_hemisphere_example"),
    ("hemisphere.max_shear_deg", "the_hemisphere_example"),
    ("hemisphere.draw_in", "the_hemisphere_example"),
    (
        "hemisphere_8mm.peak_punch_force",
        "the_hemisphere_on_8_mm_cells",
    ),
    (
        "hemisphere_8mm.max_shear_deg",
        "the_hemisphere_on_8_mm_cells",
    ),
    ("double_dome.peak_punch_force", "the_double_dome_example"),
    ("double_dome.max_shear_deg", "the_double_dome_example"),
    ("double_dome.draw_in", "the_double_dome_example"),
    ("quarter.peak_punch_force", "the_quarter_example"),
    ("quarter.max_shear_deg", "the_quarter_example"),
    ("quarter.draw_in", "the_quarter_example"),
    ("no_holder_12mm.waviness", "the_hemisphere_without_a_holder"),
    ("no_holder_12mm.lift_off", "the_hemisphere_without_a_holder"),
    ("drape.hemisphere_4mm", "the_drape_previews"),
    ("drape.double_dome", "the_drape_previews"),
    ("material_point.n12_45deg", "the_material_point_example"),
    (
        "material_point.thickness_45deg",
        "the_material_point_example",
    ),
    ("uniaxial.stress_resultant_end", "the_uniaxial_test"),
    ("fit_shear.k0", "the_twintex_shear_fit"),
    ("fit_shear.c1", "the_twintex_shear_fit"),
    ("fit_shear.c3", "the_twintex_shear_fit"),
    ("fit_shear.rms_percent_of_mean", "the_twintex_shear_fit"),
    ("fit_matrix.c10_300", "the_matrix_fit"),
    ("fit_matrix.eta1_300", "the_matrix_fit"),
];

/// The final measures of a forming run as the docs show it, written to a scratch folder.
fn forming(name: &str, args: &[&str]) -> (std::path::PathBuf, String) {
    let dir = scratch_dir("guide_figures", name);
    let (stdout, _) = run_shown(args, &["--output", dir.to_str().unwrap()]);
    (dir.join("forming-result.csv"), stdout)
}

/// The lines of the summary printed by a run (between its two rules), without those that
/// depend on the machine (times, memory, the solver's time split).
fn summary_lines(text: &str) -> Vec<String> {
    text.lines()
        .map(str::trim_end)
        .filter(|l| {
            !["solver", "wall time", "memory"]
                .iter()
                .any(|machine| l.starts_with(machine))
        })
        .map(String::from)
        .collect()
}

/// The summary the docs show after `<!-- summary: NAME -->`, in the code block that follows.
fn shown_summary(name: &str) -> Vec<String> {
    let marker = format!("<!-- summary: {name} -->");
    for (file, text) in doc_files() {
        if let Some(at) = text.find(&marker) {
            let rest = &text[at + marker.len()..];
            let start = rest
                .find("```text\n")
                .unwrap_or_else(|| panic!("{file}: no block"));
            let block = &rest[start + "```text\n".len()..];
            let end = block.find("```").unwrap();
            return summary_lines(&block[..end]);
        }
    }
    panic!("no summary {name} in the docs");
}

#[test]
fn the_hemisphere_example() {
    let (result, stdout) = forming("hemisphere", &["run", "examples/hemisphere.toml"]);
    compare(&[
        (
            "hemisphere.peak_punch_force",
            last(&result, "peak_punch_force"),
        ),
        ("hemisphere.max_shear_deg", last(&result, "max_shear_deg")),
        ("hemisphere.draw_in", last(&result, "draw_in")),
    ]);
    let rule = "-".repeat(64);
    let printed = stdout.split(&rule).nth(1).expect("a summary between rules");
    assert_eq!(
        shown_summary("hemisphere"),
        summary_lines(printed.trim_matches('\n')),
        "the summary of `thermostamp run examples/hemisphere.toml` in the docs is not what it prints"
    );
}

#[test]
fn the_hemisphere_on_8_mm_cells() {
    let (result, _) = forming(
        "hemisphere-8mm",
        &[
            "run",
            "examples/hemisphere.toml",
            "--set",
            "blank.element_size=8",
        ],
    );
    compare(&[
        (
            "hemisphere_8mm.peak_punch_force",
            last(&result, "peak_punch_force"),
        ),
        (
            "hemisphere_8mm.max_shear_deg",
            last(&result, "max_shear_deg"),
        ),
    ]);
}

#[test]
fn the_double_dome_example() {
    let (result, _) = forming("double-dome", &["run", "examples/double-dome.toml"]);
    compare(&[
        (
            "double_dome.peak_punch_force",
            last(&result, "peak_punch_force"),
        ),
        ("double_dome.max_shear_deg", last(&result, "max_shear_deg")),
        ("double_dome.draw_in", last(&result, "draw_in")),
    ]);
}

#[test]
fn the_quarter_example() {
    let (result, stdout) = forming("quarter", &["run", "examples/hemisphere-quarter.toml"]);
    // its coarse tutorial mesh is said in the summary, as the guide's "Mesh size" says
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("note") && l.contains("coarse tutorial mesh (8 mm)")),
        "{stdout}"
    );
    compare(&[
        (
            "quarter.peak_punch_force",
            last(&result, "peak_punch_force"),
        ),
        ("quarter.max_shear_deg", last(&result, "max_shear_deg")),
        ("quarter.draw_in", last(&result, "draw_in")),
    ]);
}

#[test]
fn the_hemisphere_without_a_holder() {
    let (result, _) = forming(
        "no-holder",
        &[
            "run",
            "examples/hemisphere.toml",
            "--set",
            "process.blank_holder_force=0",
            "--set",
            "process.stroke=12",
            "--set",
            "blank.element_size=8",
        ],
    );
    compare(&[
        ("no_holder_12mm.waviness", last(&result, "waviness")),
        ("no_holder_12mm.lift_off", last(&result, "lift_off")),
    ]);
}

#[test]
fn the_drape_previews() {
    let dir = scratch_dir("guide_figures", "drape-hemisphere");
    let (hemisphere, _) = run_shown(
        &[
            "drape",
            "examples/hemisphere.toml",
            "--set",
            "blank.element_size=4",
        ],
        &["--output", dir.to_str().unwrap()],
    );
    let dir = scratch_dir("guide_figures", "drape-double-dome");
    let (double_dome, _) = run_shown(
        &["drape", "examples/double-dome.toml"],
        &["--output", dir.to_str().unwrap()],
    );
    compare(&[
        (
            "drape.hemisphere_4mm",
            after(&hemisphere, "largest shear angle"),
        ),
        (
            "drape.double_dome",
            after(&double_dome, "largest shear angle"),
        ),
    ]);
}

#[test]
fn the_material_point_example() {
    let (stdout, _) = run_shown(
        &[
            "material-point",
            "--card",
            "materials/t300-5hs-pps.toml",
            "--layer",
            "laminate",
            "--history",
            "examples/material-point/laminate-shear-300C.csv",
        ],
        &[],
    );
    let path = scratch_dir("guide_figures", "material-point").join("laminate.csv");
    std::fs::write(&path, &stdout).unwrap();
    let times = csv_column(&path, "t");
    let at = times
        .iter()
        .position(|t| (t - 9.0).abs() < 1e-9)
        .expect("a row at t = 9 s");
    compare(&[
        ("material_point.n12_45deg", csv_column(&path, "N12")[at]),
        (
            "material_point.thickness_45deg",
            csv_column(&path, "thickness")[at],
        ),
    ]);
}

#[test]
fn the_uniaxial_test() {
    let dir = scratch_dir("guide_figures", "uniaxial");
    run_shown(
        &[
            "test",
            "uniaxial",
            "--card",
            "materials/t300-5hs-pps.toml",
            "--temperature",
            "300",
        ],
        &["--output", dir.to_str().unwrap()],
    );
    compare(&[(
        "uniaxial.stress_resultant_end",
        last(&dir.join("uniaxial.csv"), "stress_resultant"),
    )]);
}

/// `args` as the docs show them, with the values of the options in `replaced` changed (files
/// the command would write into the repository go to a scratch folder instead).
fn replacing(args: &[&'static str], replaced: &[(&str, String)]) -> Vec<String> {
    let mut out: Vec<String> = args.iter().map(|a| a.to_string()).collect();
    for (option, value) in replaced {
        let at = out.iter().position(|a| a == option).expect("the option");
        out[at + 1] = value.clone();
    }
    out
}

fn run_replaced(args: &[&'static str], replaced: &[(&str, String)]) -> String {
    shown(args);
    let all = replacing(args, replaced);
    let all: Vec<&str> = all.iter().map(String::as_str).collect();
    let out = thermostamp(&all);
    assert!(
        out.status.success(),
        "{all:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The number in the first column of the row whose first word is `first`.
fn row_value(text: &str, first: &str, column: usize) -> f64 {
    let line = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some(first))
        .unwrap_or_else(|| panic!("no row {first} in:\n{text}"));
    line.split_whitespace()
        .nth(column)
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn the_twintex_shear_fit() {
    let dir = scratch_dir("guide_figures", "fit-shear");
    let stdout = run_replaced(
        &[
            "fit",
            "shear",
            "--data",
            "examples/fit-shear/bias_extension_glass_pp_plain_150x450.csv",
            "--width",
            "150",
            "--length",
            "450",
            "--card",
            "materials/twintex-plain-weave.toml",
            "--output",
            "materials/twintex-plain-weave.toml",
            "--plot",
            "examples/fit-shear/fit.png",
            "--terms",
            "friction,1,3",
            "--friction-onset",
            "3",
            "--max-shear",
            "35",
        ],
        &[
            ("--output", dir.join("twintex.toml").display().to_string()),
            ("--plot", dir.join("fit.png").display().to_string()),
        ],
    );
    let rms = stdout
        .split("% of the mean")
        .next()
        .and_then(last_number)
        .expect("the misfit relative to the mean force")
        .0;
    compare(&[
        ("fit_shear.k0", row_value(&stdout, "friction", 1)),
        ("fit_shear.c1", row_value(&stdout, "c1", 1)),
        ("fit_shear.c3", row_value(&stdout, "c3", 1)),
        ("fit_shear.rms_percent_of_mean", rms),
    ]);
}

#[test]
fn the_matrix_fit() {
    let dir = scratch_dir("guide_figures", "fit-matrix");
    let stdout = run_replaced(
        &[
            "fit",
            "matrix",
            "--manifest",
            "examples/fit-matrix/manifest.toml",
            "--card",
            "materials/t300-5hs-pps.toml",
            "--output",
            "fitted.toml",
            "--bulk-modulus",
            "1500",
            "--plot",
            "fit.png",
        ],
        &[
            ("--output", dir.join("fitted.toml").display().to_string()),
            ("--plot", dir.join("fit.png").display().to_string()),
        ],
    );
    compare(&[
        ("fit_matrix.c10_300", row_value(&stdout, "300", 3)),
        ("fit_matrix.eta1_300", row_value(&stdout, "300", 6)),
    ]);
}
