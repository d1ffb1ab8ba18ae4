//! Blank meshes that are not one sheet (docs/meshes.md, "Checked at load"): hanging nodes,
//! T-junctions, unmerged seams, duplicate, overlapping, folded and inverted elements, slivers,
//! specks, elements on one node twice or with collinear corners, nodes at 1e200 or NaN,
//! non-manifold edges, pinch points and a Möbius band — each written as a Gmsh file and as an
//! Abaqus deck, and each refused before the first step with exit code 2 and one line naming
//! the file, the line and the file's label of the node or element. And every mesh shipped, and
//! one that Gmsh made unstructured around a hole, passes.

mod common;

use common::adversarial::{assert_all_pass, check, Case, Fixtures};
use common::repo_path;
use std::collections::HashMap;
use std::path::Path;
use thermostamp::mesh::read_mesh_file;

/// A mesh to write: nodes (label, position) and elements (label, corner labels: 3 or 4).
struct Sheet {
    nodes: Vec<(u64, [f64; 3])>,
    elements: Vec<(u64, Vec<u64>)>,
}

/// A written file and the line of each node (its coordinates) and element.
struct Written {
    text: String,
    node_line: HashMap<u64, usize>,
    element_line: HashMap<u64, usize>,
}

/// Appends `line` to `text` and gives its number.
fn push(text: &mut String, line: &str) -> usize {
    text.push_str(line);
    text.push('\n');
    text.lines().count()
}

impl Sheet {
    /// Nodes labelled from 101 up, elements from 11 up (so that no label is an index).
    fn new(xyz: &[[f64; 3]], elements: &[&[usize]]) -> Self {
        Self {
            nodes: xyz
                .iter()
                .enumerate()
                .map(|(i, &x)| (101 + i as u64, x))
                .collect(),
            elements: elements
                .iter()
                .enumerate()
                .map(|(e, corners)| {
                    (
                        11 + e as u64,
                        corners.iter().map(|&i| 101 + i as u64).collect(),
                    )
                })
                .collect(),
        }
    }

    /// In the plane z = 0.
    fn flat(xy: &[[f64; 2]], elements: &[&[usize]]) -> Self {
        let xyz: Vec<[f64; 3]> = xy.iter().map(|p| [p[0], p[1], 0.0]).collect();
        Self::new(&xyz, elements)
    }

    /// Gmsh MSH 4.1 ASCII: one node block, one element block per element.
    fn msh(&self) -> Written {
        let mut text = String::new();
        for line in ["$MeshFormat", "4.1 0 8", "$EndMeshFormat", "$Nodes"] {
            push(&mut text, line);
        }
        let (n, first, last) = (
            self.nodes.len(),
            self.nodes[0].0,
            self.nodes[self.nodes.len() - 1].0,
        );
        push(&mut text, &format!("1 {n} {first} {last}"));
        push(&mut text, &format!("2 1 0 {n}"));
        for (label, _) in &self.nodes {
            push(&mut text, &label.to_string());
        }
        let mut node_line = HashMap::new();
        for (label, [x, y, z]) in &self.nodes {
            node_line.insert(*label, push(&mut text, &format!("{x:?} {y:?} {z:?}")));
        }
        push(&mut text, "$EndNodes");
        push(&mut text, "$Elements");
        let m = self.elements.len();
        let (first, last) = (self.elements[0].0, self.elements[m - 1].0);
        push(&mut text, &format!("{m} {m} {first} {last}"));
        let mut element_line = HashMap::new();
        for (label, corners) in &self.elements {
            let kind = if corners.len() == 3 { 2 } else { 3 };
            push(&mut text, &format!("2 1 {kind} 1"));
            let corners: Vec<String> = corners.iter().map(u64::to_string).collect();
            let line = push(&mut text, &format!("{label} {}", corners.join(" ")));
            element_line.insert(*label, line);
        }
        push(&mut text, "$EndElements");
        Written {
            text,
            node_line,
            element_line,
        }
    }

    /// Abaqus: S3 and S4R elements, each under its own *ELEMENT line.
    fn inp(&self) -> Written {
        let mut text = String::new();
        push(&mut text, "*NODE");
        let mut node_line = HashMap::new();
        for (label, [x, y, z]) in &self.nodes {
            let line = push(&mut text, &format!("{label}, {x:?}, {y:?}, {z:?}"));
            node_line.insert(*label, line);
        }
        let mut element_line = HashMap::new();
        for (label, corners) in &self.elements {
            let kind = if corners.len() == 3 { "S3" } else { "S4R" };
            push(&mut text, &format!("*ELEMENT, TYPE={kind}"));
            let corners: Vec<String> = corners.iter().map(u64::to_string).collect();
            let line = push(&mut text, &format!("{label}, {}", corners.join(", ")));
            element_line.insert(*label, line);
        }
        Written {
            text,
            node_line,
            element_line,
        }
    }
}

/// What a message must be placed at: a node's or an element's label.
#[derive(Clone, Copy)]
enum Subject {
    Node(u64),
    Element(u64),
}

/// Two squares of 10 mm side by side, on the edge from node 102 to node 105.
fn two_squares() -> Vec<[f64; 2]> {
    vec![
        [0.0, 0.0],
        [10.0, 0.0],
        [20.0, 0.0],
        [0.0, 10.0],
        [10.0, 10.0],
        [20.0, 10.0],
    ]
}

/// A square, and on its right two half-height squares whose shared node 107 lies on the
/// square's right edge.
fn hanging() -> Sheet {
    Sheet::flat(
        &[
            [0.0, 0.0],
            [10.0, 0.0],
            [10.0, 10.0],
            [0.0, 10.0],
            [20.0, 0.0],
            [20.0, 5.0],
            [10.0, 5.0],
            [20.0, 10.0],
        ],
        &[&[0, 1, 2, 3], &[1, 4, 5, 6], &[6, 5, 7, 2]],
    )
}

/// A bar of three squares along x, and a stem below butting into the middle square's lower
/// edge: its upper corners 111 and 112 lie on that edge.
fn t_junction() -> Sheet {
    let mut xy: Vec<[f64; 2]> = (0..8)
        .map(|n| [(n % 4) as f64 * 10.0, 10.0 + (n / 4) as f64 * 10.0])
        .collect();
    xy.extend([[12.0, 0.0], [18.0, 0.0], [12.0, 10.0], [18.0, 10.0]]);
    Sheet::flat(
        &xy,
        &[&[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[8, 9, 11, 10]],
    )
}

/// The two squares, the right one on its own copies (107, 108) of the nodes 102 and 105.
fn unmerged_seam() -> Sheet {
    let mut xy = two_squares();
    xy.extend([[10.0, 0.0], [10.0, 10.0]]);
    Sheet::flat(&xy, &[&[0, 1, 4, 3], &[6, 2, 5, 7]])
}

/// A fan of six triangles around node 101, which is moved out across the edge 102-103: the
/// triangle on that edge turns over.
fn inverted_fan() -> Sheet {
    let mut xy = vec![[9.0, 6.0]];
    xy.extend((0..6).map(|k| {
        let a = k as f64 * std::f64::consts::FRAC_PI_3;
        [10.0 * a.cos(), 10.0 * a.sin()]
    }));
    let fan: Vec<Vec<usize>> = (0..6).map(|k| vec![0, 1 + k, 1 + (k + 1) % 6]).collect();
    let refs: Vec<&[usize]> = fan.iter().map(Vec::as_slice).collect();
    Sheet::flat(&xy, &refs)
}

/// A band of 24 quadrilaterals round a loop of radius 100 mm, given a half twist.
fn moebius() -> Sheet {
    let n = 24;
    let mut xyz = Vec::new();
    for i in 0..n {
        let u = std::f64::consts::TAU * i as f64 / n as f64;
        for v in [-20.0, 20.0] {
            let r = 100.0 + v * (u / 2.0).cos();
            xyz.push([r * u.cos(), r * u.sin(), v * (u / 2.0).sin()]);
        }
    }
    let mut quads: Vec<Vec<usize>> = (0..n - 1)
        .map(|i| vec![2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1])
        .collect();
    quads.push(vec![2 * n - 2, 1, 0, 2 * n - 1]);
    let refs: Vec<&[usize]> = quads.iter().map(Vec::as_slice).collect();
    Sheet::new(&xyz, &refs)
}

/// The cases: name, mesh, the node or element the message is placed at, and what it says.
fn defects() -> Vec<(&'static str, Sheet, Subject, &'static str)> {
    let squares = |cells: &[&[usize]]| Sheet::flat(&two_squares(), cells);
    let mut far = squares(&[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
    far.nodes[4].1[1] = 1e200;
    let mut nan = squares(&[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
    nan.nodes[4].1[0] = f64::NAN;
    let mut folded = two_squares();
    folded[2] = [5.0, 0.0];
    folded[5] = [5.0, 10.0];
    let mut fin = Sheet::flat(&two_squares(), &[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
    fin.nodes.push((107, [5.0, 5.0, 10.0]));
    fin.elements.push((13, vec![102, 105, 107]));
    // a sheet of 10 mm squares and, beside it, a triangle 0.005 mm across
    let mut speck = squares(&[&[0, 1, 4, 3], &[1, 2, 5, 4]]);
    speck.nodes.extend([
        (107, [30.0, 0.0, 0.0]),
        (108, [30.005, 0.0, 0.0]),
        (109, [30.0, 0.005, 0.0]),
    ]);
    speck.elements.push((13, vec![107, 108, 109]));
    vec![
        (
            "hanging node",
            hanging(),
            Subject::Node(107),
            "hanging node",
        ),
        ("T-junction", t_junction(), Subject::Node(111), "T-junction"),
        (
            "unmerged seam",
            unmerged_seam(),
            Subject::Node(102),
            "coincides with node 107",
        ),
        (
            "duplicate element",
            squares(&[&[0, 1, 4, 3], &[1, 2, 5, 4], &[4, 3, 0, 1]]),
            Subject::Element(13),
            "same nodes as element 11",
        ),
        (
            "overlapping elements",
            Sheet::flat(
                &[
                    [0.0, 0.0],
                    [10.0, 0.0],
                    [10.0, 10.0],
                    [0.0, 10.0],
                    [5.0, 5.0],
                    [15.0, 5.0],
                    [15.0, 15.0],
                    [5.0, 15.0],
                ],
                &[&[0, 1, 2, 3], &[4, 5, 6, 7]],
            ),
            Subject::Node(103),
            "overlap",
        ),
        (
            "element folded over its neighbour",
            Sheet::flat(&folded, &[&[0, 1, 4, 3], &[1, 2, 5, 4]]),
            Subject::Element(12),
            "folds back over element 11",
        ),
        (
            "inverted element",
            inverted_fan(),
            Subject::Element(12),
            "folds back over element 11",
        ),
        (
            "sliver",
            Sheet::flat(
                &[[0.0, 0.0], [100.0, 0.0], [50.0, 0.01], [50.0, -40.0]],
                &[&[0, 1, 2], &[1, 0, 3]],
            ),
            Subject::Element(11),
            "is a sliver",
        ),
        ("speck", speck, Subject::Element(13), "is a speck"),
        (
            "element on one node twice",
            squares(&[&[0, 1, 4, 3], &[1, 2, 2, 4]]),
            Subject::Element(12),
            "names node 103 twice",
        ),
        (
            "element with collinear corners",
            Sheet::flat(
                &[[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [0.0, 10.0]],
                &[&[0, 1, 3], &[1, 2, 0]],
            ),
            Subject::Element(12),
            "degenerate",
        ),
        (
            "node at 1e200",
            far,
            Subject::Node(105),
            "lies at (10, 1e200, 0) mm, beyond 1e6 mm",
        ),
        ("node at NaN", nan, Subject::Node(105), "finite"),
        (
            "non-manifold edge",
            fin,
            Subject::Element(13),
            "non-manifold edge",
        ),
        (
            "elements touching at a corner",
            Sheet::flat(
                &[
                    [0.0, 0.0],
                    [10.0, 0.0],
                    [10.0, 10.0],
                    [0.0, 10.0],
                    [20.0, 10.0],
                    [20.0, 20.0],
                    [10.0, 20.0],
                ],
                &[&[0, 1, 2, 3], &[2, 4, 5, 6]],
            ),
            Subject::Node(103),
            "only point where element 11",
        ),
    ]
}

#[test]
fn blanks_that_are_not_one_sheet_are_refused_at_their_line() {
    let f = Fixtures::new("meshes");
    let mut cases = Vec::new();
    for (k, (name, sheet, subject, words)) in defects().into_iter().enumerate() {
        for (extension, written) in [("msh", sheet.msh()), ("inp", sheet.inp())] {
            let file = f.file(&format!("defect-{k}.{extension}"), written.text.as_bytes());
            let scenario = f.file_blank(&format!("on-defect-{k}-{extension}"), &file);
            let (label, line) = match subject {
                Subject::Node(n) => (format!("node {n}"), written.node_line[&n]),
                Subject::Element(e) => (format!("element {e}"), written.element_line[&e]),
            };
            cases.push(Case {
                name: format!("{name} ({extension})"),
                args: [
                    "run",
                    &scenario,
                    "--output",
                    &f.output(&format!("defect-{k}-{extension}")),
                ]
                .map(String::from)
                .to_vec(),
                code: 2,
                names: vec![format!("{file}: line {line}: {label}"), words.to_string()],
            });
        }
    }
    assert_all_pass(&cases, 1);
}

/// A defect inside `blank.element_set` is named by the file's labels and lines, though the
/// set's elements are renumbered (a tool's rigid elements before them in the deck).
#[test]
fn a_defect_in_the_blank_s_element_set_is_named_by_its_label() {
    let f = Fixtures::new("meshes-set");
    let blank = hanging().inp();
    let tool = "*NODE\n1, 0, 0, -50\n2, 10, 0, -50\n3, 10, 10, -50\n4, 0, 10, -50\n\
                *ELEMENT, TYPE=R3D4, ELSET=TOOL\n1, 1, 2, 3, 4\n";
    let text = format!("{tool}{}*ELSET, ELSET=BLANK\n11, 12, 13\n", blank.text);
    let file = f.file("with-tool.inp", text.as_bytes());
    let scenario = f.file_blank("on-set", &file);
    let with_set = std::fs::read_to_string(&scenario)
        .unwrap()
        .replace("[blank]\n", "[blank]\nelement_set = \"BLANK\"\n");
    let scenario = f.file("on-set.toml", with_set.as_bytes());
    // the node's line in the deck: after the tool's lines
    let line = tool.lines().count() + blank.node_line[&107];
    let case = Case {
        name: "hanging node in an element set".into(),
        args: ["run", &scenario, "--output", &f.output("on-set")]
            .map(String::from)
            .to_vec(),
        code: 2,
        names: vec![
            format!("{file}: line {line}: node 107"),
            "hanging node".into(),
        ],
    };
    check(&case).unwrap();
}

/// Reads `path` as a blank: its mesh and notes, or the error.
fn blank(path: &Path) -> Result<(thermostamp::mesh::Mesh, Vec<String>), String> {
    let import = read_mesh_file(path).map_err(|e| e.to_string())?;
    import.into_blank().map_err(|e| e.to_string())
}

/// Where the contradiction is found on a band depends on the order the cells are visited in:
/// any of its elements may be named, at its own line.
#[test]
fn a_moebius_band_is_refused_at_the_line_of_an_element_of_it() {
    let f = Fixtures::new("meshes-band");
    let band = moebius();
    for (extension, written) in [("msh", band.msh()), ("inp", band.inp())] {
        let path = f.file(&format!("band.{extension}"), written.text.as_bytes());
        let e = read_mesh_file(Path::new(&path))
            .unwrap()
            .into_blank()
            .unwrap_err();
        assert!(e.message.contains("non-orientable"), "{e}");
        let label: u64 = e.message["element ".len()..]
            .split(' ')
            .next()
            .and_then(|l| l.parse().ok())
            .unwrap_or_else(|| panic!("{e}"));
        assert_eq!(e.line, Some(written.element_line[&label]), "{e}");
    }
}

#[test]
fn every_mesh_shipped_is_one_sheet() {
    let mut checked = Vec::new();
    for folder in ["examples/meshes", "tests/data/meshes"] {
        for entry in std::fs::read_dir(repo_path(folder)).unwrap() {
            let path = entry.unwrap().path();
            let extension = path.extension().and_then(|e| e.to_str());
            if !matches!(extension, Some("msh" | "inp")) {
                continue;
            }
            let (mesh, notes) = blank(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(!mesh.cells.is_empty());
            // one piece, each made by one surface (or a closed one): nothing to turn round
            assert!(
                notes
                    .iter()
                    .all(|n| !n.contains("pieces") && !n.contains("turned round")),
                "{}: {notes:?}",
                path.display()
            );
            checked.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    checked.sort();
    assert!(checked.len() >= 8, "{checked:?}");
    assert!(checked.contains(&"ring.msh".to_string()));
}

#[test]
fn an_unstructured_gmsh_mesh_with_a_hole_is_one_sheet() {
    // ring.geo: a disk of radius 60 mm less a hole of radius 15 mm, quadrangles and triangles
    let (mesh, notes) = blank(&repo_path("tests/data/meshes/ring.msh")).unwrap();
    let triangles = mesh.cells.iter().filter(|c| !c.is_quad()).count();
    assert!(triangles > 0 && triangles < mesh.cells.len(), "{triangles}");
    let area = std::f64::consts::PI * (60.0f64.powi(2) - 15.0f64.powi(2));
    assert!(
        (mesh.total_area() - area).abs() < 0.01 * area,
        "{}",
        mesh.total_area()
    );
    assert!(notes.is_empty(), "{notes:?}");
}

#[test]
fn a_blank_of_two_pieces_and_an_element_numbered_the_other_way_are_noted() {
    let f = Fixtures::new("meshes-notes");
    // two squares 10 mm apart, and a third joined to the second, numbered clockwise
    let mut xy = two_squares();
    xy.extend([[30.0, 0.0], [40.0, 0.0], [40.0, 10.0], [30.0, 10.0]]);
    let sheet = Sheet::flat(&xy, &[&[0, 1, 4, 3], &[6, 7, 8, 9], &[1, 4, 5, 2]]);
    for (extension, written) in [("msh", sheet.msh()), ("inp", sheet.inp())] {
        let path = f.file(&format!("pieces.{extension}"), written.text.as_bytes());
        let (mesh, notes) = blank(Path::new(&path)).unwrap();
        let notes = notes.join("\n");
        assert!(
            notes.contains("the blank is 2 pieces that share no edge")
                && notes.contains(&format!(
                    "element 12 (line {}) alone",
                    written.element_line[&12]
                )),
            "{notes}"
        );
        assert!(
            notes.contains("1 of 3 elements were numbered against their neighbours")
                && notes.contains("element 13 (line"),
            "{notes}"
        );
        assert!(mesh
            .cells
            .iter()
            .all(|c| c.area_vector(&mesh.nodes).z > 0.0));
    }
}
