//! Issue 6's check of meshes and tools read from files: the hemisphere example formed from the
//! same blank read from a Gmsh file and from an Abaqus deck (with the ply's direction from
//! `*ORIENTATION`), and between tools read from STL files, gives the shear angles of the
//! built-in blank and tools within 0.5° in every element.
//!
//! The blank files are `tests/data/meshes/hemisphere-blank-10mm.{msh,inp}` (10 mm quadrilaterals,
//! made by `make_hemisphere_blanks.py` there, with their own node and element numbering), read
//! as quadrilaterals and so compared with the built-in blank of pattern `quad`; the
//! STL files are the built-in tool surfaces written by this test. The built-in runs' formed
//! blanks (triangles and quadrilaterals: S3 and S4R), exported for a structural analysis, are
//! read back as well.

mod common;

use common::{element_shear, largest_twin_difference, repo_path, scratch_dir};
use nalgebra::Vector3;
use std::path::Path;
use thermostamp::contact::write_stl_ascii;
use thermostamp::forming::export::{write_formed_blank, FORMED_INP};
use thermostamp::forming::{run, FormingModel, Scenario};
use thermostamp::mesh::abaqus::read_inp_with_thickness;
use thermostamp::solver::State;

/// The hemisphere example on 10 mm cells, 20 mm of stroke; `[blank]` and `[tools]` as given.
fn scenario_text(blank: &str, tools: &str) -> String {
    let card = repo_path("materials/t300-5hs-pps.toml");
    format!(
        "[blank]\ncard = {card:?}\n{blank}\n\n[tools]\n{tools}\n\n\
         [process]\nsolver = \"explicit\"\ntemperature = 300.0\nstroke = 20.0\npunch_speed = 10.0\n\
         blank_holder_force = 200.0\ntime_scaling = 10.0\ntarget_time_step = 5e-6\n\n\
         [process.friction]\npunch = 0.2\ndie = 0.2\nholder = 0.2\n\n\
         [output]\nhistory_points = 10\n"
    )
}

const RECTANGLE: &str = "width = 160.0\nlength = 160.0\nelement_size = 10.0";
const QUAD_RECTANGLE: &str =
    "width = 160.0\nlength = 160.0\nelement_size = 10.0\npattern = \"quad\"";
const BUILT_IN_TOOLS: &str = "shape = \"hemisphere\"\npunch_radius = 40.0\n\
    die_opening_radius = 42.0\ndie_fillet_radius = 5.0\nresolution = 3.0";

fn load(dir: &Path, name: &str, text: &str) -> Scenario {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    Scenario::load(&path, &[]).unwrap()
}

/// A forming run: the model, its final state, and per element the final centroid and shear
/// angle (degrees).
struct Formed {
    forming: FormingModel,
    state: State,
    shear: Vec<(Vector3<f64>, f64)>,
}

fn formed(scenario: &Scenario) -> Formed {
    let forming = FormingModel::new(scenario).unwrap();
    let result = run::run(&forming, None, None);
    let state = result.outcome.unwrap();
    let shear = element_shear(&forming.model, &state.positions);
    Formed {
        forming,
        state,
        shear,
    }
}

/// The formed blank written for the next analysis reads back as it was: nodes where the
/// forming left them (within the precision written), each element's formed thickness, and its warp direction
/// along the formed warp and in the element's plane.
fn check_export(dir: &Path, run: &Formed) {
    let model = &run.forming.model;
    let files = write_formed_blank(dir, model, &run.state).unwrap();
    assert!(files.iter().all(|f| f.exists()), "{files:?}");
    let deck = read_inp_with_thickness(&dir.join(FORMED_INP)).unwrap();
    let mesh = &deck.import.mesh;
    // at least 13 significant digits (numbers are written in at most 20 characters)
    assert_eq!(mesh.nodes.len(), run.state.positions.len());
    for (back, x) in mesh.nodes.iter().zip(&run.state.positions) {
        assert!(
            (back - x).amax() <= 5e-13 * x.amax(),
            "{x:?} read back as {back:?}"
        );
    }
    assert_eq!(mesh.cells, model.mesh.cells);
    let warp = mesh.warp_directions.as_ref().unwrap();
    for (k, e) in model.elements.iter().enumerate() {
        assert_eq!(deck.thickness[k], Some(run.state.membrane[k].thickness));
        let formed = (e.gradient(&run.state.positions) * e.fibres.warp.xy()).normalize();
        assert!((warp[k].normalize() - formed).norm() < 1e-12, "element {k}");
        let normal = mesh.cells[k].area_vector(&mesh.nodes).normalize();
        assert!(
            warp[k].dot(&normal).abs() < 1e-12,
            "element {k}: warp off its plane"
        );
    }
}

/// Largest difference of shear angle between elements with the same final centroid (every
/// element of `other` must find its twin in `reference` within 0.1 mm).
fn largest_difference(reference: &[(Vector3<f64>, f64)], other: &[(Vector3<f64>, f64)]) -> f64 {
    assert_eq!(reference.len(), other.len());
    largest_twin_difference(reference, other, 0.1)
}

/// The five runs (built-in blank in triangles and in quadrilaterals, the two blank files, the
/// STL tools) are independent: they run side by side.
#[test]
fn imported_blanks_and_tools_form_like_the_built_in_ones() {
    let dir = scratch_dir("forming", "mesh-files");
    let built_in = load(
        &dir,
        "built-in.toml",
        &scenario_text(RECTANGLE, BUILT_IN_TOOLS),
    );
    let quads = load(
        &dir,
        "built-in-quad.toml",
        &scenario_text(QUAD_RECTANGLE, BUILT_IN_TOOLS),
    );
    let files = ["hemisphere-blank-10mm.msh", "hemisphere-blank-10mm.inp"];
    let from_files = files.map(|file| {
        let mesh = repo_path(&format!("tests/data/meshes/{file}"));
        let blank = format!("mesh = {:?}", mesh);
        load(
            &dir,
            &format!("mesh-{file}.toml"),
            &scenario_text(&blank, BUILT_IN_TOOLS),
        )
    });
    // the built-in tools written as STL files
    let mut tools = String::from("shape = \"files\"\nflange_radius = 47.0\n");
    let built_in_model = FormingModel::new(&built_in).unwrap();
    for (k, key) in ["punch", "die", "holder"].iter().enumerate() {
        let path = dir.join(format!("{key}.stl"));
        let surface = &built_in_model.model.tools[k].surface;
        write_stl_ascii(&path, surface, key).unwrap();
        tools.push_str(&format!("{key} = {{ file = {:?} }}\n", path));
    }
    let stl = load(&dir, "stl.toml", &scenario_text(RECTANGLE, &tools));

    let scenarios = vec![&built_in, &quads, &from_files[0], &from_files[1], &stl];
    let [reference_run, quad_run, msh_run, inp_run, stl_run]: [Formed; 5] =
        common::side_by_side(scenarios, formed)
            .try_into()
            .unwrap_or_else(|_| unreachable!());

    check_export(&dir, &reference_run);
    let reference = &reference_run.shear;
    let largest = reference.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
    println!("built-in: largest shear {largest:.2}°");
    assert!(largest > 5.0, "too little shear to compare: {largest}°");

    // the files' quadrilaterals against the built-in blank in quadrilaterals
    check_export(&scratch_dir("forming", "mesh-files-quad"), &quad_run);
    assert!(quad_run
        .forming
        .model
        .mesh
        .cells
        .iter()
        .all(|c| c.is_quad()));
    let quad_reference = &quad_run.shear;
    let largest = quad_reference.iter().map(|r| r.1.abs()).fold(0.0, f64::max);
    println!("built-in, quadrilaterals: largest shear {largest:.2}°");
    assert!(largest > 5.0, "too little shear to compare: {largest}°");
    for (file, run) in files.iter().zip([msh_run, inp_run]) {
        assert_eq!(
            run.forming.model.mesh.cells.len(),
            256,
            "{file}: one cell per element"
        );
        let difference = largest_difference(quad_reference, &run.shear);
        println!("{file}: largest difference {difference:.2e}°");
        assert!(difference < 0.5, "{file}: {difference}°");
    }

    let difference = largest_difference(reference, &stl_run.shear);
    println!("STL tools: largest difference {difference:.2e}°");
    assert!(difference < 0.5, "STL tools: {difference}°");
}
