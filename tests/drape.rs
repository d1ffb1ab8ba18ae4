//! Kinematic (pin-jointed net) draping: exact cases (plane, cylinder), invariants (chord
//! lengths, symmetry), and the hemisphere against the Chebyshev-net estimate γ ≈ K·u·v.

use thermostamp::drape::{
    drape, Cylinder, DrapeParams, DrapeResult, DrapeSurface, FailReason, Hemisphere, Plane,
};

fn params(cell: f64, warp_angle_deg: f64, max_cells: usize) -> DrapeParams {
    DrapeParams {
        cell,
        start: (0.0, 0.0),
        warp_angle_deg,
        max_cells,
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Every warp and weft edge between two placed nodes, as its length.
fn edge_lengths(r: &DrapeResult) -> Vec<f64> {
    let n = r.max_cells() as i64;
    let mut out = Vec::new();
    for i in -n..=n {
        for j in -n..=n {
            let Some(p) = r.node(i, j) else { continue };
            for (di, dj) in [(1, 0), (0, 1)] {
                if let Some(q) = r.node(i + di, j + dj) {
                    out.push(dist(p, q));
                }
            }
        }
    }
    out
}

fn max_edge_error(r: &DrapeResult) -> f64 {
    edge_lengths(r)
        .iter()
        .map(|l| (l - r.cell()).abs())
        .fold(0.0, f64::max)
}

fn max_abs_cell_shear(r: &DrapeResult) -> f64 {
    r.cells()
        .iter()
        .map(|c| c.shear_deg.abs())
        .fold(0.0, f64::max)
}

fn total_nodes(r: &DrapeResult) -> usize {
    let side = 2 * r.max_cells() + 1;
    side * side
}

/// R = 100 mm dome, 0/90 net from the apex: the reference case of the hemisphere tests.
fn dome(cell: f64, max_cells: usize) -> DrapeResult {
    drape(&Hemisphere { radius: 100.0 }, &params(cell, 0.0, max_cells)).unwrap()
}

#[test]
fn plane_net_stays_square_with_exact_edges() {
    let plane = Plane {
        z0: 3.0,
        slope_x: 0.2,
        slope_y: -0.1,
    };
    let p = DrapeParams {
        cell: 5.0,
        start: (7.0, -4.0),
        warp_angle_deg: 30.0,
        max_cells: 10,
    };
    let r = drape(&plane, &p).unwrap();
    assert_eq!(r.report().placed, total_nodes(&r));
    // On the inclined plane the weft is square to the warp in 3D, not in plan.
    let (warp, weft) = (
        r.warp_direction(0, 0).unwrap(),
        r.weft_direction(0, 0).unwrap(),
    );
    let dot: f64 = (0..3).map(|k| warp[k] * weft[k]).sum();
    assert!(dot.abs() < 1e-12, "{dot}");
    assert_eq!(r.cells().len(), 400);
    println!(
        "plane: max |shear| {:.3e} deg, max edge error {:.3e} mm",
        max_abs_cell_shear(&r),
        max_edge_error(&r)
    );
    assert!(max_abs_cell_shear(&r) < 1e-9, "{}", max_abs_cell_shear(&r));
    assert!(max_edge_error(&r) < 1e-9, "{}", max_edge_error(&r));
}

#[test]
fn cylinder_along_axis_and_circumference_does_not_shear() {
    // Developable, and the generators (axis line, circumference) are geodesics: the net
    // wraps without shear. 10 cells of 4 mm stay inside the quarter arc (78.5 mm).
    let r = drape(&Cylinder { radius: 50.0 }, &params(4.0, 0.0, 10)).unwrap();
    assert_eq!(r.report().placed, total_nodes(&r));
    println!(
        "cylinder: max |shear| {:.3e} deg, max edge error {:.3e} mm",
        max_abs_cell_shear(&r),
        max_edge_error(&r)
    );
    assert!(max_abs_cell_shear(&r) < 1e-6, "{}", max_abs_cell_shear(&r));
    assert!(max_edge_error(&r) < 1e-9, "{}", max_edge_error(&r));
    // It really is curved: the last weft node dropped below the axis line.
    assert!(r.node(0, 10).unwrap()[2] < -10.0);
}

#[test]
fn hemisphere_edges_keep_their_chord_length() {
    let r = dome(5.0, 20);
    let rep = r.report();
    assert_eq!(rep.placed + rep.failed() + rep.unreached, total_nodes(&r));
    let peak = r.max_shear().unwrap();
    println!(
        "dome R100 cell 5 n 20: placed {}, failed {}, unreached {}; max edge error {:.3e} mm; \
         max shear {:.3} deg at cell ({}, {})",
        rep.placed,
        rep.failed(),
        rep.unreached,
        max_edge_error(&r),
        peak.shear_deg,
        peak.i,
        peak.j
    );
    assert!(rep.placed > 1000, "placed {}", rep.placed);
    assert!(max_edge_error(&r) < 1e-9, "{}", max_edge_error(&r));
    // The dome is doubly curved: the net must shear somewhere.
    assert!(max_abs_cell_shear(&r) > 5.0);
}

#[test]
fn hemisphere_net_from_the_apex_has_fourfold_symmetry() {
    // Mirroring x → −x reverses the warp, so the signed shear changes sign; swapping warp
    // and weft (mirror about x = y) keeps it. The magnitudes are equal in all four.
    let r = dome(5.0, 15);
    let n = 15;
    let mut compared = 0;
    for i in -n..=n {
        for j in -n..=n {
            let Some(s) = r.node_shear_deg(i, j) else {
                continue;
            };
            let mirror_i = r.node_shear_deg(-i, j).unwrap();
            let mirror_j = r.node_shear_deg(i, -j).unwrap();
            let swapped = r.node_shear_deg(j, i).unwrap();
            assert!((s + mirror_i).abs() < 1e-6, "({i},{j}) {s} vs {mirror_i}");
            assert!((s + mirror_j).abs() < 1e-6, "({i},{j}) {s} vs {mirror_j}");
            assert!((s - swapped).abs() < 1e-6, "({i},{j}) {s} vs {swapped}");
            compared += 1;
        }
    }
    assert!(compared > 500, "{compared}");
    // Cells: the cell with first corner (i, j) mirrors onto (−i−1, j) and (i, −j−1).
    for c in r.cells() {
        let (i, j) = (c.i, c.j);
        let a = r.cell_shear_deg(-i - 1, j).unwrap();
        let b = r.cell_shear_deg(i, -j - 1).unwrap();
        let t = r.cell_shear_deg(j, i).unwrap();
        assert!((c.shear_deg + a).abs() < 1e-6);
        assert!((c.shear_deg + b).abs() < 1e-6);
        assert!((c.shear_deg - t).abs() < 1e-6);
    }
}

#[test]
fn hemisphere_shear_vanishes_on_generators_and_peaks_on_diagonals() {
    let r = dome(5.0, 15);
    for k in -15..=15 {
        for (i, j) in [(k, 0), (0, k)] {
            if let Some(s) = r.node_shear_deg(i, j) {
                assert!(s.abs() < 1e-9, "generator node ({i},{j}): {s}");
            }
        }
    }
    // Along each anti-diagonal i + j = m of the first quadrant, |shear| rises from the
    // generators to a maximum on the diagonal i = j.
    for m in (4..=14).step_by(2) {
        let line: Vec<f64> = (0..=m / 2)
            .filter_map(|i| r.node_shear_deg(i, m - i))
            .map(f64::abs)
            .collect();
        assert_eq!(line.len(), m as usize / 2 + 1, "m = {m}");
        assert!(line.windows(2).all(|w| w[1] > w[0]), "m = {m}: {line:?}");
    }
    let peak = r.max_shear().unwrap();
    let on_diagonal = peak.i == peak.j || peak.i == -peak.j - 1;
    assert!(on_diagonal, "max shear at cell ({}, {})", peak.i, peak.j);
}

/// Chebyshev-net estimate near the apex (Servant; see Long & Rudd 1994): the yarn angle α
/// obeys ∂²α/∂u∂v = −K sin α with u, v the yarn arc lengths, so with γ = 0 on the generators
/// γ ≈ K·u·v = (u v / R²) rad.
fn chebyshev_estimate_deg(u: f64, v: f64, radius: f64) -> f64 {
    (u * v / (radius * radius)).to_degrees()
}

#[test]
fn hemisphere_shear_grows_like_distance_squared_near_the_apex() {
    let r = dome(1.0, 10);
    let near = r.node_shear_deg(2, 2).unwrap();
    let far = r.node_shear_deg(4, 4).unwrap();
    let ratio = far / near;
    println!("shear (2,2) = {near:.6e} deg, (4,4) = {far:.6e} deg, ratio {ratio:.5}");
    assert!((3.5..=4.5).contains(&ratio), "ratio {ratio}");
    for k in [2_i64, 4, 8] {
        let s = r.node_shear_deg(k, k).unwrap();
        let est = chebyshev_estimate_deg(k as f64, k as f64, 100.0);
        println!(
            "(k,k) = ({k},{k}): shear {s:.6e}, K u v {est:.6e}, rel {:.3e}",
            s / est - 1.0
        );
        // Measured within 2.5e-5; the neglected terms are O(K u²) ≈ 6e-3 at k = 8.
        assert!((s / est - 1.0).abs() < 1e-3, "k = {k}: {s} vs {est}");
    }
}

#[test]
fn hemisphere_shear_converges_when_the_cell_is_halved() {
    // The same physical point of the fabric, u = v = 40 mm of yarn from the generators on the
    // R = 100 mm dome, at cells of 10, 5 and 2.5 mm. Measured: 9.175194°, 9.159515°,
    // 9.155610°: changes 1.57e-2° then 3.90e-3°, ratio 4.02, i.e. O(cell²) convergence (the
    // chord-vs-arc error of a cell is O(cell²/R²)). Richardson puts the 2.5 mm value within
    // 3.9e-3/3 = 1.3e-3° of the limit. Tolerances: the last change below 0.01° (2.5 times the
    // measured one, a margin for platform round-off only; a first-order error would be ~4
    // times larger) and the ratio of changes in [3, 5] (second order).
    let shear_at = |cell: f64| {
        let k = (40.0 / cell).round() as i64;
        dome(cell, k as usize + 1).node_shear_deg(k, k).unwrap()
    };
    let (s10, s5, s25) = (shear_at(10.0), shear_at(5.0), shear_at(2.5));
    let (d1, d2) = ((s5 - s10).abs(), (s25 - s5).abs());
    println!(
        "shear at u=v=40: {s10:.6} (10 mm), {s5:.6} (5 mm), {s25:.6} (2.5 mm); \
         changes {d1:.3e}, {d2:.3e}, ratio {:.3}",
        d1 / d2
    );
    assert!(d2 < 0.01, "change on halving 5 -> 2.5 mm: {d2} deg");
    assert!((3.0..=5.0).contains(&(d1 / d2)), "order: {d1} then {d2}");
}

/// A surface with only `height`, so the finite-difference default gradient is used.
struct HeightOnlyDome(Hemisphere);

impl DrapeSurface for HeightOnlyDome {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        self.0.height(x, y)
    }
}

#[test]
fn default_finite_difference_gradient_gives_the_same_net() {
    // The gradient only enters the Newton Jacobian: the nodes must not depend on it.
    let exact = dome(5.0, 12);
    let fd = drape(
        &HeightOnlyDome(Hemisphere { radius: 100.0 }),
        &params(5.0, 0.0, 12),
    )
    .unwrap();
    assert_eq!(exact.report().placed, fd.report().placed);
    for i in -12..=12 {
        for j in -12..=12 {
            match (exact.node(i, j), fd.node(i, j)) {
                (Some(a), Some(b)) => assert!(dist(a, b) < 1e-9, "({i},{j})"),
                (None, None) => {}
                _ => panic!("({i},{j}) placed in one net only"),
            }
        }
    }
}

#[test]
fn drape_stops_at_the_rim_and_reports_failures() {
    // 10 mm cells, 20 per direction: the generators (quarter arc 157 mm) reach the rim.
    let r = dome(10.0, 20);
    let rep = r.report();
    println!(
        "dome R100 cell 10 n 20: placed {}, outside {}, no solution {}, folded {}, unreached {}",
        rep.placed,
        rep.failed_for(FailReason::OutsideDomain),
        rep.failed_for(FailReason::NoSolution),
        rep.failed_for(FailReason::Folded),
        rep.unreached
    );
    assert!(rep.failed_for(FailReason::OutsideDomain) >= 4, "{rep:?}");
    assert!(rep.unreached > 0);
    assert_eq!(rep.placed + rep.failed() + rep.unreached, total_nodes(&r));
    assert!(r.node(20, 0).is_none());
    assert!(max_edge_error(&r) < 1e-9, "{}", max_edge_error(&r));
}

#[test]
fn locking_report_lists_exactly_the_cells_beyond_the_angle() {
    let r = dome(5.0, 15);
    let max = r.max_shear().unwrap().shear_deg.abs();
    let locking = 0.5 * max;
    let over = r.cells_exceeding(locking).unwrap();
    let expected = r
        .cells()
        .iter()
        .filter(|c| c.shear_deg.abs() > locking)
        .count();
    assert_eq!(over.len(), expected);
    assert!(!over.is_empty());
    assert!(over.iter().all(|c| c.shear_deg.abs() > locking));
    assert!(r.cells_exceeding(max + 1.0).unwrap().is_empty());
    let err = r.cells_exceeding(f64::NAN).unwrap_err();
    assert!(err.contains("locking_deg"), "{err}");
}

#[test]
fn bad_inputs_are_errors_naming_the_parameter() {
    let dome = Hemisphere { radius: 100.0 };
    let ok = params(5.0, 0.0, 10);
    let cases: Vec<(DrapeParams, &str)> = vec![
        (DrapeParams { cell: 0.0, ..ok }, "cell"),
        (DrapeParams { cell: -1.0, ..ok }, "cell"),
        (
            DrapeParams {
                cell: f64::NAN,
                ..ok
            },
            "cell",
        ),
        (
            DrapeParams {
                start: (f64::NAN, 0.0),
                ..ok
            },
            "start",
        ),
        (
            DrapeParams {
                start: (0.0, f64::INFINITY),
                ..ok
            },
            "start",
        ),
        (
            DrapeParams {
                start: (150.0, 0.0),
                ..ok
            },
            "start",
        ),
        (
            DrapeParams {
                warp_angle_deg: f64::NAN,
                ..ok
            },
            "warp_angle_deg",
        ),
        (DrapeParams { max_cells: 0, ..ok }, "max_cells"),
        (
            DrapeParams {
                max_cells: 1_000_000,
                ..ok
            },
            "max_cells",
        ),
    ];
    for (p, name) in cases {
        let err = drape(&dome, &p).unwrap_err();
        assert!(err.contains(name), "{p:?}: {err}");
    }
    // A degenerate tool is an empty domain, not a panic.
    let err = drape(&Hemisphere { radius: -1.0 }, &params(5.0, 0.0, 3)).unwrap_err();
    assert!(err.contains("start"), "{err}");
}
