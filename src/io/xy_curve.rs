//! Two-column measured curves (`x`, `y`) in CSV, as the identification commands read them:
//! tension, strip and shear curves differ only in their column names, the reasons given in
//! messages and the conversions applied afterwards, so the reading and the checks every such
//! curve needs (a header with one of the accepted names per column, `x` increasing, `y >= 0`)
//! live here once. Every error names the file, and the line where there is one.

use super::csv_table::parse_csv_columns;
use super::InputError;
use std::path::Path;

/// What a curve file looks like: accepted column names and why its values are checked.
#[derive(Clone, Copy, Debug)]
pub struct CurveLayout {
    /// Names the `x` column may have; the first one the header uses is read.
    pub x_names: &'static [&'static str],
    /// Names the `y` column may have, likewise.
    pub y_names: &'static [&'static str],
    /// End of a bad header's message, after "expected the columns ".
    pub expected: &'static str,
    /// Why `x` must increase, ending that message.
    pub why_increasing: &'static str,
    /// Why `y` must be `>= 0`, ending that message.
    pub why_non_negative: &'static str,
}

/// A curve read and checked against its [`CurveLayout`]: `x` strictly increasing, `y >= 0`.
#[derive(Clone, Debug, PartialEq)]
pub struct XyCurve {
    /// The `x` column's name as the header has it (one of `x_names`).
    pub x_name: &'static str,
    /// The `y` column's name as the header has it (one of `y_names`).
    pub y_name: &'static str,
    /// Line (1-based) of each point in the file.
    pub lines: Vec<usize>,
    pub x: Vec<f64>,
    pub y: Vec<f64>,
}

impl XyCurve {
    /// The `x` column as stretch for the tension curves: `1 + x` when the column is the
    /// engineering `strain`, `x` itself when it is the `stretch`. A stretch that is not positive
    /// is an error at its line of `origin`.
    pub fn stretch(&self, origin: &str) -> Result<Vec<f64>, InputError> {
        self.x
            .iter()
            .zip(&self.lines)
            .map(|(&x, &line)| {
                let stretch = if self.x_name == "strain" { 1.0 + x } else { x };
                if stretch > 0.0 {
                    Ok(stretch)
                } else {
                    Err(InputError::at_line(
                        origin,
                        line,
                        format!("{} = {x}: the stretch must be positive", self.x_name),
                    ))
                }
            })
            .collect()
    }
}

/// The text of the curve file at `path`, with the name that messages give it.
pub fn read_curve_text(path: &Path) -> Result<(String, String), InputError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::in_file(&origin, format!("cannot read the curve: {e}")))?;
    Ok((origin, text))
}

/// Parses and checks the CSV `text` of a curve laid out as `layout`; `origin` names it.
pub fn parse_xy_curve(
    text: &str,
    origin: &str,
    layout: &CurveLayout,
) -> Result<XyCurve, InputError> {
    if text.trim().is_empty() {
        return Err(InputError::in_file(origin, "the file is empty"));
    }
    let (x_name, y_name) = column_names(text, origin, layout)?;
    let table = parse_csv_columns(text, origin, &[x_name, y_name])?;
    let mut curve = XyCurve {
        x_name,
        y_name,
        lines: Vec::with_capacity(table.rows.len()),
        x: Vec::with_capacity(table.rows.len()),
        y: Vec::with_capacity(table.rows.len()),
    };
    for (row, &line) in table.rows.iter().zip(&table.lines) {
        let (x, y) = (row[0], row[1]);
        let at = |message: String| InputError::at_line(origin, line, message);
        if let Some(&previous) = curve.x.last().filter(|&&previous| x <= previous) {
            return Err(at(format!(
                "{x_name} = {x} does not increase (previous {previous}): {}",
                layout.why_increasing
            )));
        }
        if y < 0.0 {
            return Err(at(format!(
                "{y_name} = {y} is negative: {}",
                layout.why_non_negative
            )));
        }
        curve.lines.push(line);
        curve.x.push(x);
        curve.y.push(y);
    }
    Ok(curve)
}

/// Which of the accepted column names the header (the first line that is neither blank nor a
/// comment) uses; other columns are ignored, but two names for the same column are an error.
fn column_names(
    text: &str,
    origin: &str,
    layout: &CurveLayout,
) -> Result<(&'static str, &'static str), InputError> {
    let (line, header) = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .find(|(_, l)| !l.is_empty() && !l.starts_with('#'))
        .ok_or_else(|| InputError::in_file(origin, "the file has no header line and no data"))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let error = |message: String| InputError::at_line(origin, line, message);
    let pick = |choices: &[&'static str]| {
        let found: Vec<&'static str> = choices
            .iter()
            .copied()
            .filter(|c| names.contains(c))
            .collect();
        match found[..] {
            [] => Ok(None),
            [name] => Ok(Some(name)),
            _ => Err(error(format!(
                "header '{header}': the columns {} are the same quantity; keep one",
                found.join(" and ")
            ))),
        }
    };
    match (pick(layout.x_names)?, pick(layout.y_names)?) {
        (Some(x), Some(y)) => Ok((x, y)),
        _ => Err(error(format!(
            "header '{header}': expected the columns {} (others are ignored)",
            layout.expected
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAYOUT: CurveLayout = CurveLayout {
        x_names: &["strain", "stretch"],
        y_names: &["stress"],
        expected: "strain or stretch, and stress",
        why_increasing: "loading is monotonic",
        why_non_negative: "tension only",
    };

    fn error(text: &str) -> String {
        parse_xy_curve(text, "c.csv", &LAYOUT)
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn reads_the_first_accepted_name_of_each_column_in_any_order() {
        let c = parse_xy_curve(
            "# comment\nstress, stretch\n0,1\n\n2,1.5\n",
            "c.csv",
            &LAYOUT,
        )
        .unwrap();
        assert_eq!((c.x_name, c.y_name), ("stretch", "stress"));
        assert_eq!(
            (c.x, c.y, c.lines),
            (vec![1.0, 1.5], vec![0.0, 2.0], vec![3, 5])
        );
    }

    #[test]
    fn bad_curves_name_file_line_and_what_is_wrong() {
        assert_eq!(error(""), "c.csv: the file is empty");
        assert_eq!(error("  \n\n"), "c.csv: the file is empty");
        assert_eq!(
            error("# only\n"),
            "c.csv: the file has no header line and no data"
        );
        assert!(error("strain,stress\n").contains("no data rows"));
        assert_eq!(
            error("strain,stress\n0,0\n0.1,x\n"),
            "c.csv: line 3: column 'stress': 'x' is not a finite number"
        );
        assert_eq!(
            error("strain,stress\n0,0\n0.2,1\n0.2,2\n"),
            "c.csv: line 4: strain = 0.2 does not increase (previous 0.2): loading is monotonic"
        );
        assert_eq!(
            error("strain,stress\n0,0\n0.2,-1\n"),
            "c.csv: line 3: stress = -1 is negative: tension only"
        );
        assert_eq!(
            error("\nx,stress\n0,0\n"),
            "c.csv: line 2: header 'x,stress': expected the columns strain or stretch, and \
             stress (others are ignored)"
        );
        let e = error("strain,stretch,stress\n0,1,0\n");
        assert!(
            e.starts_with(
                "c.csv: line 1: header 'strain,stretch,stress': the columns strain and \
                           stretch are the same quantity"
            ),
            "{e}"
        );
        let c = parse_xy_curve("time,stress,strain\n0,0,0\n1,2,0.1\n", "c.csv", &LAYOUT).unwrap();
        assert_eq!((c.x, c.y), (vec![0.0, 0.1], vec![0.0, 2.0]));
    }
}
