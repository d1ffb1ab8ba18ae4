//! Gmsh `.msh` files in and out (src/mesh/gmsh.rs, docs/meshes.md): hand-written ASCII and
//! binary files, files written by Gmsh (the blank of the hemisphere example, a disk, a solid),
//! write-read round trips, malformed files, and mutated files that must never panic.

mod common;

use common::repo_path;
use nalgebra::Vector3;
use proptest::prelude::*;
use std::collections::BTreeMap;
use thermostamp::mesh::gmsh::{parse_msh, read_msh, write_msh, write_msh_to};
use thermostamp::mesh::{rectangle, Cell, DiagonalPattern, Mesh, MeshFileError, MeshImport};

/// A square of two quadrangles (its middle nodes pulled aside: two trapezia), sparse and unordered node tags, an unused node (99), a named curve group
/// (`clamped`, the left edge), an unnamed point group (7, node 60) and a named surface group.
const SQUARE: &str = "\
$MeshFormat
4.1 0 8
$EndMeshFormat
$Comments
written by hand for the tests
$EndComments
$PhysicalNames
2
1 3 \"clamped\"
2 5 \"sheet\"
$EndPhysicalNames
$Entities
2 1 1 0
2 1 1 0 1 7
9 5 5 5 0
1 0 0 0 0 1 0 1 3 0
1 0 0 0 1 1 0 1 5 0
$EndEntities
$Nodes
4 7 10 99
0 2 0 1
60
1 1 0
0 9 0 1
99
5 5 5
1 1 0 2
40
10
0 1 0
0 0 0
2 1 0 3
30
50
20
1 0 0
0.6 1 0
0.4 0 0
$EndNodes
$Elements
3 4 7 31
1 1 1 1
7 10 40
2 1 3 2
21 10 20 50 40
22 20 30 60 50
0 2 15 1
31 60
$EndElements
";

/// Binary data of the file format in one byte order.
struct Binary {
    bytes: Vec<u8>,
    little_endian: bool,
}

impl Binary {
    fn text(&mut self, s: &str) -> &mut Self {
        self.bytes.extend_from_slice(s.as_bytes());
        self
    }
    /// One value's bytes in the file's byte order.
    fn value(&mut self, little: &[u8], big: &[u8]) {
        let b = if self.little_endian { little } else { big };
        self.bytes.extend_from_slice(b);
    }
    fn size(&mut self, values: &[u64]) -> &mut Self {
        for v in values {
            self.value(&v.to_le_bytes(), &v.to_be_bytes());
        }
        self
    }
    fn int(&mut self, values: &[i32]) -> &mut Self {
        for v in values {
            self.value(&v.to_le_bytes(), &v.to_be_bytes());
        }
        self
    }
    fn double(&mut self, values: &[f64]) -> &mut Self {
        for v in values {
            self.value(&v.to_le_bytes(), &v.to_be_bytes());
        }
        self
    }
}

/// [`SQUARE`] as a binary MSH 4.1 file.
fn square_binary(little_endian: bool) -> Vec<u8> {
    let mut b = Binary {
        bytes: Vec::new(),
        little_endian,
    };
    b.text("$MeshFormat\n4.1 1 8\n")
        .int(&[1])
        .text("\n$EndMeshFormat\n");
    b.text("$PhysicalNames\n2\n1 3 \"clamped\"\n2 5 \"sheet\"\n$EndPhysicalNames\n");
    b.text("$Entities\n").size(&[2, 1, 1, 0]);
    b.int(&[2]).double(&[1.0, 1.0, 0.0]).size(&[1]).int(&[7]);
    b.int(&[9]).double(&[5.0, 5.0, 5.0]).size(&[0]);
    b.int(&[1]).double(&[0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    b.size(&[1]).int(&[3]).size(&[0]);
    b.int(&[1]).double(&[0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
    b.size(&[1]).int(&[5]).size(&[0]);
    b.text("\n$EndEntities\n");
    b.text("$Nodes\n").size(&[4, 7, 10, 99]);
    b.int(&[0, 2, 0]).size(&[1, 60]).double(&[1.0, 1.0, 0.0]);
    b.int(&[0, 9, 0]).size(&[1, 99]).double(&[5.0, 5.0, 5.0]);
    b.int(&[1, 1, 0]).size(&[2, 40, 10]);
    b.double(&[0.0, 1.0, 0.0, 0.0, 0.0, 0.0]);
    b.int(&[2, 1, 0]).size(&[3, 30, 50, 20]);
    b.double(&[1.0, 0.0, 0.0, 0.6, 1.0, 0.0, 0.4, 0.0, 0.0]);
    b.text("\n$EndNodes\n");
    b.text("$Elements\n").size(&[3, 4, 7, 31]);
    b.int(&[1, 1, 1]).size(&[1, 7, 10, 40]);
    b.int(&[2, 1, 3])
        .size(&[2, 21, 10, 20, 50, 40, 22, 20, 30, 60, 50]);
    b.int(&[0, 2, 15]).size(&[1, 31, 60]);
    b.text("\n$EndElements\n");
    b.bytes
}

fn sets(entries: &[(&str, &[usize])]) -> BTreeMap<String, Vec<usize>> {
    entries
        .iter()
        .map(|(name, members)| (name.to_string(), members.to_vec()))
        .collect()
}

/// What [`SQUARE`] reads to: nodes in file order without the unused node 99 (60, 40, 10, 30,
/// 50, 20 become 0..5), each quadrangle one cell with its corners in the file's order.
fn square_expected() -> Mesh {
    Mesh {
        nodes: vec![
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.6, 1.0, 0.0),
            Vector3::new(0.4, 0.0, 0.0),
        ],
        // quadrangle 21 (10 20 50 40) and quadrangle 22 (20 30 60 50)
        cells: vec![Cell::Quad([2, 5, 4, 1]), Cell::Quad([5, 3, 0, 4])],
        node_sets: sets(&[
            ("clamped", &[1, 2]),
            ("physical 7", &[0]),
            ("sheet", &[0, 1, 2, 3, 4, 5]),
        ]),
        element_sets: sets(&[("sheet", &[0, 1])]),
        warp_directions: None,
    }
}

fn parse(bytes: &[u8]) -> MeshImport {
    match parse_msh(bytes, "square.msh") {
        Ok(import) => import,
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn a_hand_written_ascii_file_reads_to_the_expected_quadrangles_and_sets() {
    let import = parse(SQUARE.as_bytes());
    assert_eq!(import.mesh, square_expected());
    assert_eq!(import.rigid, vec![false; 2]);
    let notes = import.notes.join("\n");
    assert!(!notes.contains("split"), "{notes}");
    assert_eq!(import.notes.len(), 1, "{notes}");
    assert!(
        notes.contains("1 nodes used by no triangle") && notes.contains("99"),
        "{notes}"
    );
    assert!(!notes.contains("oriented"), "{notes}");
    // counter-clockwise about +z, as in the file; the two trapezia fill the unit square
    let m = &import.mesh;
    assert!(m.cells.iter().all(|c| c.area_vector(&m.nodes).z > 0.0));
    assert!((m.area(0) - 0.5).abs() < 1e-15 && (m.area(1) - 0.5).abs() < 1e-15);
}

#[test]
fn the_same_mesh_as_a_binary_file_in_either_byte_order_reads_the_same() {
    let ascii = parse(SQUARE.as_bytes());
    for little_endian in [true, false] {
        let binary = parse(&square_binary(little_endian));
        assert_eq!(binary.mesh, ascii.mesh, "little-endian {little_endian}");
        assert_eq!(binary.notes, ascii.notes);
    }
}

#[test]
fn windows_line_ends_and_a_byte_order_mark_read_the_same() {
    let mut bytes = vec![0xEF, 0xBB, 0xBF];
    bytes.extend_from_slice(SQUARE.replace('\n', "\r\n").as_bytes());
    assert_eq!(parse(&bytes).mesh, square_expected());
}

fn fixture(name: &str) -> MeshImport {
    read_msh(&repo_path(&format!("tests/data/meshes/{name}"))).unwrap()
}

/// Files written by Gmsh 4.15.2 from the `.geo` files beside them (docs/meshes.md).
#[test]
fn the_blank_of_the_hemisphere_example_from_gmsh_reads_as_400_quadrangles_with_its_groups() {
    let import = fixture("hemisphere-blank.msh");
    let m = &import.mesh;
    // the same mesh saved by Gmsh as binary: exact coordinates there, 16 digits in ASCII
    let binary = fixture("hemisphere-blank-binary.msh");
    let b = &binary.mesh;
    assert_eq!(b.nodes.len(), m.nodes.len());
    assert!(b
        .nodes
        .iter()
        .zip(&m.nodes)
        .all(|(p, q)| (p - q).amax() < 1e-12));
    assert!(b.nodes.iter().zip(&m.nodes).any(|(p, q)| p != q));
    assert!(b.node_sets == m.node_sets);
    // the same quadrangles, whatever the last bits of the coordinates
    assert!(b.cells == m.cells);
    assert!(b.element_sets == m.element_sets && binary.notes == import.notes);
    assert_eq!((m.nodes.len(), m.cells.len()), (441, 400));
    assert!(m.cells.iter().all(Cell::is_quad));
    let area: f64 = (0..m.cells.len()).map(|t| m.area(t)).sum();
    assert!((area - 160.0 * 160.0).abs() < 1e-8, "{area}");
    for cell in &m.cells {
        assert!(cell.area_vector(&m.nodes).z > 0.0);
        // 8 mm square cells
        for (p, q) in cell.edges() {
            let l = (m.nodes[q] - m.nodes[p]).norm();
            assert!((l - 8.0).abs() < 1e-9, "{l}");
        }
        assert!((cell.area(&m.nodes) - 64.0).abs() < 1e-9);
    }
    assert_eq!(m.element_sets.keys().collect::<Vec<_>>(), ["blank"]);
    assert_eq!(m.element_sets["blank"], (0..400).collect::<Vec<_>>());
    assert_eq!(
        m.node_sets.keys().collect::<Vec<_>>(),
        ["blank", "clamped", "corner"]
    );
    assert_eq!(m.node_sets["blank"], (0..441).collect::<Vec<_>>());
    let clamped = m.node_set("clamped").unwrap();
    assert_eq!(clamped.len(), 21);
    assert!(clamped.iter().all(|&n| m.nodes[n].x == -80.0));
    let corner = m.node_set("corner").unwrap();
    assert_eq!(corner.len(), 1);
    assert_eq!(m.nodes[corner[0]], Vector3::new(-80.0, 80.0, 0.0));
    assert_eq!(import.notes, Vec::<String>::new());
}

#[test]
fn an_unstructured_disk_from_gmsh_reads_with_its_rim() {
    let import = fixture("disk.msh");
    let m = &import.mesh;
    assert_eq!((m.nodes.len(), m.cells.len()), (411, 757));
    assert!(!m.has_quads());
    assert_eq!(import.notes, Vec::<String>::new());
    assert!(m.cells.iter().all(|c| c.area_vector(&m.nodes).z > 0.0));
    let area: f64 = (0..m.cells.len()).map(|t| m.area(t)).sum();
    let circle = std::f64::consts::PI * 60.0 * 60.0;
    assert!(area < circle && area > 0.99 * circle, "{area}");
    let rim = m.node_set("rim").unwrap();
    assert_eq!(rim.len(), 63);
    assert!(rim.iter().all(|&n| (m.nodes[n].norm() - 60.0).abs() < 1e-9));
    assert_eq!(m.element_sets["disk"].len(), 757);
}

#[test]
fn a_solid_meshed_in_tetrahedra_gives_its_closed_outward_surface() {
    let import = fixture("box.msh");
    let m = &import.mesh;
    assert_eq!(m.cells.len(), 244);
    assert!(!m.has_quads());
    assert!(m.node_sets.is_empty() && m.element_sets.is_empty());
    // no orientation note: every edge runs once each way
    assert_eq!(
        import.notes,
        [
            "340 volume elements skipped (340 of type 4): the sheet is the surface elements",
            "7 nodes used by no triangle or quadrangle left out (tags 125, 126, 127, 128, 129, \
             ...)"
        ]
    );
    // enclosed volume by the divergence theorem: 10 x 20 x 5, positive for outward normals
    let volume: f64 = m
        .cells
        .iter()
        .map(|t| {
            let [a, b, c] = t.positions(&m.nodes)[..] else {
                panic!("{t:?} is not a triangle")
            };
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum();
    assert!((volume - 1000.0).abs() < 1e-9, "{volume}");
}

fn round_trip(mesh: &Mesh) -> MeshImport {
    let mut text = Vec::new();
    write_msh_to(&mut text, mesh, "round-trip.msh").unwrap();
    parse(&text)
}

#[test]
fn every_rectangle_pattern_survives_write_and_read_bit_for_bit() {
    for pattern in [
        DiagonalPattern::Quad,
        DiagonalPattern::Right,
        DiagonalPattern::Alternating,
        DiagonalPattern::Crossed,
    ] {
        // widths that no decimal fraction writes exactly
        let mesh = rectangle(150.0 / 7.0, 450.0 / 11.0, 7, 5, pattern);
        let back = round_trip(&mesh);
        assert_eq!(back.mesh, mesh, "{pattern:?}");
        assert_eq!(back.notes, Vec::<String>::new(), "{pattern:?}");
        for (a, b) in mesh.nodes.iter().zip(&back.mesh.nodes) {
            for k in 0..3 {
                assert_eq!(a[k].to_bits(), b[k].to_bits());
            }
        }
        for name in ["bottom", "top", "left", "right", "all"] {
            assert_eq!(
                back.mesh.node_set(name).unwrap(),
                mesh.node_set(name).unwrap()
            );
        }
    }
}

/// A 4 x 3 mesh of quadrilaterals in which cells 1, 5 and 6 are cut in two triangles: runs of
/// each kind, in the order of the cells.
fn mixed_cells() -> Mesh {
    let quads = rectangle(40.0, 30.0, 4, 3, DiagonalPattern::Quad);
    let mut mesh = quads.clone();
    mesh.cells = quads
        .cells
        .iter()
        .enumerate()
        .flat_map(|(k, cell)| match k {
            1 | 5 | 6 => cell.triangles().into_iter().map(Cell::Triangle).collect(),
            _ => vec![*cell],
        })
        .collect();
    mesh.element_sets = sets(&[("mixed", &[0, 1, 2, 3, 7, 8]), ("quads", &[0, 3, 4])]);
    mesh
}

#[test]
fn triangles_and_quadrangles_in_one_mesh_keep_their_order_through_write_and_read() {
    let mesh = mixed_cells();
    mesh.validate().unwrap();
    let quads = mesh.cells.iter().filter(|c| c.is_quad()).count();
    assert_eq!((mesh.cells.len(), quads), (15, 9));
    let mut text = Vec::new();
    write_msh_to(&mut text, &mesh, "mixed.msh").unwrap();
    let back = parse(&text);
    let mut expected = mesh.clone();
    for name in ["mixed", "quads"] {
        let nodes = mesh.nodes_of_element_set(name).unwrap();
        expected.node_sets.insert(name.to_string(), nodes);
    }
    assert_eq!(back.mesh, expected);
    assert_eq!(back.notes, Vec::<String>::new());
}

#[test]
fn overlapping_and_interleaved_element_sets_survive_write_and_read() {
    let mut mesh = rectangle(40.0, 30.0, 4, 3, DiagonalPattern::Alternating);
    mesh.nodes[5].z = -1.0 / 3.0;
    let cells = mesh.cells.len();
    mesh.element_sets = sets(&[
        ("even", &(0..cells).step_by(2).collect::<Vec<_>>()),
        ("first half", &(0..cells / 2).collect::<Vec<_>>()),
        ("one", &[7]),
    ]);
    // the node set of an element set's name: here not that set's nodes
    mesh.node_sets.insert("one".to_string(), vec![0, 1]);
    // the node set of 'even' is its elements' nodes, which the reader rebuilds
    let mut even: Vec<usize> = mesh
        .nodes_of_element_set("even")
        .unwrap()
        .into_iter()
        .collect();
    even.sort_unstable();
    even.dedup();
    mesh.node_sets.insert("even".to_string(), even);
    // 'first half' has no node set: the reader adds one, its elements' nodes
    let back = round_trip(&mesh).mesh;
    let mut first_half: Vec<usize> = mesh.element_sets["first half"]
        .iter()
        .flat_map(|&t| mesh.cells[t].nodes().to_vec())
        .collect();
    first_half.sort_unstable();
    first_half.dedup();
    let mut expected = mesh.clone();
    expected
        .node_sets
        .insert("first half".to_string(), first_half);
    assert_eq!(back, expected);
}

#[test]
fn files_read_written_and_read_again_are_the_same_meshes() {
    let first = fixture("hemisphere-blank.msh").mesh;
    let folder = std::env::temp_dir().join(format!("thermostamp-gmsh-{}", std::process::id()));
    std::fs::create_dir_all(&folder).unwrap();
    let out = folder.join("blank.msh");
    write_msh(&out, &first).unwrap();
    let second = read_msh(&out).unwrap().mesh;
    std::fs::remove_dir_all(&folder).unwrap();
    assert_eq!(second, first);
    // the square, whose sets came from curve, point and surface groups, and the disk
    let square = parse(SQUARE.as_bytes()).mesh;
    assert_eq!(round_trip(&square).mesh, square);
    let disk = fixture("disk.msh").mesh;
    assert_eq!(round_trip(&disk).mesh, disk);
}

#[test]
fn the_writer_refuses_names_that_msh_cannot_hold_and_invalid_meshes() {
    let mut mesh = rectangle(1.0, 1.0, 1, 1, DiagonalPattern::Right);
    mesh.node_sets.insert("say \"clamp\"".to_string(), vec![0]);
    let e = write_msh_to(Vec::new(), &mesh, "out.msh").unwrap_err();
    assert!(e.to_string().starts_with("out.msh: set name"), "{e}");
    let mut mesh = rectangle(1.0, 1.0, 1, 1, DiagonalPattern::Right);
    mesh.nodes[0].x = f64::NAN;
    let e = write_msh_to(Vec::new(), &mesh, "out.msh").unwrap_err();
    assert!(e.to_string().contains("invalid mesh"), "{e}");
}

#[test]
fn elements_oriented_against_their_neighbours_get_a_note_naming_the_element() {
    // quadrangle 22 listed clockwise: 20 50 60 30
    let text = SQUARE.replace("22 20 30 60 50", "22 20 50 60 30");
    let import = parse(text.as_bytes());
    let note = import
        .notes
        .iter()
        .find(|n| n.contains("not consistently oriented"))
        .unwrap();
    assert!(note.contains("element 21 and element 22"), "{note}");
}

#[test]
fn groups_sharing_a_name_are_merged_by_the_documented_rule() {
    // the point group 7 named 'clamped' too: the node set is the curve's and the point's nodes
    let text = SQUARE.replace("2\n1 3 \"clamped\"", "3\n0 7 \"clamped\"\n1 3 \"clamped\"");
    let import = parse(text.as_bytes());
    assert_eq!(import.mesh.node_sets["clamped"], [0, 1, 2]);
    assert!(import
        .notes
        .iter()
        .any(|n| n.contains("2 physical groups are named 'clamped'")));
    // the surface named 'clamped' too: its element set, the curve's and point's node set
    let text = text.replace("2 5 \"sheet\"", "2 5 \"clamped\"");
    let m = parse(text.as_bytes()).mesh;
    assert_eq!(m.element_sets["clamped"], [0, 1]);
    assert_eq!(m.node_sets["clamped"], [0, 1, 2]);
}

#[test]
fn volume_elements_are_skipped_with_a_note() {
    // a tetrahedron on the square's nodes and the unused node, in a volume entity
    let text = SQUARE
        .replace("3 4 7 31\n", "4 5 7 41\n")
        .replace("$EndElements", "3 1 4 1\n41 10 30 60 99\n$EndElements");
    let import = parse(text.as_bytes());
    assert_eq!(import.mesh, square_expected());
    assert!(import
        .notes
        .iter()
        .any(|n| n.contains("1 volume elements skipped (1 of type 4)")));
}

/// Where a broken file fails: the file's name, the line (where there is one) and a piece of
/// the message.
fn fails(bytes: &[u8], line: Option<usize>, message: &str) {
    match parse_msh(bytes, "broken.msh") {
        Ok(_) => panic!("read without error; expected: {message}"),
        Err(MeshFileError {
            file,
            line: l,
            message: m,
        }) => {
            assert_eq!(file, "broken.msh");
            assert_eq!(l, line, "{m}");
            assert!(m.contains(message), "'{m}' does not contain '{message}'");
        }
    }
}

fn replaced(from: &str, to: &str) -> Vec<u8> {
    assert!(SQUARE.contains(from), "{from}");
    SQUARE.replacen(from, to, 1).into_bytes()
}

#[test]
fn malformed_ascii_files_name_the_file_the_line_and_what_was_expected() {
    fails(b"", Some(1), "the file is empty");
    fails(b"solid cube\n", Some(1), "not a Gmsh MSH file");
    fails(
        &replaced("4.1 0 8", "2.2 0 8"),
        Some(2),
        "reads version 4.1 only",
    );
    fails(
        &replaced("4.1 0 8", "4 0 8"),
        Some(2),
        "version \"4\" is not read",
    );
    fails(&replaced("4.1 0 8", "4.1 2 8"), Some(2), "file type 2");
    // the section's end missing: the next section's header where $EndNodes should be
    fails(&replaced("$EndNodes\n", ""), Some(39), "expected $EndNodes");
    // the file cut short inside $Nodes
    let cut: String = SQUARE.lines().take(30).collect::<Vec<_>>().join("\n");
    fails(
        cut.as_bytes(),
        Some(30),
        "the file ends in the $Nodes section",
    );
    fails(
        &replaced("4 7 10 99", "4 8 10 99"),
        Some(20),
        "says 8 nodes, its blocks hold 7",
    );
    fails(
        &replaced("2 1 0 3", "2 1 0 4"),
        Some(32),
        "more nodes than the 7",
    );
    fails(
        &replaced("3 4 7 31", "3 5 7 31"),
        Some(41),
        "says 5 elements, its blocks hold 4",
    );
    fails(
        &replaced("0 2 15 1\n31 60", "0 2 15 2\n31 60"),
        Some(47),
        "more elements than the 4",
    );
    fails(
        &replaced("21 10 20 50 40", "21 10 20 55 40"),
        Some(45),
        "refers to node 55",
    );
    fails(
        &replaced("0.6 1 0", "nan 1 0"),
        Some(37),
        "non-finite coordinate",
    );
    fails(
        &replaced("0.6 1 0", "0.6 1e999 0"),
        Some(37),
        "non-finite coordinate",
    );
    fails(
        &replaced("0.4 0 0", "0.4 zero 0"),
        Some(38),
        "expected the y coordinate",
    );
    fails(
        &replaced("2 1 3 2", "2 1 9 2"),
        Some(44),
        "element type 9 (6-node second-order triangle) is not supported",
    );
    fails(&replaced("2 1 3 2", "2 1 1 2"), Some(44), "of dimension 1");
    fails(
        &replaced("50\n20", "50\n30"),
        Some(35),
        "node tag 30 appears twice",
    );
    fails(
        &replaced("2 5 \"sheet\"", "2 5 \"sheet"),
        Some(10),
        "not closed by a double quote",
    );
    fails(
        &replaced("$EndPhysicalNames", "3 5 \"more\"\n$EndPhysicalNames"),
        Some(11),
        "expected $EndPhysicalNames",
    );
    fails(
        &replaced("$Elements\n", "$Nodes\n"),
        Some(40),
        "a second $Nodes section (the first is at line 19)",
    );
    fails(
        &replaced("$EndComments", "$EndComment"),
        Some(4),
        "never closed",
    );
    // quadrangle 22 with a repeated node, crossing itself, re-entrant at node 50 (moved to
    // (0.6, 0.3), where quadrangle 21 stays convex), on one node twice over: at its line
    let folded = "element 22 is a quadrilateral that is not convex";
    for (bytes, error) in [
        (
            replaced("22 20 30 60 50", "22 20 30 30 50"),
            "element 22 names node 30 twice",
        ),
        (replaced("22 20 30 60 50", "22 20 30 50 60"), folded),
        (replaced("0.6 1 0", "0.6 0.3 0"), folded),
        (
            replaced("22 20 30 60 50", "22 20 30 30 20"),
            "element 22 names node 30 twice",
        ),
    ] {
        let e = parse_msh(&bytes, "broken.msh").unwrap_err();
        assert_eq!((e.file.as_str(), e.line), ("broken.msh", Some(46)), "{e}");
        assert!(e.message.contains(error), "{e}");
    }
    // a node at 1e200 is named at its line, not found as an element of no area
    let e = parse_msh(&replaced("0.6 1 0", "0.6 1e200 0"), "broken.msh").unwrap_err();
    assert_eq!((e.file.as_str(), e.line), ("broken.msh", Some(37)), "{e}");
    assert!(
        e.message.contains("node 50 lies at (0.6, 1e200, 0) mm"),
        "{e}"
    );
    // no $Elements at all
    let text = &SQUARE[..SQUARE.find("$Elements").unwrap()];
    let e = parse_msh(text.as_bytes(), "broken.msh").unwrap_err();
    assert!(e.message.contains("no $Elements section"), "{e}");
    // only lines and points: no sheet
    let text = SQUARE
        .replace("3 4 7 31", "2 2 7 31")
        .replace("2 1 3 2\n21 10 20 50 40\n22 20 30 60 50\n", "");
    let e = parse_msh(text.as_bytes(), "broken.msh").unwrap_err();
    assert!(
        e.message
            .contains("no triangles (type 2) or quadrangles (type 3)"),
        "{e}"
    );
}

#[test]
fn malformed_binary_files_name_the_byte_or_the_header_line() {
    let good = square_binary(true);
    // cut inside the node coordinates
    let at = good.windows(6).position(|w| w == b"$Nodes").unwrap() + 60;
    fails(
        &good[..at],
        None,
        "binary data cut short in the $Nodes section",
    );
    // cut right after the last binary data of $Elements
    let end = good.len() - "\n$EndElements\n".len();
    fails(&good[..end], None, "the file ends before $EndElements");
    // the byte-order check is neither 1 nor 1 reversed
    let mut bad = good.clone();
    bad[20..24].copy_from_slice(&[2, 0, 0, 0]);
    fails(&bad, Some(3), "the byte-order check");
    // a size_t of 3 bytes
    let mut bad = good.clone();
    bad[18] = b'3';
    fails(&bad, Some(2), "data size 3 in a binary file");
    // counts far beyond what the file holds: nothing is set aside for them
    let mut bad = good.clone();
    let nodes = good.windows(7).position(|w| w == b"$Nodes\n").unwrap() + 7;
    bad[nodes + 8..nodes + 16].copy_from_slice(&(u64::MAX / 2).to_le_bytes());
    bad[nodes + 32 + 12..nodes + 32 + 20].copy_from_slice(&(u64::MAX / 4).to_le_bytes());
    let e = parse_msh(&bad, "broken.msh").unwrap_err();
    assert_eq!(e.line, None, "{e}");
    assert!(e.message.contains("byte"), "{e}");
    // node 60 (the first of $Nodes, after 32 bytes of counts, the block's 12 and 16) at 1e200,
    // and quadrangle 22 on node 30 twice: each named with the byte where it starts
    let mut far = good.clone();
    far[nodes + 68..nodes + 76].copy_from_slice(&1e200f64.to_le_bytes());
    let e = parse_msh(&far, "broken.msh").unwrap_err();
    assert_eq!(e.line, None, "{e}");
    assert!(
        e.message.starts_with("node 60 lies at (1, 1e200, 0) mm")
            && e.message
                .ends_with(&format!("(byte {} of the file)", nodes + 60)),
        "{e}"
    );
    let elements = good.windows(10).position(|w| w == b"$Elements\n").unwrap() + 10;
    // counts 32, line block 12 + 8 + 24, quadrangle block 12 + 8, quadrangle 21 40 bytes
    let quadrangle = elements + 32 + 44 + 20 + 40;
    let mut twice = good.clone();
    twice[quadrangle + 24..quadrangle + 32].copy_from_slice(&30u64.to_le_bytes());
    let e = parse_msh(&twice, "broken.msh").unwrap_err();
    assert!(
        e.message.starts_with("element 22 names node 30 twice")
            && e.message
                .ends_with(&format!("(byte {quadrangle} of the file)")),
        "{e}"
    );
}

fn mutated(base: Vec<u8>) -> impl Strategy<Value = Vec<u8>> {
    let len = base.len();
    (
        0..=len,
        prop::collection::vec((0..len, any::<u8>()), 0..6),
        prop::collection::vec(0..len, 0..3),
    )
        .prop_map(move |(cut, flips, deletions)| {
            let mut bytes = base.clone();
            for (at, byte) in flips {
                bytes[at] = byte;
            }
            for at in deletions {
                if at < bytes.len() {
                    bytes.remove(at);
                }
            }
            bytes.truncate(cut);
            bytes
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..600)) {
        let _ = parse_msh(&bytes, "fuzz.msh");
        let mut with_header = b"$MeshFormat\n4.1 1 8\n\x01\x00\x00\x00\n$EndMeshFormat\n$Nodes\n".to_vec();
        with_header.extend_from_slice(&bytes);
        let _ = parse_msh(&with_header, "fuzz.msh");
    }

    #[test]
    fn mutated_ascii_files_never_panic(bytes in mutated(SQUARE.as_bytes().to_vec())) {
        let _ = parse_msh(&bytes, "fuzz.msh");
    }

    #[test]
    fn mutated_binary_files_never_panic(bytes in mutated(square_binary(true))) {
        let _ = parse_msh(&bytes, "fuzz.msh");
    }

    #[test]
    fn mutated_big_endian_files_never_panic(bytes in mutated(square_binary(false))) {
        let _ = parse_msh(&bytes, "fuzz.msh");
    }
}
