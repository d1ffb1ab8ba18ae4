//! Runs that stop early keep what they wrote: `thermostamp run` and `thermostamp test
//! bias-extension` interrupted (SIGINT) or killed (SIGKILL) mid-run leave CSV rows that parse
//! and a `.pvd` that lists only frames that exist; one run per output folder; results that
//! cannot be written stop the run with exit 2, naming the file, and leave no temporary file.

mod common;

use common::thermostamp;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// A hemisphere run long enough to be stopped (a full run would take minutes): a row every
/// hundred steps or so, a frame every fourth row.
fn long_forming_run(dir: &Path) -> Vec<String> {
    [
        "run",
        "tests/data/hemisphere-explicit.toml",
        "--set",
        "blank.element_size=10",
        "--set",
        "output.frames=100",
        "--set",
        "output.history_points=400",
        "--threads",
        "1",
        "--output",
        dir.to_str().unwrap(),
    ]
    .map(String::from)
    .to_vec()
}

/// The same hemisphere over half a millimetre of stroke: a few seconds.
fn short_forming_run(dir: &Path) -> Vec<String> {
    let mut args = long_forming_run(dir);
    args.extend(
        [
            "--set",
            "process.stroke=0.5",
            "--set",
            "output.history_points=4",
            "--set",
            "output.frames=2",
        ]
        .map(String::from),
    );
    args
}

fn spawn(args: &[String]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_thermostamp"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the binary starts")
}

fn run_to_end(args: &[String]) -> Output {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    thermostamp(&refs)
}

fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([format!("-{name}"), child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(status.success(), "kill -{name} failed");
}

/// Waits until `csv` holds the header and at least `rows` rows; the run must still be going.
fn wait_for_rows(child: &mut Child, csv: &Path, rows: usize) {
    let start = Instant::now();
    loop {
        let lines = std::fs::read_to_string(csv).map_or(0, |t| t.lines().count());
        if lines > rows {
            return;
        }
        if let Some(status) = child.try_wait().unwrap() {
            panic!("the run ended ({status}) before {csv:?} had {rows} rows");
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            panic!("{csv:?} did not reach {rows} rows in two minutes");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The rows of a CSV history: each line whole (ends in a newline), as many cells as the
/// header, every cell a finite number.
fn parsed_rows(csv: &Path) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(csv).unwrap();
    assert!(text.ends_with('\n'), "{csv:?} ends in a cut line");
    let mut lines = text.lines();
    let width = lines.next().expect("a header").split(',').count();
    lines
        .enumerate()
        .map(|(i, line)| {
            let cells: Result<Vec<f64>, _> = line.split(',').map(str::parse::<f64>).collect();
            let cells = cells.unwrap_or_else(|e| panic!("{csv:?} row {}: {line}: {e}", i + 1));
            assert_eq!(cells.len(), width, "{csv:?} row {}: {line}", i + 1);
            cells
        })
        .collect()
}

/// The frames a `.pvd` lists, `(time, file)`, after checking it is a whole collection whose
/// files all exist.
fn pvd_frames(pvd: &Path) -> Vec<(f64, String)> {
    let text = std::fs::read_to_string(pvd).unwrap();
    assert!(text.starts_with("<?xml"), "{text}");
    assert!(text.ends_with("</Collection>\n</VTKFile>\n"), "{text}");
    let dir = pvd.parent().unwrap();
    // the sheet's frames, part 0; each frame's tools (part 1) are checked where they are
    text.lines()
        .filter(|l| l.starts_with("<DataSet") && l.contains("part=\"0\""))
        .map(|l| {
            let attribute = |name: &str| {
                let start = l.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
                l[start..].split('"').next().unwrap().to_string()
            };
            let file = attribute("file");
            assert!(dir.join(&file).exists(), "{pvd:?} lists {file}, missing");
            (attribute("timestep").parse().unwrap(), file)
        })
        .collect()
}

fn temporary_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// SIGINT mid-run: exit 130, the summary says interrupted, every row parses, the `.pvd` lists
/// existing frames only, and its last frame is the state of the last row (recorded at the
/// interrupt).
#[test]
fn interrupted_forming_run_keeps_whole_rows_and_frames() {
    let dir = out_dir("safety-sigint");
    let mut child = spawn(&long_forming_run(&dir));
    wait_for_rows(&mut child, &dir.join("forming.csv"), 5);
    signal(&child, "INT");
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("status                      interrupted at step"),
        "{stdout}"
    );
    assert!(stdout.contains("results so far kept"), "{stdout}");
    assert!(stderr.contains("interrupted at step"), "{stderr}");
    let rows = parsed_rows(&dir.join("forming.csv"));
    assert!(rows.len() >= 5, "{} rows", rows.len());
    let frames = pvd_frames(&dir.join("forming.pvd"));
    assert!(frames.len() >= 2, "{frames:?}");
    // frames and the CSV's `time` are both at process time
    let last_time = rows.last().unwrap()[0];
    assert!(
        (frames.last().unwrap().0 - last_time).abs() <= 1e-9 * last_time,
        "last frame {frames:?} is not the last row's process time {last_time}"
    );
    assert!(
        temporary_files(&dir).is_empty(),
        "{:?}",
        temporary_files(&dir)
    );
}

/// SIGKILL mid-run: the rows so far parse; the next run into the folder takes it over (the
/// dead run's lock is no obstacle) and clears the dead run's frames and an older run's stray
/// files, but not the user's own files.
#[test]
fn killed_forming_run_keeps_whole_rows_and_the_next_run_clears_its_frames() {
    let dir = out_dir("safety-sigkill");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("notes.txt"), "mine").unwrap();
    std::fs::write(dir.join("forming_0099.vtu.tmp"), "half a frame").unwrap();
    let mut child = spawn(&long_forming_run(&dir));
    wait_for_rows(&mut child, &dir.join("forming.csv"), 16);
    signal(&child, "KILL");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), None, "killed by a signal");
    let rows = parsed_rows(&dir.join("forming.csv"));
    assert!(rows.len() >= 16, "{} rows", rows.len());
    let frames = pvd_frames(&dir.join("forming.pvd"));
    assert!(frames.len() >= 4, "{frames:?}");
    assert!(!dir.join("forming_0099.vtu.tmp").exists());

    let out = run_to_end(&short_forming_run(&dir));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let frames = pvd_frames(&dir.join("forming.pvd"));
    assert_eq!(frames.len(), 3, "{frames:?}");
    assert!(!dir.join("forming_0003.vtu").exists(), "a dead run's frame");
    assert_eq!(
        std::fs::read_to_string(dir.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(parsed_rows(&dir.join("forming.csv")).len(), 5);
    assert!(
        temporary_files(&dir).is_empty(),
        "{:?}",
        temporary_files(&dir)
    );
}

/// A second run into a folder that a run is writing is refused, naming the first; the first
/// goes on undisturbed.
#[test]
fn second_run_into_a_busy_folder_is_refused_naming_the_first() {
    let dir = out_dir("safety-busy");
    let mut first = spawn(&long_forming_run(&dir));
    wait_for_rows(&mut first, &dir.join("forming.csv"), 2);
    let second = run_to_end(&short_forming_run(&dir));
    let stderr = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "is being written by another run (pid {},",
            first.id()
        )) && stderr.contains("choose another --output"),
        "{stderr}"
    );
    assert!(first.try_wait().unwrap().is_none(), "the first run stopped");
    signal(&first, "INT");
    let out = first.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130));
    assert!(parsed_rows(&dir.join("forming.csv")).len() >= 2);
}

/// The bias-extension test interrupted: exit 130, the summary says so, the rows parse (the
/// test's own columns, computed as the run goes, included), the frames are listed.
#[test]
fn interrupted_bias_extension_keeps_whole_rows() {
    bias_extension_stopped_by("INT", "safety-bias-sigint");
}

/// SIGTERM (what a batch system sends) stops it the same way.
#[test]
fn terminated_bias_extension_keeps_whole_rows() {
    bias_extension_stopped_by("TERM", "safety-bias-sigterm");
}

fn bias_extension_stopped_by(signal_name: &str, folder: &str) {
    let dir = out_dir(folder);
    let args = [
        "test",
        "bias-extension",
        "--card",
        "tests/data/stiff-yarn-fabric.toml",
        "--element-size",
        "37.5",
        "--end-displacement",
        "100",
        "--speed",
        "200",
        "--time-scaling",
        "1",
        "--target-step",
        "0",
        "--frames",
        "50",
        "--history-points",
        "400",
        "--threads",
        "1",
        "--output",
        dir.to_str().unwrap(),
    ]
    .map(String::from);
    let mut child = spawn(&args);
    let csv = dir.join("bias-extension.csv");
    wait_for_rows(&mut child, &csv, 10);
    signal(&child, signal_name);
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(130),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("interrupted at step"), "{stdout}");
    let rows = parsed_rows(&csv);
    assert!(rows.len() >= 10, "{} rows", rows.len());
    // the displacement grows row after row, and the pin-jointed angle with it
    assert!(rows
        .windows(2)
        .all(|w| w[1][1] > w[0][1] && w[1][4] >= w[0][4]));
    let frames = pvd_frames(&dir.join("bias-extension.pvd"));
    assert!(!frames.is_empty());
    assert!(dir.join("bias-extension-force.png").exists());
}

/// An output folder that cannot be created (under a regular file): exit 2, naming it.
#[test]
fn output_under_a_regular_file_is_refused_naming_it() {
    let dir = out_dir("safety-under-file");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    let out = run_to_end(&short_forming_run(&file.join("sub")));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "{}: cannot create the output folder",
            file.join("sub").display()
        )),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

/// Results that cannot be written stop the run with exit 2, naming the file: a frame larger
/// than the files the process may write (`RLIMIT_FSIZE` below a frame's size and above the
/// plots', as a disk that fills up while the frame is written) leaves no temporary file and
/// keeps the rows before it; a history that cannot be created (a folder in its place) stops
/// the run before its first step. (Results are never written through a symbolic link, so a
/// link to `/dev/full` is no way to fill the disk.)
#[test]
fn results_that_cannot_be_written_stop_the_run_with_exit_2_naming_the_file() {
    use std::os::unix::process::CommandExt;
    let dir = out_dir("safety-full-frame");
    // frames of these 10 mm cells are 120 kB, the pictures 80 to 110 kB: the first frame, at
    // the start, is the first file over the limit; the pictures after the run fail too, and
    // the error named is the frame's, which stopped the run
    const LIMIT: libc::rlim_t = 80_000;
    let mut command = Command::new(env!("CARGO_BIN_EXE_thermostamp"));
    command
        .args(short_forming_run(&dir))
        .current_dir(env!("CARGO_MANIFEST_DIR"));
    // SAFETY: between fork and exec the child only ignores a signal and lowers its own limit,
    // both async-signal-safe calls that touch no memory of the parent
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let limit = libc::rlimit {
                rlim_cur: LIMIT,
                rlim_max: LIMIT,
            };
            match libc::setrlimit(libc::RLIMIT_FSIZE, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let out = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("forming_0000.vtu: cannot write the file: File too large"),
        "{stderr}"
    );
    assert!(
        temporary_files(&dir).is_empty(),
        "{:?}",
        temporary_files(&dir)
    );
    assert!(!dir.join("forming_0000.vtu").exists());
    assert!(
        !dir.join("forming-punch-force.png").exists(),
        "half a picture"
    );
    // the rows before the failed frame are kept
    assert!(!parsed_rows(&dir.join("forming.csv")).is_empty());

    let dir = out_dir("safety-csv-folder");
    std::fs::create_dir_all(dir.join("forming.csv")).unwrap();
    let out = run_to_end(&short_forming_run(&dir));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "cannot write {}: Is a directory",
            dir.join("forming.csv").display()
        )),
        "{stderr}"
    );
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
}
