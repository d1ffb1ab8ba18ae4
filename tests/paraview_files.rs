//! Every ParaView file the product writes, read by VTK itself (`tests/read_vtk.py`, the
//! `vtk` Python package, whose XML reader is ParaView's): the frames of a forming run and
//! their `.pvd`, the formed blank (of triangles and of quadrilaterals), the frames of a virtual test, and the drape preview. Point
//! and cell counts, array names (the same whatever the card's stack), component names, no
//! NaN, the meanings of the `contact_status` codes, the frames' process times, and the drape
//! preview's cells sharing their points.
//!
//! Without Python and VTK this test fails when `CI` is set (CI installs them: `.ci/run`) and
//! is skipped, with a printed line, otherwise.

mod common;

use common::{repo_path, run_ok, scratch_dir, QUICK_BIAS_EXTENSION};
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// What VTK read from one `.vtu`.
#[derive(Debug, Default)]
struct Grid {
    points: usize,
    cells: usize,
    types: String,
    shared_points: usize,
    /// "point NAME" or "cell NAME" -> (components, component names, non-finite values)
    arrays: BTreeMap<String, (usize, String, usize)>,
    /// field-data arrays: name -> values joined by '|'
    fields: BTreeMap<String, String>,
}

/// What VTK read from the files: the grids by file name and the `.pvd` times by file name.
#[derive(Debug, Default)]
struct Read {
    grids: BTreeMap<String, Grid>,
    times: BTreeMap<String, Vec<f64>>,
}

/// Whether python3 with VTK can run the reader (with no files, it only imports VTK); `false`
/// (skip) only outside CI.
fn vtk_available(dir: &Path) -> bool {
    let found = Command::new("python3")
        .arg(repo_path("tests/read_vtk.py"))
        .current_dir(dir)
        .output()
        .is_ok_and(|o| o.status.success());
    common::reader_available(
        found,
        "paraview_files",
        "python3 with VTK (pip install vtk)",
    )
}

/// Runs the reader in `dir` (where VTK's error log goes).
fn read_with_vtk(dir: &Path, files: &[&Path]) -> Read {
    parse(&run_reader("tests/read_vtk.py", dir, files))
}

/// Runs the Python `script` on `files` in `dir`; its standard output, once it read them all.
fn run_reader(script: &str, dir: &Path, files: &[&Path]) -> String {
    common::run_python(script, files, dir)
}

fn parse(text: &str) -> Read {
    let mut read = Read::default();
    let mut current = String::new();
    for line in text.lines() {
        let words: Vec<&str> = line.split(' ').collect();
        match words[0] {
            "pvd" => {
                let times = words[3..].iter().map(|t| t.parse().unwrap()).collect();
                read.times.insert(words[1].to_string(), times);
            }
            "vtu" => {
                current = words[1].to_string();
                read.grids.insert(
                    current.clone(),
                    Grid {
                        points: words[3].parse().unwrap(),
                        cells: words[5].parse().unwrap(),
                        types: words[7].to_string(),
                        shared_points: words[9].parse().unwrap(),
                        ..Grid::default()
                    },
                );
            }
            "point" | "cell" => {
                let grid = read.grids.get_mut(&current).unwrap();
                grid.arrays.insert(
                    format!("{} {}", words[0], words[1]),
                    (
                        words[3].parse().unwrap(),
                        words[5].to_string(),
                        words[7].parse().unwrap(),
                    ),
                );
            }
            "field" => {
                let grid = read.grids.get_mut(&current).unwrap();
                let (name, values) = line["field ".len()..].split_once(" values ").unwrap();
                grid.fields.insert(name.to_string(), values.to_string());
            }
            other => panic!("unexpected reader line '{other}': {line}"),
        }
    }
    read
}

/// The arrays of a sheet frame: name -> component names ("-" for scalars).
fn sheet_arrays(contact: bool, stresses: &[&str]) -> BTreeMap<String, String> {
    let mut arrays: BTreeMap<String, String> = [
        ("point displacement", "x,y,z"),
        ("point velocity", "x,y,z"),
        ("point reaction", "x,y,z"),
        ("cell shear_angle_deg", "-"),
        ("cell warp", "x,y,z"),
        ("cell weft", "x,y,z"),
        ("cell thickness", "-"),
        ("cell membrane_force", "xx,yy,xy"),
        ("cell yarn_tension_warp", "-"),
        ("cell yarn_tension_weft", "-"),
    ]
    .iter()
    .map(|(n, c)| (n.to_string(), c.to_string()))
    .collect();
    if contact {
        for name in [
            "contact_pressure",
            "contact_status",
            "gap_punch",
            "gap_die",
            "gap_blank_holder",
        ] {
            arrays.insert(format!("point {name}"), "-".into());
        }
    }
    for stress in stresses {
        arrays.insert(format!("cell {stress}"), "xx,yy,xy".into());
    }
    arrays
}

fn assert_grid(name: &str, grid: &Grid, counts: (usize, usize), arrays: &BTreeMap<String, String>) {
    assert_cells(name, grid, counts, "5", arrays);
}

/// [`assert_grid`] with the VTK cell types expected: "5" triangles, "9" quadrilaterals.
fn assert_cells(
    name: &str,
    grid: &Grid,
    counts: (usize, usize),
    types: &str,
    arrays: &BTreeMap<String, String>,
) {
    assert_eq!((grid.points, grid.cells), counts, "{name}");
    assert_eq!(grid.types, types, "{name}: VTK cell types");
    let got: BTreeMap<String, String> = grid
        .arrays
        .iter()
        .map(|(n, (_, c, _))| (n.clone(), c.clone()))
        .collect();
    assert_eq!(&got, arrays, "{name}: arrays and their component names");
    for (array, (components, _, nan)) in &grid.arrays {
        assert_eq!(*nan, 0, "{name}: {array} has non-finite values");
        let expected = if arrays[array] == "-" { 1 } else { 3 };
        assert_eq!(*components, expected, "{name}: {array}");
    }
}

#[test]
fn every_paraview_file_reads_in_vtk_as_written() {
    let dir = scratch_dir("paraview_files", "all");
    if !vtk_available(&dir) {
        return;
    }
    for sub in ["run", "quad", "bias", "drape"] {
        let _ = std::fs::remove_dir_all(dir.join(sub));
    }
    let (run, bias, drape) = (dir.join("run"), dir.join("bias"), dir.join("drape"));
    let quad = dir.join("quad");
    // the hemisphere example on 10 mm cells cut into triangles, 4 mm of stroke at 10 mm/s, on
    // the explicit solver with time scaling 10
    run_ok(&[
        "run",
        "tests/data/hemisphere-explicit.toml",
        "--set",
        "blank.pattern=right",
        "--set",
        "blank.element_size=10",
        "--set",
        "process.stroke=4",
        "--set",
        "output.frames=2",
        "--set",
        "output.history_points=8",
        "--output",
        run.to_str().unwrap(),
    ]);
    // the same on quadrilaterals with the example's implicit solver, one frame at the end
    run_ok(&[
        "run",
        "examples/hemisphere.toml",
        "--set",
        "blank.element_size=10",
        "--set",
        "blank.pattern=quad",
        "--set",
        "process.stroke=4",
        "--set",
        "output.frames=1",
        "--set",
        "output.history_points=8",
        "--output",
        quad.to_str().unwrap(),
    ]);
    // a dry fabric card (one fabric layer): the same stress array name as the prepreg's
    run_ok(
        &[
            &QUICK_BIAS_EXTENSION[..],
            &["--threads", "1", "--output", bias.to_str().unwrap()],
        ]
        .concat(),
    );
    run_ok(&[
        "drape",
        "examples/hemisphere.toml",
        "--output",
        drape.to_str().unwrap(),
    ]);
    let quad_blank = quad.join("quad-formed-blank.vtu");
    std::fs::rename(quad.join("formed-blank.vtu"), &quad_blank).unwrap();
    let files = [
        run.join("forming.pvd"),
        run.join("formed-blank.vtu"),
        quad_blank.clone(),
        bias.join("bias-extension.pvd"),
        drape.join("drape.vtu"),
    ];
    let paths: Vec<&Path> = files.iter().map(|f| f.as_path()).collect();
    let read = read_with_vtk(&dir, &paths);

    // forming: 17 x 17 nodes, 2 x 16 x 16 triangles, frames at 0, half and all the stroke in
    // process time (4 mm at 10 mm/s and a smooth start: 0.41 s; the solver's time is a tenth)
    let times = &read.times["forming.pvd"];
    assert_eq!(times.len(), 3, "{times:?}");
    assert!(times[0] == 0.0 && times[1] < times[2], "{times:?}");
    assert!((0.40..0.42).contains(&times[2]), "{times:?}");
    let forming = sheet_arrays(true, &["stress_matrix", "stress_fabric"]);
    for name in [
        "forming_0000.vtu",
        "forming_0001.vtu",
        "forming_0002.vtu",
        "formed-blank.vtu",
    ] {
        let grid = &read.grids[name];
        assert_grid(name, grid, (289, 512), &forming);
        for (k, meaning) in ["free", "punch", "die", "blank holder"].iter().enumerate() {
            assert_eq!(
                grid.fields[&format!("contact_status {k} {meaning}")],
                k.to_string(),
                "{name}"
            );
        }
    }
    // each frame's tools, its part 1: triangles, a code per triangle naming its tool
    for k in 0..3 {
        let name = format!("forming_{k:04}_tools.vtu");
        let tools = &read.grids[&name];
        assert!(tools.cells > 1000, "{name}: {tools:?}");
        let codes: BTreeMap<String, String> = [("cell tool".to_string(), "-".to_string())]
            .into_iter()
            .collect();
        assert_cells(&name, tools, (tools.points, tools.cells), "5", &codes);
        for (k, tool) in ["punch", "die", "blank holder"].iter().enumerate() {
            assert_eq!(tools.fields[&format!("tool {k} {tool}")], k.to_string());
        }
    }

    // quadrilaterals: 16 x 16 cells of VTK type 9 on the same 17 x 17 nodes, the same arrays
    assert_cells(
        "quad-formed-blank.vtu",
        &read.grids["quad-formed-blank.vtu"],
        (289, 256),
        "9",
        &forming,
    );

    // virtual test: no tools, no contact fields, the fabric's stress under the same name
    assert_eq!(read.times["bias-extension.pvd"].len(), 4);
    let test = sheet_arrays(false, &["stress_fabric"]);
    for k in 0..4 {
        let name = format!("bias-extension_{k:04}.vtu");
        let grid = &read.grids[&name];
        assert_eq!(grid.points, grid.shared_points, "{name}");
        assert_grid(&name, grid, (grid.points, grid.cells), &test);
        assert!(grid.fields.is_empty(), "{name}: {:?}", grid.fields);
    }

    // drape preview: a quadrilateral per cell of the net, one point per node of the net shared
    // by the cells around it (a point per corner of each cell would give four points a cell,
    // none shared)
    let net = &read.grids["drape.vtu"];
    let shear: BTreeMap<String, String> = [("cell shear_angle_deg".to_string(), "-".to_string())]
        .into_iter()
        .collect();
    assert_cells("drape.vtu", net, (net.points, net.cells), "9", &shear);
    assert!(net.cells > 50, "{net:?}");
    assert!(net.points < 2 * net.cells, "{net:?}");
    assert!(2 * net.shared_points > net.points, "{net:?}");

    same_in_meshio_and_pyvista(&dir, &read, &[&run, &bias, &drape], &quad_blank);
    csv_times_are_the_frames(&run, &read.times["forming.pvd"]);
}

/// Every `.vtu` VTK read above, read again by meshio and by pyvista: the same points, cells and
/// arrays; the forming `.pvd` through pyvista, its sheet and tools as two blocks at each time;
/// the sheets' points flat (the reference blank), the formed blanks' lifted onto the punch by
/// `displacement`.
fn same_in_meshio_and_pyvista(dir: &Path, vtk: &Read, folders: &[&Path], quad_blank: &Path) {
    let found = Command::new("python3")
        .arg(repo_path("tests/read_meshio_pyvista.py"))
        .output()
        .is_ok_and(|o| o.status.success());
    let missing = "meshio and pyvista (pip install meshio pyvista)";
    if !common::reader_available(found, "paraview_files", missing) {
        return;
    }
    let mut files = vec![folders[0].join("forming.pvd"), quad_blank.to_path_buf()];
    for folder in folders {
        for entry in std::fs::read_dir(folder).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "vtu") {
                files.push(path);
            }
        }
    }
    let paths: Vec<&Path> = files.iter().map(|f| f.as_path()).collect();
    let stdout = run_reader("tests/read_meshio_pyvista.py", dir, &paths);
    let (mut checked, mut times, mut rising) = (0, 0, 0);
    for line in stdout.lines() {
        let words: Vec<&str> = line.split(' ').collect();
        match words[0] {
            "meshio" | "pyvista" => {
                let grid = &vtk.grids[words[1]];
                let counts = (words[3].parse().unwrap(), words[5].parse().unwrap());
                assert_eq!(counts, (grid.points, grid.cells), "{line}");
                for (kind, list) in [("point", words[7]), ("cell", words[9])] {
                    let theirs: Vec<String> = list
                        .split(',')
                        .filter(|n| *n != "-")
                        .map(|n| format!("{kind} {n}"))
                        .collect();
                    let ours: Vec<&String> =
                        grid.arrays.keys().filter(|k| k.starts_with(kind)).collect();
                    assert_eq!(theirs.iter().collect::<Vec<_>>(), ours, "{line}");
                }
                checked += 1;
            }
            "z" => {
                let z: Vec<f64> = [3, 4, 6, 7].map(|k| words[k].parse().unwrap()).to_vec();
                assert!(z[0].abs() < 1e-12 && z[1].abs() < 1e-12, "{line}");
                if words[1].contains("formed-blank") {
                    assert!(z[3] > 1.0, "{line}");
                    rising += 1;
                }
            }
            "pvd" => {
                assert_eq!(words[5], "2", "{line}: the sheet and the tools");
                assert_eq!(words[7].split(',').next(), Some("289"), "{line}");
                times += 1;
            }
            other => panic!("unexpected reader line '{other}': {line}"),
        }
    }
    assert_eq!((times, rising), (3, 2), "{stdout}");
    assert_eq!(checked, 2 * (files.len() - 1), "{stdout}");
}

/// The CSV history's `time` is process time, as the frames': its last row is the last frame's
/// time, and ten times its `solver_time` (the run's time scaling).
fn csv_times_are_the_frames(run: &Path, frame_times: &[f64]) {
    let (header, last) = common::csv_header_and_last_row(&run.join("forming.csv"));
    let column = |name: &str| last[header.iter().position(|h| *h == name).unwrap()];
    let (time, solver_time) = (column("time"), column("solver_time"));
    assert!(
        (time - 10.0 * solver_time).abs() < 1e-9 * time,
        "{time} {solver_time}"
    );
    let frame = frame_times[frame_times.len() - 1];
    assert!((time - frame).abs() < 1e-9 * time, "{time} {frame}");
}
