//! The shear field of a formed part does not depend on how the mesh is cut (docs/model.md §4,
//! element technology): on quadrilaterals the hemisphere's four shear lobes are alike, the
//! field is smooth at the element scale where the pin-jointed net is, a ±45° ply gives the 0/90
//! ply's field turned by 45°, and the largest shear converges as the mesh is refined.
//!
//! The fast checks run on a shortened hemisphere (the test fabric of stiff yarns and soft
//! shear, 15 mm of stroke at 50 mm/s); the ignored ones on the shipped example at 4 and 2 mm
//! cells (`cargo test --release --test forming_mesh_cut -- --ignored --nocapture`, about
//! 35 minutes on 2 cores), their figures in docs/model.md §4.

mod common;

use nalgebra::{Rotation3, Vector3};
use thermostamp::forming::drape_preview::{drape_preview, Generators};
use thermostamp::forming::{run, FormingModel, Scenario};

/// The hemisphere example with `overrides`, shortened to the test fabric and 15 mm of stroke
/// when `short`.
fn scenario(short: bool, overrides: &[String]) -> Scenario {
    let shortened = [
        "blank.card=forming-fabric.toml",
        "process.stroke=15",
        "process.punch_speed=50",
        "process.time_scaling=1",
        "output.history_points=10",
    ];
    let all: Vec<String> = shortened
        .iter()
        .filter(|_| short)
        .map(|s| s.to_string())
        .chain(overrides.iter().cloned())
        .collect();
    Scenario::load(
        &common::repo_path("tests/data/hemisphere-explicit.toml"),
        &all,
    )
    .unwrap()
}

fn mesh(size: f64, pattern: &str, ply_angle: f64) -> Vec<String> {
    vec![
        format!("blank.element_size={size}"),
        format!("blank.pattern={pattern}"),
        format!("blank.ply_angle={ply_angle}"),
    ]
}

/// The formed part: per element its current centroid and |shear angle| (degrees).
struct Formed {
    centroids: Vec<Vector3<f64>>,
    shear: Vec<f64>,
    /// Pairs of elements that share an edge.
    neighbours: Vec<(usize, usize)>,
}

fn form(scenario: &Scenario) -> Formed {
    let forming = FormingModel::new(scenario).unwrap();
    let result = run::run(&forming, None, None);
    let state = result.outcome.as_ref().unwrap();
    let x = &state.positions;
    let elements = &forming.model.elements;
    let mut by_edge = std::collections::HashMap::<(usize, usize), Vec<usize>>::new();
    for (k, cell) in forming.model.mesh.cells.iter().enumerate() {
        for (a, b) in cell.edges() {
            by_edge.entry((a.min(b), a.max(b))).or_default().push(k);
        }
    }
    Formed {
        centroids: elements.iter().map(|e| e.centroid(x)).collect(),
        shear: elements
            .iter()
            .map(|e| e.shear_angle(x).abs().to_degrees())
            .collect(),
        neighbours: by_edge
            .values()
            .filter(|v| v.len() == 2)
            .map(|v| (v[0], v[1]))
            .collect(),
    }
}

/// Largest |shear| of the elements whose centroid lies in each quadrant (degrees).
fn quadrant_maxima(part: &Formed) -> [f64; 4] {
    let mut maxima = [0.0f64; 4];
    for (c, &gamma) in part.centroids.iter().zip(&part.shear) {
        let q = usize::from(c.x > 0.0) + 2 * usize::from(c.y > 0.0);
        maxima[q] = maxima[q].max(gamma);
    }
    maxima
}

fn spread(maxima: &[f64; 4]) -> f64 {
    let lo = maxima.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = maxima.iter().copied().fold(0.0, f64::max);
    hi - lo
}

/// |shear| of the pin-jointed net draped on the same punch at each element: that of the net's
/// cell whose centre is nearest in plan, where one lies within half a cell (`None` off the
/// net).
fn net_at_elements(scenario: &Scenario, part: &Formed, cell: f64) -> Vec<Option<f64>> {
    let net = drape_preview(scenario, &Generators::of(scenario)).unwrap();
    let cells = net.cells();
    part.centroids
        .iter()
        .map(|c| {
            let (d, shear) = cells
                .iter()
                .map(|n| (n.centre[0] - c.x).hypot(n.centre[1] - c.y))
                .zip(cells.iter().map(|n| n.shear_deg.abs()))
                .min_by(|a, b| a.0.total_cmp(&b.0))?;
            (d < 0.5 * cell).then_some(shear)
        })
        .collect()
}

/// Neighbouring elements where the net varies by less than 1° between them: how many pairs,
/// and their largest difference of shear (degrees).
fn oscillation(part: &Formed, net: &[Option<f64>]) -> (usize, f64) {
    part.neighbours
        .iter()
        .filter_map(|&(a, b)| Some((net[a]?, net[b]?, a, b)))
        .filter(|(na, nb, _, _)| (na - nb).abs() < 1.0)
        .map(|(_, _, a, b)| (part.shear[a] - part.shear[b]).abs())
        .fold((0, 0.0), |(n, worst), d| (n + 1, f64::max(worst, d)))
}

/// RMS (degrees) over the elements within `radius` of the axis in plan of the difference
/// between the field of `turned` (the ply at +45°) and that of `part` (0/90) at the point
/// turned back by 45°, interpolated by inverse distance from its three nearest elements.
fn rotated_rms(part: &Formed, turned: &Formed, radius: f64) -> f64 {
    let back = Rotation3::from_axis_angle(&Vector3::z_axis(), -std::f64::consts::FRAC_PI_4);
    let mut sum = 0.0;
    let mut count = 0;
    for (c, &gamma) in turned.centroids.iter().zip(&turned.shear) {
        if c.x.hypot(c.y) > radius {
            continue;
        }
        let p = back * c;
        let mut near: Vec<(f64, f64)> = part
            .centroids
            .iter()
            .zip(&part.shear)
            .map(|(q, &s)| ((q.x - p.x).hypot(q.y - p.y), s))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (w, ws) = near[..3]
            .iter()
            .map(|&(d, s)| (1.0 / (d + 1e-9), s / (d + 1e-9)))
            .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
        sum += (gamma - ws / w).powi(2);
        count += 1;
    }
    (sum / count as f64).sqrt()
}

/// The shortened hemisphere on 8 mm quadrilaterals, 0/90 and ±45°: the four quadrant maxima
/// within 1° of each other, neighbours within 2° wherever the net varies by less than 1°, and
/// the ±45° ply's field the 0/90 one's turned by 45° within 1.5° RMS over the cap (measured
/// 0.01°, 0.03° over 16 pairs and 1.06°).
#[test]
fn quadrilaterals_shear_alike_in_every_lobe_smoothly_and_at_any_ply_angle() {
    check_free_of_the_cut(true, 8.0, 10);
}

/// The same checks on the shipped example at 4 mm cells (1,600 quadrilaterals, 30 mm of
/// stroke; its runs of docs/model.md §4 measured 0.04°, 0.95° and 0.66°).
#[test]
#[ignore = "about 10 minutes on 2 cores; figures in docs/model.md §4"]
fn example_on_4_mm_quadrilaterals_is_free_of_the_cut() {
    check_free_of_the_cut(false, 4.0, 100);
}

fn check_free_of_the_cut(short: bool, size: f64, min_pairs: usize) {
    let straight = scenario(short, &mesh(size, "quad", 0.0));
    let turned = scenario(short, &mesh(size, "quad", 45.0));
    // the two runs side by side
    let (part, turned) = common::both(|| form(&straight), || form(&turned));
    let maxima = quadrant_maxima(&part);
    eprintln!("{size} mm: quadrant maxima {maxima:?}");
    assert!(spread(&maxima) < 1.0, "quadrant maxima {maxima:?}");
    let net = net_at_elements(&straight, &part, size);
    let (pairs, worst) = oscillation(&part, &net);
    eprintln!(
        "{size} mm: {pairs} neighbour pairs where the net is smooth, {worst:.2}° apart at most"
    );
    assert!(pairs > min_pairs && worst < 2.0, "{pairs} pairs, {worst}°");
    let maxima_turned = quadrant_maxima(&turned);
    assert!(spread(&maxima_turned) < 1.0, "±45°: {maxima_turned:?}");
    let rms = rotated_rms(&part, &turned, 35.0);
    eprintln!("{size} mm: ±45° against 0/90 turned: RMS {rms:.2}°");
    assert!(rms < 1.5, "RMS {rms}°");
}

/// Mesh convergence of the shipped example on quadrilaterals, 8, 4 and 2 mm cells: the quadrant
/// maxima within 1° of each other at every size, and the largest shear on the cap converging
/// (the change from 4 to 2 mm below that from 8 to 4; measured 26.0, 28.3, 29.4°). The
/// pin-jointed net on the same cap does not converge (27.65, 31.65, 35.8°: its largest cell
/// is at its edge on the punch's flank), so the gap to it is printed, not asserted
/// (docs/model.md §4).
#[test]
#[ignore = "about 25 minutes on 2 cores; figures in docs/model.md §4"]
fn largest_shear_converges_under_refinement() {
    let mut largest = Vec::new();
    for size in [8.0, 4.0, 2.0] {
        let s = scenario(false, &mesh(size, "quad", 0.0));
        let part = form(&s);
        let maxima = quadrant_maxima(&part);
        let net = drape_preview(&s, &Generators::of(&s)).unwrap();
        let pin_jointed = net.max_shear().unwrap().shear_deg.abs();
        let on_cap = net_at_elements(&s, &part, size);
        let cap = part
            .shear
            .iter()
            .zip(&on_cap)
            .filter(|(_, n)| n.is_some())
            .map(|(&g, _)| g)
            .fold(0.0, f64::max);
        eprintln!(
            "{size} mm: quadrant maxima {maxima:?}, largest on the cap {cap:.2}°, net \
             {pin_jointed:.2}°"
        );
        assert!(spread(&maxima) < 1.0, "{size} mm: {maxima:?}");
        largest.push(cap);
    }
    let (first, second) = (largest[1] - largest[0], largest[2] - largest[1]);
    assert!(second.abs() < first.abs(), "largest on the cap {largest:?}");
}

/// A blank cut with alternating or crossed diagonals is formed with a note that its bending
/// is soft; quadrilaterals and single diagonals are not.
#[test]
fn soft_bending_patterns_are_noted() {
    for (pattern, noted) in [
        ("quad", false),
        ("right", false),
        ("alternating", true),
        ("crossed", true),
    ] {
        let forming = FormingModel::new(&scenario(false, &mesh(8.0, pattern, 0.0))).unwrap();
        let note = forming
            .notes
            .iter()
            .any(|n| n.contains("bending of these triangles is soft"));
        assert_eq!(note, noted, "{pattern}: {:?}", forming.notes);
    }
}
