//! Press set-ups as a user writes them (docs/guide/scenario.md, "Tool motions" and "Springs,
//! grippers and gravity"): a strip hanging under gravity against the elastic catenary of its own
//! membrane law, springs against the weight they carry, a preloaded pair, matched dies closing
//! on a stack, stages against the same motion as one table, a tool dragging a squeezed blank
//! with `mu N`, and the refusals of motions that cannot run.

mod common;

use nalgebra::{Matrix2, Vector3};
use std::path::{Path, PathBuf};
use thermostamp::contact::{write_stl_ascii, TriangleSurface};
use thermostamp::forming::run::{run, FormingRun};
use thermostamp::forming::{FormingModel, Scenario};
use thermostamp::material::{FibreDirections, MaterialCard, MembraneKinematics};
use thermostamp::solver::implicit::{self, ImplicitSettings};

/// The shipped card without its bending rigidity: a membrane, what the catenary assumes.
fn membrane_card(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(common::repo_path("materials/t300-5hs-pps.toml")).unwrap();
    let start = text.find("\n[bending]").unwrap();
    let end = text.find("\n[thermal]").unwrap();
    let path = dir.join("membrane.toml");
    std::fs::write(&path, format!("{}{}", &text[..start], &text[end..])).unwrap();
    path
}

/// A flat square plate of half-side `half` in the plane `z`, its normal `+z`.
fn plate(dir: &Path, name: &str, z: f64, half: f64) -> PathBuf {
    let vertices = vec![
        Vector3::new(-half, -half, z),
        Vector3::new(half, -half, z),
        Vector3::new(half, half, z),
        Vector3::new(-half, half, z),
    ];
    let surface = TriangleSurface {
        vertices,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
    };
    let path = dir.join(format!("{name}.stl"));
    write_stl_ascii(&path, &surface, name).unwrap();
    path
}

/// A scenario between two flat plates, the punch's at `punch_z` and the die's at `die_z`, on
/// the card `card`, with `rest` appended; run from `dir`.
fn between_plates(
    dir: &Path,
    card: &Path,
    (punch_z, die_z): (f64, f64),
    blank: &str,
    rest: &str,
) -> String {
    let punch = plate(dir, "punch", punch_z, 200.0);
    let die = plate(dir, "die", die_z, 200.0);
    format!(
        "[blank]\ncard = \"{}\"\n{blank}\n\
         [tools]\nshape = \"files\"\npunch = {{ file = \"{}\" }}\ndie = {{ file = \"{}\" }}\n\
         {rest}",
        card.display(),
        punch.display(),
        die.display()
    )
}

fn form(text: &str, dir: &Path, overrides: &[&str]) -> (FormingModel, FormingRun) {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    let scenario = Scenario::from_text(text, "test.toml", dir, &overrides).unwrap();
    let forming = FormingModel::new(&scenario).unwrap();
    let result = run(&forming, None, None);
    (forming, result)
}

fn refusal(text: &str, dir: &Path, overrides: &[&str]) -> String {
    let overrides: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    match Scenario::from_text(text, "test.toml", dir, &overrides) {
        Err(e) => e.to_string(),
        Ok(s) => match FormingModel::new(&s) {
            Err(e) => e,
            Ok(_) => panic!("{overrides:?} was not refused"),
        },
    }
}

/// The membrane force along the warp per unit reference width (N/mm) of the card's laminate
/// stretched by `stretch` along the warp at rest, the weft held at its length.
fn warp_force(card: &MaterialCard, stretch: f64) -> f64 {
    let laminate = card.laminate.at_temperature(300.0);
    let kin = MembraneKinematics {
        c: Matrix2::new(stretch * stretch, 0.0, 0.0, 1.0),
        c_dot: Matrix2::zeros(),
        temperature: 300.0.into(),
        fibres: FibreDirections::default(),
    };
    let mut state = laminate.initial_state();
    let response = laminate.membrane_response(&kin, 1.0, &mut state).unwrap();
    // the resultant is per current width, along the current (stretched) warp: per reference
    // width it is the same, the weft not being stretched
    response.n[(0, 0)] * stretch
}

/// The sag (mm) of an elastic string of reference length `span`, hung between two points
/// `span` apart, under `w` N per reference length, its tension `t(stretch)`: the horizontal
/// tension `H` found by bisection so that the string reaches its supports, the sag the integral
/// of `dz/dS = stretch V / T` over the half string (`V = w S`, `T = sqrt(H^2 + V^2)`).
fn elastic_catenary_sag(span: f64, w: f64, t: &dyn Fn(f64) -> f64) -> f64 {
    let stretch_at = |tension: f64| {
        let (mut lo, mut hi) = (1.0, 1.001);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if t(mid) < tension {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let half = 0.5 * span;
    let steps = 400;
    let integrate = |h: f64| {
        let (mut x, mut z) = (0.0, 0.0);
        for i in 0..steps {
            let s = (i as f64 + 0.5) / steps as f64 * half;
            let v = w * s;
            let tension = h.hypot(v);
            let stretch = stretch_at(tension);
            x += stretch * h / tension * half / steps as f64;
            z += stretch * v / tension * half / steps as f64;
        }
        (x, z)
    };
    let (mut lo, mut hi): (f64, f64) = (1e-6, 1e3);
    for _ in 0..60 {
        let mid = (lo * hi).sqrt();
        if integrate(mid).0 < half {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    integrate((lo * hi).sqrt()).1
}

/// A 200 x 10 mm membrane strip held at both ends hangs under gravity; its sag at mid-span is
/// the elastic catenary's of its own warp law within 1 %.
#[test]
fn a_strip_hung_by_its_ends_sags_as_its_elastic_catenary() {
    let dir = common::scratch_dir("press_setups", "catenary");
    let card_path = membrane_card(&dir);
    let text = between_plates(
        &dir,
        &card_path,
        (-80.0, 80.0),
        "width = 200.0\nlength = 10.0\nelement_size = 2.5\n",
        "[[boundary]]\nnode_set = \"left\"\nheld = [\"x\", \"y\", \"z\"]\n\
         [[boundary]]\nnode_set = \"right\"\nheld = [\"x\", \"y\", \"z\"]\n\
         [process]\ntemperature = 300.0\ngravity = [0.0, 0.0, -9806.65]\n\
         [[process.stages]]\ntools = [\"punch\"]\ntravel = 1.0\nspeed = 0.5\n\
         [process.friction]\npunch = 0.0\ndie = 0.0\nholder = 0.0\n\
         [output]\nframes = 0\nhistory_points = 10\n",
    );
    let (forming, result) = form(&text, &dir, &[]);
    let state = result.outcome.as_ref().expect("the run ends");
    let mid: f64 = state
        .positions
        .iter()
        .zip(&forming.model.mesh.nodes)
        .filter(|(_, x0)| x0.x.abs() < 1e-9)
        .map(|(x, _)| x.z)
        .sum::<f64>()
        / 5.0;
    let card = MaterialCard::load(&card_path).unwrap();
    let w = card.density * card.laminate.reference_thickness() * 10.0 * 9806.65;
    let t = |stretch: f64| 10.0 * warp_force(&card, stretch);
    let sag = elastic_catenary_sag(200.0, w, &t);
    assert!(sag > 0.1, "the reference sags: {sag} mm");
    assert!(
        (-mid - sag).abs() < 0.01 * sag,
        "the strip sags {} mm at mid-span, its elastic catenary {sag} mm",
        -mid
    );
    let last = result.records.last().unwrap();
    assert!(
        (last.supports.sag + mid).abs() < 0.02 * sag,
        "{:?}",
        last.supports
    );
}

/// A blank between far plates, for the tests of the supports.
fn hanging(dir: &Path, rest: &str) -> String {
    between_plates(
        dir,
        &common::repo_path("materials/t300-5hs-pps.toml"),
        (-60.0, 60.0),
        "width = 100.0\nlength = 100.0\nelement_size = 10.0\n",
        &format!(
            "{rest}\n[process]\ntemperature = 300.0\n\
             [[process.stages]]\ntools = [\"punch\"]\ntravel = 1.0\nspeed = 1.0\n\
             [process.friction]\npunch = 0.0\ndie = 0.0\nholder = 0.0\n\
             [output]\nframes = 0\nhistory_points = 10\n"
        ),
    )
}

/// Four springs straight up from the corners of a blank: at rest, what they pull balances the
/// blank's weight, and each is stretched by its share of the weight over its stiffness.
#[test]
fn springs_balance_the_weight_of_the_blank_they_hold() {
    let dir = common::scratch_dir("press_setups", "springs");
    let corner = |x: f64, y: f64| {
        format!(
            "[[springs]]\nat = [{x}, {y}]\nstiffness = 0.01\nfree_length = 20.0\n\
             direction = [0.0, 0.0, 1.0]\n"
        )
    };
    let springs: String = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)]
        .iter()
        .map(|&(x, y)| corner(x, y))
        .collect();
    let (forming, result) = form(&hanging(&dir, &springs), &dir, &[]);
    let state = result.outcome.as_ref().expect("the run ends");
    let weight: f64 = forming.model.physical_nodal_masses().iter().sum::<f64>() * 9806.65;
    let loads = &state.supports.loads;
    assert!(
        (loads.weight.z + weight).abs() < 1e-12 * weight,
        "gravity is on by default"
    );
    let pulled: Vector3<f64> = loads.springs.iter().sum();
    assert!(
        (pulled + loads.weight).norm() < 1e-3 * weight,
        "springs {pulled:?} against the weight {weight} N"
    );
    for f in &loads.springs {
        assert!((f.z - 0.25 * weight).abs() < 0.02 * weight, "{f:?}");
    }
    let corner_drop = -state
        .positions
        .iter()
        .zip(&forming.model.mesh.nodes)
        .filter(|(_, x0)| x0.x.abs() > 49.0 && x0.y.abs() > 49.0)
        .map(|(x, x0)| x.z - x0.z)
        .sum::<f64>()
        / 4.0;
    let stretch = 0.25 * weight / 0.01;
    assert!(
        (corner_drop - stretch).abs() < 0.02 * stretch,
        "the corners dropped {corner_drop} mm, the springs stretch {stretch} mm"
    );
}

/// Two spring sets on the same nodes pulling opposite ways with the same preload: nothing
/// moves, and each holds its preload to 1e-6.
#[test]
fn a_preloaded_spring_pair_holds_its_preload() {
    let dir = common::scratch_dir("press_setups", "preload");
    let pair = "[[springs]]\nat = [0.0, 0.0]\nradius = 25.0\nstiffness = 0.5\nfree_length = 5.0\n\
                preload = 2.0\ndirection = [1.0, 0.0, 0.0]\n\
                [[springs]]\nat = [0.0, 0.0]\nradius = 25.0\nstiffness = 0.5\nfree_length = 5.0\n\
                preload = 2.0\ndirection = [-1.0, 0.0, 0.0]\n";
    let text = hanging(&dir, pair);
    let (forming, result) = form(&text, &dir, &["process.gravity=[0.0, 0.0, 0.0]"]);
    let state = result.outcome.as_ref().expect("the run ends");
    assert!(forming.model.supports.gravity.is_none());
    for f in &state.supports.loads.springs {
        assert!((f.norm() - 2.0).abs() < 2e-6, "{f:?}");
    }
    let moved = state
        .positions
        .iter()
        .zip(&forming.model.mesh.nodes)
        .map(|(x, x0)| (x - x0).norm())
        .fold(0.0, f64::max);
    assert!(moved < 1e-9, "the blank moved {moved} mm");
}

/// Matched flat dies close on a stack of two plies until the gap is the stack's thickness: the
/// plies end where the stack puts them, no node outside the gap by a tenth of a ply, and the
/// contact, rigid through the thickness until it is crossed, takes no force; pushed with a
/// force instead, the die carries it.
#[test]
fn matched_dies_close_on_a_flat_stack_to_its_thickness() {
    let dir = common::scratch_dir("press_setups", "matched");
    let card = common::repo_path("materials/t300-5hs-pps.toml");
    let ply = MaterialCard::load(&card)
        .unwrap()
        .laminate
        .reference_thickness();
    let stack = 2.0 * ply;
    let blank = "width = 60.0\nlength = 60.0\nelement_size = 10.0\n";
    let rest = "[process]\ntemperature = 300.0\n\
                [[process.stages]]\ntools = [\"die\"]\nclose_to = \"punch\"\nspeed = 1.0\n\
                [process.friction]\npunch = 0.2\ndie = 0.2\nholder = 0.2\n\
                [output]\nframes = 0\nhistory_points = 10\n";
    let two = format!("{blank}ply_angles = [0.0, 90.0]\n[blank.interply]\nfriction = 0.2\n");
    let text = between_plates(&dir, &card, (-0.5 * stack, 0.5 * stack + 2.0), &two, rest);
    let (forming, result) = form(&text, &dir, &[]);
    let state = result.outcome.as_ref().expect("the run ends");
    let die = state.tool_translations[forming.die_tool].z;
    assert!((die + 2.0).abs() < 1e-6, "the die closed by {} mm", -die);
    for (p, mid) in forming.model.plies.iter().zip([-0.5 * ply, 0.5 * ply]) {
        for n in p.nodes.clone() {
            let off = (state.positions[n].z - mid).abs();
            assert!(
                off < 0.1 * ply,
                "node {n} is {off} mm off its place in the stack"
            );
        }
    }
    assert!(result.records.last().unwrap().die_force > 0.0);

    // one ply closed on to its thickness: each node pressed by both tools' springs, each
    // engaged from a tenth of half the ply before touching, the die carries
    // `sum_n k_n (t / 20)`
    let one = between_plates(&dir, &card, (-0.5 * ply, 0.5 * ply + 2.0), blank, rest);
    let (forming, result) = form(&one, &dir, &[]);
    result.outcome.as_ref().expect("the run ends");
    let settings = ImplicitSettings::new(1.0, 1.0);
    let layout = implicit::layout(&forming.model, &settings, &[]).unwrap();
    let springs: f64 = layout.penalty.iter().sum();
    let expected = springs * 0.1 * 0.5 * ply;
    let closing = result.records.last().unwrap().die_force;
    assert!(
        (closing - expected).abs() < 0.01 * expected,
        "the die carries {closing} N, the contact's springs {expected} N"
    );

    let text = between_plates(&dir, &card, (-0.5 * stack, 0.5 * stack + 2.0), &two, rest);
    let (forming, result) = form(
        &text.replace(
            "[[process.stages]]\ntools = [\"die\"]\nclose_to = \"punch\"",
            "[[process.stages]]\ntools = [\"punch\"]\ntravel = 0.1",
        ),
        &dir,
        &["tools.die.motion.force=50"],
    );
    let state = result.outcome.as_ref().expect("the run ends");
    let last = result.records.last().unwrap();
    assert!(
        (last.die_force - 50.0).abs() < 0.5,
        "the die carries {} N",
        last.die_force
    );
    let top = forming.model.plies[1].nodes.clone();
    let lowest = top
        .map(|n| state.positions[n].z)
        .fold(f64::INFINITY, f64::min);
    assert!(lowest > 0.5 * ply - 0.1 * ply, "squeezed to {lowest} mm");
}

/// The holder closing by 1 mm and then the punch, as stages, is the run of the same motions
/// written as speed tables, to round-off.
#[test]
fn stages_are_the_same_motion_written_as_one_table() {
    let base = [
        "blank.element_size=10".to_string(),
        "process.blank_holder_force=0".into(),
        "process.blank_holder_gap=1.2".into(),
        "output.history_points=12".into(),
    ];
    let scenario_text = std::fs::read_to_string(common::repo_path("examples/hemisphere.toml"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("stroke =") && !l.starts_with("punch_speed ="))
        .collect::<Vec<_>>()
        .join("\n");
    let folder = common::repo_path("examples");
    let staged_text = format!(
        "{scenario_text}\n[[process.stages]]\ntools = [\"holder\"]\ntravel = 1.0\nspeed = 2.0\n\
         [[process.stages]]\ntools = [\"punch\"]\ntravel = 10.0\nspeed = 10.0\n"
    );
    let staged = {
        let s = Scenario::from_text(&staged_text, "staged", &folder, &base).unwrap();
        let f = FormingModel::new(&s).unwrap();
        let r = run(&f, None, None);
        (f, r)
    };
    // the stages' trapezoids: a twentieth of each stage's cruise to speed up and as long to stop
    let (cruise1, cruise2) = (1.0 / 2.0, 10.0 / 10.0);
    let (ramp1, ramp2) = (0.05 * cruise1, 0.05 * cruise2);
    let end1 = 0.0 + cruise1 + ramp1;
    let end2 = end1 + cruise2 + ramp2;
    let tables = [
        format!(
            "tools.holder.motion.speed=[[0.0, 0.0], [{ramp1:e}, 2.0], [{:e}, 2.0], [{end1:e}, 0.0]]",
            end1 - ramp1
        ),
        format!(
            "tools.punch.motion.speed=[[0.0, 0.0], [{end1:e}, 0.0], [{:e}, 10.0], [{:e}, 10.0], [{end2:e}, 0.0]]",
            end1 + ramp2,
            end2 - ramp2
        ),
    ];
    let overrides: Vec<String> = base.iter().cloned().chain(tables).collect();
    let tabled = {
        let s = Scenario::from_text(&scenario_text, "tabled", &folder, &overrides).unwrap();
        let f = FormingModel::new(&s).unwrap();
        let r = run(&f, None, None);
        (f, r)
    };
    let (a, b) = (
        staged.1.outcome.as_ref().expect("the staged run ends"),
        tabled.1.outcome.as_ref().expect("the tabled run ends"),
    );
    assert!(
        (a.time - b.time).abs() < 1e-12,
        "{} against {}",
        a.time,
        b.time
    );
    assert!(staged.1.records.last().unwrap().punch_force > 0.1);
    let apart = a
        .positions
        .iter()
        .zip(&b.positions)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    assert!(apart < 1e-9, "the runs end {apart} mm apart");
    for (ra, rb) in staged.1.records.iter().zip(&tabled.1.records) {
        assert!((ra.punch_force - rb.punch_force).abs() < 1e-6 * ra.punch_force.abs().max(1.0));
        assert!((ra.holder_travel - rb.holder_travel).abs() < 1e-12);
    }
}

/// A die sliding along x over a blank squeezed against a frictionless holder by 100 N, the
/// blank held at its edge, pulls it with `mu N`: within 2 %.
#[test]
fn a_tool_sliding_along_x_drags_a_squeezed_blank_with_mu_n() {
    let dir = common::scratch_dir("press_setups", "drag");
    let card = common::repo_path("materials/t300-5hs-pps.toml");
    let half = 0.5
        * MaterialCard::load(&card)
            .unwrap()
            .laminate
            .reference_thickness();
    let holder = plate(&dir, "holder", -half, 200.0);
    let text = between_plates(
        &dir,
        &card,
        (-40.0, half),
        "width = 60.0\nlength = 60.0\nelement_size = 10.0\n",
        &format!(
            "holder = {{ file = \"{}\" }}\n\
             [[boundary]]\nnode_set = \"left\"\nheld = [\"x\"]\n\
             [process]\ntemperature = 300.0\nblank_holder_force = 100.0\n\
             [[process.stages]]\ntools = [\"die\"]\ntravel = 2.0\nspeed = 1.0\n\
             [process.friction]\npunch = 0.0\ndie = 0.3\nholder = 0.0\n\
             [output]\nframes = 0\nhistory_points = 10\n",
            holder.display()
        ),
    );
    let text = text.replace(
        "die.stl\" }",
        "die.stl\", motion = { direction = [1.0, 0.0, 0.0] } }",
    );
    let (forming, result) = form(&text, &dir, &[]);
    let state = result.outcome.as_ref().expect("the run ends");
    let load = state.tool_loads[forming.die_tool];
    let pull = -load.force.x;
    assert!(
        (pull - 0.3 * 100.0).abs() < 0.02 * 30.0,
        "the die pulls {pull} N, mu N = 30 N (normal force {} N)",
        load.normal_force
    );
}

/// An extra tool under the blank, read from a file, slides along x under a blank that the die
/// presses on it with 100 N: it pulls the blank with `mu N` within 2 %; a stage moves it by
/// its name.
#[test]
fn an_extra_tool_slides_under_a_pressed_blank_with_mu_n() {
    let dir = common::scratch_dir("press_setups", "extra");
    let card = common::repo_path("materials/t300-5hs-pps.toml");
    let half = 0.5
        * MaterialCard::load(&card)
            .unwrap()
            .laminate
            .reference_thickness();
    let sled = plate(&dir, "sled", -half, 200.0);
    let text = between_plates(
        &dir,
        &card,
        (-40.0, half),
        "width = 60.0\nlength = 60.0\nelement_size = 10.0\n",
        &format!(
            "[[tools.extra]]\nname = \"sled\"\nfile = \"{}\"\nfriction = 0.3\n\
             blank_side = \"below\"\nmotion = {{ direction = [1.0, 0.0, 0.0] }}\n\
             [[boundary]]\nnode_set = \"left\"\nheld = [\"x\"]\n\
             [process]\ntemperature = 300.0\n\
             [[process.stages]]\ntools = [\"sled\"]\ntravel = 2.0\nspeed = 1.0\n\
             [process.friction]\npunch = 0.0\ndie = 0.0\nholder = 0.0\n\
             [output]\nframes = 0\nhistory_points = 10\n",
            sled.display()
        ),
    );
    let text = text.replace("die.stl\" }", "die.stl\", motion = { force = 100.0 } }");
    let (forming, result) = form(&text, &dir, &[]);
    let state = result.outcome.as_ref().expect("the run ends");
    let sled = forming
        .model
        .tools
        .iter()
        .position(|t| t.name == "sled")
        .unwrap();
    assert!((state.tool_translations[sled].x - 2.0).abs() < 1e-9);
    let pull = -state.tool_loads[sled].force.x;
    assert!(
        (pull - 0.3 * 100.0).abs() < 0.02 * 30.0,
        "the sled pulls {pull} N, mu N = 30 N"
    );
    let e = refusal(&text, &dir, &["tools.extra[1].blank_side=\"left\""]);
    assert!(e.contains("tools.extra[1].blank_side"), "{e}");
}

/// Motions that cannot run are refused before the first step, naming their key.
#[test]
fn bad_motions_and_supports_are_refused_naming_the_key() {
    let dir = common::scratch_dir("press_setups", "refusals");
    let text = hanging(
        &dir,
        "[[springs]]\nat = [50.0, 0.0]\nstiffness = 0.01\nfree_length = 20.0\n\
         [[grippers]]\nnode_set = \"left\"\n",
    );
    let cases: [(&[&str], &[&str]); 7] = [
        (
            &["process.stages[1].travel=-1"],
            &["process.stages[1].travel"],
        ),
        (
            &["process.stages[1].speed=0"],
            &["process.stages[1].speed", "never end"],
        ),
        (
            &["springs[1].stiffness=-1"],
            &["springs[1].stiffness", "positive"],
        ),
        (
            &["springs[1].at=[47.0, 3.0]", "springs[1].radius=1e-3"],
            &["springs[1]", "empty"],
        ),
        (
            &["grippers[1].node_set=\"nowhere\""],
            &["grippers[1].node_set"],
        ),
        (
            &["grippers[1].release_force=-3"],
            &["grippers[1].release_force"],
        ),
        (&["process.stroke=5"], &["process.stroke", "stages"]),
    ];
    for (overrides, expected) in cases {
        let e = refusal(&text, &dir, overrides);
        for piece in expected {
            assert!(e.contains(piece), "{overrides:?}: '{piece}' not in {e}");
        }
    }
    let closing = text.replace(
        "[[process.stages]]\ntools = [\"punch\"]\ntravel = 1.0",
        "[[process.stages]]\ntools = [\"punch\"]\nclose_to = \"die\"",
    );
    let e = refusal(&closing, &dir, &["process.stages[1].gap=0.1"]);
    assert!(
        e.contains("process.stages[1].gap") && e.contains("thickness"),
        "{e}"
    );
    let nowhere = text.replace(
        "[[grippers]]\nnode_set = \"left\"\n",
        "[[grippers]]\nat = [47.0, 3.0]\nradius = 1e-3\n",
    );
    let e = refusal(&nowhere, &dir, &[]);
    assert!(e.contains("grippers[1]") && e.contains("empty"), "{e}");
    let e = refusal(&closing, &dir, &["tools.punch.motion.direction=[0, 0, -1]"]);
    assert!(
        e.contains("process.stages[1]") && e.contains("never"),
        "{e}"
    );
}

/// The explicit solver lets a blank on four soft springs fall under gravity as the mass on the
/// springs does, `g / w^2 (1 - cos w t)` with `w^2 = 4 k / M`, within 1 %.
#[test]
fn the_explicit_solver_drops_a_blank_on_soft_springs_as_a_mass_on_springs() {
    let dir = common::scratch_dir("press_setups", "falling");
    let k = 1e-4;
    let corner = |x: f64, y: f64| {
        format!(
            "[[springs]]\nat = [{x}, {y}]\nstiffness = {k}\nfree_length = 20.0\n\
             direction = [0.0, 0.0, 1.0]\n"
        )
    };
    let springs: String = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)]
        .iter()
        .map(|&(x, y)| corner(x, y))
        .collect();
    let text = hanging(&dir, &springs).replace("speed = 1.0", "speed = 100.0");
    let (forming, result) = form(&text, &dir, &["process.solver=\"explicit\""]);
    let state = result.outcome.as_ref().expect("the run ends");
    let masses = forming.model.physical_nodal_masses();
    let total: f64 = masses.iter().sum();
    let fall = -state
        .positions
        .iter()
        .zip(&forming.model.mesh.nodes)
        .zip(&masses)
        .map(|((x, x0), m)| (x.z - x0.z) * m)
        .sum::<f64>()
        / total;
    let w = (4.0 * k / total).sqrt();
    let expected = 9806.65 / (w * w) * (1.0 - (w * state.time).cos());
    assert!(expected > 0.1, "{expected}");
    assert!(
        (fall - expected).abs() < 0.01 * expected,
        "the blank fell {fall} mm in {} s, a mass on the springs {expected} mm",
        state.time
    );
    let balance = result.records.last().unwrap().energies.balance_error();
    assert!(balance < 1e-2, "energy balance error {balance}");
}

/// The tutorial of matched dies on springs, reduced: 10 mm cells, closed to 3 mm only. Its two
/// stages run, the blank sags before the dies touch it, and the springs pull at least their
/// preload once the punch lifts the blank.
#[test]
fn the_matched_die_example_runs_in_reduced_form() {
    let (forming, result) = common::form(
        "examples/double-dome-matched.toml",
        &[
            "blank.element_size=10".into(),
            "process.stages[2].gap=3.0".into(),
            "output.frames=0".into(),
            "output.history_points=20".into(),
        ],
    );
    result.outcome.as_ref().expect("the run ends");
    assert_eq!(forming.stages.len(), 2);
    assert_eq!(forming.model.supports.springs.len(), 8);
    assert!(
        forming.model.supports.gravity.is_some(),
        "on by default on springs"
    );
    let before: Vec<_> = result
        .records
        .iter()
        .filter(|r| r.time < forming.stages[0].1 && r.punch_force.abs() < 1e-3)
        .collect();
    assert!(
        before.iter().any(|r| r.supports.sag > 0.1),
        "no sag before the punch"
    );
    let last = result.records.last().unwrap();
    assert!(last.supports.springs > 8.0 * 5.0, "{:?}", last.supports);
    assert!(last.die_force > 0.0 && last.punch_force > 0.0);
}
