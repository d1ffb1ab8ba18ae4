//! Bad input and faults over every subcommand, as a careless or adversarial user would give
//! them: each case has the exit code it must give (2: bad input, found before the first step)
//! and the pieces its one-line message must name (the file and line, the key, or the
//! command-line option). None may panic (101), abort (134) or hang.

mod common;

use common::adversarial::{args, assert_all_pass, case, repo, Case, Fixtures};
use common::thermostamp;
use std::path::Path;

/// Usage errors that clap finds, before any file is read.
fn usage_cases(f: &Fixtures) -> Vec<Case> {
    let card = repo("materials/t300-5hs-pps.toml");
    let example = repo("tests/data/hemisphere-explicit.toml");
    vec![
        case("no command", &[], 2, &["Usage"]),
        case("unknown command", &["frobnicate"], 2, &["frobnicate"]),
        case("run without scenario", &["run"], 2, &["<SCENARIO>"]),
        case(
            "test without card",
            &["test", "bias-extension"],
            2,
            &["--card"],
        ),
        case(
            "width not a number",
            &["test", "uniaxial", "--card", &card, "--width", "abc"],
            2,
            &["--width", "abc"],
        ),
        case(
            "threads not a number",
            &["run", &example, "--threads", "many"],
            2,
            &["--threads"],
        ),
        case(
            "threads zero",
            &[
                "run",
                &example,
                "--threads",
                "0",
                "--output",
                &f.output("t0"),
            ],
            2,
            &["--threads"],
        ),
        case(
            "unknown layer",
            &[
                "material-point",
                "--card",
                &card,
                "--layer",
                "core",
                "--history",
                "x.csv",
            ],
            2,
            &["--layer", "core"],
        ),
        case(
            "unknown test",
            &[
                "fit", "shear", "--test", "tumble", "--data", "x.csv", "--card", &card,
            ],
            2,
            &["--test", "tumble"],
        ),
        case(
            "unknown pattern",
            &[
                "test",
                "bias-extension",
                "--card",
                &card,
                "--pattern",
                "zigzag",
            ],
            2,
            &["--pattern", "zigzag"],
        ),
    ]
}

/// Material cards and histories of `material-point`.
fn material_point_cases(f: &Fixtures) -> Vec<Case> {
    let history = repo("examples/material-point/laminate-shear-300C.csv");
    let point = |card: &str, layer: &str, history: &str| {
        vec![
            "material-point".to_string(),
            "--card".into(),
            card.into(),
            "--layer".into(),
            layer.into(),
            "--history".into(),
            history.into(),
        ]
    };
    let mut cases = Vec::new();
    let mut add = |name: &str, args: Vec<String>, names: &[String]| {
        cases.push(Case {
            name: name.into(),
            args,
            code: 2,
            names: names.to_vec(),
        })
    };
    let missing = f.dir.join("no-such-card.toml").display().to_string();
    add(
        "card missing",
        point(&missing, "laminate", &history),
        std::slice::from_ref(&missing),
    );
    let folder = f.dir.display().to_string();
    add(
        "card is a folder",
        point(&folder, "laminate", &history),
        std::slice::from_ref(&folder),
    );
    let empty = f.file("empty-card.toml", b"");
    add(
        "card empty",
        point(&empty, "laminate", &history),
        &[empty.clone(), "name".into()],
    );
    let garbage = f.file(
        "garbage-card.toml",
        &[0xff, 0xfe, 0x00, 0x9c, 0x42, 0x00, 0x13],
    );
    add(
        "card garbage bytes",
        point(&garbage, "laminate", &history),
        std::slice::from_ref(&garbage),
    );
    let cards: [(&str, &str, &str, &str); 10] = [
        (
            "unknown key",
            "density = 1.56e-9",
            "density = 1.56e-9\ndensty = 1",
            "densty",
        ),
        (
            "density text",
            "density = 1.56e-9",
            "density = \"heavy\"",
            "density",
        ),
        (
            "density negative",
            "density = 1.56e-9",
            "density = -1.56e-9",
            "density",
        ),
        (
            "c10 nan",
            "c10 = [80.0, 50.0, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10, 0.05]",
            "c10 = [80.0, nan, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10, 0.05]",
            "c10",
        ),
        (
            "temperatures decreasing",
            "temperature = [150.0, 170.0, 200.0, 230.0, 245.0, 260.0, 280.0, 300.0, 320.0]",
            "temperature = [150.0, 170.0, 200.0, 230.0, 245.0, 260.0, 280.0, 320.0, 300.0]",
            "temperature",
        ),
        (
            "table lengths differ",
            "c10 = [80.0, 50.0, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10, 0.05]",
            "c10 = [80.0, 50.0, 20.0, 3.0, 0.6, 0.3, 0.20, 0.10]",
            "c10",
        ),
        (
            "thickness zero",
            "fabric_thickness = 0.23",
            "fabric_thickness = 0.0",
            "fabric_thickness",
        ),
        (
            "shear text",
            "shear = [0.25, 0.0, 2.0]",
            "shear = \"stiff\"",
            "shear",
        ),
        (
            "bending negative",
            "warp = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
            "warp = [120.0, -1.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
            "warp",
        ),
        (
            "bending table short",
            "weft = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0, 0.66]",
            "weft = [120.0, 100.0, 50.0, 10.0, 3.8, 2.6, 1.58, 1.0]",
            "weft",
        ),
    ];
    for (name, from, to, key) in cards {
        let card = f.card(&format!("card-{}", name.replace(' ', "-")), from, to);
        add(
            &format!("card {name}"),
            point(&card, "laminate", &history),
            &[card.clone(), key.into()],
        );
    }
    let card = repo("materials/t300-5hs-pps.toml");
    let missing = f.dir.join("no-such-history.csv").display().to_string();
    add(
        "history missing",
        point(&card, "laminate", &missing),
        std::slice::from_ref(&missing),
    );
    let header = "t,F11,F12,F21,F22,T\n";
    let histories: [(&str, String, &str); 7] = [
        ("empty", String::new(), ""),
        (
            "wrong column",
            "t,F11,F12,F21,G22,T\n0,1,0,0,1,300\n".into(),
            "G22",
        ),
        (
            "text cell",
            format!("{header}0,1,0,0,1,300\n0.1,1,abc,0,1,300\n"),
            "line 3",
        ),
        (
            "nan cell",
            format!("{header}0,1,0,0,1,300\n0.1,1,nan,0,1,300\n"),
            "line 3",
        ),
        (
            "time backwards",
            format!("{header}0,1,0,0,1,300\n1,1,0,0,1,300\n0.5,1,0,0,1,300\n"),
            "line 4",
        ),
        (
            "inverted",
            format!("{header}0,1,0,0,1,300\n1,-1,0,0,1,300\n"),
            "line 3",
        ),
        (
            "too hot",
            format!("{header}0,1,0,0,1,300\n1,1,0,0,1,900\n"),
            "900",
        ),
    ];
    for (name, text, piece) in histories {
        let path = f.file(
            &format!("history-{}.csv", name.replace(' ', "-")),
            text.as_bytes(),
        );
        add(
            &format!("history {name}"),
            point(&card, "laminate", &path),
            &[path.clone(), piece.into()],
        );
    }
    let mut angle = point(&card, "laminate", &history);
    angle.extend(["--angle".into(), "nan".into()]);
    add("angle nan", angle, &["--angle".into()]);
    cases
}

/// Virtual tests: options out of range, refused before the first step.
fn virtual_test_cases(f: &Fixtures) -> Vec<Case> {
    let card = repo("materials/t300-5hs-pps.toml");
    let fabric = repo("materials/twintex-plain-weave.toml");
    let test = |kind: &str, card: &str, extra: &[&str], out: &str| {
        let mut args: Vec<String> = ["test", kind, "--card", card]
            .iter()
            .map(|s| s.to_string())
            .collect();
        args.extend(["--output".to_string(), f.output(out)]);
        args.extend(extra.iter().map(|s| s.to_string()));
        args
    };
    let prepreg = ["--temperature", "300"];
    let with = |base: &[&'static str], more: &[&'static str]| -> Vec<&'static str> {
        base.iter().chain(more).copied().collect()
    };
    let cases: Vec<(&str, &str, &str, Vec<&str>, &str)> = vec![
        (
            "bias width negative",
            "bias-extension",
            &fabric,
            vec!["--width", "-5"],
            "--width",
        ),
        (
            "bias too short",
            "bias-extension",
            &fabric,
            vec!["--width", "150", "--length", "200"],
            "length",
        ),
        (
            "bias speed zero",
            "bias-extension",
            &fabric,
            vec!["--speed", "0"],
            "--speed",
        ),
        (
            "bias speed infinite",
            "bias-extension",
            &fabric,
            vec!["--speed", "inf"],
            "--speed",
        ),
        (
            "bias element size zero",
            "bias-extension",
            &fabric,
            vec!["--element-size", "0"],
            "--element-size",
        ),
        (
            "bias prepreg without temperature",
            "bias-extension",
            &card,
            vec![],
            "--temperature",
        ),
        (
            "bias prepreg too hot",
            "bias-extension",
            &card,
            vec!["--temperature", "400"],
            "--temperature",
        ),
        (
            "bias time scaling below one",
            "bias-extension",
            &card,
            with(&prepreg, &["--time-scaling", "0.5"]),
            "--time-scaling",
        ),
        (
            "bias negative target step",
            "bias-extension",
            &fabric,
            vec!["--target-step", "-1"],
            "--target-step",
        ),
        (
            "bias negative damping",
            "bias-extension",
            &fabric,
            vec!["--damping", "-1"],
            "--damping",
        ),
        (
            "bias negative travel",
            "bias-extension",
            &fabric,
            vec!["--end-displacement", "-3"],
            "--end-displacement",
        ),
        (
            "uniaxial ply angle nan",
            "uniaxial",
            &fabric,
            vec!["--ply-angle", "nan"],
            "--ply-angle",
        ),
        (
            "uniaxial length zero",
            "uniaxial",
            &fabric,
            vec!["--length", "0"],
            "--length",
        ),
        (
            "picture frame side zero",
            "picture-frame",
            &fabric,
            vec!["--side", "0"],
            "--side",
        ),
        (
            "picture frame side nan",
            "picture-frame",
            &fabric,
            vec!["--side", "nan"],
            "--side",
        ),
    ];
    cases
        .into_iter()
        .map(|(name, kind, card, extra, piece)| Case {
            name: name.into(),
            args: test(kind, card, &extra, &name.replace(' ', "-")),
            code: 2,
            names: vec![piece.into()],
        })
        .collect()
}

/// Scenario files and their overrides for `run` (and `drape`).
fn scenario_cases(f: &Fixtures) -> Vec<Case> {
    let example = repo("tests/data/hemisphere-explicit.toml");
    let run = |scenario: &str, extra: &[&str], out: &str| {
        let mut args = vec!["run".to_string(), scenario.to_string()];
        args.extend(extra.iter().map(|s| s.to_string()));
        args.extend(["--output".to_string(), f.output(out)]);
        args
    };
    let mut cases = Vec::new();
    let missing = f.dir.join("no-such-scenario.toml").display().to_string();
    cases.push(Case {
        name: "scenario missing".into(),
        args: run(&missing, &[], "missing"),
        code: 2,
        names: vec![missing.clone()],
    });
    let syntax = f.file("syntax.toml", b"[blank\ncard = 1\n");
    cases.push(Case {
        name: "scenario syntax".into(),
        args: run(&syntax, &[], "syntax"),
        code: 2,
        names: vec![syntax.clone(), "line 1".into()],
    });
    let empty = f.file("empty-scenario.toml", b"");
    cases.push(Case {
        name: "scenario empty".into(),
        args: run(&empty, &[], "empty"),
        code: 2,
        names: vec![empty.clone(), "blank".into()],
    });
    let edits: [(&str, &str, &str, &str); 22] = [
        ("unknown section", "[output]", "[outputs]", "outputs"),
        (
            "unknown key",
            "stroke = 30.0",
            "stroke = 30.0\nstroke_depth = 3",
            "stroke_depth",
        ),
        (
            "element size zero",
            "element_size = 8.0",
            "element_size = 0.0",
            "blank.element_size",
        ),
        (
            "element size text",
            "element_size = 8.0",
            "element_size = \"fine\"",
            "blank.element_size",
        ),
        ("width nan", "width = 160.0", "width = nan", "blank.width"),
        (
            "punch speed negative",
            "punch_speed = 10.0",
            "punch_speed = -1.0",
            "process.punch_speed",
        ),
        (
            "punch speed infinite",
            "punch_speed = 10.0",
            "punch_speed = inf",
            "process.punch_speed",
        ),
        (
            "time scaling below one",
            "time_scaling = 10.0",
            "time_scaling = 0.5",
            "process.time_scaling",
        ),
        (
            "friction negative",
            "die = 0.2",
            "die = -0.1",
            "process.friction.die",
        ),
        (
            "history points zero",
            "history_points = 60",
            "history_points = 0",
            "output.history_points",
        ),
        (
            "history points negative",
            "history_points = 60",
            "history_points = -5",
            "output.history_points",
        ),
        (
            "frames text",
            "frames = 10",
            "frames = \"many\"",
            "output.frames",
        ),
        (
            "locking angle 95",
            "locking_angle = 45.0",
            "locking_angle = 95.0",
            "output.locking_angle",
        ),
        (
            "target step zero",
            "target_time_step = 5e-6",
            "target_time_step = 0.0",
            "process.target_time_step",
        ),
        (
            "pattern unknown",
            "pattern = \"quad\"",
            "pattern = \"diagonal\"",
            "blank.pattern",
        ),
        (
            "too hot",
            "temperature = 300.0",
            "temperature = 400.0",
            "process.temperature",
        ),
        (
            "stroke beyond the punch",
            "stroke = 30.0",
            "stroke = 95.0",
            "process.stroke",
        ),
        (
            "holder force and gap",
            "blank_holder_force = 200.0",
            "blank_holder_force = 200.0\nblank_holder_gap = 0.1",
            "blank_holder_gap",
        ),
        (
            "coarse mesh",
            "element_size = 8.0",
            "element_size = 30.0",
            "blank.element_size",
        ),
        (
            "tool resolution zero",
            "resolution = 3.0",
            "resolution = 0.0",
            "tools.resolution",
        ),
        (
            "card missing",
            "t300-5hs-pps.toml",
            "t400.toml",
            "t400.toml",
        ),
        ("card of wrong type", "card = ", "card = 3 #", "blank.card"),
    ];
    for (name, from, to, key) in edits {
        let path = f.scenario(&format!("scenario-{}", name.replace(' ', "-")), from, to);
        cases.push(Case {
            name: format!("scenario {name}"),
            args: run(&path, &[], &name.replace(' ', "-")),
            code: 2,
            names: vec![key.into()],
        });
    }
    let absurd = f.card(
        "card-absurd-stiffness",
        "warp_tension = [4.0e4, 2.0e6]\nweft_tension = [4.0e4, 2.0e6]",
        "warp_tension = [4.0e300, 2.0e6]\nweft_tension = [4.0e300, 2.0e6]",
    );
    let on_absurd = f.scenario_on_card("scenario-absurd-card", &absurd);
    cases.push(Case {
        name: "scenario on a card of absurd stiffness".into(),
        args: run(&on_absurd, &[], "absurd-card"),
        code: 2,
        names: vec![absurd, "warp_tension[0] (A2)".into()],
    });
    let garbage_card = f.file("garbage.toml", b"\x00\x01binary\xff");
    let on_garbage = f.scenario_on_card("scenario-garbage-card", &garbage_card);
    cases.push(Case {
        name: "scenario on a garbage card".into(),
        args: run(&on_garbage, &[], "garbage-card"),
        code: 2,
        names: vec![garbage_card],
    });
    let overrides: [(&str, &str, &str); 12] = [
        ("set without value", "process.stroke", "--set"),
        (
            "cells beyond the memory",
            "blank.element_size=0.01",
            "blank.element_size",
        ),
        ("blank of 1e300 mm", "blank.width=1e300", "blank.width"),
        (
            "punch through the ply in a step",
            "process.punch_speed=100000",
            "process.punch_speed",
        ),
        (
            "stroke in a few hundred steps",
            "process.punch_speed=2000",
            "process.punch_speed",
        ),
        (
            "absurd step count",
            "process.punch_speed=1e-6",
            "process.punch_speed",
        ),
        (
            "mass scaling beyond reason",
            "process.target_time_step=1",
            "process.target_time_step",
        ),
        (
            "set text for a number",
            "process.stroke=abc",
            "process.stroke",
        ),
        ("set a section", "process=3", "process"),
        ("set unknown key", "process.strok=3", "strok"),
        ("set empty key", "process..stroke=3", "--set"),
        (
            "set too hot",
            "process.temperature=400",
            "process.temperature",
        ),
    ];
    for (name, assignment, key) in overrides {
        cases.push(Case {
            name: name.into(),
            args: run(&example, &["--set", assignment], &name.replace(' ', "-")),
            code: 2,
            names: vec![key.into()],
        });
    }
    let mesh_missing = f.file_blank("scenario-mesh-missing", "no-such-mesh.msh");
    cases.push(Case {
        name: "mesh file missing".into(),
        args: run(&mesh_missing, &[], "mesh-missing"),
        code: 2,
        names: vec!["no-such-mesh.msh".into()],
    });
    let bad_mesh = f.file(
        "bad.msh",
        b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 1\n",
    );
    let on_bad_mesh = f.file_blank("scenario-bad-mesh", &bad_mesh);
    cases.push(Case {
        name: "mesh file truncated".into(),
        args: run(&on_bad_mesh, &[], "bad-mesh"),
        code: 2,
        names: vec![bad_mesh, "line".into()],
    });
    // a quadrilateral whose third corner turns back inside it: refused at its line, by label
    let folded = f.file(
        "folded.inp",
        b"*NODE\n1, 0, 0, 0\n2, 100, 0, 0\n3, 20, 20, 0\n4, 0, 100, 0\n\
          *ELEMENT, TYPE=S4R\n7, 1, 2, 3, 4\n",
    );
    let on_folded = f.file_blank("scenario-folded-quad", &folded);
    cases.push(Case {
        name: "mesh file with a folded quadrilateral".into(),
        args: run(&on_folded, &[], "folded-quad"),
        code: 2,
        names: vec![
            folded,
            "line 7".into(),
            "element 7".into(),
            "not convex".into(),
        ],
    });
    let drape = |extra: &[&str], out: &str| {
        let mut args = vec!["drape".to_string(), example.clone()];
        args.extend(extra.iter().map(|s| s.to_string()));
        args.extend(["--output".to_string(), f.output(out)]);
        args
    };
    for (name, extra, piece) in [
        ("drape start text", vec!["--start", "abc"], "--start"),
        (
            "drape start outside",
            vec!["--start", "1000,1000"],
            "--start",
        ),
        (
            "drape warp angle nan",
            vec!["--warp-angle", "nan"],
            "--warp-angle",
        ),
    ] {
        cases.push(Case {
            name: name.into(),
            args: drape(&extra, &name.replace(' ', "-")),
            code: 2,
            names: vec![piece.into()],
        });
    }
    cases
}

/// Fits: manifests, curves and options.
fn fit_cases(f: &Fixtures) -> Vec<Case> {
    let card = repo("materials/t300-5hs-pps.toml");
    let fabric = repo("materials/twintex-plain-weave.toml");
    let benchmark = repo("examples/fit-shear/bias_extension_glass_pp_plain_150x450.csv");
    let manifest = repo("examples/fit-matrix/manifest.toml");
    let warp = repo("examples/fit-fabric-tension/warp.csv");
    let out = |name: &str| {
        f.dir
            .join(format!("fitted-{name}.toml"))
            .display()
            .to_string()
    };
    let missing_curve = f.file(
        "manifest-missing-curve.toml",
        b"[[curve]]\nfile = \"no-such-curve.csv\"\ntemperature = 300.0\nstrain_rate = 1.0\n",
    );
    let manifest_text = f.file(
        "manifest-text.toml",
        b"[[curve]]\nfile = \"x.csv\"\ntemperature = \"hot\"\nstrain_rate = 1.0\n",
    );
    let negative = f.file(
        "warp-negative.csv",
        b"strain,force_per_width\n0,0\n0.001,5\n0.002,-3\n0.003,12\n",
    );
    let short = f.file("bias-short.csv", b"displacement_mm,force_N\n0,0\n");
    let unsorted = f.file(
        "bias-unsorted.csv",
        b"displacement_mm,force_N\n0,0\n2,1\n1,2\n3,3\n4,4\n5,5\n",
    );
    let cases: Vec<(&str, Vec<String>, Vec<String>)> = vec![
        (
            "fit matrix manifest missing",
            args(&[
                "fit",
                "matrix",
                "--manifest",
                "no-such.toml",
                "--bulk-modulus",
                "1000",
                "--output",
                &out("a"),
            ]),
            vec!["no-such.toml".into()],
        ),
        (
            "fit matrix curve missing",
            args(&[
                "fit",
                "matrix",
                "--manifest",
                &missing_curve,
                "--bulk-modulus",
                "1000",
                "--output",
                &out("b"),
            ]),
            vec!["no-such-curve.csv".into()],
        ),
        (
            "fit matrix manifest text",
            args(&[
                "fit",
                "matrix",
                "--manifest",
                &manifest_text,
                "--bulk-modulus",
                "1000",
                "--output",
                &out("c"),
            ]),
            vec![manifest_text.clone(), "temperature".into()],
        ),
        (
            "fit matrix poisson above half",
            args(&[
                "fit",
                "matrix",
                "--manifest",
                &manifest,
                "--poisson",
                "0.6",
                "--output",
                &out("d"),
            ]),
            vec!["--poisson".into()],
        ),
        (
            "fit matrix negative bulk modulus",
            args(&[
                "fit",
                "matrix",
                "--manifest",
                &manifest,
                "--bulk-modulus",
                "-5",
                "--output",
                &out("e"),
            ]),
            vec!["--bulk-modulus".into()],
        ),
        (
            "fit tension negative force",
            args(&[
                "fit",
                "fabric-tension",
                "--warp",
                &negative,
                "--card",
                &card,
                "--output",
                &out("f"),
            ]),
            vec![negative.clone(), "line".into()],
        ),
        (
            "fit tension no curve",
            args(&[
                "fit",
                "fabric-tension",
                "--card",
                &card,
                "--output",
                &out("g"),
            ]),
            vec!["--warp".into()],
        ),
        (
            "fit tension zero terms",
            args(&[
                "fit",
                "fabric-tension",
                "--warp",
                &warp,
                "--card",
                &card,
                "--terms",
                "0",
                "--output",
                &out("h"),
            ]),
            vec!["--terms".into()],
        ),
        (
            "fit shear too few points",
            args(&[
                "fit",
                "shear",
                "--data",
                &short,
                "--width",
                "150",
                "--length",
                "450",
                "--card",
                &fabric,
                "--output",
                &out("i"),
            ]),
            vec![short.clone()],
        ),
        (
            "fit shear displacement backwards",
            args(&[
                "fit",
                "shear",
                "--data",
                &unsorted,
                "--width",
                "150",
                "--length",
                "450",
                "--card",
                &fabric,
                "--output",
                &out("j"),
            ]),
            vec![unsorted.clone(), "line".into()],
        ),
        (
            "fit shear specimen too short",
            args(&[
                "fit",
                "shear",
                "--data",
                &benchmark,
                "--width",
                "150",
                "--length",
                "200",
                "--card",
                &fabric,
                "--output",
                &out("k"),
            ]),
            vec!["length/width".into()],
        ),
        (
            "fit shear max shear 100",
            args(&[
                "fit",
                "shear",
                "--data",
                &benchmark,
                "--width",
                "150",
                "--length",
                "450",
                "--card",
                &fabric,
                "--max-shear",
                "100",
                "--output",
                &out("l"),
            ]),
            vec!["--max-shear".into()],
        ),
        (
            "fit shear prepreg without conditions",
            args(&[
                "fit",
                "shear",
                "--data",
                &benchmark,
                "--width",
                "150",
                "--length",
                "450",
                "--card",
                &card,
                "--output",
                &out("m"),
            ]),
            vec!["--temperature".into()],
        ),
        (
            "fit shear output folder missing",
            args(&[
                "fit",
                "shear",
                "--data",
                &benchmark,
                "--width",
                "150",
                "--length",
                "450",
                "--card",
                &fabric,
                "--output",
                "/no/such/folder/card.toml",
            ]),
            vec!["/no/such/folder/card.toml".into()],
        ),
    ];
    cases
        .into_iter()
        .map(|(name, args, names)| Case {
            name: name.into(),
            args,
            code: 2,
            names,
        })
        .collect()
}

fn all_cases(f: &Fixtures) -> Vec<Case> {
    let mut cases = usage_cases(f);
    cases.extend(material_point_cases(f));
    cases.extend(virtual_test_cases(f));
    cases.extend(scenario_cases(f));
    cases.extend(fit_cases(f));
    cases
}

#[test]
fn every_bad_input_is_refused_with_exit_2_naming_its_source() {
    let fixtures = Fixtures::new("fixtures");
    let cases = all_cases(&fixtures);
    assert_all_pass(&cases, 60);
}

#[test]
fn refused_runs_write_no_output_folder() {
    let fixtures = Fixtures::new("fixtures");
    let out = fixtures.output("refused-run");
    let _ = std::fs::remove_dir_all(&out);
    let scenario = fixtures.scenario("refused-hot", "temperature = 300.0", "temperature = 400.0");
    let result = thermostamp(&["run", &scenario, "--output", &out]);
    assert_eq!(result.status.code(), Some(2));
    assert!(
        !Path::new(&out).exists(),
        "{out} was created by a refused run"
    );
}
