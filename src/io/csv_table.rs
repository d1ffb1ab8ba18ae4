//! Numeric CSV tables with named columns: a header line, then one row of numbers per line.
//! Blank lines and lines starting with `#` are comments. Every error names the file and line.

use super::InputError;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A numeric table whose columns are exactly the ones asked for, in that order.
#[derive(Clone, Debug, PartialEq)]
pub struct CsvTable {
    pub origin: String,
    /// Line number (1-based) of each row in the file.
    pub lines: Vec<usize>,
    /// `rows[i][j]`: row `i`, the `j`-th of the requested columns.
    pub rows: Vec<Vec<f64>>,
}

/// Reads the table at `path`, which must have exactly the columns `columns` (in any order).
pub fn read_csv_table(path: &Path, columns: &[&str]) -> Result<CsvTable, InputError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::in_file(&origin, format!("cannot read the file: {e}")))?;
    parse_csv_table(&text, &origin, columns)
}

/// Parses CSV `text`, which must have exactly the columns `columns`; `origin` names it in
/// messages.
pub fn parse_csv_table(text: &str, origin: &str, columns: &[&str]) -> Result<CsvTable, InputError> {
    parse(text, origin, columns, OtherColumns::Refused)
}

/// Parses CSV `text` for the columns `columns`, ignoring any others (a test machine's export
/// has time, extension, ... beside the two a fit reads); a requested column that is missing is
/// still an error, so a misspelt name does not go unnoticed.
pub fn parse_csv_columns(
    text: &str,
    origin: &str,
    columns: &[&str],
) -> Result<CsvTable, InputError> {
    parse(text, origin, columns, OtherColumns::Ignored)
}

/// What a header column that was not asked for means.
#[derive(Clone, Copy, PartialEq, Eq)]
enum OtherColumns {
    Refused,
    Ignored,
}

fn parse(
    text: &str,
    origin: &str,
    columns: &[&str],
    others: OtherColumns,
) -> Result<CsvTable, InputError> {
    let mut content = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let (header_line, header) = content
        .next()
        .ok_or_else(|| InputError::in_file(origin, "the file has no header line and no data"))?;
    let width = header.split(',').count();
    let order = column_order(header, header_line, origin, columns, others)?;
    let mut table = CsvTable {
        origin: origin.to_string(),
        lines: Vec::new(),
        rows: Vec::new(),
    };
    for (line, text) in content {
        let cells: Vec<&str> = text.split(',').map(str::trim).collect();
        if cells.len() != width {
            return Err(InputError::at_line(
                origin,
                line,
                format!("{} cells, the header has {width}", cells.len()),
            ));
        }
        let row = order
            .iter()
            .zip(columns)
            .map(|(&j, name)| parse_number(cells[j], name, origin, line))
            .collect::<Result<Vec<f64>, _>>()?;
        table.lines.push(line);
        table.rows.push(row);
    }
    if table.rows.is_empty() {
        return Err(InputError::in_file(
            origin,
            "the table has a header but no data rows",
        ));
    }
    Ok(table)
}

/// For each requested column, its position in the header.
fn column_order(
    header: &str,
    line: usize,
    origin: &str,
    columns: &[&str],
    others: OtherColumns,
) -> Result<Vec<usize>, InputError> {
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let expected = columns.join(",");
    let unknown = names.iter().find(|n| !columns.contains(n));
    if let Some(unknown) = unknown.filter(|_| others == OtherColumns::Refused) {
        return Err(InputError::at_line(
            origin,
            line,
            format!("unexpected column '{unknown}' (expected columns: {expected})"),
        ));
    }
    columns
        .iter()
        .map(|c| {
            let mut at = names
                .iter()
                .enumerate()
                .filter(|(_, n)| *n == c)
                .map(|(i, _)| i);
            match (at.next(), at.next()) {
                (Some(i), None) => Ok(i),
                (None, _) => Err(format!(
                    "missing column '{c}' (expected columns: {expected})"
                )),
                (Some(_), Some(_)) => Err(format!("column '{c}' appears twice")),
            }
            .map_err(|m| InputError::at_line(origin, line, m))
        })
        .collect()
}

fn parse_number(cell: &str, column: &str, origin: &str, line: usize) -> Result<f64, InputError> {
    match cell.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(InputError::at_line(
            origin,
            line,
            format!("column '{column}': '{cell}' is not a finite number"),
        )),
    }
}

/// Writes a header and rows of numbers as CSV, each as the shortest text that reads back to the
/// same double ([`number_text`]). A NaN or an
/// infinity is refused (`InvalidData`, naming the column and the row) rather than written:
/// the rows before it are kept.
pub fn write_csv<W: Write, R: AsRef<[f64]>>(
    out: &mut W,
    header: &[&str],
    rows: impl IntoIterator<Item = R>,
) -> std::io::Result<()> {
    writeln!(out, "{}", header.join(","))?;
    for (i, row) in rows.into_iter().enumerate() {
        if let Err(e) = check_finite_row(header, i + 1, row.as_ref()) {
            out.flush()?;
            return Err(e);
        }
        let cells: Vec<String> = row.as_ref().iter().map(|&v| number_text(v)).collect();
        writeln!(out, "{}", cells.join(","))?;
    }
    out.flush()
}

/// Data row `row` (1-based; line `row + 1` of the file) must hold only finite numbers: a NaN
/// or an infinity in a result file is a failure to report, never a cell for other tools to
/// choke on.
pub fn check_finite_row(header: &[&str], row: usize, values: &[f64]) -> std::io::Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(j) => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "column '{}', row {row} (line {}): {} is not a finite number",
                header.get(j).copied().unwrap_or("?"),
                row + 1,
                values[j]
            ),
        )),
    }
}

/// A CSV file written while a run goes: the header when it is created, then one row per
/// [`CsvStream::write_row`], each in a single write straight to the file (no buffer), so that a
/// run killed at any instant leaves whole rows only.
#[derive(Debug)]
pub struct CsvStream {
    path: PathBuf,
    file: std::fs::File,
    header: Vec<String>,
    /// Data rows written so far.
    rows: usize,
}

/// A file of results that could not be written, named.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {}: {source}", path.display())]
pub struct WriteError {
    pub path: PathBuf,
    pub source: std::io::Error,
}

impl CsvStream {
    /// Creates (or empties) `path` and writes `header` into it; a symbolic link at `path` is
    /// refused ([`super::product_file`]).
    pub fn create(path: &Path, header: &[&str]) -> Result<Self, WriteError> {
        let failed = |source| WriteError {
            path: path.to_path_buf(),
            source,
        };
        let file = super::product_file::create(path).map_err(failed)?;
        let mut stream = Self {
            path: path.to_path_buf(),
            file,
            header: header.iter().map(|h| h.to_string()).collect(),
            rows: 0,
        };
        stream.write_line(format!("{}\n", header.join(",")))?;
        Ok(stream)
    }

    /// Appends one row of numbers ([`number_text`]); it must have one per column.
    pub fn write_row(&mut self, row: &[f64]) -> Result<(), WriteError> {
        let failed = |source| WriteError {
            path: self.path.clone(),
            source,
        };
        if row.len() != self.header.len() {
            return Err(failed(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "a row of {} cells for {} columns",
                    row.len(),
                    self.header.len()
                ),
            )));
        }
        let header: Vec<&str> = self.header.iter().map(String::as_str).collect();
        check_finite_row(&header, self.rows + 1, row).map_err(failed)?;
        self.write_line(csv_line(row))?;
        self.rows += 1;
        Ok(())
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    fn write_line(&mut self, line: String) -> Result<(), WriteError> {
        self.file
            .write_all(line.as_bytes())
            .and_then(|()| self.file.flush())
            .map_err(|source| WriteError {
                path: self.path.clone(),
                source,
            })
    }
}

/// One row as a CSV line, newline included.
fn csv_line(row: &[f64]) -> String {
    let cells: Vec<String> = row.iter().map(|&v| number_text(v)).collect();
    format!("{}\n", cells.join(","))
}

/// `v` in the shortest exponent form that reads back to the same double (`1.8e0`,
/// `-2.5e-7`, at most 17 significant digits): a script reading the CSV gets the very numbers
/// the run computed, those the Python package hands over as arrays.
pub fn number_text(v: f64) -> String {
    format!("{v:e}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_columns_in_any_order_and_skips_comments() {
        let text = "# a comment\nb, a\n\n2.5, 1\n# another\n4,3e-1\n";
        let t = parse_csv_table(text, "h.csv", &["a", "b"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, 2.5], vec![0.3, 4.0]]);
        assert_eq!(t.lines, vec![4, 6]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_csv_table("a,b\n1,2\n3,x\n", "h.csv", &["a", "b"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "h.csv: line 3: column 'b': 'x' is not a finite number"
        );
        let e = parse_csv_table("a\n1\n", "h.csv", &["a", "b"]).unwrap_err();
        assert!(e.to_string().contains("missing column 'b'"), "{e}");
        let e = parse_csv_table("a,b,c\n1,2,3\n", "h.csv", &["a", "b"]).unwrap_err();
        assert!(e.to_string().contains("unexpected column 'c'"), "{e}");
        let e = parse_csv_table("a,b\n1,2,3\n", "h.csv", &["a", "b"]).unwrap_err();
        assert_eq!(e.line, Some(2));
        let e = parse_csv_table("a,b\n1,nan\n", "h.csv", &["a", "b"]).unwrap_err();
        assert_eq!(e.line, Some(2));
        assert!(parse_csv_table("# only\n", "h.csv", &["a"]).is_err());
        assert!(parse_csv_table("a\n", "h.csv", &["a"]).is_err());
    }

    #[test]
    fn other_columns_can_be_ignored_but_requested_ones_must_be_there() {
        let text = "time,b,note,a\n0,2.5,x,1\n1,4,y,3\n";
        let t = parse_csv_columns(text, "h.csv", &["a", "b"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, 2.5], vec![3.0, 4.0]]);
        assert!(parse_csv_table(text, "h.csv", &["a", "b"]).is_err());
        let e = parse_csv_columns(text, "h.csv", &["a", "c"]).unwrap_err();
        assert!(e.to_string().contains("missing column 'c'"), "{e}");
        let e = parse_csv_columns("a,b,c\n1,2\n", "h.csv", &["a"]).unwrap_err();
        assert_eq!(e.line, Some(2));
    }

    #[test]
    fn numbers_read_back_to_the_same_double() {
        for v in [
            0.1,
            1.0 / 3.0,
            -2.5e-7,
            6.02214076e23,
            f64::MIN_POSITIVE,
            0.0,
            -0.0,
        ] {
            let text = number_text(v);
            assert_eq!(
                text.parse::<f64>().unwrap().to_bits(),
                v.to_bits(),
                "{text}"
            );
        }
        assert_eq!(number_text(1.8), "1.8e0");
    }

    #[test]
    fn a_non_finite_value_is_refused_naming_column_and_row() {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut out = Vec::new();
            let e = write_csv(&mut out, &["x", "y"], [[1.0, 2.0], [3.0, bad]]).unwrap_err();
            assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
            assert_eq!(
                e.to_string(),
                format!("column 'y', row 2 (line 3): {bad} is not a finite number")
            );
            assert_eq!(std::str::from_utf8(&out).unwrap(), "x,y\n1e0,2e0\n");
        }
    }

    #[test]
    fn written_values_read_back() {
        let mut out = Vec::new();
        write_csv(&mut out, &["x", "y"], [[1.0, -2.5e-7], [3.25, 1e6]]).unwrap();
        let t = parse_csv_table(std::str::from_utf8(&out).unwrap(), "o.csv", &["x", "y"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, -2.5e-7], vec![3.25, 1e6]]);
    }

    #[test]
    fn streamed_rows_are_on_disk_after_each_call() {
        let dir =
            std::env::temp_dir().join(format!("thermostamp-csv-stream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("h.csv");
        let mut csv = CsvStream::create(&path, &["x", "y"]).unwrap();
        csv.write_row(&[1.0, -2.5e-7]).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, "x,y\n1e0,-2.5e-7\n");
        csv.write_row(&[3.25, 1e6]).unwrap();
        let t = read_csv_table(&path, &["x", "y"]).unwrap();
        assert_eq!(t.rows, vec![vec![1.0, -2.5e-7], vec![3.25, 1e6]]);
        let e = csv.write_row(&[1.0]).unwrap_err();
        assert!(e.to_string().contains("h.csv"), "{e}");
        let e = csv.write_row(&[f64::NAN, 1.0]).unwrap_err();
        assert!(e.to_string().contains("column 'x', row 3"), "{e}");
        let t = read_csv_table(&path, &["x", "y"]).unwrap();
        assert_eq!(t.rows.len(), 2, "the refused row is not written");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_full_disk_is_a_write_error_naming_the_file() {
        let e = CsvStream::create(Path::new("/dev/full"), &["x"]).unwrap_err();
        assert_eq!(e.source.raw_os_error(), Some(28), "{e}");
        assert!(e.to_string().starts_with("cannot write /dev/full"), "{e}");
    }
}
