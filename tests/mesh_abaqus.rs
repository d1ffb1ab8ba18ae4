//! Abaqus input files in and out (`thermostamp::mesh::abaqus`): round trips through the writer,
//! hand-written decks, the hemisphere blank fixture, malformed decks, and arbitrary text.

mod common;

use nalgebra::Vector3;
use proptest::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use thermostamp::mesh::abaqus::{
    parse_inp, read_inp, read_inp_with_thickness, write_inp, write_inp_to, AbaqusMesh,
    ElementOutput, MAX_FIELD,
};
use thermostamp::mesh::conformity::COORDINATE_LIMIT;
use thermostamp::mesh::{rectangle, Cell, DiagonalPattern, Mesh, MeshFileError};

/// Reads the first of `files` (path, text), the others being what it may include.
fn parse(files: &[(&str, &str)]) -> Result<AbaqusMesh, MeshFileError> {
    let map: HashMap<PathBuf, String> = files
        .iter()
        .map(|(p, t)| (PathBuf::from(p), t.to_string()))
        .collect();
    let mut read = |p: &Path| {
        map.get(p)
            .cloned()
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
    };
    parse_inp(files[0].1, Path::new(files[0].0), &mut read)
}

fn deck(text: &str) -> AbaqusMesh {
    match parse(&[("deck.inp", text)]) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    }
}

fn written(mesh: &Mesh, elements: Option<&ElementOutput>) -> String {
    let mut bytes = Vec::new();
    write_inp_to(&mut bytes, "out.inp", mesh, elements).unwrap();
    String::from_utf8(bytes).unwrap()
}

fn patterns() -> [DiagonalPattern; 4] {
    [
        DiagonalPattern::Quad,
        DiagonalPattern::Right,
        DiagonalPattern::Alternating,
        DiagonalPattern::Crossed,
    ]
}

/// A rectangle with awkward coordinates (none a short decimal), a slight dome, element sets,
/// and a node set whose name needs quotes.
fn awkward_rectangle(pattern: DiagonalPattern) -> Mesh {
    let mut mesh = rectangle(150.0, 90.0, 5, 3, pattern);
    for (k, x) in mesh.nodes.iter_mut().enumerate() {
        *x = Vector3::new(
            x.x * (1.0 + 1e-7) + 0.1,
            x.y / 3.0,
            1e-3 * (x.x * x.x + x.y * x.y) / 7.0 + k as f64 * 1e-13,
        );
    }
    let n = mesh.cells.len();
    mesh.element_sets
        .insert("half".to_string(), (0..n / 2).rev().collect());
    mesh.element_sets
        .insert("Every-Third".to_string(), (0..n).step_by(3).collect());
    let left = mesh.node_sets["left"].clone();
    mesh.node_sets.insert("clamp edge".to_string(), left);
    mesh
}

/// A warp direction per cell: in its plane, of any length, turning across the mesh.
fn warp(mesh: &Mesh) -> Vec<Vector3<f64>> {
    (0..mesh.cells.len())
        .map(|t| {
            let normal = mesh.cells[t].area_vector(&mesh.nodes).normalize();
            let angle = 0.37 * t as f64;
            let d = Vector3::new(angle.cos(), angle.sin(), 0.0) * (1.0 + t as f64);
            d - normal * normal.dot(&d)
        })
        .collect()
}

/// `back` is `x` written in at most 20 characters and read again: the same `f64` where its
/// shortest round-trip form fits (plain or scientific), else within half a unit of the 13th
/// significant digit (the fewest the writer keeps: "-1.234567890123e-300").
fn assert_read_back(back: f64, x: f64) {
    let fits = format!("{x:?}").len() <= MAX_FIELD || format!("{x:e}").len() <= MAX_FIELD;
    if fits {
        assert_eq!(back.to_bits(), x.to_bits(), "{x:?} read back as {back:?}");
    } else {
        assert!(
            (back - x).abs() <= 5e-13 * x.abs(),
            "{x:?} read back as {back:?}"
        );
    }
}

fn assert_same_mesh(read: &AbaqusMesh, mesh: &Mesh, warp: Option<&[Vector3<f64>]>) {
    let back = &read.import.mesh;
    assert_eq!(back.nodes.len(), mesh.nodes.len());
    for (p, q) in back.nodes.iter().zip(&mesh.nodes) {
        for k in 0..3 {
            assert_read_back(p[k], q[k]);
        }
    }
    assert_eq!(back.cells, mesh.cells);
    assert_eq!(back.node_sets, mesh.node_sets);
    assert_eq!(back.element_sets, mesh.element_sets);
    match (warp, &back.warp_directions) {
        (None, None) => {}
        (Some(expected), Some(got)) => {
            assert_eq!(expected.len(), got.len());
            for (e, g) in expected.iter().zip(got) {
                assert!((e.normalize() - g).norm() < 1e-15, "{e:?} -> {g:?}");
            }
        }
        (e, g) => panic!("warp directions {e:?} read back as {g:?}"),
    }
    assert!(read.import.rigid.iter().all(|r| !r));
}

#[test]
fn rectangles_of_every_pattern_round_trip_without_orientations() {
    for pattern in patterns() {
        let mesh = awkward_rectangle(pattern);
        let text = written(&mesh, None);
        assert!(!text
            .lines()
            .any(|l| l.starts_with("*ORIENTATION") || l.starts_with("*SHELL SECTION")));
        let read = deck(&text);
        assert_same_mesh(&read, &mesh, None);
        assert!(read.thickness.iter().all(Option::is_none));
    }
}

#[test]
fn rectangles_of_every_pattern_round_trip_with_the_mesh_warp_directions() {
    for pattern in patterns() {
        let mut mesh = awkward_rectangle(pattern);
        mesh.warp_directions = Some(warp(&mesh));
        let text = written(&mesh, None);
        let read = deck(&text);
        assert_same_mesh(&read, &mesh, mesh.warp_directions.as_deref());
        // no thickness known: the section's thickness is left blank
        assert!(read.thickness.iter().all(Option::is_none), "{pattern:?}");
    }
}

#[test]
fn rectangles_of_every_pattern_round_trip_with_warp_and_thickness_of_a_formed_blank() {
    for pattern in patterns() {
        let mesh = awkward_rectangle(pattern);
        // a weft 60° from the warp (a fabric sheared by 30°): the deck keeps it as the
        // orientations' second points, the warp as their 1-axes, which the reader reads back
        let turn = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), 60_f64.to_radians());
        let output = ElementOutput {
            warp: warp(&mesh),
            weft: Some(warp(&mesh).iter().map(|w| turn * w).collect()),
            thickness: (0..mesh.cells.len())
                .map(|t| 0.31 * (1.0 + 0.01 * (t as f64).sin()))
                .collect(),
        };
        let read = deck(&written(&mesh, Some(&output)));
        assert_same_mesh(&read, &mesh, Some(&output.warp));
        let thickness: Vec<f64> = read.thickness.iter().map(|t| t.unwrap()).collect();
        assert_eq!(thickness, output.thickness, "{pattern:?}");
    }
}

#[test]
fn round_trip_through_files_on_disk() {
    let folder = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_abaqus_round_trip");
    std::fs::create_dir_all(&folder).unwrap();
    let path = folder.join("blank.inp");
    let mesh = awkward_rectangle(DiagonalPattern::Crossed);
    let output = ElementOutput {
        warp: warp(&mesh),
        weft: None,
        thickness: vec![0.29; mesh.cells.len()],
    };
    write_inp(&path, &mesh, Some(&output)).unwrap();
    let read = read_inp_with_thickness(&path).unwrap();
    assert_same_mesh(&read, &mesh, Some(&output.warp));
    assert!(read.thickness.iter().all(|t| *t == Some(0.29)));
    assert_eq!(read_inp(&path).unwrap(), read.import);
}

#[test]
fn the_writer_refuses_what_abaqus_cannot_hold() {
    let mut mesh = rectangle(10.0, 10.0, 2, 2, DiagonalPattern::Right);
    let n = mesh.cells.len();
    let bad = |mesh: &Mesh, output: Option<&ElementOutput>| {
        let mut sink = Vec::new();
        write_inp_to(&mut sink, "out.inp", mesh, output)
            .unwrap_err()
            .to_string()
    };
    let e = bad(
        &mesh,
        Some(&ElementOutput {
            warp: vec![Vector3::x(); n],
            weft: None,
            thickness: vec![0.3; n - 1],
        }),
    );
    assert!(
        e.starts_with("out.inp: ") && e.contains("thicknesses"),
        "{e}"
    );
    let e = bad(
        &mesh,
        Some(&ElementOutput {
            warp: vec![Vector3::z(); n],
            weft: None,
            thickness: vec![0.3; n],
        }),
    );
    assert!(e.contains("normal to the element"), "{e}");
    let e = bad(
        &mesh,
        Some(&ElementOutput {
            warp: vec![Vector3::x(); n],
            weft: Some(vec![Vector3::new(1.0, 1e-4, 0.0); n]),
            thickness: vec![0.3; n],
        }),
    );
    assert!(
        e.contains("element 0: weft direction") && e.contains("along the warp"),
        "{e}"
    );
    let e = bad(
        &mesh,
        Some(&ElementOutput {
            warp: vec![Vector3::x(); n],
            weft: Some(vec![Vector3::y(); n - 1]),
            thickness: vec![0.3; n],
        }),
    );
    assert!(e.contains("weft directions"), "{e}");
    mesh.node_sets.insert("TOP".to_string(), vec![0]);
    let e = bad(&mesh, None);
    assert!(e.contains("differ only in case"), "{e}");
    // nothing is left on disk when the mesh cannot be written
    let path = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_abaqus_refused.inp");
    let _ = std::fs::remove_file(&path);
    assert!(write_inp(&path, &mesh, None).is_err());
    assert!(!path.exists());
}

const QUADS: &str = "\
*Heading
two quads
** labels sparse, out of order
*Node, nset=NALL
 105, 2., 1., 0.
 101, 0., 0., 0.
 102, 1., 0., 0.
 103, 2., 0., 0.
 104, 0., 1., 0.
 106, 1., 1., 0.
 200, 9., 9., 9.
*Element, type=S4R, elset=Plate
 13, 102, 103, 105, 106
 11, 101, 102,
  106, 104
*Nset, nset=Corner
 101
*Nset, nset=Bottom, generate
 101, 103, 1
*nset, NSET=EDGE
 corner, 104, Bottom
*Nset, nset=Odd, generate
 101, 105, 2
*Elset, elset=First, generate
 11, 13, 2
*Elset, elset=Second
 13
*Nset, nset=OnSecond, elset=Second
*Nset, nset=Spare
 200, 101
";

#[test]
fn s4r_quadrilaterals_with_sets_and_generate() {
    let read = deck(QUADS);
    let mesh = &read.import.mesh;
    // node 200 belongs to no element: dropped
    assert_eq!(mesh.nodes.len(), 6);
    // label 105, first in the file
    assert_eq!(mesh.nodes[0], Vector3::new(2.0, 1.0, 0.0));
    let index = |label: usize| {
        [105, 101, 102, 103, 104, 106]
            .iter()
            .position(|&l| l == label)
            .unwrap()
    };
    // element 13 (file order first), then element 11, one quadrilateral each, the corners in
    // the element's order
    let quad13 = [102, 103, 105, 106].map(index);
    let quad11 = [101, 102, 106, 104].map(index);
    assert_eq!(mesh.cells, vec![Cell::Quad(quad13), Cell::Quad(quad11)]);
    for cell in &mesh.cells {
        assert!(cell.area_vector(&mesh.nodes).z > 0.0, "orientation kept");
        assert!((cell.area(&mesh.nodes) - 1.0).abs() < 1e-15);
    }
    let set = |name: &str| mesh.node_sets[name].clone();
    assert_eq!(set("Corner"), vec![index(101)]);
    assert_eq!(set("Bottom"), [101, 102, 103].map(index));
    assert_eq!(set("EDGE"), [101, 104, 102, 103].map(index));
    assert_eq!(set("Odd"), [101, 103, 105].map(index));
    assert_eq!(set("OnSecond"), [102, 103, 105, 106].map(index));
    assert_eq!(set("NALL").len(), 6);
    assert_eq!(set("Spare"), vec![index(101)]);
    assert_eq!(mesh.element_sets["Plate"], vec![0, 1]);
    assert_eq!(mesh.element_sets["First"], vec![1, 0]);
    assert_eq!(mesh.element_sets["Second"], vec![0]);
    let notes = read.import.notes.join("\n");
    assert!(!notes.contains("split"), "{notes}");
    assert!(
        notes.contains("1 node used by no element dropped"),
        "{notes}"
    );
    assert!(
        notes.contains("node set 'Spare': 1 of its 2 nodes"),
        "{notes}"
    );
    assert!(notes.contains("*HEADING (line 1)"), "{notes}");
    assert!(read.import.mesh.warp_directions.is_none());
}

#[test]
fn quadrilaterals_of_every_shell_and_membrane_type_are_one_cell_each() {
    for kind in ["S4", "S4R", "M3D4", "M3D4R"] {
        let read = deck(&format!(
            "{NODES}5, 2, 0, 0\n6, 2, 1, 0\n*ELEMENT, TYPE={kind}, ELSET=P\n\
             7, 1, 2, 3, 4\n8, 2, 5, 6, 3\n*SHELL SECTION, ELSET=P, MATERIAL=M\n0.4\n"
        ));
        let mesh = &read.import.mesh;
        assert_eq!(
            mesh.cells,
            vec![Cell::Quad([0, 1, 2, 3]), Cell::Quad([1, 4, 5, 2])],
            "{kind}"
        );
        assert_eq!(mesh.element_sets["P"], vec![0, 1], "{kind}");
        assert_eq!(read.thickness, vec![Some(0.4); 2], "{kind}");
        assert_eq!(read.import.rigid, vec![false; 2], "{kind}");
        assert!((mesh.total_area() - 2.0).abs() < 1e-15, "{kind}");
    }
}

/// The awkward 5 x 3 quadrilaterals with cells 1, 5 and 6 cut in two triangles: runs of
/// each kind, in the order of the cells.
fn mixed_cells() -> Mesh {
    let mut mesh = awkward_rectangle(DiagonalPattern::Quad);
    mesh.cells = mesh
        .cells
        .iter()
        .enumerate()
        .flat_map(|(k, cell)| match k {
            1 | 5 | 6 => cell.triangles().into_iter().map(Cell::Triangle).collect(),
            _ => vec![*cell],
        })
        .collect();
    let n = mesh.cells.len();
    mesh.element_sets
        .insert("half".to_string(), (0..n / 2).rev().collect());
    mesh.element_sets
        .insert("Every-Third".to_string(), (0..n).step_by(3).collect());
    mesh
}

#[test]
fn triangles_and_quadrilaterals_in_one_mesh_round_trip_in_their_order() {
    let mesh = mixed_cells();
    mesh.validate().unwrap();
    let output = ElementOutput {
        warp: warp(&mesh),
        weft: None,
        thickness: (0..mesh.cells.len())
            .map(|t| 0.3 + 0.001 * t as f64)
            .collect(),
    };
    let text = written(&mesh, Some(&output));
    // a block per run: S4R (cell 0), S3 (1-2), S4R (3-5), S3 (6-9), S4R (10-17)
    let blocks: Vec<&str> = text.lines().filter(|l| l.starts_with("*ELEMENT")).collect();
    assert_eq!(
        blocks,
        [
            "*ELEMENT, TYPE=S4R",
            "*ELEMENT, TYPE=S3",
            "*ELEMENT, TYPE=S4R",
            "*ELEMENT, TYPE=S3",
            "*ELEMENT, TYPE=S4R"
        ]
    );
    let read = deck(&text);
    assert_same_mesh(&read, &mesh, Some(&output.warp));
    let thickness: Vec<f64> = read.thickness.iter().map(|t| t.unwrap()).collect();
    assert_eq!(thickness, output.thickness);
}

#[test]
fn nested_includes_relative_to_the_including_file() {
    let read = parse(&[
        (
            "model/main.inp",
            "*HEADING\n*INCLUDE, INPUT=mesh/nodes.inp\n*ELEMENT, TYPE=S3, ELSET=ALL\n1, 1, 2, 3\n2, 1, 3, 4\n",
        ),
        (
            "model/mesh/nodes.inp",
            "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n*INCLUDE, INPUT=more/top.inp\n",
        ),
        ("model/mesh/more/top.inp", "** the top nodes\n3, 1, 1, 0\n4, 0, 1, 0\n"),
    ])
    .unwrap();
    assert_eq!(read.import.mesh.nodes.len(), 4);
    let two = vec![Cell::Triangle([0, 1, 2]), Cell::Triangle([0, 2, 3])];
    assert_eq!(read.import.mesh.cells, two);

    // the same on disk, through read_inp
    let folder = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_abaqus_includes");
    std::fs::create_dir_all(folder.join("mesh/more")).unwrap();
    std::fs::write(
        folder.join("main.inp"),
        "*INCLUDE, INPUT=mesh/nodes.inp\n*ELEMENT, TYPE=S3, ELSET=ALL\n1, 1, 2, 3\n2, 1, 3, 4\n",
    )
    .unwrap();
    std::fs::write(
        folder.join("mesh/nodes.inp"),
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n*INCLUDE, INPUT=more/top.inp\n",
    )
    .unwrap();
    std::fs::write(folder.join("mesh/more/top.inp"), "3, 1, 1, 0\n4, 0, 1, 0\n").unwrap();
    let on_disk = read_inp(&folder.join("main.inp")).unwrap();
    assert_eq!(on_disk.mesh.cells, two);

    // INPUT= on *ELEMENT (and *NODE, *NSET, *ELSET, *DISTRIBUTION): data lines from a file
    let read = parse(&[
        (
            "m/main.inp",
            "*NODE, INPUT=n.inp
*ELEMENT, TYPE=S3, ELSET=E, INPUT=sub/e.inp
*NSET, NSET=A
4
",
        ),
        (
            "m/n.inp",
            "1, 0, 0, 0
2, 1, 0, 0
3, 1, 1, 0
4, 0, 1, 0
",
        ),
        (
            "m/sub/e.inp",
            "1, 1, 2, 3
2, 1, 3, 4
",
        ),
    ])
    .unwrap();
    assert_eq!(read.import.mesh.cells, two);
    assert_eq!(read.import.mesh.node_sets["A"], vec![3]);
    let e = parse(&[
        (
            "m/main.inp",
            "*NODE, INPUT=n.inp
",
        ),
        (
            "m/n.inp",
            "1, 0, 0, 0
*ELEMENT, TYPE=S3
",
        ),
    ])
    .unwrap_err();
    assert_eq!((e.file.as_str(), e.line), ("m/n.inp", Some(2)), "{e}");
}

const ORIENTED: &str = "\
*NODE
1, 0, 0, 0
2, 1, 0, 0
3, 2, 0, 0
4, 0, 1, 0
5, 1, 1, 0
6, 2, 1, 0
*ELEMENT, TYPE=S4R, ELSET=PLY
1, 1, 2, 5, 4
*ELEMENT, TYPE=M3D3, ELSET=SKIN
2, 2, 3, 6
*ELEMENT, TYPE=S3, ELSET=BARE
3, 2, 6, 5
** a 1-axis along global x, b in the x-y plane, then 30 degrees about the normal (axis 3)
*ORIENTATION, NAME=Ply-30, SYSTEM=RECTANGULAR
1., 0., 0., 0., 1., 0.
3, 30.
*Orientation, name=diagonal
6., 6., 1., 4., 6., 1., 5., 5., 1.
*SHELL SECTION, ELSET=PLY, MATERIAL=PREPREG, ORIENTATION=PLY-30
0.31, 5
*MEMBRANE SECTION, ELSET=skin, MATERIAL=PREPREG, ORIENTATION=Diagonal
0.5
";

#[test]
fn orientations_through_sections_give_the_warp_directions() {
    let read = deck(ORIENTED);
    // one warp direction per element: the quadrilateral, then the two triangles
    let warp = read.import.mesh.warp_directions.clone().unwrap();
    assert_eq!(warp.len(), 3);
    assert!(read.import.mesh.cells[0].is_quad());
    let ply = Vector3::new(30f64.to_radians().cos(), 30f64.to_radians().sin(), 0.0);
    assert!((warp[0] - ply).norm() < 1e-15, "{warp:?}");
    let diagonal = Vector3::new(1.0, 1.0, 0.0).normalize();
    assert!((warp[1] - diagonal).norm() < 1e-15, "{warp:?}");
    // no section: the global x axis, with a note
    assert_eq!(warp[2], Vector3::x());
    let notes = read.import.notes.join("\n");
    assert!(
        notes.contains("1 of 3 shell and membrane elements have no orientation (elements 3)"),
        "{notes}"
    );
    assert_eq!(read.thickness, vec![Some(0.31), Some(0.5), None]);
}

#[test]
fn rigid_elements_are_flagged() {
    let read = deck(
        "*NODE\n1,0,0,0\n2,1,0,0\n3,1,1,0\n4,0,1,0\n5,0,0,-1\n6,1,0,-1\n7,1,1,-1\n8,0,1,-1\n\
         *ELEMENT, TYPE=S3\n1, 1, 2, 3\n2, 1, 3, 4\n\
         *ELEMENT, TYPE=R3D4, ELSET=TOOL\n10, 5, 6, 7, 8\n\
         *ELEMENT, TYPE=R3D3, ELSET=TOOL\n11, 5, 7, 8\n\
         *RIGID BODY, REF NODE=5, ELSET=TOOL\n",
    );
    assert_eq!(read.import.rigid, vec![false, false, true, true]);
    assert_eq!(read.import.mesh.element_sets["TOOL"], vec![2, 3]);
    assert_eq!(read.import.mesh.cells[2], Cell::Quad([4, 5, 6, 7]));
    let notes = read.import.notes.join("\n");
    assert!(notes.contains("2 rigid elements"), "{notes}");
    assert!(notes.contains("*RIGID BODY (line 17)"), "{notes}");
}

#[test]
fn keywords_of_the_model_that_are_not_the_mesh_are_listed_in_the_notes() {
    let read = parse(&[
        (
            "job.inp",
            "*Heading\nA job\n*Preprint, echo=NO\n*NODE\n1,0,0,0\n2,1,0,0\n3,0,1,0\n\
             *ELEMENT, TYPE=S3, ELSET=E\n1,1,2,3\n*INCLUDE, INPUT=material.inp\n\
             *Step, name=Form\n*Static\n1., 1.\n*Boundary\n1, 1, 6\n*End Step\n",
        ),
        (
            "material.inp",
            "*Material, name=PPS\n*Elastic\n1000., 0.3\n*Material, name=Steel\n*Elastic\n210000., 0.3\n",
        ),
    ])
    .unwrap();
    let notes = read.import.notes.join("\n");
    for expected in [
        "*HEADING (line 1)",
        "*PREPRINT (line 3)",
        "*MATERIAL (material.inp line 1, material.inp line 4)",
        "*ELASTIC (material.inp line 2, material.inp line 5)",
        "*STEP (line 11)",
        "*STATIC (line 12)",
        "*BOUNDARY (line 14)",
        "*END STEP (line 16)",
    ] {
        assert!(notes.contains(expected), "{expected} not in {notes}");
    }
}

#[test]
fn a_single_part_with_its_instance_is_read() {
    let path = common::repo_path("tests/data/meshes/hemisphere-blank-s4r.inp");
    let read = read_inp_with_thickness(&path).unwrap();
    let mesh = &read.import.mesh;
    assert_eq!(mesh.nodes.len(), 441);
    assert_eq!(mesh.cells.len(), 400);
    let area: f64 = (0..mesh.cells.len()).map(|t| mesh.area(t)).sum();
    assert!((area - 160.0 * 160.0).abs() < 1e-9, "{area}");
    for cell in &mesh.cells {
        assert!(cell.is_quad() && cell.area_vector(&mesh.nodes).z > 0.0);
        assert!((cell.area(&mesh.nodes) - 64.0).abs() < 1e-9);
    }
    let edge = |name: &str, coordinate: usize, value: f64| {
        let set = &mesh.node_sets[name];
        assert_eq!(set.len(), 21, "{name}");
        assert!(
            set.iter().all(|&n| mesh.nodes[n][coordinate] == value),
            "{name}"
        );
    };
    edge("BOTTOM", 1, -80.0);
    edge("TOP", 1, 80.0);
    edge("LEFT", 0, -80.0);
    edge("RIGHT", 0, 80.0);
    assert_eq!(mesh.node_sets["EDGES"].len(), 80);
    assert_eq!(mesh.node_sets["CORNERS"].len(), 4);
    assert_eq!(mesh.element_sets["BLANK"].len(), 400);
    assert_eq!(read.thickness.len(), 400);
    assert!(mesh
        .warp_directions
        .as_ref()
        .unwrap()
        .iter()
        .all(|w| *w == Vector3::x()));
    assert!(read.thickness.iter().all(|t| *t == Some(0.31)));
    let notes = read.import.notes.join("\n");
    assert!(
        notes.contains("part 'Blank' read (instance 'Blank-1')"),
        "{notes}"
    );
    assert!(notes.contains("*MATERIAL"), "{notes}");
    mesh.validate().unwrap();
}

/// (what, deck files, file and line of the error, words of its message)
type Case<'a> = (
    &'a str,
    Vec<(&'a str, &'a str)>,
    (&'a str, Option<usize>),
    &'a [&'a str],
);

const NODES: &str = "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n";

#[test]
fn malformed_decks_fail_naming_the_file_and_line() {
    let with_nodes = |rest: &str| format!("{NODES}{rest}");
    let texts: Vec<String> = vec![
        with_nodes("*ELEMENT, TYPE=C3D8\n1, 1, 2, 3, 4, 1, 2, 3, 4\n"),
        with_nodes("*ELEMENT, ELSET=E\n1, 1, 2, 3\n"),
        "*NODE\n1, 0.0, abc, 0\n".to_string(),
        with_nodes("*ELEMENT, TYPE=S4R\n1, 1, 2, 3\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 9\n"),
        "*NODE\n1, 0, 0, 0\n2, 1, 0, 0\n1, 1, 1, 0\n".to_string(),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n1, 1, 3, 4\n"),
        with_nodes("*INCLUDE, INPUT=missing.inp\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*NSET, NSET=N, GENERATE\n1, 4, 0\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*ORIENTATION, NAME=O\n1, 1, 0, 2, 2, 0\n"),
        with_nodes("*ORIENTATION, NAME=O, SYSTEM=CYLINDRICAL\n0, 0, 0, 0, 0, 1\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*NSET, NSET=N\n1, 7\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*ELSET, ELSET=E\n1, LATER\n*ELSET, ELSET=LATER\n1\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*ORIENTATION, NAME=O\n1, 0, 0, 0, 1, 0\n1, 30.\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n7, 1, 2, 2\n"),
        "*PART, NAME=A\n*END PART\n*PART, NAME=B\n*END PART\n".to_string(),
        format!("*PART, NAME=A\n{NODES}*ELEMENT, TYPE=S3\n1,1,2,3\n*END PART\n*ASSEMBLY, NAME=X\n*INSTANCE, NAME=A-1, PART=A\n10., 0., 0.\n*END INSTANCE\n*END ASSEMBLY\n"),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*SHELL SECTION, ELSET=NOPE, MATERIAL=M\n0.3\n"),
        "1, 0, 0, 0\n*NODE\n".to_string(),
        "*NODE\n-3, 0, 0, 0\n".to_string(),
        with_nodes("*ELEMENT, TYPE=S3\n1, 1, 2, 3\n*NSET, NSET=HUGE, GENERATE\n1, 1000000000000000000, 1\n"),
        with_nodes("*ELEMENT, TYPE=S3, ELSET=ALL\n1, 1, 2, 3\n*SHELL SECTION, ELSET=ALL, MATERIAL=M, ORIENTATION=NONE\n0.3\n"),
        with_nodes("*ELEMENT, TYPE=S3, ELSET=ALL\n1, 1, 2, 3\n*SHELL SECTION, ELSET=ALL, MATERIAL=M\n-0.3\n"),
        with_nodes("*ELEMENT, TYPE=S3, ELSET=ALL\n1, 1, 2, 3\n*SHELL SECTION, ELSET=ALL, MATERIAL=M, SHELL THICKNESS=T\n\n*DISTRIBUTION, NAME=T, LOCATION=ELEMENT, TABLE=TT\n, 0.3\n"),
        "*NODE\n1, 0, 0, 0\n2, 1e400, 0, 0\n".to_string(),
        "*NODE\n".to_string(),
        with_nodes("5, 0.2, 0.2, 0\n*ELEMENT, TYPE=S4R\n3, 1, 2, 5, 4\n"),
        with_nodes("*ELEMENT, TYPE=M3D4\n3, 1, 2, 4, 3\n"),
    ];
    let cases: Vec<Case> = vec![
        (
            "unknown element type",
            vec![("d.inp", &texts[0])],
            ("d.inp", Some(6)),
            &["C3D8", "S4R", "R3D4"],
        ),
        (
            "missing TYPE",
            vec![("d.inp", &texts[1])],
            ("d.inp", Some(6)),
            &["TYPE="],
        ),
        (
            "bad number",
            vec![("d.inp", &texts[2])],
            ("d.inp", Some(2)),
            &["'abc'", "node 1"],
        ),
        (
            "too few nodes",
            vec![("d.inp", &texts[3])],
            ("d.inp", Some(7)),
            &["element 1", "S4R has 4 nodes", "gives 3"],
        ),
        (
            "unknown node",
            vec![("d.inp", &texts[4])],
            ("d.inp", Some(7)),
            &["node 9", "not defined"],
        ),
        (
            "duplicate node",
            vec![("d.inp", &texts[5])],
            ("d.inp", Some(4)),
            &["node 1", "twice", "line 2"],
        ),
        (
            "duplicate element",
            vec![("d.inp", &texts[6])],
            ("d.inp", Some(8)),
            &["element 1", "twice", "line 7"],
        ),
        (
            "include not found",
            vec![("dir/d.inp", &texts[7])],
            ("dir/d.inp", Some(6)),
            &["missing.inp", "dir/missing.inp"],
        ),
        (
            "include cycle",
            vec![
                ("d.inp", "*INCLUDE, INPUT=a.inp\n"),
                ("a.inp", "** a\n*INCLUDE, INPUT=b.inp\n"),
                ("b.inp", "*INCLUDE, INPUT=a.inp\n"),
            ],
            ("b.inp", Some(1)),
            &["cycle", "a.inp includes b.inp includes a.inp"],
        ),
        (
            "GENERATE step 0",
            vec![("d.inp", &texts[8])],
            ("d.inp", Some(9)),
            &["step 0"],
        ),
        (
            "collinear orientation",
            vec![("d.inp", &texts[9])],
            ("d.inp", Some(9)),
            &["collinear"],
        ),
        (
            "cylindrical system",
            vec![("d.inp", &texts[10])],
            ("d.inp", Some(6)),
            &["CYLINDRICAL", "RECTANGULAR"],
        ),
        (
            "unknown set member",
            vec![("d.inp", &texts[11])],
            ("d.inp", Some(9)),
            &["node set 'N'", "node 7"],
        ),
        (
            "set used before its definition",
            vec![("d.inp", &texts[12])],
            ("d.inp", Some(9)),
            &["'LATER'", "defined before"],
        ),
        (
            "rotation about axis 1",
            vec![("d.inp", &texts[13])],
            ("d.inp", Some(10)),
            &["axis 1", "axis 3"],
        ),
        (
            "element on one node twice",
            vec![("d.inp", &texts[14])],
            ("d.inp", Some(8)),
            &["element 7", "names node 2 twice"],
        ),
        (
            "several parts",
            vec![("d.inp", &texts[15])],
            ("d.inp", Some(3)),
            &["second *PART", "single part"],
        ),
        (
            "instance transform",
            vec![("d.inp", &texts[16])],
            ("d.inp", Some(12)),
            &["transform"],
        ),
        (
            "section of an unknown set",
            vec![("d.inp", &texts[17])],
            ("d.inp", Some(8)),
            &["'NOPE'"],
        ),
        (
            "data before any keyword",
            vec![("d.inp", &texts[18])],
            ("d.inp", Some(1)),
            &["before any keyword"],
        ),
        (
            "negative label",
            vec![("d.inp", &texts[19])],
            ("d.inp", Some(2)),
            &["'-3'", "positive"],
        ),
        (
            "huge GENERATE",
            vec![("d.inp", &texts[20])],
            ("d.inp", Some(9)),
            &["node set 'HUGE'", "node 5 is not defined"],
        ),
        (
            "unknown orientation",
            vec![("d.inp", &texts[21])],
            ("d.inp", Some(8)),
            &["'NONE'"],
        ),
        (
            "negative thickness",
            vec![("d.inp", &texts[22])],
            ("d.inp", Some(9)),
            &["thickness -0.3"],
        ),
        (
            "distribution without table",
            vec![("d.inp", &texts[23])],
            ("d.inp", Some(10)),
            &["table 'TT'"],
        ),
        (
            "overflowing number",
            vec![("d.inp", &texts[24])],
            ("d.inp", Some(3)),
            &["1e400"],
        ),
        (
            "no elements",
            vec![("d.inp", &texts[25])],
            ("d.inp", None),
            &["no elements"],
        ),
        (
            "re-entrant quadrilateral",
            vec![("d.inp", &texts[26])],
            ("d.inp", Some(8)),
            &["element 3", "quadrilateral that is not convex"],
        ),
        (
            "crossed quadrilateral (its diagonals parallel)",
            vec![("d.inp", &texts[27])],
            ("d.inp", Some(7)),
            &["element 3", "degenerate"],
        ),
        (
            "error inside an included file",
            vec![
                ("d.inp", "*INCLUDE, INPUT=inc/mesh.inp\n"),
                (
                    "inc/mesh.inp",
                    "*NODE\n1, 0, 0\n*ELEMENT, TYPE=S3\n1, 1, 1\n",
                ),
            ],
            ("inc/mesh.inp", Some(4)),
            &["element 1", "S3 has 3 nodes", "gives 2"],
        ),
    ];
    let mut failures = Vec::new();
    for (what, files, (file, line), words) in cases {
        match parse(&files) {
            Ok(m) => failures.push(format!("{what}: read {} cells", m.import.mesh.cells.len())),
            Err(e) => {
                if (e.file.as_str(), e.line) != (file, line)
                    || !words.iter().all(|w| e.message.contains(w))
                {
                    failures.push(format!(
                        "{what}: expected {file} {line:?} {words:?}, got '{e}'"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn an_included_file_is_named_by_its_path_in_errors_and_found_relative_to_the_includer() {
    let e = parse(&[
        (
            "a/main.inp",
            "*HEADING\n*INCLUDE, INPUT=\"b/part one.inp\"\n",
        ),
        (
            "a/b/part one.inp",
            "*NODE\n1, 0, 0, 0\n*NSET, NSET=N, GENERATE\n1, 2\n3, 4, 5, 6\n",
        ),
    ])
    .unwrap_err();
    assert_eq!(
        (e.file.as_str(), e.line),
        ("a/b/part one.inp", Some(5)),
        "{e}"
    );
    assert!(
        e.to_string()
            .starts_with("a/b/part one.inp: line 5: GENERATE"),
        "{e}"
    );
}

/// Element sets in the deck in any order of keywords; the result does not depend on
/// node labels, only on file order.
#[test]
fn labels_are_renumbered_in_file_order() {
    let read =
        deck("*NODE\n30, 0, 0, 0\n10, 1, 0, 0\n20, 1, 1, 0\n*ELEMENT, TYPE=S3\n99, 30, 10, 20\n");
    assert_eq!(
        read.import.mesh.nodes,
        vec![Vector3::zeros(), Vector3::x(), Vector3::new(1.0, 1.0, 0.0)]
    );
    assert_eq!(read.import.mesh.cells, vec![Cell::Triangle([0, 1, 2])]);
    assert_eq!(read.import.mesh.node_sets, BTreeMap::new());
}

/// A deck with most of what the reader reads: the writer's output (distributions, an
/// orientation, a section), sparse labels, quadrilaterals, sets, GENERATE, an include, a
/// rotated orientation and a section.
fn valid_deck() -> String {
    let mesh = rectangle(20.0, 10.0, 2, 2, DiagonalPattern::Alternating);
    let output = ElementOutput {
        warp: warp(&mesh),
        weft: None,
        thickness: vec![0.3; mesh.cells.len()],
    };
    format!(
        "{}{QUADS}*INCLUDE, INPUT=self.inp\n*ORIENTATION, NAME=P\n1, 0, 0, 0, 1, 0\n3, 30\n\
         *SHELL SECTION, ELSET=Plate, MATERIAL=M, ORIENTATION=P\n0.3, 5\n",
        written(&mesh, Some(&output))
    )
}

/// A finite float of any sign and magnitude from 1e-300 to 1e150 (squares stay finite, so
/// that areas are), with up to 17 significant digits, or zero.
fn any_magnitude() -> impl Strategy<Value = f64> {
    prop_oneof![
        1 => Just(0.0),
        9 => (-9.999_999_999_999_999f64..9.999_999_999_999_999, -300i32..150)
            .prop_map(|(m, e)| m * 10f64.powi(e)),
    ]
}

const SELF: &str = "*NODE\n1000, 0, 0, 0\n";

#[test]
fn the_deck_that_the_property_test_mutates_is_valid() {
    let read = parse(&[("d.inp", &valid_deck()), ("self.inp", SELF)]).unwrap();
    assert_eq!(read.import.mesh.cells.len(), 8 + 2);
    assert!(read.thickness.iter().all(|t| *t == Some(0.3)));
}

const TOKENS: [&str; 16] = [
    ",",
    "\n",
    "*",
    "**",
    "=",
    "\"",
    "GENERATE",
    "*NSET, NSET=X, GENERATE\n1, 18446744073709551615, 1\n",
    "*INCLUDE, INPUT=self.inp\n",
    "-1",
    "1e400",
    "0",
    "*ELEMENT, TYPE=S4R\n",
    "*ORIENTATION, NAME=Q\nQ\n3, 9\n",
    "*PART\n",
    "*INSTANCE, NAME=A, PART=\n",
];

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Any coordinates, warp directions and thicknesses: every numeric field of the deck has at
    /// most 20 characters, no data line more than 16 entries, no line more than 256
    /// characters (the Abaqus input rules, which CalculiX shares), and the deck reads back
    /// within the precision written — or, with a coordinate beyond the readers' limit, is
    /// refused naming the node.
    #[test]
    fn every_field_of_a_written_deck_fits_abaqus_and_reads_back(
        scale in any_magnitude(),
        jitter in prop::collection::vec(-0.2f64..0.2, 12),
        warp in prop::collection::vec(any_magnitude(), 6),
        thickness in prop::collection::vec(any_magnitude(), 2),
        quad in any::<bool>(),
    ) {
        // a unit square of two triangles or one quadrilateral, its corners moved by up to 0.2
        // in x, y and z (so that no cell degenerates), at any scale
        let pattern = if quad { DiagonalPattern::Quad } else { DiagonalPattern::Right };
        let mut mesh = rectangle(1.0, 1.0, 1, 1, pattern);
        let cells = mesh.cells.len();
        for (n, x) in mesh.nodes.iter_mut().enumerate() {
            *x = (*x + Vector3::from_column_slice(&jitter[3 * n..3 * n + 3])) * scale;
        }
        prop_assume!(mesh.validate().is_ok());
        let output = ElementOutput {
            warp: warp.chunks(3).take(cells).map(Vector3::from_column_slice).collect(),
            weft: None,
            thickness: thickness.iter().take(cells).map(|t| t.abs()).collect(),
        };
        let mut bytes = Vec::new();
        prop_assume!(write_inp_to(&mut bytes, "out.inp", &mesh, Some(&output)).is_ok());
        let text = String::from_utf8(bytes).unwrap();
        for line in text.lines() {
            prop_assert!(line.len() <= 256, "{line}");
            if line.starts_with('*') {
                continue;
            }
            let fields: Vec<&str> = line.split(',').map(str::trim).collect();
            prop_assert!(fields.len() <= 16, "{line}");
            for field in fields.iter().filter(|f| f.parse::<f64>().is_ok()) {
                prop_assert!(field.len() <= MAX_FIELD, "{field} in {line}");
            }
        }
        if mesh.nodes.iter().any(|x| x.amax() > COORDINATE_LIMIT) {
            let e = parse(&[("deck.inp", &text)]).unwrap_err();
            prop_assert!(e.message.contains("beyond 1e6 mm of the origin"), "{e}");
            return Ok(());
        }
        let read = deck(&text);
        prop_assert_eq!(&read.import.mesh.cells, &mesh.cells);
        for (p, q) in read.import.mesh.nodes.iter().zip(&mesh.nodes) {
            for k in 0..3 {
                assert_read_back(p[k], q[k]);
            }
        }
        for (back, t) in read.thickness.iter().zip(&output.thickness) {
            assert_read_back(back.unwrap(), *t);
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let text = String::from_utf8_lossy(&bytes);
        let _ = parse(&[("d.inp", &text), ("self.inp", &text)]);
    }

    #[test]
    fn keyword_soup_never_panics(parts in prop::collection::vec(
        prop_oneof![
            prop::sample::select(TOKENS.to_vec()).prop_map(str::to_string),
            "[ -~]{0,12}",
            prop::sample::select(vec!["1", "2", "3", "4", "5", "6"]).prop_map(str::to_string),
        ],
        0..120,
    )) {
        let text = format!("*NODE\n{}", parts.concat());
        let _ = parse(&[("d.inp", &text), ("self.inp", &text)]);
    }

    #[test]
    fn mutations_of_a_valid_deck_never_panic(
        edits in prop::collection::vec((any::<prop::sample::Index>(), 0..40usize, prop::sample::select(TOKENS.to_vec())), 1..6),
    ) {
        let mut text = valid_deck();
        for (at, remove, insert) in edits {
            let mut start = at.index(text.len() + 1);
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let mut end = (start + remove).min(text.len());
            while !text.is_char_boundary(end) {
                end -= 1;
            }
            text.replace_range(start..end, insert);
        }
        let _ = parse(&[("d.inp", &text), ("self.inp", SELF)]);
    }
}
