//! Readers and writers of the files users hand in and get back.

pub mod csv_table;
pub mod dxf;
pub mod message;
pub mod output_folder;
pub mod plot;
pub mod product_file;
pub mod sheet_frame;
pub mod tool_frame;
pub mod vtk;
pub mod xy_curve;

pub use csv_table::{check_finite_row, read_csv_table, write_csv, CsvStream, CsvTable, WriteError};

/// Bad input, located in its file: `origin: line N: message`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{origin}: {}{message}", line.map(|l| format!("line {l}: ")).unwrap_or_default())]
pub struct InputError {
    pub origin: String,
    pub line: Option<usize>,
    pub message: String,
}

impl InputError {
    pub fn at_line(origin: &str, line: usize, message: impl Into<String>) -> Self {
        Self {
            origin: origin.to_string(),
            line: Some(line),
            message: message.into(),
        }
    }

    pub fn in_file(origin: &str, message: impl Into<String>) -> Self {
        Self {
            origin: origin.to_string(),
            line: None,
            message: message.into(),
        }
    }
}

/// Deserializes TOML `text` into `T`; an error is one line naming where and what:
/// `line L, column C: key `a.b`: message` (the key is left out where the text has none, e.g.
/// a syntax error).
pub fn from_toml_text<T: serde::de::DeserializeOwned>(text: &str) -> Result<T, String> {
    let deserializer = toml::Deserializer::new(text);
    serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let key = key_of(e.path());
        let inner = e.into_inner();
        let message = format!("{key}{}", toml_message(&inner));
        match inner.span() {
            Some(span) => format!("{}: {message}", line_and_column(text, span.start)),
            None => message,
        }
    })
}

/// Deserializes a TOML table built in memory (a scenario with `--set` overrides applied) into
/// `T`; an error names the key: `key `a.b`: message`.
pub fn from_toml_value<T: serde::de::DeserializeOwned>(value: toml::Value) -> Result<T, String> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let key = key_of(e.path());
        format!("{key}{}", toml_message(e.inner()))
    })
}

/// `key `a.b`: ` for a path inside the document, nothing at its root; a list's element by its
/// place from 1 (`a[1]` the first), as `--set` names it.
fn key_of(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut key = String::new();
    for segment in path.iter() {
        match segment {
            Segment::Seq { index } => key += &format!("[{}]", index + 1),
            Segment::Map { key: name } => {
                if !key.is_empty() {
                    key.push('.');
                }
                key += name;
            }
            Segment::Enum { variant } => {
                if !key.is_empty() {
                    key.push('.');
                }
                key += variant;
            }
            Segment::Unknown => key += ".?",
        }
    }
    if key.is_empty() {
        String::new()
    } else {
        format!("key `{key}`: ")
    }
}

fn toml_message(e: &toml::de::Error) -> String {
    e.message().trim().replace('\n', " ")
}

/// `line L, column C` of the byte offset `at` in `text`.
fn line_and_column(text: &str, at: usize) -> String {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    format!("line {line}, column {column}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct Doc {
        process: Process,
    }

    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct Process {
        stroke: f64,
    }

    #[test]
    fn a_type_error_names_the_key_and_the_line() {
        let e = from_toml_text::<Doc>("[process]\nstroke = \"abc\"\n").unwrap_err();
        assert!(
            e.starts_with("line 2, column 10: key `process.stroke`: "),
            "{e}"
        );
    }

    #[test]
    fn a_value_built_in_memory_names_the_key() {
        let value: toml::Value = toml::from_str("[process]\nstroke = \"abc\"\n").unwrap();
        let e = from_toml_value::<Doc>(value).unwrap_err();
        assert!(e.starts_with("key `process.stroke`: "), "{e}");
    }

    #[derive(serde::Deserialize, Debug)]
    #[allow(dead_code)]
    struct Layup {
        plies: Vec<Process>,
    }

    /// A list's element is named by its place from 1, as `--set plies[2].stroke=1` names it.
    #[test]
    fn an_element_of_a_list_is_named_by_its_place_from_one() {
        let e = from_toml_text::<Layup>("[[plies]]\nstroke = 1.0\n[[plies]]\nstroke = \"x\"\n")
            .unwrap_err();
        assert!(e.contains("key `plies[2].stroke`: "), "{e}");
    }

    #[test]
    fn a_syntax_error_names_the_line() {
        let e = from_toml_text::<Doc>("[process]\nstroke = = 1\n").unwrap_err();
        assert!(e.starts_with("line 2, column"), "{e}");
    }
}
