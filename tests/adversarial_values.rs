//! Values nobody means, and messages that must name the true cause (issue 38, classes 6 and 8).
//!
//! - Every number of a scenario, of the options of the virtual tests, drape, material-point and
//!   the fits, and of a material card has a physical range (`thermostamp::limits`); a value
//!   outside is refused with exit code 2, naming its key or option, instead of running (a holder
//!   force of 1e300 N, a ply turned by 1e300°). Fits refuse powers beyond what data determine
//!   (before allocating anything for them), coefficients the data leave undetermined, and data
//!   that do not vary; a fitted card that would not load names the data, not the unwritten card.
//! - A message says the true cause: tables of a card that do not overlap are refused as such
//!   when it is read; a value a rounding error past an end is at the end, one further out is
//!   shown with the digits that put it outside; a mesh group the formed blank's deck cannot
//!   name is refused when the mesh is read, not after the whole stroke.
//!
//! Everything is written under the scratch folder `adversarial/values`.

mod common;

use common::adversarial::{args as strings, check, repo, Case, Fixtures};
use common::thermostamp;
use std::path::Path;
use thermostamp::fit::synthetic::{bias_extension_curve, Lcg};
use thermostamp::limits::{ranges_help, ANGLE, LENGTH, SPEED};
use thermostamp::material::fabric::ShearInteraction;

/// `run scenario --set ... --output out/<name>`.
fn run(f: &Fixtures, name: &str, scenario: &str, sets: &[&str]) -> Vec<String> {
    let mut args = vec!["run".to_string(), scenario.to_string()];
    for set in sets {
        args.extend(["--set".to_string(), set.to_string()]);
    }
    args.extend(["--output".to_string(), f.output(name)]);
    args
}

fn cases_of(list: Vec<(&str, Vec<String>, Vec<String>)>) -> Vec<Case> {
    list.into_iter()
        .map(|(name, args, names)| Case {
            name: name.into(),
            args,
            code: 2,
            names,
        })
        .collect()
}

/// Scenario keys outside their ranges, from the file or from `--set`.
fn scenario_cases(f: &Fixtures) -> Vec<Case> {
    let example = repo("tests/data/hemisphere-explicit.toml");
    let edits: [(&str, &str, &str, &str); 6] = [
        (
            "direction overflowing",
            "ply_angle = 0.0",
            "ply_angle = 0.0\nreference_direction = [1e300, 1e300, 0.0]",
            "blank.reference_direction = [1e300, 1e300, 0]",
        ),
        (
            "direction underflowing",
            "ply_angle = 0.0",
            "ply_angle = 0.0\nreference_direction = [1e-200, 0.0, 0.0]",
            "blank.reference_direction = [1e-200, 0, 0]",
        ),
        (
            "punch of 1e300 mm",
            "punch_radius = 40.0",
            "punch_radius = 1e300",
            "tools.punch_radius = 1e300 mm",
        ),
        (
            "holder gap of 1e300 mm",
            "blank_holder_force = 200.0",
            "blank_holder_gap = 1e300",
            "process.blank_holder_gap = 1e300 mm",
        ),
        (
            "ply angle beyond a turn",
            "ply_angle = 0.0",
            "ply_angle = 1e300",
            "blank.ply_angle = 1e300°",
        ),
        (
            "frames by the billion",
            "frames = 10",
            "frames = 1000000000",
            "output.frames = 1e9",
        ),
    ];
    let mut list: Vec<(&str, Vec<String>, Vec<String>)> = edits
        .iter()
        .map(|(name, from, to, piece)| {
            let path = f.scenario(&name.replace(' ', "-"), from, to);
            (*name, run(f, name, &path, &[]), strings(&[piece]))
        })
        .collect();
    let sets: [(&str, &str, &[&str]); 7] = [
        (
            "holder force of 1e300 N",
            "process.blank_holder_force=1e300",
            &["process.blank_holder_force = 1e300 N", "1e7 N"],
        ),
        (
            "holder pressing at 195 MPa",
            "process.blank_holder_force=5e6",
            &["process.blank_holder_force", "mean pressure", "50 MPa"],
        ),
        (
            "friction of 1e300",
            "process.friction.holder=1e300",
            &["process.friction.holder"],
        ),
        (
            "time scaling of 1e300",
            "process.time_scaling=1e300",
            &["process.time_scaling"],
        ),
        (
            "below absolute zero",
            "process.temperature=-300",
            &["process.temperature = -300 °C", "-273.15"],
        ),
        (
            "punch at 1 km/s",
            "process.punch_speed=1e6",
            &["process.punch_speed", "mm/s"],
        ),
        (
            "history of a trillion rows",
            "output.history_points=1000000000000",
            &["output.history_points"],
        ),
    ];
    list.extend(
        sets.iter()
            .map(|(name, set, pieces)| (*name, run(f, name, &example, &[set]), strings(pieces))),
    );
    cases_of(list)
}

/// Options of the virtual tests, drape and material-point outside their ranges.
fn option_cases(f: &Fixtures) -> Vec<Case> {
    let fabric = repo("materials/twintex-plain-weave.toml");
    let example = repo("tests/data/hemisphere-explicit.toml");
    let history = repo("examples/material-point/laminate-shear-300C.csv");
    let card = repo("materials/t300-5hs-pps.toml");
    let test = |kind: &str, name: &str, extra: &[&str]| {
        let mut args = strings(&["test", kind, "--card", &fabric, "--output"]);
        args.push(f.output(name));
        args.extend(strings(extra));
        args
    };
    let list = vec![
        (
            "test ply angle of 1e300",
            test("uniaxial", "ply", &["--ply-angle", "1e300"]),
            strings(&["--ply-angle 1e300°"]),
        ),
        (
            "test damping of 1e300",
            test("bias-extension", "damping", &["--damping", "1e300"]),
            strings(&["--damping 1e300 1/s"]),
        ),
        (
            "test below absolute zero",
            test("picture-frame", "cold", &["--temperature", "-300"]),
            strings(&["--temperature -300 °C"]),
        ),
        (
            "test specimen of 1e300 mm",
            test("picture-frame", "side", &["--side", "1e300"]),
            strings(&["--side 1e300 mm"]),
        ),
        (
            "test history of ten million rows",
            test("uniaxial", "rows", &["--history-points", "10000000"]),
            strings(&["--history-points"]),
        ),
        (
            "drape warp angle of 1e300",
            strings(&[
                "drape",
                &example,
                "--warp-angle",
                "1e300",
                "--output",
                &f.output("drape-angle"),
            ]),
            strings(&["--warp-angle"]),
        ),
        (
            "material point angle of 1e300",
            strings(&[
                "material-point",
                "--card",
                &card,
                "--layer",
                "laminate",
                "--history",
                &history,
                "--angle",
                "-1e300",
            ]),
            strings(&["--angle -1e300°"]),
        ),
    ];
    cases_of(list)
}

/// Card values outside their ranges, read by `material-point` (the fastest reader).
fn card_cases(f: &Fixtures) -> Vec<Case> {
    let history = repo("examples/material-point/laminate-shear-300C.csv");
    let edits: [(&str, &str, &str, &str); 5] = [
        (
            "density of 1e300",
            "density = 1.56e-9",
            "density = 1.56e300",
            "density = 1.56e300 tonne/mm^3",
        ),
        (
            "c10 of 1e300",
            "c10 = [80.0, 50.0, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10, 0.05]",
            "c10 = [80.0, 1e300, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10, 0.05]",
            "[matrix] c10[1] = 1e300 MPa",
        ),
        (
            "ply a kilometre thick",
            "fabric_thickness = 0.23",
            "fabric_thickness = 1e6",
            "[layers] fabric_thickness",
        ),
        (
            "shear stiffer than any fibre",
            "shear = [0.25, 0.0, 2.0]",
            "shear = [0.25, 0.0, 2.0e9]",
            "W_s'(I10)",
        ),
        (
            "bending rigidity of 1e300",
            "weft = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
            "weft = [120.0, 1e300, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
            "[bending] weft[1]",
        ),
    ];
    let list = edits
        .iter()
        .map(|(name, from, to, piece)| {
            let path = f.card(&format!("card-{}", name.replace(' ', "-")), from, to);
            let args = strings(&[
                "material-point",
                "--card",
                &path,
                "--layer",
                "laminate",
                "--history",
                &history,
            ]);
            (*name, args, vec![path, piece.to_string()])
        })
        .collect();
    cases_of(list)
}

/// Where the fits write a card that must not appear.
fn fitted(f: &Fixtures, name: &str) -> String {
    f.dir
        .join(format!("fitted-{name}.toml"))
        .display()
        .to_string()
}

/// A bias-extension curve (150 x 450 mm, 1.2 mm fabric) of a law whose shear force rises up to
/// 33° but whose energy falls from 72°: fitted up to 30° it is recovered and stiffens over the
/// fitted range, but no card may hold it.
fn curve_softening_beyond_the_fit(f: &Fixtures) -> String {
    let law = ShearInteraction::new(vec![0.02, -0.02 / 1.8]);
    let text = bias_extension_curve(
        &law,
        1.2,
        (150.0, 450.0),
        (32f64.to_radians(), 60),
        0.0,
        &mut Lcg::new(1),
    );
    f.file("softening-beyond.csv", text.as_bytes())
}

/// The fits' refusals: terms beyond what data determine, data that do not vary, a card that
/// the fitted coefficients would make unloadable; with the output each must not write.
fn fit_cases(f: &Fixtures) -> Vec<(Case, String)> {
    let fabric = repo("materials/twintex-plain-weave.toml");
    let card = repo("materials/t300-5hs-pps.toml");
    let benchmark = repo("examples/fit-shear/bias_extension_glass_pp_plain_150x450.csv");
    let warp = repo("examples/fit-fabric-tension/warp.csv");
    let manifest = repo("examples/fit-matrix/manifest.toml");
    let mut flat_force = String::from("displacement_mm,force_N\n");
    let mut flat_tension = String::from("strain,force_per_width\n");
    for i in 0..40 {
        flat_force.push_str(&format!("{i},5\n"));
        flat_tension.push_str(&format!("{},5\n", 0.001 * f64::from(i)));
    }
    let flat_force = f.file("flat-force.csv", flat_force.as_bytes());
    let flat_tension = f.file("flat-tension.csv", flat_tension.as_bytes());
    let softening = curve_softening_beyond_the_fit(f);
    let shear = |name: &str, data: &str, extra: &[&str]| {
        let mut args = strings(&[
            "fit", "shear", "--data", data, "--width", "150", "--length", "450", "--card", &fabric,
            "--output",
        ]);
        args.push(fitted(f, name));
        args.extend(strings(extra));
        (args, fitted(f, name))
    };
    let tension = |name: &str, data: &str, extra: &[&str]| {
        let mut args = strings(&["fit", "fabric-tension", "--warp", data, "--card", &card]);
        args.extend(["--output".to_string(), fitted(f, name)]);
        args.extend(strings(extra));
        (args, fitted(f, name))
    };
    let list = vec![
        (
            "fit shear power 100",
            shear("p100", &benchmark, &["--terms", "1,100"]),
            strings(&["--terms 1,100", "power 100 is beyond 10"]),
        ),
        (
            "fit shear 4294967295 terms",
            shear("p-max", &benchmark, &["--terms", "4294967295"]),
            strings(&["--terms", "beyond 10"]),
        ),
        (
            "fit shear power past any integer",
            shear(
                "p-huge",
                &benchmark,
                &["--terms", "friction,99999999999999999999999"],
            ),
            strings(&["--terms", "beyond 10"]),
        ),
        (
            "fit shear coefficient undetermined",
            shear(
                "undetermined",
                &benchmark,
                &[
                    "--terms",
                    "friction,1,2",
                    "--friction-onset",
                    "3",
                    "--max-shear",
                    "35",
                ],
            ),
            strings(&[
                &benchmark,
                "do not determine c1",
                "standard error",
                "--terms friction,1,2",
            ]),
        ),
        (
            "fit shear constant force",
            shear("flat", &flat_force, &["--terms", "1"]),
            strings(&[&flat_force, "does not vary", "5 N"]),
        ),
        (
            "fit shear card that would not load",
            shear(
                "softening",
                &softening,
                &["--terms", "1,2", "--max-shear", "30"],
            ),
            strings(&[&softening, "is not written", "checked up to 75°"]),
        ),
        (
            "fit shear max shear of 1e300",
            shear("max-shear", &benchmark, &["--max-shear", "1e300"]),
            strings(&["--max-shear 1e300°"]),
        ),
        (
            "fit shear speed of 1e300",
            shear("speed", &benchmark, &["--speed", "1e300"]),
            strings(&["--speed 1e300 mm/s"]),
        ),
        (
            "fit tension 4294967295 terms",
            tension("t-max", &warp, &["--terms", "4294967295"]),
            strings(&["--terms 4294967295", "more than the 10"]),
        ),
        (
            "fit tension constant force",
            tension("t-flat", &flat_tension, &[]),
            strings(&[&flat_tension, "does not vary"]),
        ),
        (
            "fit tension strip of 1e300 mm",
            tension("t-width", &warp, &["--width", "1e300"]),
            strings(&["--width 1e300 mm"]),
        ),
        (
            "fit matrix bulk modulus of 1e-300",
            (
                strings(&[
                    "fit",
                    "matrix",
                    "--manifest",
                    &manifest,
                    "--card",
                    &card,
                    "--bulk-modulus",
                    "1e-300",
                    "--output",
                    &fitted(f, "bulk"),
                ]),
                fitted(f, "bulk"),
            ),
            strings(&["--bulk-modulus 1e-300 MPa"]),
        ),
    ];
    list.into_iter()
        .map(|(name, (args, output), names)| {
            (
                Case {
                    name: name.into(),
                    args,
                    code: 2,
                    names,
                },
                output,
            )
        })
        .collect()
}

/// Messages that used to hide or misname their cause.
fn true_cause_cases(f: &Fixtures) -> Vec<Case> {
    let example = repo("tests/data/hemisphere-explicit.toml");
    let apart = f.card(
        "card-tables-apart",
        "temperature = [150.0, 170.0, 200.0, 230.0, 245.0, 260.0, 280.0, 300.0, 320.0]\nwarp = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]\nweft = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
        "temperature = [100.0]\nwarp = [1.58]\nweft = [1.58]",
    );
    let on_apart = f.scenario_on_card("scenario-tables-apart", &apart);
    let disk = std::fs::read_to_string(repo("tests/data/meshes/disk.msh")).unwrap();
    assert!(disk.contains("\"disk\""));
    let comma = f.file(
        "disk-comma.msh",
        disk.replace("\"disk\"", "\"blank, part 1\"").as_bytes(),
    );
    let on_comma = f.file_blank("scenario-comma-group", &comma);
    let list = vec![
        (
            "card tables that do not overlap",
            run(f, "apart", &on_apart, &[]),
            vec![
                apart.clone(),
                "do not overlap".into(),
                "[matrix] temperature 150 to 320 °C and [bending] temperature 100 °C".into(),
            ],
        ),
        (
            "temperature a rounding error past the table holds",
            // accepted at the end of the table: the next check, the memory, refuses the run
            run(
                f,
                "rounding",
                &example,
                &[
                    "process.temperature=320.0000000001",
                    "blank.element_size=0.01",
                ],
            ),
            strings(&["blank.element_size", "of memory"]),
        ),
        (
            "temperature past the table shows why",
            run(
                f,
                "past",
                &example,
                &["process.temperature=320.00000041234567"],
            ),
            strings(&["process.temperature = 320.0000004 °C", "150 to 320 °C"]),
        ),
        (
            "stroke past the punch shows why",
            run(f, "stroke", &example, &["process.stroke=80.00000004"]),
            strings(&["process.stroke = 80.00000004 mm", "80 mm of stroke at most"]),
        ),
        (
            "element size past the limit shows why",
            run(f, "coarse", &example, &["blank.element_size=10.0001"]),
            strings(&["blank.element_size = 10.0001 mm", "10 mm at most"]),
        ),
        (
            "mesh group with a comma",
            run(f, "comma", &on_comma, &[]),
            vec![
                comma,
                "'blank, part 1'".into(),
                "comma".into(),
                "formed-blank.inp".into(),
            ],
        ),
    ];
    cases_of(list)
}

/// Fails with every failure listed, out of `total` cases.
fn assert_none_failed(failures: &[String], total: usize) {
    assert!(
        failures.is_empty(),
        "{} of {total} cases failed:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

fn failures(cases: &[Case]) -> Vec<String> {
    cases.iter().filter_map(|c| check(c).err()).collect()
}

#[test]
fn values_nobody_means_are_refused_naming_their_key() {
    let f = Fixtures::new("values");
    let mut cases = scenario_cases(&f);
    cases.extend(option_cases(&f));
    cases.extend(card_cases(&f));
    assert!(cases.len() >= 25, "only {} cases", cases.len());
    assert_none_failed(&failures(&cases), cases.len());
}

/// Each refused fit names its cause and leaves no card behind.
#[test]
fn fits_beyond_their_data_are_refused_and_write_nothing() {
    let f = Fixtures::new("values-fits");
    let cases = fit_cases(&f);
    for (_, output) in &cases {
        let _ = std::fs::remove_file(output);
    }
    let mut failed: Vec<String> = cases.iter().filter_map(|(c, _)| check(c).err()).collect();
    failed.extend(
        cases
            .iter()
            .filter(|(_, output)| Path::new(output).exists())
            .map(|(c, output)| format!("{}: wrote {output}", c.name)),
    );
    assert_none_failed(&failed, cases.len());
}

#[test]
fn messages_name_the_true_cause() {
    let f = Fixtures::new("values-causes");
    let cases = true_cause_cases(&f);
    assert_none_failed(&failures(&cases), cases.len());
}

/// The `--help` of the commands says the ranges that their refusals apply, from the same
/// constants.
#[test]
fn help_lists_the_ranges() {
    for (command, option, range) in [
        (&["test", "bias-extension"][..], "--speed", SPEED),
        (&["test", "uniaxial"][..], "--ply-angle", ANGLE),
        (&["drape"][..], "--warp-angle", ANGLE),
        (&["material-point"][..], "--angle", ANGLE),
        (
            &["fit", "shear"][..],
            "--max-shear, --locking-angle",
            thermostamp::limits::SHEAR_ANGLE,
        ),
        (&["fit", "fabric-tension"][..], "--width", LENGTH),
    ] {
        let mut args = command.to_vec();
        args.push("--help");
        let out = thermostamp(&args);
        let help = String::from_utf8_lossy(&out.stdout);
        let line = ranges_help(&[(option, range)]);
        let line = line.lines().last().unwrap();
        assert!(help.contains(line), "{command:?}: '{line}' not in\n{help}");
    }
    let out = thermostamp(&["fit", "shear", "--help"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("--terms: powers 1 to 10"));
}
