//! Which study a study folder holds: `study-identity.toml`, written when a study first takes
//! the folder, records the study's parameters (their values, in order), its design (a sampled
//! one's method, number of cases and seed; nothing for the full factorial, whose record is
//! what it was before designs existed) and its base scenario (standalone, as each case's own
//! scenario is built from it). A case folder is named by its number alone, and case 7 of one
//! study is not case 7 of another: a study whose parameters, design or base scenario differ
//! from the record is refused, so that one folder never mixes the cases of two studies, nor
//! lists one's with the other's parameters.

use super::design::{DesignSection, Method};
use super::file::{parameters, Study, StudyError};
use crate::forming::Scenario;
use crate::io::product_file;
use std::path::{Path, PathBuf};

/// The record of the study a folder holds.
pub const IDENTITY_FILE: &str = "study-identity.toml";

/// What identifies a study: its parameters, its design and its base scenario.
struct Identity {
    /// The study file it was recorded from (named in messages only: the same study may be
    /// run from a copy of its file).
    study: String,
    parameters: toml::Table,
    /// The `[design]` table; `None` for the full factorial.
    design: Option<toml::Table>,
    base: toml::Table,
}

/// The folder holds no other study's cases: its record, if any, is this study's; without a
/// record, it holds no case folders. Reads only.
pub fn verify(study: &Study) -> Result<(), StudyError> {
    recorded(study).map(drop)
}

/// [`verify`], then records the study in its folder if it has no record yet. Several processes
/// may claim a folder at once (the cases of one study run one per process): the record is
/// written aside and linked into place, which fails for all but the first, and those compare
/// against it.
pub fn claim(study: &Study) -> Result<(), StudyError> {
    if recorded(study)? {
        return Ok(());
    }
    let path = study.folder.join(IDENTITY_FILE);
    let aside = study
        .folder
        .join(format!("{IDENTITY_FILE}.{}.tmp", std::process::id()));
    let written = product_file::write(&aside, text(&identity(study)?).as_bytes())
        .and_then(|()| std::fs::hard_link(&aside, &path));
    let _ = std::fs::remove_file(&aside);
    match written {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => verify(study),
        Err(e) => Err(error(
            study,
            format!("cannot write {}: {e}", path.display()),
        )),
    }
}

/// Whether the folder has a record (this study's); refused where it is another study's, or
/// where there is none but case folders are there.
fn recorded(study: &Study) -> Result<bool, StudyError> {
    match read(study)? {
        Some(record) => compare(study, &identity(study)?, &record).map(|()| true),
        None => unrecorded_cases(study).map(|()| false),
    }
}

fn error(study: &Study, message: String) -> StudyError {
    StudyError {
        origin: study.origin.clone(),
        message,
    }
}

/// This study's identity.
fn identity(study: &Study) -> Result<Identity, StudyError> {
    let parameters = study
        .parameters
        .iter()
        .map(|p| (p.key.clone(), p.values.as_written()))
        .collect();
    let base = Scenario::standalone_text(&study.base, &[])
        .map_err(|e| e.to_string())
        .and_then(|text| toml::from_str(&text).map_err(|e| e.to_string()))
        .map_err(|e| error(study, format!("base scenario: {e}")))?;
    Ok(Identity {
        study: study.origin.clone(),
        parameters,
        design: study.design.as_written(),
        base,
    })
}

/// The record's text. The parameters are written one line each, in their order, a range as
/// an inline table: written as tables of their own, TOML puts them after every list, and the
/// record read back would hold the parameters in another order than the study's.
fn text(identity: &Identity) -> String {
    let study = toml::Value::String(identity.study.clone());
    let parameters: String = identity
        .parameters
        .iter()
        .map(|(key, values)| format!("{} = {values}\n", toml::Value::String(key.clone())))
        .collect();
    let mut rest = toml::Table::new();
    if let Some(design) = &identity.design {
        rest.insert("design".into(), toml::Value::Table(design.clone()));
    }
    rest.insert("base".into(), toml::Value::Table(identity.base.clone()));
    format!(
        "# The study whose cases this folder holds, recorded by `thermostamp sweep` \
         (docs/study.md):\n# a sweep of a study with other parameters or another base scenario \
         into this folder is refused.\nstudy = {study}\n\n[parameters]\n{parameters}\n{}",
        toml::to_string(&rest).unwrap_or_default()
    )
}

/// The folder's record, `None` where it has none.
fn read(study: &Study) -> Result<Option<Identity>, StudyError> {
    let path = study.folder.join(IDENTITY_FILE);
    let text = match std::fs::read_to_string(&path) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(error(study, format!("cannot read {}: {e}", path.display()))),
    };
    let unreadable = |why: String| {
        error(
            study,
            format!(
                "{} holds the cases of a study whose record {} cannot be read ({why}); a \
                 folder holds one study: choose another output.folder, or remove that one",
                study.folder.display(),
                path.display()
            ),
        )
    };
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| unreadable(e.message().to_string()))?;
    let mut section = |name: &str| match table.remove(name) {
        Some(toml::Value::Table(t)) => Ok(t),
        _ => Err(unreadable(format!("no [{name}]"))),
    };
    let (parameters, base) = (section("parameters")?, section("base")?);
    let design = match table.remove("design") {
        None => None,
        Some(toml::Value::Table(t)) => Some(t),
        Some(_) => return Err(unreadable("[design] is not a table".into())),
    };
    let recorded_study = match table.remove("study") {
        Some(toml::Value::String(s)) => s,
        _ => "?".into(),
    };
    Ok(Some(Identity {
        study: recorded_study,
        parameters,
        design,
        base,
    }))
}

/// Refused where `recorded` is another study than `ours`, naming its file, the record and what
/// differs.
fn compare(study: &Study, ours: &Identity, recorded: &Identity) -> Result<(), StudyError> {
    let recorded_method = recorded
        .design
        .as_ref()
        .map_or(Ok(Method::FullFactorial), |d| {
            DesignSection::from_table(d).and_then(|s| s.method())
        });
    let difference = if ours.design != recorded.design {
        "its design differs"
    } else if !recorded_method
        .is_ok_and(|method| same_parameters(&ours.parameters, &recorded.parameters, method))
    {
        "its parameters differ"
    } else if ours.base != recorded.base {
        "its base scenario differs"
    } else {
        return Ok(());
    };
    Err(error(
        study,
        format!(
            "{} holds the cases of another study ({}, recorded in {}): {difference}; a folder \
             holds one study: choose another output.folder, or remove that one",
            study.folder.display(),
            recorded.study,
            study.folder.join(IDENTITY_FILE).display()
        ),
    ))
}

/// The same keys in the same order, each with the same values, however written (ranges read
/// as the design `method` reads them).
fn same_parameters(ours: &toml::Table, recorded: &toml::Table, method: Method) -> bool {
    match (parameters(ours, method), parameters(recorded, method)) {
        (Ok(a), Ok(b)) => {
            a.len() == b.len()
                && a.iter()
                    .zip(&b)
                    .all(|(p, q)| p.key == q.key && p.values.same_as(&q.values))
        }
        _ => false,
    }
}

/// A folder without a record may hold no case folders: whose they are cannot be told.
fn unrecorded_cases(study: &Study) -> Result<(), StudyError> {
    let Some(case) = case_folders(&study.folder).next() else {
        return Ok(());
    };
    Err(error(
        study,
        format!(
            "{} holds case folders ({}) but no record of their study ({IDENTITY_FILE}): a \
             folder holds one study: choose another output.folder, or remove that one",
            study.folder.display(),
            case.display()
        ),
    ))
}

/// The entries `case-NNN` of `folder`, folders or not.
pub fn case_folders(folder: &Path) -> impl Iterator<Item = PathBuf> {
    std::fs::read_dir(folder)
        .into_iter()
        .flatten()
        .flatten()
        .filter(|entry| {
            entry.file_name().to_str().is_some_and(|name| {
                name.strip_prefix("case-").is_some_and(|digits| {
                    !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())
                })
            })
        })
        .map(|entry| entry.path())
}
