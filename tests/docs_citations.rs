//! The project stands alone: what it cites is in the repository. No file refers to a
//! specification a clone does not have, every "docs/model.md §N" names a section that
//! docs/model.md has, and every docs/*.md named exists.

mod common;

use common::repo_path;
use std::path::{Path, PathBuf};

/// The folders and files whose text a user or a fitted card reads.
const SOURCES: [&str; 8] = [
    "README.md",
    "docs",
    "src",
    "examples",
    "materials",
    "tests",
    "benches",
    "Cargo.toml",
];

/// Every text file under `path` (binary files are skipped).
fn text_files(path: &Path, found: &mut Vec<(PathBuf, String)>) {
    if path.is_dir() {
        let mut entries: Vec<_> = std::fs::read_dir(path)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        for entry in entries {
            text_files(&entry, found);
        }
    } else if let Ok(text) = std::fs::read_to_string(path) {
        found.push((path.to_path_buf(), text));
    }
}

fn all_text() -> Vec<(PathBuf, String)> {
    let mut found = Vec::new();
    for source in SOURCES {
        text_files(&repo_path(source), &mut found);
    }
    assert!(found.len() > 100, "only {} files read", found.len());
    found
}

/// The section numbers of docs/model.md (`## N. Title`).
fn model_sections() -> Vec<u32> {
    let model = std::fs::read_to_string(repo_path("docs/model.md")).unwrap();
    model
        .lines()
        .filter_map(|l| l.strip_prefix("## "))
        .filter_map(|l| l.split('.').next()?.parse().ok())
        .collect()
}

/// The numbers `N` of every "model.md §N" in `text` (also "§N.M" and "§N–§M" lists after it).
fn cited_sections(text: &str) -> Vec<u32> {
    let mut cited = Vec::new();
    for (at, _) in text.match_indices("model.md §") {
        let rest = &text[at + "model.md ".len()..];
        // "§3, §5", "§2–§4", "§3/§5": the run of section marks right after the file name
        let run: String = rest
            .chars()
            .take_while(|c| c.is_ascii_digit() || "§.,–/ ".contains(*c))
            .collect();
        for mark in run.split('§').skip(1) {
            let number: String = mark.chars().take_while(|c| c.is_ascii_digit()).collect();
            if let Ok(n) = number.parse() {
                cited.push(n);
            }
        }
    }
    cited
}

#[test]
fn nothing_cites_a_file_outside_the_repository() {
    let unshipped = [
        ["MODEL", ".md"].concat(),
        ["shared", "/spec"].concat(),
        ["shared", "/seed"].concat(),
    ];
    for (path, text) in all_text() {
        for name in &unshipped {
            assert!(
                !text.contains(name.as_str()),
                "{}: cites {name}, which a clone does not have",
                path.display()
            );
        }
    }
}

#[test]
fn every_cited_section_of_the_model_exists() {
    let sections = model_sections();
    assert_eq!(
        sections,
        (1..=10).collect::<Vec<_>>(),
        "docs/model.md sections"
    );
    let mut citations = 0;
    for (path, text) in all_text() {
        for n in cited_sections(&text) {
            citations += 1;
            assert!(
                sections.contains(&n),
                "{}: cites docs/model.md §{n}, which does not exist",
                path.display()
            );
        }
    }
    // the code, the tests and the cards cite the model throughout
    assert!(citations > 100, "only {citations} citations found");
}

#[test]
fn every_named_doc_exists() {
    for (path, text) in all_text() {
        for (at, _) in text.match_indices("docs/") {
            let name: String = text[at..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || "/-_.".contains(*c))
                .collect();
            let name = name.trim_end_matches('.');
            if name.ends_with(".md") {
                assert!(
                    repo_path(name).is_file(),
                    "{}: names {name}, which does not exist",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn section_citations_are_read_as_written() {
    assert_eq!(cited_sections("see docs/model.md §3, §5 and §7.1"), [3, 5]);
    assert_eq!(cited_sections("docs/model.md §7.1"), [7]);
    assert_eq!(cited_sections("(model.md §2–§4)"), [2, 4]);
    assert_eq!(cited_sections("model.md §3/§5; then §9 elsewhere"), [3, 5]);
}
