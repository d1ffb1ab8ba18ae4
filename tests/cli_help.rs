//! `--help` of every subcommand, as a user reads it: it succeeds, every option says what
//! happens when it is not given (a `[default: ...]`, a required input, a flag, or its text
//! says the default), `fit` names its three commands, `run` and `drape` point to the
//! scenario reference, and the process defaults a virtual test prints are the ones it runs with.

mod common;

use common::thermostamp;
use thermostamp::experiment::bias_extension::BiasExtension;
use thermostamp::experiment::picture_frame::PictureFrame;
use thermostamp::experiment::sheet_test::TestProcess;
use thermostamp::experiment::uniaxial::UniaxialTension;

const SUBCOMMANDS: [&[&str]; 10] = [
    &["material-point"],
    &["test", "bias-extension"],
    &["test", "uniaxial"],
    &["test", "picture-frame"],
    &["run"],
    &["drape"],
    &["fit"],
    &["fit", "matrix"],
    &["fit", "fabric-tension"],
    &["fit", "shear"],
];

/// The help text of `command --help`; exit code 0 is required.
fn help(command: &[&str]) -> String {
    let mut args = command.to_vec();
    args.push("--help");
    let out = thermostamp(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// One option as the help lists it: its long name, whether it takes a value, and its text.
#[derive(Debug)]
struct OptionEntry {
    name: String,
    takes_value: bool,
    text: String,
}

/// The entries of the "Options:" section (up to the next unindented line).
fn options(help: &str) -> Vec<OptionEntry> {
    let mut entries: Vec<OptionEntry> = Vec::new();
    let mut inside = false;
    for line in help.lines() {
        if line == "Options:" {
            inside = true;
            continue;
        }
        if !inside {
            continue;
        }
        if !line.is_empty() && !line.starts_with(' ') {
            break;
        }
        let trimmed = line.trim_start();
        let flag = trimmed
            .strip_prefix("-h, ")
            .or_else(|| trimmed.strip_prefix("-V, "))
            .unwrap_or(trimmed);
        match flag.strip_prefix("--") {
            Some(rest) if line.len() - trimmed.len() <= 6 => {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                    .collect();
                let after = &rest[name.len()..];
                entries.push(OptionEntry {
                    takes_value: after.starts_with(" <"),
                    text: after.to_string(),
                    name,
                });
            }
            _ => {
                if let Some(last) = entries.last_mut() {
                    last.text.push(' ');
                    last.text.push_str(trimmed);
                }
            }
        }
    }
    entries
}

/// The "Usage:" line, which names the required options.
fn usage(help: &str) -> &str {
    help.lines()
        .find(|l| l.starts_with("Usage:"))
        .expect("a usage line")
}

#[test]
fn every_option_says_its_default_or_is_required() {
    for command in SUBCOMMANDS {
        let text = help(command);
        let listed = options(&text);
        assert!(
            listed.iter().any(|o| o.name == "help"),
            "{command:?}: no options parsed from\n{text}"
        );
        let usage = usage(&text);
        for option in &listed {
            let required = usage.contains(&format!("--{} <", option.name));
            let says_default = option.text.to_lowercase().contains("default");
            assert!(
                !option.takes_value || required || says_default,
                "{command:?} --{}: neither required nor a default in its help: {}",
                option.name,
                option.text
            );
        }
    }
}

#[test]
fn fit_lists_its_three_commands() {
    let text = help(&["fit"]);
    for name in ["matrix", "fabric-tension", "shear"] {
        let listed = text
            .lines()
            .any(|l| l.trim_start().starts_with(&format!("{name} ")));
        assert!(listed, "fit --help does not list `{name}`:\n{text}");
        assert!(
            text.lines()
                .next()
                .is_some_and(|about| about.contains(&format!("fit {name}`"))),
            "the about line of fit does not name `fit {name}`:\n{text}"
        );
    }
}

#[test]
fn run_and_drape_point_to_the_scenario_reference() {
    for command in ["run", "drape"] {
        let text = help(&[command]);
        assert!(
            text.contains("docs/guide/scenario.md"),
            "{command} --help does not name the scenario reference:\n{text}"
        );
    }
    let reference = std::fs::read_to_string(common::repo_path("docs/guide/scenario.md")).unwrap();
    for key in [
        "blank.card",
        "tools.shape",
        "process.solver",
        "output.frames",
    ] {
        assert!(
            reference.contains(&format!("| `{key}`")),
            "docs/guide/scenario.md has no row for {key}"
        );
    }
}

/// What the help of a test must print for its process, in the help's own format.
fn expected_defaults(p: &TestProcess) -> Vec<String> {
    let target = match p.target_time_step {
        Some(dt) => format!("--target-step {dt:e} s"),
        None => "--target-step none".to_string(),
    };
    vec![
        format!("--speed {:.3} mm/s", p.speed),
        format!("--time-scaling {}", p.time_scaling),
        target,
        format!("--element-size {} mm", p.element_size),
        format!("--end-displacement {} mm", p.end_displacement),
    ]
}

#[test]
fn virtual_tests_print_the_process_defaults_they_run_with() {
    let tests = [
        ("bias-extension", BiasExtension::benchmark(20.0).process),
        ("uniaxial", UniaxialTension::standard(20.0).process),
        ("picture-frame", PictureFrame::standard(20.0).process),
    ];
    for (name, process) in tests {
        let text = help(&["test", name]);
        let defaults = text
            .split("Defaults of this test:")
            .nth(1)
            .unwrap_or_else(|| panic!("test {name} --help lists no defaults:\n{text}"));
        for line in expected_defaults(&process) {
            assert!(
                defaults.lines().any(|l| l.trim_start().starts_with(&line)),
                "test {name} --help: `{line}` missing from\n{defaults}"
            );
        }
        // every option that sends the reader below is listed there
        for option in options(&text) {
            if option.text.contains("the test's, below") {
                assert!(
                    defaults.contains(&format!("--{} ", option.name)),
                    "test {name} --{}: its default is not listed below",
                    option.name
                );
            }
        }
    }
}
