//! The trim line: a closed curve on the formed part (`x,y,z`), or its plan view (`x,y`, seen
//! along the stroke axis z), read from a CSV file or made as a circle about the axis, and
//! checked before any run: enough points, closed, not crossing itself.

use super::polygon::{self, Polygon};
use crate::io::csv_table::parse_csv_table;
use crate::io::InputError;
use nalgebra::{Vector2, Vector3};
use std::path::Path;

/// A closing edge this many times longer than every other edge marks an open curve: points
/// along three sides of a part and none along the fourth.
const OPEN_RATIO: f64 = 5.0;

/// A closed trim line.
#[derive(Clone, Debug, PartialEq)]
pub struct TrimLine {
    /// Where it came from, for messages: the file, or `--trim-circle R`.
    pub origin: String,
    /// Its points in order (mm), the last joined to the first; z = 0 for a plan trim line.
    pub points: Vec<Vector3<f64>>,
    /// Whether only the plan view is known (the file had no z column): the points are matched
    /// to the formed part seen from above, not in space.
    pub in_plan: bool,
}

impl TrimLine {
    /// The plan view of the line.
    pub fn plan(&self) -> Polygon {
        self.points.iter().map(|p| p.xy()).collect()
    }

    /// The line with every edge cut into pieces no longer than `longest` (mm), as it is mapped
    /// point by point.
    pub fn resampled(&self, longest: f64) -> TrimLine {
        let n = self.points.len();
        let mut points = Vec::new();
        for k in 0..n {
            let (a, b) = (self.points[k], self.points[(k + 1) % n]);
            let pieces = ((b - a).norm() / longest).ceil().max(1.0) as usize;
            points.extend((0..pieces).map(|s| a + (b - a) * (s as f64 / pieces as f64)));
        }
        TrimLine {
            points,
            ..self.clone()
        }
    }
}

/// A circle of `radius` (mm) about the stroke axis, in plan, in `segments` equal chords
/// counter-clockwise from +x.
pub fn trim_circle(radius: f64, segments: usize) -> TrimLine {
    let segments = segments.max(8);
    let points = (0..segments)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / segments as f64;
            Vector3::new(radius * t.cos(), radius * t.sin(), 0.0)
        })
        .collect();
    TrimLine {
        origin: format!("--trim-circle {radius}"),
        points,
        in_plan: true,
    }
}

/// Reads the trim line at `path`: a CSV with the header `x,y,z` (on the formed part) or `x,y`
/// (its plan view), mm; every error names the file and, where it can, the line.
pub fn read_trim_csv(path: &Path) -> Result<TrimLine, InputError> {
    let origin = path.display().to_string();
    let text = std::fs::read_to_string(path)
        .map_err(|e| InputError::in_file(&origin, format!("cannot read the trim line: {e}")))?;
    parse_trim_csv(&text, &origin)
}

/// [`read_trim_csv`] of `text`, named `origin` in messages.
pub fn parse_trim_csv(text: &str, origin: &str) -> Result<TrimLine, InputError> {
    let header = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap_or("");
    let in_plan = !header.split(',').any(|c| c.trim() == "z");
    let columns: &[&str] = if in_plan {
        &["x", "y"]
    } else {
        &["x", "y", "z"]
    };
    let table = parse_csv_table(text, origin, columns)?;
    let mut points = Vec::new();
    let mut lines = Vec::new();
    for (row, &line) in table.rows.iter().zip(&table.lines) {
        let p = Vector3::new(row[0], row[1], row.get(2).copied().unwrap_or(0.0));
        // a point repeating the one before adds nothing (a closed curve often repeats its
        // first point at the end)
        if points
            .last()
            .is_some_and(|q: &Vector3<f64>| (p - q).norm() == 0.0)
        {
            continue;
        }
        points.push(p);
        lines.push(line);
    }
    if points.len() > 1 && points[0] == points[points.len() - 1] {
        points.pop();
        lines.pop();
    }
    check_closed_curve(&points, &lines, origin)?;
    if in_plan {
        let plan: Polygon = points.iter().map(|p| p.xy()).collect();
        if let Some((i, j)) = polygon::first_crossing(&plan) {
            let n = plan.len();
            return Err(InputError::at_line(
                origin,
                lines[i],
                format!(
                    "the trim line crosses itself: its segment from line {} to line {} meets the \
                     one from line {} to line {}",
                    lines[i],
                    lines[(i + 1) % n],
                    lines[j],
                    lines[(j + 1) % n]
                ),
            ));
        }
    }
    Ok(TrimLine {
        origin: origin.to_string(),
        points,
        in_plan,
    })
}

/// At least three distinct points, and a closing edge not much longer than the others.
fn check_closed_curve(
    points: &[Vector3<f64>],
    lines: &[usize],
    origin: &str,
) -> Result<(), InputError> {
    if points.len() < 3 {
        return Err(InputError::in_file(
            origin,
            format!(
                "{} distinct point(s): a closed trim line needs at least 3",
                points.len()
            ),
        ));
    }
    let n = points.len();
    let longest_inner = (0..n - 1)
        .map(|k| (points[k + 1] - points[k]).norm())
        .fold(0.0, f64::max);
    let closing = (points[0] - points[n - 1]).norm();
    if n > 3 && closing > OPEN_RATIO * longest_inner {
        return Err(InputError::at_line(
            origin,
            lines[n - 1],
            format!(
                "the curve ends {closing:.1} mm from where it starts (line {}), more than {OPEN_RATIO} \
                 times any step between its points: is it open? Give the missing points, or \
                 repeat the first point at the end",
                lines[0]
            ),
        ));
    }
    Ok(())
}

/// Where a plan point lies for messages: `(x, y)` to 0.1 mm.
pub fn at(p: &Vector2<f64>) -> String {
    format!("({:.1}, {:.1}) mm", p.x, p.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plan_csv_and_a_space_csv() {
        let plan = parse_trim_csv("x,y\n0,0\n1,0\n1,1\n0,1\n0,0\n", "t.csv").unwrap();
        assert!(plan.in_plan);
        assert_eq!(plan.points.len(), 4, "the repeated first point is dropped");
        let space = parse_trim_csv("# on the part\nz,x,y\n1,0,0\n2,1,0\n3,0,1\n", "s.csv").unwrap();
        assert!(!space.in_plan);
        assert_eq!(space.points[1], Vector3::new(1.0, 0.0, 2.0));
    }

    #[test]
    fn bad_trim_lines_name_the_file_and_line() {
        let e = parse_trim_csv("x,y\n0,0\n1,0\n", "t.csv").unwrap_err();
        assert!(e.to_string().contains("t.csv: 2 distinct point(s)"), "{e}");
        let e = parse_trim_csv("x,y\n0,0\n1,NaN\n1,1\n", "t.csv").unwrap_err();
        assert!(e.to_string().starts_with("t.csv: line 3:"), "{e}");
        let e = parse_trim_csv("x,y\n0,0\n1,1\n1,0\n0,1\n", "t.csv").unwrap_err();
        assert!(e.to_string().contains("crosses itself"), "{e}");
        let open = "x,y\n0,0\n1,0\n2,0\n3,0\n4,0\n5,0\n6,0\n6,1\n6,2\n6,3\n6,4\n6,5\n6,6\n";
        let e = parse_trim_csv(open, "t.csv").unwrap_err();
        assert!(e.to_string().contains("line 14: the curve ends"), "{e}");
    }

    #[test]
    fn a_circle_and_its_resampling() {
        let c = trim_circle(10.0, 4);
        assert_eq!(c.points.len(), 8, "at least 8 chords");
        let fine = c.resampled(1.0);
        assert!(fine.points.len() >= 64);
        assert!(fine.points.iter().all(|p| p.norm() <= 10.0 + 1e-12));
    }
}
