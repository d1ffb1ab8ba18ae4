//! Rigid tools of the hemispherical and double-dome set-ups (`contact::tools`) and STL files
//! (`contact::stl`): the geometry of each tool against its analytic surface, orientation towards
//! the blank, tangent continuity, and STL round trips and robustness.

use nalgebra::Vector3;
use proptest::prelude::*;
use std::collections::HashMap;
use std::f64::consts::PI;
use thermostamp::contact::stl::{parse_stl, write_ascii, write_binary, StlError};
use thermostamp::contact::{
    blank_holder, double_dome_die, double_dome_holder, double_dome_punch, hemisphere_die,
    hemisphere_punch, hemisphere_punch_with_skirt, read_stl, write_stl_ascii, write_stl_binary,
    DieShape, TriangleSurface,
};

const RP: f64 = 50.0;

fn centroid(s: &TriangleSurface, k: usize) -> Vector3<f64> {
    s.triangles[k]
        .iter()
        .map(|&i| s.vertices[i])
        .sum::<Vector3<f64>>()
        / 3.0
}

fn triangle_area(s: &TriangleSurface, k: usize) -> f64 {
    let [a, b, c] = s.triangles[k].map(|i| s.vertices[i]);
    0.5 * (b - a).cross(&(c - a)).norm()
}

fn area(s: &TriangleSurface) -> f64 {
    (0..s.triangles.len()).map(|k| triangle_area(s, k)).sum()
}

/// Largest angle (rad) between the normals of two triangles sharing an edge, over the pairs of
/// triangles both accepted by `keep`.
fn max_neighbour_angle(s: &TriangleSurface, keep: impl Fn(usize) -> bool) -> f64 {
    let mut by_edge: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    for (k, t) in s.triangles.iter().enumerate() {
        for e in 0..3 {
            let (i, j) = (t[e], t[(e + 1) % 3]);
            by_edge.entry((i.min(j), i.max(j))).or_default().push(k);
        }
    }
    let mut worst: f64 = 0.0;
    for pair in by_edge.values() {
        assert!(
            pair.len() <= 2,
            "an edge is shared by more than two triangles"
        );
        if let [p, q] = pair[..] {
            if keep(p) && keep(q) {
                let cos = s.normal(p).dot(&s.normal(q)).clamp(-1.0, 1.0);
                worst = worst.max(cos.acos());
            }
        }
    }
    worst
}

/// Each interior edge must be traversed once in each direction: the triangles are consistently
/// oriented and the mesh is a manifold.
fn assert_consistently_oriented(s: &TriangleSurface) {
    let mut directed = HashMap::new();
    for t in &s.triangles {
        for e in 0..3 {
            let edge = (t[e], t[(e + 1) % 3]);
            assert!(
                directed.insert(edge, ()).is_none(),
                "edge {edge:?} used twice the same way"
            );
        }
    }
}

#[test]
fn every_hemisphere_cap_vertex_lies_on_the_sphere() {
    let punch = hemisphere_punch(RP, 2.0).unwrap();
    let centre = Vector3::new(0.0, 0.0, -RP);
    let cap: Vec<_> = punch.vertices.iter().filter(|v| v.z >= -RP).collect();
    assert!(cap.len() > 100);
    for v in cap {
        assert!(((v - centre).norm() - RP).abs() < 1e-9, "{v:?}");
    }
    let skirt: Vec<_> = punch.vertices.iter().filter(|v| v.z < -RP).collect();
    assert!(!skirt.is_empty());
    for v in skirt {
        assert!(
            (v.xy().norm() - RP).abs() < 1e-9 && v.z >= -2.0 * RP - 1e-9,
            "{v:?}"
        );
    }
    let (lo, hi) = punch.bounds();
    assert!(hi.z.abs() < 1e-12 && (lo.z + 2.0 * RP).abs() < 1e-9);
}

/// A triangulation inscribed in a smooth surface misses area in proportion to the square of its
/// edge length: halving the resolution divides the error by about 4.
#[test]
fn cap_area_converges_quadratically_to_two_pi_r_squared() {
    let exact = 2.0 * PI * RP * RP;
    let errors: Vec<f64> = [4.0, 2.0, 1.0]
        .iter()
        .map(|&h| {
            let cap = hemisphere_punch_with_skirt(RP, 0.0, h).unwrap();
            (area(&cap) - exact).abs() / exact
        })
        .collect();
    assert!(errors[2] < 2e-4, "{errors:?}");
    for w in errors.windows(2) {
        let ratio = w[0] / w[1];
        assert!(
            (3.0..5.0).contains(&ratio),
            "ratio {ratio}, errors {errors:?}"
        );
    }
}

#[test]
fn punch_normals_point_out_of_the_punch() {
    let punch = hemisphere_punch(RP, 3.0).unwrap();
    assert_consistently_oriented(&punch);
    let centre = Vector3::new(0.0, 0.0, -RP);
    for k in 0..punch.triangles.len() {
        let (c, n) = (centroid(&punch, k), punch.normal(k));
        if punch.triangles[k]
            .iter()
            .all(|&i| punch.vertices[i].z >= -RP)
        {
            assert!(n.dot(&(c - centre)) > 0.0, "cap triangle {k}");
        } else {
            assert!(
                n.dot(&Vector3::new(c.x, c.y, 0.0)) > 0.0,
                "skirt triangle {k}"
            );
            assert!(n.z.abs() < 1e-9, "skirt triangle {k} is not vertical");
        }
    }
    // At the apex the punch faces the blank straight on.
    let apex = (0..punch.triangles.len())
        .min_by(|&a, &b| centroid(&punch, b).z.total_cmp(&centroid(&punch, a).z))
        .unwrap();
    assert!(punch.normal(apex).z > 0.99);
}

struct Die {
    rd: f64,
    rf: f64,
    ro: f64,
    depth: f64,
}

const DIE: Die = Die {
    rd: 52.0,
    rf: 5.0,
    ro: 100.0,
    depth: 60.0,
};

#[test]
fn die_normals_point_down_and_into_the_hole() {
    let Die { rd, rf, ro, depth } = DIE;
    let die = hemisphere_die(rd, rf, ro, depth, 1.5).unwrap();
    assert_consistently_oriented(&die);
    let (lo, hi) = die.bounds();
    assert!(lo.z.abs() < 1e-12 && (hi.z - depth).abs() < 1e-9 && (hi.x - ro).abs() < 1e-9);
    let (mut flat, mut fillet, mut wall) = (0, 0, 0);
    for k in 0..die.triangles.len() {
        let (c, n) = (centroid(&die, k), die.normal(k));
        let corners = die.triangles[k].map(|i| die.vertices[i]);
        let radial = Vector3::new(c.x, c.y, 0.0).normalize();
        if corners.iter().all(|v| v.z == 0.0) {
            flat += 1;
            assert!(n.z < -0.999_999, "plate triangle {k}: {n:?}");
        } else if corners.iter().all(|v| v.z >= rf) {
            wall += 1;
            assert!(n.dot(&radial) < -0.99, "wall triangle {k}: {n:?}");
        } else {
            // Fillet: away from the centre circle of the torus, i.e. out of the die material.
            fillet += 1;
            let centre = (rd + rf) * radial + Vector3::new(0.0, 0.0, rf);
            assert!(n.dot(&(c - centre)) > 0.0, "fillet triangle {k}");
            assert!(
                n.z <= 1e-12 && n.dot(&radial) <= 1e-12,
                "fillet triangle {k}: {n:?}"
            );
        }
    }
    assert!(flat > 0 && fillet > 0 && wall > 0);
    // Every vertex of the fillet lies on the torus.
    for v in die.vertices.iter().filter(|v| v.z > 0.0 && v.z < rf) {
        let rho = v.xy().norm();
        assert!(((rho - rd - rf).hypot(v.z - rf) - rf).abs() < 1e-9, "{v:?}");
    }
}

/// Tangent continuity of plate, fillet and wall: neighbouring facets turn by about one facet's
/// worth of curvature, `resolution / fillet_radius` (plus the ring's own `resolution / r`), never
/// by a crease.
#[test]
fn die_fillet_is_tangent_continuous() {
    let Die { rd, rf, ro, depth } = DIE;
    for h in [0.5, 0.25] {
        let die = hemisphere_die(rd, rf, ro, depth, h).unwrap();
        let near_fillet = |k: usize| {
            let c = centroid(&die, k);
            c.z < 2.0 * rf && c.xy().norm() < rd + 2.0 * rf
        };
        let worst = max_neighbour_angle(&die, near_fillet);
        let facet_turn = h / rf + h / rd;
        assert!(
            worst < 1.5 * facet_turn,
            "h {h}: {worst} rad vs {facet_turn}"
        );
    }
}

#[test]
fn blank_holder_faces_up_and_covers_the_annulus() {
    let holder = blank_holder(55.0, 120.0, 2.0).unwrap();
    assert_consistently_oriented(&holder);
    for k in 0..holder.triangles.len() {
        assert!(holder.normal(k).z > 0.999_999, "triangle {k}");
    }
    for v in &holder.vertices {
        let rho = v.xy().norm();
        assert!(v.z == 0.0 && rho > 55.0 - 1e-9 && rho < 120.0 + 1e-9);
    }
    let exact = PI * (120.0f64.powi(2) - 55.0f64.powi(2));
    assert!((area(&holder) - exact).abs() / exact < 2e-3);
}

#[test]
fn double_dome_is_a_smooth_offset_of_its_ridge() {
    let (l, r, skirt) = (40.0, 25.0, 20.0);
    let dome = double_dome_punch(l, r, skirt, 0.5).unwrap();
    assert_consistently_oriented(&dome);
    let nearest_on_ridge = |p: &Vector3<f64>| Vector3::new(p.x.clamp(-l, l), 0.0, -r);
    for v in dome.vertices.iter().filter(|v| v.z >= -r) {
        assert!(((v - nearest_on_ridge(v)).norm() - r).abs() < 1e-9, "{v:?}");
    }
    for k in 0..dome.triangles.len() {
        let c = centroid(&dome, k);
        let away = if c.z >= -r {
            c - nearest_on_ridge(&c)
        } else {
            let q = nearest_on_ridge(&c);
            Vector3::new(c.x - q.x, c.y, 0.0)
        };
        assert!(dome.normal(k).dot(&away) > 0.0, "triangle {k}");
    }
    // C1: no crease where the cylinder meets the spherical ends, or the crown meets the skirt.
    let worst = max_neighbour_angle(&dome, |_| true);
    assert!(worst < 1.5 * 2.0 * 0.5 / r, "{worst} rad");
    // Zero half-length is the hemisphere punch.
    assert_eq!(
        double_dome_punch(0.0, RP, 10.0, 3.0).unwrap(),
        hemisphere_punch_with_skirt(RP, 10.0, 3.0).unwrap()
    );
}

#[test]
fn invalid_tool_sizes_are_errors_naming_the_parameter() {
    let cases = [
        (hemisphere_punch(-1.0, 1.0).unwrap_err(), "radius"),
        (hemisphere_punch(10.0, f64::NAN).unwrap_err(), "resolution"),
        (
            hemisphere_punch_with_skirt(10.0, -1.0, 1.0).unwrap_err(),
            "skirt_height",
        ),
        (
            hemisphere_die(0.0, 5.0, 100.0, 60.0, 1.0).unwrap_err(),
            "opening_radius",
        ),
        (
            hemisphere_die(50.0, 50.0, 100.0, 60.0, 1.0).unwrap_err(),
            "fillet_radius",
        ),
        (
            hemisphere_die(50.0, 5.0, 55.0, 60.0, 1.0).unwrap_err(),
            "outer_radius",
        ),
        (
            hemisphere_die(50.0, 5.0, 100.0, 5.0, 1.0).unwrap_err(),
            "depth",
        ),
        (
            hemisphere_die(50.0, 5.0, f64::INFINITY, 60.0, 1.0).unwrap_err(),
            "outer_radius",
        ),
        (blank_holder(60.0, 60.0, 1.0).unwrap_err(), "outer_radius"),
        (blank_holder(-60.0, 80.0, 1.0).unwrap_err(), "inner_radius"),
        (
            double_dome_punch(-1.0, 10.0, 5.0, 1.0).unwrap_err(),
            "half_length",
        ),
    ];
    for (message, parameter) in cases {
        assert!(
            message.contains(parameter),
            "{message:?} should name {parameter}"
        );
    }
}

/// The same triangles, corner by corner, within `tol` (the read surface is welded in order of
/// first appearance, so vertex indices may differ).
fn assert_same_triangles(a: &TriangleSurface, b: &TriangleSurface, tol: f64) {
    assert_eq!(a.vertices.len(), b.vertices.len());
    assert_eq!(a.triangles.len(), b.triangles.len());
    for (ta, tb) in a.triangles.iter().zip(&b.triangles) {
        for (&i, &j) in ta.iter().zip(tb) {
            let (p, q) = (a.vertices[i], b.vertices[j]);
            assert!((p - q).amax() <= tol * p.amax().max(1.0), "{p:?} vs {q:?}");
        }
    }
}

#[test]
fn binary_stl_round_trip_keeps_the_tool_up_to_f32() {
    let die = hemisphere_die(52.0, 5.0, 100.0, 60.0, 4.0).unwrap();
    let mut bytes = Vec::new();
    write_binary(&mut bytes, &die, "die.stl").unwrap();
    assert_eq!(bytes.len(), 84 + 50 * die.triangles.len());
    let back = parse_stl(&bytes, "die.stl").unwrap();
    assert_same_triangles(&die, &back, f32::EPSILON as f64);
    // A header starting with "solid" (as some exporters write) is still binary.
    bytes[..6].copy_from_slice(b"solid ");
    assert_same_triangles(
        &die,
        &parse_stl(&bytes, "die.stl").unwrap(),
        f32::EPSILON as f64,
    );
}

#[test]
fn ascii_stl_round_trip_is_exact() {
    let dome = double_dome_punch(30.0, 20.0, 10.0, 4.0).unwrap();
    let mut bytes = Vec::new();
    write_ascii(&mut bytes, &dome, "double dome", "dome.stl").unwrap();
    assert!(bytes.starts_with(b"solid double_dome\n"));
    let back = parse_stl(&bytes, "dome.stl").unwrap();
    assert_same_triangles(&dome, &back, 0.0);
}

#[test]
fn stl_files_round_trip_on_disk() {
    let dir = std::env::temp_dir().join(format!("thermostamp-stl-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let holder = blank_holder(55.0, 80.0, 5.0).unwrap();
    let (bin, ascii) = (dir.join("holder.stl"), dir.join("holder-ascii.stl"));
    write_stl_binary(&bin, &holder).unwrap();
    write_stl_ascii(&ascii, &holder, "holder").unwrap();
    assert_same_triangles(&holder, &read_stl(&bin).unwrap(), f32::EPSILON as f64);
    assert_same_triangles(&holder, &read_stl(&ascii).unwrap(), 0.0);
    let missing = read_stl(&dir.join("missing.stl")).unwrap_err();
    assert!(matches!(missing, StlError::Io { .. }) && missing.to_string().contains("missing.stl"));
    std::fs::remove_dir_all(&dir).unwrap();
}

const ONE_FACET: &str = "solid t
  facet normal 0 0 1
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 1 0
    endloop
  endfacet
endsolid t
";

#[test]
fn shared_corners_are_merged_and_orientation_kept() {
    let two = ONE_FACET.replace(
        "  endfacet\n",
        "  endfacet\n  facet normal 0 0 0\n    outer loop\n      vertex 1 0 0\n      \
         vertex 1 1 0\n      vertex -0 1 0\n    endloop\n  endfacet\n",
    );
    let s = parse_stl(two.as_bytes(), "two.stl").unwrap();
    assert_eq!(s.vertices.len(), 4, "{:?}", s.vertices);
    assert_eq!(s.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    assert!(s.normal(0).z > 0.0 && s.normal(1).z > 0.0);
}

#[test]
fn malformed_ascii_stl_names_the_line_and_what_was_expected() {
    let cases = [
        (
            ONE_FACET.replace("outer loop", "outer lop"),
            3,
            "outer loop",
        ),
        (
            ONE_FACET.replace("vertex 1 0 0", "vertex 1 zero 0"),
            5,
            "vertex x y z",
        ),
        (
            ONE_FACET.replace("vertex 1 0 0", "vertex 1 nan 0"),
            5,
            "finite",
        ),
        (ONE_FACET.replace("    endloop\n", ""), 7, "endloop"),
        (ONE_FACET.replace("endsolid t\n", ""), 9, "endsolid"),
        (
            ONE_FACET.replace("facet normal 0 0 1", "facet 0 0 1"),
            2,
            "facet normal",
        ),
        (format!("{ONE_FACET}garbage\n"), 10, "solid"),
    ];
    for (text, line, expected) in cases {
        let error = parse_stl(text.as_bytes(), "bad.stl").unwrap_err();
        let message = error.to_string();
        match error {
            StlError::Ascii { line: l, .. } => assert_eq!(l, line, "{message}"),
            other => panic!("not an ASCII error: {other}"),
        }
        assert!(
            message.contains(&format!("bad.stl: line {line}:")),
            "{message}"
        );
        assert!(
            message.contains(expected),
            "{message} should mention {expected}"
        );
    }
}

#[test]
fn degenerate_facets_are_errors_naming_the_facet() {
    let second = |corners: &str| {
        format!(
            "solid t\n{}{}endsolid t\n",
            &ONE_FACET[8..ONE_FACET.len() - 11],
            ONE_FACET[8..ONE_FACET.len() - 11].replace(
                "      vertex 0 0 0\n      vertex 1 0 0\n      vertex 0 1 0\n",
                corners
            )
        )
    };
    let coincident = second("      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 0 0\n");
    let collinear = second("      vertex 0 0 0\n      vertex 1 0 0\n      vertex 2 0 0\n");
    for text in [coincident, collinear] {
        match parse_stl(text.as_bytes(), "deg.stl").unwrap_err() {
            StlError::Degenerate { facet, .. } => assert_eq!(facet, 1),
            other => panic!("not a degenerate-facet error: {other}"),
        }
    }
    let mut binary = Vec::new();
    let flat = TriangleSurface {
        vertices: vec![Vector3::zeros(), Vector3::x(), Vector3::x() * 2.0],
        triangles: vec![[0, 1, 2]],
    };
    write_binary(&mut binary, &flat, "deg.stl").unwrap();
    assert!(matches!(
        parse_stl(&binary, "deg.stl"),
        Err(StlError::Degenerate { facet: 0, .. })
    ));
}

#[test]
fn non_stl_inputs_are_errors() {
    assert!(matches!(
        parse_stl(b"", "e.stl"),
        Err(StlError::Binary { .. })
    ));
    assert!(matches!(
        parse_stl(b"solid empty\nendsolid empty\n", "e.stl"),
        Err(StlError::Empty { .. })
    ));
    let mut header_only = vec![0u8; 84];
    assert!(matches!(
        parse_stl(&header_only, "e.stl"),
        Err(StlError::Empty { .. })
    ));
    header_only[80] = 3; // announces 3 facets that are not there
    let message = parse_stl(&header_only, "e.stl").unwrap_err().to_string();
    assert!(message.contains("3 facets"), "{message}");
    let mut nan = Vec::new();
    write_binary(&mut nan, &blank_holder(1.0, 2.0, 1.0).unwrap(), "nan.stl").unwrap();
    nan[84 + 50 + 12..84 + 50 + 16].copy_from_slice(&f32::NAN.to_le_bytes());
    assert!(matches!(
        parse_stl(&nan, "nan.stl"),
        Err(StlError::NonFinite { facet: 1, .. })
    ));
}

/// A binary STL body of `n` random facets with a consistent header.
fn binary_with_random_facets() -> impl Strategy<Value = Vec<u8>> {
    (0usize..6).prop_flat_map(|n| {
        proptest::collection::vec(any::<u8>(), 50 * n).prop_map(move |body| {
            let mut bytes = vec![0u8; 80];
            bytes.extend_from_slice(&(n as u32).to_le_bytes());
            bytes.extend(body);
            bytes
        })
    })
}

/// Lines made of STL keywords, numbers and junk, after a `solid` line.
fn ascii_soup() -> impl Strategy<Value = Vec<u8>> {
    let token = prop_oneof![
        Just("facet".to_string()),
        Just("normal".to_string()),
        Just("outer".to_string()),
        Just("loop".to_string()),
        Just("vertex".to_string()),
        Just("endloop".to_string()),
        Just("endfacet".to_string()),
        Just("endsolid".to_string()),
        Just("solid".to_string()),
        Just("\n".to_string()),
        any::<f64>().prop_map(|x| x.to_string()),
        "[ -~\t\r\n]{0,6}",
    ];
    proptest::collection::vec(token, 0..80).prop_map(|tokens| {
        let mut text = "solid fuzz\n".to_string();
        text.push_str(&tokens.join(" "));
        text.into_bytes()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let _ = parse_stl(&bytes, "fuzz.stl");
        let mut solid = b"solid ".to_vec();
        solid.extend(&bytes);
        let _ = parse_stl(&solid, "fuzz.stl");
    }

    #[test]
    fn random_binary_facets_never_panic(bytes in binary_with_random_facets()) {
        if let Ok(s) = parse_stl(&bytes, "fuzz.stl") {
            prop_assert!(s.vertices.iter().all(|v| v.iter().all(|x| x.is_finite())));
            prop_assert!(s.triangles.iter().all(|t| t.iter().all(|&i| i < s.vertices.len())));
        }
    }

    #[test]
    fn ascii_keyword_soup_never_panics(bytes in ascii_soup()) {
        let _ = parse_stl(&bytes, "fuzz.stl");
    }
}

/// The double-dome die and holder are the hemisphere's profiles swept around the ridge: the
/// plate faces down, the opening wall faces the ridge, every fillet vertex lies at its torus
/// distance from the ridge, and the holder's area is the stadium ring's.
#[test]
fn double_dome_die_and_holder_follow_the_ridge() {
    let Die { rd, rf, ro, depth } = DIE;
    let l = 30.0;
    let shape = DieShape {
        opening_radius: rd,
        fillet_radius: rf,
        outer_radius: ro,
        depth,
    };
    let die = double_dome_die(l, &shape, 1.0).unwrap();
    assert_consistently_oriented(&die);
    let towards_ridge = |c: &Vector3<f64>| Vector3::new(c.x.clamp(-l, l) - c.x, -c.y, 0.0);
    let ridge_distance = |v: &Vector3<f64>| (v.x.abs() - l).max(0.0).hypot(v.y);
    let (mut plate, mut wall) = (0, 0);
    for k in 0..die.triangles.len() {
        let (c, n) = (centroid(&die, k), die.normal(k));
        let corners = die.triangles[k].map(|i| die.vertices[i]);
        if corners.iter().all(|v| v.z == 0.0) {
            plate += 1;
            assert!(n.z < -0.999_999, "plate triangle {k}: {n:?}");
        } else if corners.iter().all(|v| v.z >= rf) {
            wall += 1;
            assert!(
                n.dot(&towards_ridge(&c).normalize()) > 0.99,
                "wall {k}: {n:?}"
            );
        }
    }
    assert!(plate > 0 && wall > 0);
    for v in die.vertices.iter().filter(|v| v.z > 0.0 && v.z < rf) {
        let rho = ridge_distance(v);
        assert!(((rho - rd - rf).hypot(v.z - rf) - rf).abs() < 1e-9, "{v:?}");
    }
    assert!(die.vertices.iter().all(|v| ridge_distance(v) < ro + 1e-9));
    assert_eq!(
        double_dome_die(0.0, &shape, 3.0).unwrap(),
        hemisphere_die(rd, rf, ro, depth, 3.0).unwrap()
    );

    let holder = double_dome_holder(l, 55.0, 120.0, 2.0).unwrap();
    assert_consistently_oriented(&holder);
    assert!((0..holder.triangles.len()).all(|k| holder.normal(k).z > 0.999_999));
    let exact = PI * (120.0f64.powi(2) - 55.0f64.powi(2)) + 4.0 * l * (120.0 - 55.0);
    assert!((area(&holder) - exact).abs() / exact < 2e-3);
    assert_eq!(
        double_dome_holder(0.0, 55.0, 120.0, 2.0).unwrap(),
        blank_holder(55.0, 120.0, 2.0).unwrap()
    );
    assert!(double_dome_holder(-1.0, 55.0, 120.0, 2.0)
        .unwrap_err()
        .contains("half_length"));
}
