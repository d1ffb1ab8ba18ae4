//! CalculiX (`ccx`), the reader the tests run exported Abaqus decks through: whether it is
//! there, a run of `job.inp` checked to have read every card and finished, and the rows of its
//! `.dat` output.
//!
//! Without `ccx` on the PATH the tests that need it fail when `CI` is set (CI installs it:
//! `.ci/run`) and are skipped, with a printed line, otherwise.

use std::path::Path;
use std::process::Command;

/// Whether `ccx` can be run; `false` (skip) only outside CI.
pub fn ccx_available(test: &str) -> bool {
    let found = Command::new("ccx").arg("-v").output().is_ok();
    super::reader_available(found, test, "CalculiX (ccx, Debian package calculix-ccx)")
}

/// Runs `ccx` on `dir/job.inp` and returns its standard output, after checking that it read
/// every card (no `*WARNING`, no `*ERROR`) and finished. Its exit code is checked too, though
/// CalculiX 2.20 exits with 0 even when it cannot open the input file.
pub fn run_ccx(dir: &Path) -> String {
    let out = Command::new("ccx")
        .args(["-i", "job"])
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(out.status.success(), "ccx failed:\n{stdout}");
    for bad in ["*WARNING", "*ERROR"] {
        assert!(
            !stdout.contains(bad),
            "ccx: {bad} reading the deck:\n{stdout}"
        );
    }
    assert!(
        stdout.contains("Job finished"),
        "ccx did not finish:\n{stdout}"
    );
    stdout
}

/// The rows of the `.dat` block whose title contains `title`: each line's last three numbers,
/// up to the first line without numbers after them.
pub fn dat_rows(dat: &str, title: &str) -> Vec<[f64; 3]> {
    let mut rows = Vec::new();
    let mut lines = dat.lines().skip_while(|l| !l.contains(title)).skip(1);
    for line in lines.by_ref() {
        let numbers: Vec<f64> = line
            .split_whitespace()
            .filter_map(|f| f.parse().ok())
            .collect();
        if numbers.len() >= 3 {
            let n = numbers.len();
            rows.push([numbers[n - 3], numbers[n - 2], numbers[n - 1]]);
        } else if !rows.is_empty() {
            break;
        }
    }
    rows
}
