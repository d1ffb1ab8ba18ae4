//! Scenarios naming mesh and tool files (issue 6), run as a user runs them: what cannot be
//! honoured is refused with exit code 2 and one line that names the file (and line) or the
//! key; the imported quarter example prints what its reader noticed.

mod common;

use common::{assert_bad_input, repo_path, scratch_dir, write_stl};
use std::path::{Path, PathBuf};

const PROCESS: &str = "[process]\ntemperature = 300.0\nstroke = 10.0\npunch_speed = 10.0\n";
const FRICTION: &str = "[process.friction]\npunch = 0.2\ndie = 0.2\nholder = 0.2\n";
const BUILT_IN_TOOLS: &str = "[tools]\nshape = \"hemisphere\"\npunch_radius = 40.0\n\
    die_opening_radius = 42.0\ndie_fillet_radius = 5.0\nresolution = 3.0\n";

/// A scenario of `blank` (the `[blank]` lines after the card), `tools` and `more` (process
/// lines, then tables), written as `name` in `dir`.
fn scenario(dir: &Path, name: &str, blank: &str, tools: &str, more: (&str, &str)) -> PathBuf {
    let card = repo_path("materials/t300-5hs-pps.toml");
    let (process, tables) = more;
    let text = format!(
        "[blank]\ncard = {card:?}\n{blank}\n{tools}\n{PROCESS}{process}\n{FRICTION}\n{tables}"
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

fn refused(path: &Path, expected: &[&str]) {
    assert_bad_input(&["run", path.to_str().unwrap()], expected);
}

/// Corners of the 200 mm square about the axis in the plane z = `z`, counter-clockwise.
fn square(z: f64) -> [[f64; 3]; 4] {
    [
        [-100.0, -100.0, z],
        [100.0, -100.0, z],
        [100.0, 100.0, z],
        [-100.0, 100.0, z],
    ]
}

/// A pyramid on the square at z = -20 with its apex at z = `apex`, faces outward.
fn pyramid(apex: f64) -> Vec<[[f64; 3]; 3]> {
    let c = square(-20.0);
    (0..4)
        .map(|k| [c[k], c[(k + 1) % 4], [0.0, 0.0, apex]])
        .collect()
}

#[test]
fn blanks_that_cannot_be_honoured_are_refused() {
    let dir = scratch_dir("forming-files", "blanks");
    let quarter = repo_path("examples/meshes/hemisphere-quarter.msh");
    let mesh = format!("mesh = {quarter:?}");
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        (
            "missing file",
            "mesh = \"nothere.msh\"".into(),
            vec!["nothere.msh", "cannot read"],
        ),
        (
            "both a file and a rectangle",
            format!("{mesh}\nwidth = 160.0"),
            vec!["blank.width is for the built-in rectangle"],
        ),
        (
            "neither",
            "ply_angle = 0.0".into(),
            vec!["blank.width is needed", "blank.mesh"],
        ),
        (
            "unknown format",
            "mesh = \"blank.stl\"".into(),
            vec!["blank.stl", "unknown mesh format"],
        ),
        (
            "unknown element set",
            format!("{mesh}\nelement_set = \"ply\""),
            vec!["blank.element_set", "no set named 'ply'", "symmetry_x"],
        ),
        (
            "zero reference direction",
            format!("{mesh}\nreference_direction = [0.0, 0.0, 0.0]"),
            vec!["blank.reference_direction"],
        ),
    ];
    for (name, blank, expected) in cases {
        let path = scenario(&dir, "blank.toml", &blank, BUILT_IN_TOOLS, ("", ""));
        println!("{name}");
        refused(&path, &expected);
    }
    // a malformed mesh names its file and line
    let broken = dir.join("broken.msh");
    std::fs::write(
        &broken,
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1\n",
    )
    .unwrap();
    let path = scenario(
        &dir,
        "broken.toml",
        "mesh = \"broken.msh\"",
        BUILT_IN_TOOLS,
        ("", ""),
    );
    refused(&path, &["broken.msh", "line"]);
    // rigid elements cannot be a blank
    let rigid = dir.join("rigid.inp");
    std::fs::write(
        &rigid,
        "*NODE\n1, 0., 0., 0.\n2, 80., 0., 0.\n3, 80., 80., 0.\n4, 0., 80., 0.\n\
         *ELEMENT, TYPE=R3D4, ELSET=TOOL\n1, 1, 2, 3, 4\n",
    )
    .unwrap();
    let path = scenario(
        &dir,
        "rigid.toml",
        "mesh = \"rigid.inp\"",
        BUILT_IN_TOOLS,
        ("", ""),
    );
    refused(&path, &["rigid.inp", "rigid element"]);
    // boundaries: unknown set, unknown axis, two sets in one table
    for (boundary, expected) in [
        (
            "node_set = \"clamp\"\nheld = [\"x\"]",
            vec!["boundary", "no set named 'clamp'"],
        ),
        (
            "node_set = \"symmetry_x\"\nheld = [\"w\"]",
            vec!["\"w\" is not an axis"],
        ),
        (
            "node_set = \"symmetry_x\"\nelement_set = \"blank\"\nheld = [\"x\"]",
            vec!["one node_set or one element_set"],
        ),
    ] {
        let more = format!("[[boundary]]\n{boundary}\n");
        let path = scenario(&dir, "boundary.toml", &mesh, BUILT_IN_TOOLS, ("", &more));
        refused(&path, &expected);
    }
}

#[test]
fn tools_that_cannot_be_honoured_are_refused() {
    let dir = scratch_dir("forming-files", "tools");
    let rectangle = "width = 160.0\nlength = 160.0\nelement_size = 10.0";
    let files = |punch: &str, die: &str| {
        format!(
            "[tools]\nshape = \"files\"\npunch = {{ file = \"{punch}\" }}\n\
             die = {{ file = \"{die}\" }}\n"
        )
    };
    let plane = square(10.0);
    write_stl(
        &dir.join("flat-die.stl"),
        &[
            [plane[0], plane[2], plane[1]],
            [plane[0], plane[3], plane[2]],
        ],
    );
    let mut incoherent = pyramid(-1.0);
    incoherent[1].swap(0, 1);
    write_stl(&dir.join("incoherent.stl"), &incoherent);
    write_stl(&dir.join("inside.stl"), &pyramid(1.0));
    let cases = [
        (
            "built-in keys with files".to_string(),
            format!("{}punch_radius = 40.0\n", files("a.stl", "b.stl")),
            vec!["tools.punch_radius is for the built-in tool shapes"],
        ),
        (
            "no die".into(),
            "[tools]\nshape = \"files\"\npunch = { file = \"a.stl\" }\n".into(),
            vec!["tools.die = { file"],
        ),
        (
            "files without shape = files".into(),
            format!("{BUILT_IN_TOOLS}punch = {{ file = \"a.stl\" }}\n"),
            vec!["tools.punch is for tool surfaces read from files"],
        ),
        (
            "missing tool file".into(),
            files("nothere.stl", "flat-die.stl"),
            vec!["nothere.stl"],
        ),
        (
            "incoherent normals".into(),
            files("incoherent.stl", "flat-die.stl"),
            vec!["incoherent.stl", "punch", "not consistently oriented"],
        ),
        (
            "punch through the blank".into(),
            files("inside.stl", "flat-die.stl"),
            vec!["the blank starts", "inside the punch", "node"],
        ),
    ];
    for (name, tools, expected) in cases {
        println!("{name}");
        let path = scenario(&dir, "tools.toml", rectangle, &tools, ("", ""));
        refused(&path, &expected);
    }
    // a holder force needs a holder
    let tools = files("flat-die.stl", "flat-die.stl");
    let force = ("blank_holder_force = 100.0\n", "");
    let path = scenario(&dir, "holder.toml", rectangle, &tools, force);
    refused(&path, &["blank_holder_force", "tools.holder"]);
}

/// The quarter example reads its mesh: one element per quadrangle of the file.
#[test]
fn the_quarter_example_reports_its_mesh() {
    let dir = scratch_dir("forming-files", "quarter");
    let out = common::thermostamp(&[
        "run",
        "examples/hemisphere-quarter.toml",
        "--set",
        "process.stroke=3",
        "--set",
        "output.frames=0",
        "--set",
        "output.history_points=3",
        "--output",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // the file's 100 quadrangles, one element each
    assert!(stderr.contains(" on 100 elements"), "{stderr}");
    assert!(!stderr.contains("split"), "{stderr}");
    assert!(dir.join("formed-blank.inp").exists());
}

/// A pre-shaped blank: the right half of a 100 mm square folded up by 70°. The warp along x
/// leaves the folded half's plane by 70°, past the 60° at which the projection is called
/// ill-conditioned: the set-up says so, naming those triangles; a reference direction along the
/// fold projects well everywhere, and nothing is said.
#[test]
fn an_ill_conditioned_fibre_projection_is_reported_before_the_run() {
    use thermostamp::forming::{FormingModel, Scenario};
    use thermostamp::mesh::{gmsh::write_msh, rectangle, DiagonalPattern};
    let dir = scratch_dir("forming-files", "folded");
    let mut mesh = rectangle(100.0, 100.0, 10, 10, DiagonalPattern::Right);
    let (sin, cos) = 70f64.to_radians().sin_cos();
    for x in &mut mesh.nodes {
        if x.x > 0.0 {
            *x = nalgebra::Vector3::new(x.x * cos, x.y, x.x * sin);
        }
    }
    write_msh(&dir.join("folded.msh"), &mesh).unwrap();
    let plane = square(60.0);
    write_stl(
        &dir.join("die.stl"),
        &[
            [plane[0], plane[2], plane[1]],
            [plane[0], plane[3], plane[2]],
        ],
    );
    write_stl(&dir.join("punch.stl"), &pyramid(-10.0));
    let tools = "[tools]\nshape = \"files\"\npunch = { file = \"punch.stl\" }\n\
                 die = { file = \"die.stl\" }\n";
    let notes = |direction: &str| {
        let blank = format!("mesh = \"folded.msh\"\nreference_direction = {direction}");
        let path = scenario(&dir, "folded.toml", &blank, tools, ("", ""));
        let scenario = Scenario::load(&path, &["process.stroke=5".into()]).unwrap();
        FormingModel::new(&scenario).unwrap().notes
    };
    let along_x = notes("[1.0, 0.0, 0.0]");
    let warning = along_x
        .iter()
        .find(|n| n.contains("out of the plane"))
        .unwrap_or_else(|| panic!("no projection warning in {along_x:?}"));
    assert!(
        warning.contains("of 100 of 200 triangles") && warning.contains("(70.0°)"),
        "{warning}"
    );
    let along_fold = notes("[0.0, 1.0, 0.0]");
    assert!(
        along_fold.iter().all(|n| !n.contains("out of the plane")),
        "{along_fold:?}"
    );
}

/// Tools from mesh files: the punch an Abaqus deck of rigid R3D3 elements (plus a shell part
/// that `element_set` leaves out), the die a Gmsh file written with its normals up, away from
/// the blank. Both are read, the die is turned to face the blank, and the notes say so.
#[test]
fn tools_from_gmsh_and_abaqus_files_are_read_and_oriented() {
    use thermostamp::forming::{FormingModel, Scenario};
    use thermostamp::mesh::{gmsh::write_msh, Cell, Mesh};
    let dir = scratch_dir("forming-files", "mesh-tools");
    let mut deck = String::from("*NODE\n");
    let base = square(-20.0);
    for (k, p) in base.iter().chain([&[0.0, 0.0, -1.0]]).enumerate() {
        deck.push_str(&format!("{}, {}, {}, {}\n", k + 1, p[0], p[1], p[2]));
    }
    deck.push_str("*ELEMENT, TYPE=R3D3, ELSET=PUNCH\n");
    for k in 0..4 {
        deck.push_str(&format!("{}, {}, {}, 5\n", k + 1, k + 1, (k + 1) % 4 + 1));
    }
    deck.push_str("*ELEMENT, TYPE=S4R, ELSET=OTHER\n9, 1, 4, 3, 2\n");
    std::fs::write(dir.join("punch.inp"), deck).unwrap();
    let plane = square(10.0);
    let die = Mesh {
        nodes: plane.iter().map(|p| nalgebra::Vector3::from(*p)).collect(),
        // one quadrangle: a tool's surface is its two triangles
        cells: vec![Cell::Quad([0, 1, 2, 3])],
        node_sets: Default::default(),
        element_sets: Default::default(),
        warp_directions: None,
    };
    write_msh(&dir.join("die.msh"), &die).unwrap();
    let tools = "[tools]\nshape = \"files\"\n\
                 punch = { file = \"punch.inp\", element_set = \"PUNCH\" }\n\
                 die = { file = \"die.msh\" }\n";
    let blank = "width = 100.0\nlength = 100.0\nelement_size = 10.0";
    let path = scenario(&dir, "mesh-tools.toml", blank, tools, ("", ""));
    let scenario = Scenario::load(&path, &["process.stroke=5".into()]).unwrap();
    let forming = FormingModel::new(&scenario).unwrap();
    let notes = forming.notes.join("\n");
    assert!(
        notes.contains("punch: 4 triangles from") && notes.contains("normals towards the blank"),
        "{notes}"
    );
    assert!(
        notes.contains("die: 2 triangles from") && notes.contains("were flipped"),
        "{notes}"
    );
    let die_tool = &forming.model.tools[forming.die_tool];
    assert!(die_tool.surface.mean_facing(&-nalgebra::Vector3::z()) > 0.99);
}
