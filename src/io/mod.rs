//! Readers and writers of the files users hand in and get back.

pub mod csv_table;
pub mod output_folder;
pub mod plot;
pub mod sheet_frame;
pub mod vtk;
pub mod xy_curve;

pub use csv_table::{read_csv_table, write_csv, CsvStream, CsvTable, WriteError};

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

/// One line: `line L, column C: message`.
pub fn describe_toml_error(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: {message}")
        }
        None => message,
    }
}
