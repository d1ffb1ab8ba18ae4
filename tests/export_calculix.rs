//! The exported formed blank read by a real reader: CalculiX (`ccx`) runs `formed-blank.inp`
//! of a short forming run with a material and a static step appended, and a flat plate written
//! by the same writer shows that CalculiX takes each element's orientation and thickness.
//!
//! Without `ccx` on the PATH these tests fail when `CI` is set (CI installs it: `.ci/run`) and
//! are skipped, with a printed line, otherwise (`tests/common/calculix.rs`).

mod common;

use common::calculix::{ccx_available, dat_rows, run_ccx};
use common::{run_ok, scratch_dir};
use nalgebra::Vector3;
use thermostamp::mesh::abaqus::{write_inp, ElementOutput};
use thermostamp::mesh::{rectangle, DiagonalPattern};

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
