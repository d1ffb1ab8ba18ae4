//! The exported formed blank read by a real reader: CalculiX (`ccx`) runs `formed-blank.inp`
//! of a short forming run with a material and a static step appended, with one material and
//! with a non-orthogonal material per band of shear angle (`examples/next-analysis/
//! band_materials.py`); a flat plate written by the same writer shows that CalculiX takes each
//! element's orientation and thickness, and that the stiffness follows a sheared weft.
//!
//! Without `ccx` on the PATH these tests fail when `CI` is set (CI installs it: `.ci/run`) and
//! are skipped, with a printed line, otherwise (`tests/common/calculix.rs`).

mod common;

use common::calculix::{ccx_available, dat_rows, run_ccx};
use common::{run_ok, scratch_dir};
use nalgebra::Vector3;
use std::path::Path;
use thermostamp::mesh::abaqus::{write_inp, ElementOutput};
use thermostamp::mesh::{rectangle, DiagonalPattern};

/// Runs the recipe's script on `dir/deck` (the moduli of the docs' example: yarns 40 GPa along
/// themselves, an isotropic matrix of 3.8 GPa, 0.35), writing `dir/bands.inp`; its line.
fn band_materials(dir: &Path, deck: &str, band: f64) -> String {
    let band = band.to_string();
    common::run_python(
        "examples/next-analysis/band_materials.py",
        &[
            deck,
            "--warp-modulus",
            "40000",
            "--weft-modulus",
            "40000",
            "--matrix-modulus",
            "3800",
            "--matrix-poisson",
            "0.35",
            "--band",
            &band,
            "--output",
            "bands.inp",
        ],
        dir,
    )
}

/// The hemisphere example, 10 mm cells, 4 mm of stroke: its `formed-blank.inp`, included
/// unchanged in a deck with an elastic material, the `left` edge clamped and 1 N a node on the
/// `right` edge along z, runs to the end in CalculiX, and the reaction on the clamped edge is
/// the load applied (17 nodes: 17 N), the displacements of every node in the `.frd` file.
#[test]
fn the_formed_blank_runs_in_calculix() {
    if !ccx_available("the_formed_blank_runs_in_calculix") {
        return;
    }
    let dir = scratch_dir("export_calculix", "formed");
    let run = dir.join("run");
    let _ = std::fs::remove_dir_all(&run);
    run_ok(&[
        "run",
        "examples/hemisphere.toml",
        "--set",
        "blank.element_size=10",
        "--set",
        "process.stroke=4",
        "--set",
        "output.frames=1",
        "--output",
        run.to_str().unwrap(),
    ]);
    let deck = std::fs::read_to_string(run.join("formed-blank.inp")).unwrap();
    let right = deck
        .lines()
        .skip_while(|l| !l.eq_ignore_ascii_case("*NSET, NSET=right"))
        .skip(1)
        .take_while(|l| !l.starts_with('*'))
        .flat_map(|l| l.split(','))
        .count();
    assert_eq!(right, 17);
    std::fs::write(dir.join("formed-blank.inp"), &deck).unwrap();
    std::fs::write(
        dir.join("job.inp"),
        "*INCLUDE, INPUT=formed-blank.inp\n\
         *MATERIAL, NAME=PREPREG\n*ELASTIC\n10000.0, 0.3\n\
         *BOUNDARY\nleft, 1, 6\n\
         *STEP\n*STATIC\n*CLOAD\nright, 3, 1.0\n\
         *NODE PRINT, NSET=left, TOTALS=ONLY\nRF\n*NODE FILE\nU\n*END STEP\n",
    )
    .unwrap();
    run_ccx(&dir);
    let dat = std::fs::read_to_string(dir.join("job.dat")).unwrap();
    let total = dat_rows(&dat, "total force");
    assert_eq!(total.len(), 1, "{dat}");
    let [fx, fy, fz] = total[0];
    assert!(
        (fz + right as f64).abs() < 1e-6 && fx.abs() < 1e-6 && fy.abs() < 1e-6,
        "reaction {:?} for {right} N applied along z",
        total[0]
    );
    let frd = std::fs::read_to_string(dir.join("job.frd")).unwrap();
    assert!(frd.contains("DISP"), "no displacements in job.frd");

    // the same deck with a non-orthogonal material per 2° band of shear: the weft of each
    // element is in its orientation, every band's material reads, the load goes through
    let bands = dir.join("bands");
    std::fs::create_dir_all(&bands).unwrap();
    std::fs::write(bands.join("formed-blank.inp"), &deck).unwrap();
    let line = band_materials(&bands, "formed-blank.inp", 2.0);
    assert!(line.contains("256 elements in"), "{line}");
    std::fs::write(
        bands.join("job.inp"),
        "*INCLUDE, INPUT=bands.inp\n*BOUNDARY\nleft, 1, 6\n\
         *STEP\n*STATIC\n*CLOAD\nright, 3, 1.0\n\
         *NODE PRINT, NSET=left, TOTALS=ONLY\nRF\n*END STEP\n",
    )
    .unwrap();
    run_ccx(&bands);
    let dat = std::fs::read_to_string(bands.join("job.dat")).unwrap();
    let fz = dat_rows(&dat, "total force")[0][2];
    assert!((fz + right as f64).abs() < 1e-6, "{fz}");
}

/// A flat 10 x 10 mm plate of 2 x 2 S4R elements, 0.5 mm thick, its warp along x and its weft
/// at `90° - gamma` from it, in the recipe's material of its band: pulled along y by 10 N
/// (free to contract and to shear), its stretch is `S_yy F L / (W t)`, `S` the in-plane
/// compliance of that material under plane stress; with gamma = 0 the weft is along the pull,
/// with 30° it has turned 30° away and the plate is softer, by as much as the compliance says.
#[test]
fn calculix_stiffness_follows_the_sheared_weft() {
    if !ccx_available("calculix_stiffness_follows_the_sheared_weft") {
        return;
    }
    let mut stretches = Vec::new();
    for gamma in [0.0_f64, 30.0] {
        let mesh = rectangle(10.0, 10.0, 2, 2, DiagonalPattern::Quad);
        let n = mesh.cells.len();
        let dir = scratch_dir("export_calculix", &format!("sheared-{gamma}"));
        let g = gamma.to_radians();
        write_inp(
            &dir.join("plate.inp"),
            &mesh,
            Some(&ElementOutput {
                warp: vec![Vector3::x(); n],
                weft: Some(vec![Vector3::new(g.sin(), g.cos(), 0.0); n]),
                thickness: vec![0.5; n],
            }),
        )
        .unwrap();
        let line = band_materials(&dir, "plate.inp", 1.0);
        assert!(
            line.contains(&format!("from {gamma} to {gamma} degrees")),
            "{line}"
        );
        // bottom edge held along y, one corner along x too, every node in its plane; the top
        // edge's three nodes carry 10 N as a uniform traction would (1/4, 1/2, 1/4)
        std::fs::write(
            dir.join("job.inp"),
            "*INCLUDE, INPUT=bands.inp\n*NSET, NSET=ALL, GENERATE\n1, 9, 1\n\
             *BOUNDARY\nbottom, 2, 2\n1, 1, 1\nALL, 3, 3\n\
             *STEP\n*STATIC\n*CLOAD\n7, 2, 2.5\n8, 2, 5.0\n9, 2, 2.5\n\
             *NODE PRINT, NSET=top\nU\n*END STEP\n",
        )
        .unwrap();
        run_ccx(&dir);
        let dat = std::fs::read_to_string(dir.join("job.dat")).unwrap();
        let u = dat_rows(&dat, "displacements");
        assert_eq!(u.len(), 3, "{dat}");
        let mean = u.iter().map(|r| r[1]).sum::<f64>() / 3.0;
        let expected = plane_stress_compliance_yy(gamma) * 10.0 * 10.0 / (10.0 * 0.5);
        assert!(
            (mean - expected).abs() < 0.01 * expected,
            "shear {gamma}°: stretch {mean} mm, the material's compliance gives {expected} mm"
        );
        stretches.push(mean);
    }
    assert!(stretches[1] > 1.5 * stretches[0], "{stretches:?}");
}

/// `S_yy` (1/MPa) of the recipe's material (docs/forming.md) at shear angle `gamma` (degrees)
/// under plane stress: the inverse of its 6 x 6 stiffness (Voigt, engineering shear), entry yy.
fn plane_stress_compliance_yy(gamma: f64) -> f64 {
    let (e_yarn, e_m, nu) = (40000.0, 3800.0, 0.35);
    let lam = e_m * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let mu = e_m / (2.0 * (1.0 + nu));
    let g = gamma.to_radians();
    let yarns = [[1.0, 0.0, 0.0], [g.sin(), g.cos(), 0.0]];
    let voigt = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];
    let delta = |i: usize, j: usize| f64::from(u8::from(i == j));
    let c = nalgebra::Matrix6::from_fn(|p, q| {
        let ((i, j), (k, l)) = (voigt[p], voigt[q]);
        let iso = lam * delta(i, j) * delta(k, l)
            + mu * (delta(i, k) * delta(j, l) + delta(i, l) * delta(j, k));
        iso + yarns
            .iter()
            .map(|y| e_yarn * y[i] * y[j] * y[k] * y[l])
            .sum::<f64>()
    });
    c.try_inverse().unwrap()[(1, 1)]
}

/// A flat 10 x 10 mm plate of two S3 elements, then of one S4R, written with a thickness of
/// 0.5 mm and the warp along x, then along y, in an orthotropic material (E1 = 100 GPa, E2 = 1 GPa, no Poisson
/// effect), clamped on its left edge and pulled by 10 N on each right node: CalculiX's
/// stretch is F L / (E t W) with the E of the warp's direction and the written thickness,
/// 4e-4 mm then 4e-2 mm. (CalculiX 2.20 applies only the default line of an orientation
/// `*DISTRIBUTION` to every element: an export in that form would give 4e-4 mm both times.)
#[test]
fn calculix_takes_each_elements_orientation_and_thickness() {
    if !ccx_available("calculix_takes_each_elements_orientation_and_thickness") {
        return;
    }
    for (pattern, warp, modulus) in [
        (DiagonalPattern::Right, Vector3::x(), 100e3),
        (DiagonalPattern::Right, Vector3::y(), 1e3),
        (DiagonalPattern::Quad, Vector3::x(), 100e3),
        (DiagonalPattern::Quad, Vector3::y(), 1e3),
    ] {
        let mesh = rectangle(10.0, 10.0, 1, 1, pattern);
        let n = mesh.cells.len();
        let dir = scratch_dir("export_calculix", &format!("plate-{pattern:?}-{modulus}"));
        write_inp(
            &dir.join("plate.inp"),
            &mesh,
            Some(&ElementOutput {
                warp: vec![warp; n],
                weft: None,
                thickness: vec![0.5; n],
            }),
        )
        .unwrap();
        std::fs::write(
            dir.join("job.inp"),
            "*INCLUDE, INPUT=plate.inp\n\
             *MATERIAL, NAME=PREPREG\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n\
             100000.0, 1000.0, 1000.0, 0.0, 0.0, 0.0, 500.0, 500.0\n500.0, 0.0\n\
             *BOUNDARY\nleft, 1, 6\n\
             *STEP\n*STATIC\n*CLOAD\nright, 1, 10.0\n\
             *NODE PRINT, NSET=right\nU\n*END STEP\n",
        )
        .unwrap();
        let kind = if pattern == DiagonalPattern::Quad {
            "S4R"
        } else {
            "S3"
        };
        let plate = std::fs::read_to_string(dir.join("plate.inp")).unwrap();
        assert!(
            plate.contains(&format!("*ELEMENT, TYPE={kind}\n")),
            "{plate}"
        );
        run_ccx(&dir);
        let dat = std::fs::read_to_string(dir.join("job.dat")).unwrap();
        let u = dat_rows(&dat, "displacements");
        assert_eq!(u.len(), 2, "{dat}");
        let expected = 20.0 * 10.0 / (modulus * 0.5 * 10.0);
        for [ux, _, _] in u {
            assert!(
                (ux - expected).abs() < 1e-6 * expected,
                "{kind}, warp {warp:?}: stretch {ux} mm, expected {expected} mm"
            );
        }
    }
}
