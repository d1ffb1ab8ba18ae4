//! Readers and writers of the files users hand in and get back.

pub mod csv_table;
pub mod plot;
pub mod sheet_frame;
pub mod vtk;

pub use csv_table::{read_csv_table, write_csv, CsvTable};

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
