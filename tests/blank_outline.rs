//! `thermostamp blank-outline`: the flat outline whose formed part covers a trim line with a
//! margin. The hemisphere with a trim circle on its flange, checked on the formed part itself
//! (its edge in plan around the circle) and by the iterations' history; the kinematic first
//! guess against closed forms (a plane, the hemisphere's generators); bad input through the
//! binary; the DXF read by ezdxf (`tests/read_dxf.py`).

mod common;

use common::{assert_bad_input, scratch_dir, thermostamp};
use nalgebra::{Vector2, Vector3};
use std::f64::consts::{PI, TAU};
use std::path::Path;
use thermostamp::drape::{drape, DrapeParams, Hemisphere, Plane};
use thermostamp::forming::drape_preview::Generators;
use thermostamp::forming::outline::iterate::outline_around;
use thermostamp::forming::outline::mapping::flat_from_drape;
use thermostamp::forming::outline::trim_circle;

/// Plan radius of the trim circle on the hemisphere's flange (the die's opening and fillet end
/// at 47 mm) and the margin asked for (mm).
const TRIM_RADIUS: f64 = 55.0;
const MARGIN: f64 = 5.0;
/// The tolerance asked for: below the default (a quarter of the 10 mm cells), so that the
/// command iterates past its first forming run.
const TOLERANCE: f64 = 1.0;

/// The rows of a numeric CSV file after its header.
fn csv_rows(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect()
}

/// The lines of the block after the keyword line starting with `keyword` in an Abaqus deck,
/// split at the commas.
fn deck_block(text: &str, keyword: &str) -> Vec<Vec<f64>> {
    text.lines()
        .skip_while(|l| !l.to_ascii_uppercase().starts_with(keyword))
        .skip(1)
        .take_while(|l| !l.starts_with('*'))
        .map(|l| l.split(',').map(|x| x.trim().parse().unwrap()).collect())
        .collect()
}

/// The formed blank's edge in plan, from an Abaqus deck of quadrilaterals: the element edges
/// that belong to one element only, as pairs of points (mm).
fn formed_edge(path: &Path) -> Vec<(Vector2<f64>, Vector2<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let nodes: std::collections::HashMap<usize, Vector2<f64>> = deck_block(&text, "*NODE")
        .iter()
        .map(|v| (v[0] as usize, Vector2::new(v[1], v[2])))
        .collect();
    let mut count: std::collections::HashMap<(usize, usize), usize> = Default::default();
    for e in deck_block(&text, "*ELEMENT") {
        let corners: Vec<usize> = e[1..].iter().map(|&n| n as usize).collect();
        for k in 0..corners.len() {
            let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    count
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|((a, b), _)| (nodes[&a], nodes[&b]))
        .collect()
}

/// How far from the axis the ray at `angle` (radians) leaves the plan edge `edge` (mm).
fn reach(edge: &[(Vector2<f64>, Vector2<f64>)], angle: f64) -> f64 {
    let d = Vector2::new(angle.cos(), angle.sin());
    edge.iter()
        .filter_map(|(a, b)| {
            let e = b - a;
            let denominator = d.perp(&e);
            let t = a.perp(&e) / denominator;
            let s = a.perp(&d) / denominator;
            (denominator.abs() > 1e-12 && t > 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
        })
        .fold(0.0, f64::max)
}

#[test]
fn the_formed_hemisphere_covers_a_trim_circle_with_the_margin() {
    let dir = scratch_dir("blank_outline", "hemisphere");
    let out = dir.join("outline");
    let started = std::time::Instant::now();
    let run = thermostamp(&[
        "blank-outline",
        "examples/hemisphere.toml",
        "--trim-circle",
        &TRIM_RADIUS.to_string(),
        "--margin",
        &MARGIN.to_string(),
        "--tolerance",
        &TOLERANCE.to_string(),
        "--iterations",
        "3",
        "--set",
        "blank.element_size=10",
        "--set",
        "output.frames=0",
        "--output",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&run.stdout);
    println!("{stdout}\n({:.1} s)", started.elapsed().as_secs_f64());
    assert_eq!(
        run.status.code(),
        Some(0),
        "{stdout}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // the history: the error falls from one forming run to the next, and the last is within
    // the tolerance, every trim point at least the margin less the tolerance inside the edge
    let history = csv_rows(&out.join("outline-history.csv"));
    assert!(!history.is_empty());
    let errors: Vec<f64> = history.iter().map(|r| r[1]).collect();
    assert!(
        errors.windows(2).all(|w| w[1] <= w[0]),
        "the error rises: {errors:?}"
    );
    let last = history.last().unwrap();
    assert!(last[1] < TOLERANCE, "not converged: {history:?}");
    assert!(last[2] >= MARGIN - TOLERANCE, "{history:?}");
    let iterations = history.len();
    assert!(stdout.contains(&format!("converged in {iterations} iterations")));

    // on the formed part itself: the flange lies flat on the die, so along the part is in
    // plan there; all round, the formed blank's edge lies the margin beyond the trim circle,
    // within the tolerance and half a millimetre for the flange's stretch and the edge's
    // chords between its nodes
    let edge = formed_edge(&out.join(format!("iteration-{iterations:02}/formed-blank.inp")));
    for degree in 0..360 {
        let r = reach(&edge, (degree as f64).to_radians());
        let beyond = r - TRIM_RADIUS;
        assert!(
            (beyond - MARGIN).abs() <= TOLERANCE + 0.5,
            "at {degree}°: the formed blank ends {beyond:.2} mm beyond the trim circle"
        );
    }

    // the flat outline: closed, smaller than the scenario's 160 mm square, larger than the
    // trim circle plus the margin (the flange draws in over the die)
    let outline = csv_rows(&out.join("outline.csv"));
    assert_eq!(outline.first(), outline.last(), "closed");
    let radii: Vec<f64> = outline.iter().map(|p| p[0].hypot(p[1])).collect();
    assert!(
        radii.iter().all(|&r| r > TRIM_RADIUS + MARGIN && r < 80.0),
        "{radii:?}"
    );
    assert_eq!(
        outline,
        csv_rows(&out.join(format!("outline-{iterations:02}.csv"))),
        "the result is the last iteration's outline"
    );
    check_dxf_with_ezdxf(&out.join("outline.dxf"), &outline);
}

/// `outline.dxf` as ezdxf reads it: one closed polyline on the layer OUTLINE, the outline's
/// vertices.
fn check_dxf_with_ezdxf(dxf: &Path, outline: &[Vec<f64>]) {
    let found = std::process::Command::new("python3")
        .arg(common::repo_path("tests/read_dxf.py"))
        .output()
        .is_ok_and(|o| o.status.success());
    if !common::reader_available(
        found,
        "blank_outline",
        "python3 with ezdxf (pip install ezdxf)",
    ) {
        return;
    }
    let text = common::run_python("tests/read_dxf.py", &[dxf], dxf.parent().unwrap());
    let summary = text.lines().next().unwrap();
    for piece in [
        "version AC1009",
        "errors 0",
        "polylines 1",
        "layer OUTLINE",
        "closed 1",
    ] {
        assert!(summary.contains(piece), "{piece} not in: {summary}");
    }
    let vertices: Vec<(f64, f64)> = text
        .lines()
        .filter_map(|l| l.strip_prefix("vertex "))
        .map(|l| {
            let (x, y) = l.split_once(' ').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    // the CSV repeats the first point to close the outline; the polyline is closed instead
    assert_eq!(vertices.len(), outline.len() - 1);
    for (v, p) in vertices.iter().zip(outline) {
        assert_eq!(*v, (p[0], p[1]));
    }
}

#[test]
fn the_first_guess_on_a_plane_is_the_trim_circle_grown_by_the_margin() {
    let (radius, margin, cell) = (55.0, 5.0, 7.0);
    let generators = Generators {
        start: (0.0, 0.0),
        warp_angle: 30.0,
    };
    let net = drape(
        &Plane {
            z0: -12.0,
            slope_x: 0.0,
            slope_y: 0.0,
        },
        &DrapeParams {
            cell,
            start: generators.start,
            warp_angle_deg: generators.warp_angle,
            max_cells: 10,
        },
    )
    .unwrap();
    let trim = trim_circle(radius, 360);
    // in plan and in space: a flat sheet maps to itself
    for (points, in_plan) in [
        (trim.points.clone(), true),
        (
            trim.points
                .iter()
                .map(|p| p + Vector3::new(0.0, 0.0, -12.0))
                .collect(),
            false,
        ),
    ] {
        let flat = flat_from_drape(&net, &generators, &points, in_plan);
        for (f, p) in flat.iter().zip(&trim.points) {
            assert!((f - p.xy()).norm() < 1e-9, "{f} for {p}");
        }
        let outline = outline_around(&flat, margin).unwrap();
        for v in &outline {
            // the mitre of a 360-gon: its vertices at R + m / cos(pi / 360)
            let expected = radius + margin / (PI / 360.0).cos();
            assert!((v.norm() - expected).abs() < 1e-9, "{}", v.norm());
        }
    }
}

#[test]
fn the_first_guess_on_a_hemisphere_unrolls_the_generators() {
    // along the generators the pin-jointed net keeps its yarns straight: a point at plan
    // distance r from the apex lies at the arc length R asin(r / R) on the flat fabric
    let (sphere, cell) = (40.0, 2.0);
    let generators = Generators {
        start: (0.0, 0.0),
        warp_angle: 0.0,
    };
    let net = drape(
        &Hemisphere { radius: sphere },
        &DrapeParams {
            cell,
            start: generators.start,
            warp_angle_deg: 0.0,
            max_cells: 40,
        },
    )
    .unwrap();
    for r in [10.0, 25.0, 35.0] {
        for t in [0.0, 0.5 * PI, PI, 1.5 * PI] {
            let p = Vector3::new(r * f64::cos(t), r * f64::sin(t), 0.0);
            let flat = flat_from_drape(&net, &generators, &[p], true)[0];
            let arc = sphere * (r / sphere).asin();
            let expected = Vector2::new(arc * t.cos(), arc * t.sin());
            assert!(
                (flat - expected).norm() < 0.05,
                "r {r} at {t}: {flat} instead of {expected}"
            );
        }
    }
    // the cell diagonal is 2.8 mm: the map holds between generators too, nowhere folding
    let ring: Vec<Vector3<f64>> = (0..72)
        .map(|k| {
            let t = TAU * k as f64 / 72.0;
            Vector3::new(30.0 * t.cos(), 30.0 * t.sin(), 0.0)
        })
        .collect();
    let flat = flat_from_drape(&net, &generators, &ring, true);
    assert!(outline_around(&flat, 5.0).is_ok());
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn bad_trim_lines_and_options_are_refused_naming_the_file_or_option() {
    let dir = scratch_dir("blank_outline", "bad-input");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let base = |trim: &str| {
        vec![
            "blank-outline".to_string(),
            "examples/hemisphere.toml".into(),
            "--trim".into(),
            trim.to_string(),
            "--margin".into(),
            "5".into(),
            "--output".into(),
            out.into(),
        ]
    };
    let missing = dir.join("missing.csv");
    let missing = missing.to_str().unwrap();
    let two = write(&dir, "two.csv", "x,y\n0,0\n10,0\n");
    let nan = write(&dir, "nan.csv", "x,y,z\n0,0,0\n10,0,0\nNaN,10,0\n");
    let crossing = write(&dir, "crossing.csv", "x,y\n0,0\n60,60\n60,0\n0,60\n");
    let open = write(
        &dir,
        "open.csv",
        "x,y\n0,0\n10,0\n20,0\n30,0\n40,0\n50,0\n60,0\n60,10\n60,20\n60,30\n60,40\n60,50\n60,60\n",
    );
    for (trim, pieces) in [
        (
            missing.to_string(),
            vec![missing, "cannot read the trim line"],
        ),
        (two.clone(), vec![two.as_str(), "2 distinct point(s)"]),
        (nan.clone(), vec![nan.as_str(), "line 4", "column 'x'"]),
        (
            crossing.clone(),
            vec![crossing.as_str(), "line 2", "crosses itself"],
        ),
        (open.clone(), vec![open.as_str(), "line 14", "open"]),
    ] {
        let args = base(&trim);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_bad_input(&args, &pieces);
    }
    // options: clap's usage errors, exit code 2, naming the option
    for (args, piece) in [
        (
            vec!["blank-outline", "examples/hemisphere.toml", "--margin", "5"],
            "--trim",
        ),
        (
            vec![
                "blank-outline",
                "examples/hemisphere.toml",
                "--trim-circle",
                "55",
                "--margin",
                "-1",
            ],
            "--margin",
        ),
        (
            vec![
                "blank-outline",
                "examples/hemisphere.toml",
                "--trim-circle",
                "0",
                "--margin",
                "5",
            ],
            "--trim-circle",
        ),
        (
            vec![
                "blank-outline",
                "examples/hemisphere.toml",
                "--trim-circle",
                "55",
                "--margin",
                "5",
                "--iterations",
                "0",
            ],
            "--iterations",
        ),
    ] {
        let run = thermostamp(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(piece), "{args:?}: {stderr}");
    }
}

#[test]
fn the_help_points_to_the_guide_and_says_every_default() {
    let run = thermostamp(&["blank-outline", "--help"]);
    assert_eq!(run.status.code(), Some(0));
    let help = String::from_utf8_lossy(&run.stdout);
    for piece in [
        "docs/guide/blank-outline.md",
        "docs/guide/scenario.md",
        "[default: 6]",
        "default: a quarter",
        "default: the scenario's output.folder + /outline",
        "outline.dxf",
    ] {
        assert!(help.contains(piece), "'{piece}' not in:\n{help}");
    }
}
