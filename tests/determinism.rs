//! The same answer on any number of threads, and no NaN or infinity in any history: the
//! command-line runs of a forming scenario and of the virtual tests, compared file by file.

mod common;

use common::{assert_bad_input, thermostamp, QUICK_BIAS_EXTENSION};
use std::path::{Path, PathBuf};

fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("determinism")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Runs `thermostamp <args> --threads <threads> --output <dir>`, asserts success and returns
/// its standard error.
fn run_on_threads(args: &[&str], threads: &str, dir: &Path) -> String {
    let out = thermostamp(
        &[
            args,
            &["--threads", threads, "--output", dir.to_str().unwrap()],
        ]
        .concat(),
    );
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "{args:?} on {threads} threads: {stderr}"
    );
    stderr
}

/// The result files of `a` and `b` have the same names and the same bytes; returns the names.
/// The folder's lock file, which names the run's process, is not a result.
fn assert_same_files(a: &Path, b: &Path) -> Vec<String> {
    let names = |dir: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|name| name != ".thermostamp.lock")
            .collect();
        names.sort();
        names
    };
    let files = names(a);
    assert_eq!(
        files,
        names(b),
        "{} and {} hold other files",
        a.display(),
        b.display()
    );
    for name in &files {
        let (x, y) = (
            std::fs::read(a.join(name)).unwrap(),
            std::fs::read(b.join(name)).unwrap(),
        );
        if x != y {
            let line = String::from_utf8_lossy(&x)
                .lines()
                .zip(String::from_utf8_lossy(&y).lines())
                .position(|(p, q)| p != q)
                .map_or(0, |i| i + 1);
            panic!(
                "{name} differs between {} and {} (first at line {line})",
                a.display(),
                b.display()
            );
        }
    }
    files
}

/// Every data cell of the CSV file at `path` is a finite number; returns the number of rows.
fn assert_finite_cells(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut rows = 0;
    for (i, line) in lines.enumerate() {
        for (cell, column) in line.split(',').zip(&header) {
            let ok = cell.parse::<f64>().is_ok_and(f64::is_finite);
            assert!(
                ok,
                "{}: line {}, column '{column}': '{cell}' is not a finite number",
                path.display(),
                i + 2
            );
        }
        rows += 1;
    }
    rows
}

/// Each of `extensions` is among `files`.
fn assert_has(files: &[String], extensions: &[&str]) {
    for ext in extensions {
        assert!(
            files.iter().any(|f| f.ends_with(ext)),
            "no {ext} file among {files:?}"
        );
    }
}

/// The hemisphere example on 10 mm cells, 3 mm of stroke, on each solver: the punch and the
/// force-driven holder touch the blank, so the contact loads (which move the holder) and the
/// element sums (the explicit solver's forces, the implicit one's assembled residual and
/// tangent) both feed the trajectory; and a hot blank on colder tools, whose temperature field
/// (its columns solved in parallel) feeds the laminate. 1 and 2 threads write the same bytes.
#[test]
fn forming_run_is_bit_identical_on_one_and_two_threads() {
    for (solver, scenario) in [
        ("explicit", "tests/data/hemisphere-explicit.toml"),
        ("implicit", "examples/hemisphere.toml"),
        ("non-isothermal", "tests/data/hemisphere-hot.toml"),
    ] {
        let args = [
            "run",
            scenario,
            "--set",
            "blank.element_size=10",
            "--set",
            "process.stroke=3",
            "--set",
            "output.frames=2",
            "--set",
            "output.history_points=6",
        ];
        let one = out_dir(&format!("forming-{solver}-1"));
        let two = out_dir(&format!("forming-{solver}-2"));
        run_on_threads(&args, "1", &one);
        run_on_threads(&args, "2", &two);
        let files = assert_same_files(&one, &two);
        assert_has(&files, &[".csv", ".vtu", ".pvd", ".inp"]);
        let rows = assert_finite_cells(&one.join("forming.csv"));
        assert!(rows >= 6, "{solver}: {rows} rows");
        let last = std::fs::read_to_string(one.join("forming.csv")).unwrap();
        let punch: f64 = last
            .lines()
            .last()
            .unwrap()
            .split(',')
            .nth(2)
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            punch > 0.1,
            "{solver}: the punch pushes the blank: {punch} N"
        );
    }
}

/// A short bias-extension test on 1, 2 and 100,000 threads: the same bytes in every file, and
/// 100,000 is cut to the machine's cores with a note instead of hanging.
#[test]
fn bias_extension_is_bit_identical_on_any_thread_count() {
    let args = QUICK_BIAS_EXTENSION;
    let (one, two, many) = (out_dir("bias-1"), out_dir("bias-2"), out_dir("bias-many"));
    run_on_threads(&args, "1", &one);
    run_on_threads(&args, "2", &two);
    let stderr = run_on_threads(&args, "100000", &many);
    let cores = std::thread::available_parallelism().unwrap().get();
    let note = format!(
        "note: --threads 100000 is more than the {cores} cores of this machine; using {cores}"
    );
    assert!(stderr.contains(&note), "no clamp note in: {stderr}");
    let files = assert_same_files(&one, &two);
    assert_same_files(&one, &many);
    assert_has(&files, &[".csv", ".vtu", ".pvd"]);
    assert_eq!(assert_finite_cells(&one.join("bias-extension.csv")), 13);
}

/// The uniaxial and picture-frame histories (the bias-extension and forming ones are checked
/// above) have a finite number in every cell, the first row at rest included.
#[test]
fn uniaxial_and_picture_frame_histories_are_finite() {
    let quick = [
        "--card",
        "tests/data/stiff-yarn-fabric.toml",
        "--time-scaling",
        "1",
        "--frames",
        "0",
        "--history-points",
        "12",
    ];
    let tests: [(&str, &[&str]); 2] = [
        (
            "uniaxial",
            &[
                "--ply-angle",
                "-90",
                "--end-displacement",
                "1.5",
                "--speed",
                "200",
            ],
        ),
        (
            "picture-frame",
            &[
                "--element-size",
                "75",
                "--end-displacement",
                "20",
                "--speed",
                "200",
                "--target-step",
                "5e-5",
            ],
        ),
    ];
    for (name, own) in tests {
        let dir = out_dir(name);
        run_on_threads(&[&["test", name], own, &quick].concat(), "1", &dir);
        let rows = assert_finite_cells(&dir.join(format!("{name}.csv")));
        assert_eq!(rows, 13, "{name}");
    }
}

#[test]
fn zero_threads_is_refused_naming_the_option() {
    assert_bad_input(
        &[
            "test",
            "uniaxial",
            "--card",
            "tests/data/stiff-yarn-fabric.toml",
            "--threads",
            "0",
        ],
        &["--threads", "at least 1"],
    );
}
