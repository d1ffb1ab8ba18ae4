//! The iterations: the kinematic first guess, then forming runs of the blank cut to the
//! outline, each measuring how far inside the formed blank's edge the trim line lies and
//! giving the next outline: the trim line mapped back through that run, offset by the margin.

use super::mapping::{flat_from_drape, flat_from_formed};
use super::mesher::{mesh_outline, OutlineMesh};
use super::polygon::{self, Polygon};
use super::trim::{at, TrimLine};
use crate::drape::{drape, DoubleDome, DrapeParams, DrapeSurface};
use crate::forming::drape_preview::Generators;
use crate::forming::scenario::BlankShape;
use crate::forming::setup::blank_mesh;
use crate::forming::{FormingModel, FormingRun, Scenario};
use crate::io::csv_table::{write_csv, CsvStream};
use crate::io::output_folder::create_folder;
use anyhow::Context;
use nalgebra::Vector2;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The columns of [`HISTORY_CSV`].
pub const HISTORY_COLUMNS: [&str; 6] = [
    "iteration",
    "error_mm",
    "min_margin_mm",
    "max_margin_mm",
    "blank_area_mm2",
    "wall_s",
];

/// One row per forming iteration, written as each ends.
pub const HISTORY_CSV: &str = "outline-history.csv";

/// The trim line is mapped point by point, at most this many element sizes apart.
const TRIM_STEP: f64 = 0.25;

/// What the iterations aim at and when they stop.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutlineSettings {
    /// The margin asked for (mm): how far inside the formed blank's edge the trim line should
    /// lie, along the part.
    pub margin: f64,
    /// The most forming runs.
    pub iterations: usize,
    /// Stop once every trim point's margin is within this of the one asked for (mm).
    pub tolerance: f64,
}

/// How a formed blank covers the trim line.
#[derive(Clone, Debug, PartialEq)]
pub struct Coverage {
    /// Per trim point, its distance (mm) inside the blank's edge on the flat blank (negative
    /// outside: the part does not reach it).
    pub margins: Vec<f64>,
    /// The largest |margin − the margin asked for| (mm).
    pub error: f64,
    pub min: f64,
    pub max: f64,
}

/// The margins of the trim points `mapped` (on the flat blank) inside the blank's edge `edge`,
/// against the margin asked for.
pub fn coverage(edge: &[Vector2<f64>], mapped: &[Vector2<f64>], margin: f64) -> Coverage {
    let margins: Vec<f64> = mapped
        .iter()
        .map(|p| polygon::signed_distance(edge, p))
        .collect();
    let min = margins.iter().copied().fold(f64::INFINITY, f64::min);
    let max = margins.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let error = margins
        .iter()
        .map(|m| (m - margin).abs())
        .fold(0.0, f64::max);
    Coverage {
        margins,
        error,
        min,
        max,
    }
}

/// The outline that gives `margin` (mm) around the trim line `mapped` onto the flat blank: that
/// curve counter-clockwise, offset outward ([`polygon::offset_mitre`]). Errors where the mapped
/// curve crosses itself.
pub fn outline_around(mapped: &[Vector2<f64>], margin: f64) -> Result<Polygon, String> {
    let curve = polygon::counter_clockwise(mapped.to_vec());
    if let Some((i, _)) = polygon::first_crossing(&curve) {
        return Err(format!(
            "the trim line mapped onto the flat blank crosses itself near {}: the part folds \
             there (a wrinkle, or a trim line across the die's wall)",
            at(&curve[i])
        ));
    }
    let outline = polygon::offset_mitre(&curve, margin);
    if let Some((i, _)) = polygon::first_crossing(&outline) {
        return Err(format!(
            "the outline offset by the margin crosses itself near {}: the trim line turns \
             there more sharply than the margin allows; a smaller --margin",
            at(&outline[i])
        ));
    }
    Ok(outline)
}

/// The element size (mm) the blank is meshed at: the rectangle's, or its mesh file's.
pub fn element_size(scenario: &Scenario) -> Result<f64, String> {
    match scenario.blank.shape {
        BlankShape::Rectangle { element_size, .. } => Ok(element_size),
        BlankShape::File { .. } => Ok(blank_mesh(scenario)?.0.element_size()),
    }
}

/// The formed part as the kinematic first guess sees it: the punch's cap down to the stroke's
/// depth, as in the drape preview ([`crate::forming::drape_preview::FormedCap`]), continued
/// by a flat flange at that depth out to any distance, so that the net reaches a trim line on
/// the flange (the wall between punch and die, a clearance wide, is left out).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapAndFlange {
    pub dome: DoubleDome,
    /// Depth of the flange below the apex (mm).
    pub depth: f64,
}

impl DrapeSurface for CapAndFlange {
    fn height(&self, x: f64, y: f64) -> Option<f64> {
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        Some(
            self.dome
                .height(x, y)
                .map_or(-self.depth, |z| z.max(-self.depth)),
        )
    }

    fn gradient(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        match self.dome.height(x, y) {
            Some(z) if z > -self.depth => self.dome.gradient(x, y),
            _ => Some((0.0, 0.0)),
        }
    }
}

/// The first guess: the trim line mapped onto the flat blank through the kinematic drape of
/// the scenario's fabric (cells of `size` mm, from the punch's apex at the blank's ply angle,
/// as `thermostamp drape` lays it) on [`CapAndFlange`], and how it was made. Tools read from
/// files have no drape: the plan view of the trim line is taken as it is.
pub fn first_guess(scenario: &Scenario, trim: &TrimLine, size: f64) -> (Polygon, String) {
    let generators = Generators::of(scenario);
    match drape_cap_and_flange(scenario, trim, size, &generators) {
        Ok(net) => {
            // the net's apex is at z = 0, the formed part's at the stroke
            let stroke = scenario.process.stroke;
            let points: Vec<_> = trim
                .points
                .iter()
                .map(|p| p - nalgebra::Vector3::new(0.0, 0.0, stroke))
                .collect();
            let mapped = flat_from_drape(&net, &generators, &points, trim.in_plan);
            (
                mapped,
                format!(
                    "kinematic drape on the punch and a flat flange, {} mm cells",
                    net.cell()
                ),
            )
        }
        Err(e) => (
            trim.plan(),
            format!("the trim line's plan view (no drape: {e})"),
        ),
    }
}

/// The pin-jointed net on [`CapAndFlange`], out past the farthest trim point.
fn drape_cap_and_flange(
    scenario: &Scenario,
    trim: &TrimLine,
    size: f64,
    generators: &Generators,
) -> Result<crate::drape::DrapeResult, String> {
    let tools = scenario.built_in_tools("the kinematic first guess")?;
    let surface = CapAndFlange {
        dome: DoubleDome {
            radius: tools.punch_radius,
            half_length: tools.ridge_half_length(),
        },
        depth: scenario.process.stroke.min(tools.punch_radius),
    };
    let start = Vector2::new(generators.start.0, generators.start.1);
    let farthest = trim
        .points
        .iter()
        .map(|p| (p.xy() - start).norm())
        .fold(0.0, f64::max);
    // the flat fabric reaches farther than the plan view by what the cap takes up
    let reach = farthest + 0.5 * std::f64::consts::PI * tools.punch_radius + size;
    let params = DrapeParams {
        cell: size,
        start: generators.start,
        warp_angle_deg: generators.warp_angle,
        max_cells: (reach / size).ceil() as usize + 1,
    };
    drape(&surface, &params)
}

/// One forming iteration.
#[derive(Clone, Debug)]
pub struct IterationRecord {
    /// 1, 2, ...
    pub iteration: usize,
    /// The outline run (flat, counter-clockwise) and the blank's edge as meshed.
    pub outline: Polygon,
    pub edge: Polygon,
    /// The trim line mapped back through this run.
    pub mapped: Polygon,
    pub coverage: Coverage,
    /// The blank's area (mm²).
    pub area: f64,
    /// This iteration's wall time (s): meshing, the run and its files, the measures.
    pub wall_seconds: f64,
    /// The forming run's folder.
    pub folder: PathBuf,
}

/// The iterations' outcome.
#[derive(Clone, Debug)]
pub struct OutlineResult {
    /// The first guess: the trim line on the flat blank and how it was made.
    pub first_guess: (Polygon, String),
    pub history: Vec<IterationRecord>,
    /// The iteration whose outline is the result (index into `history`): the one that
    /// converged, or else the covering one nearest the margin, or else the last.
    pub chosen: usize,
    /// Whether the error fell below the tolerance.
    pub converged: bool,
    /// Whether the chosen outline's blank covers the trim line with at least the margin less
    /// the tolerance everywhere.
    pub covered: bool,
}

impl OutlineResult {
    pub fn chosen(&self) -> &IterationRecord {
        &self.history[self.chosen]
    }
}

/// Runs the scenario on its blank cut to an outline, into a folder, and hands back the model
/// and the run: the command line's run with its progress bar and files.
pub type FormingRunner<'a> =
    dyn FnMut(&Scenario, &Path) -> anyhow::Result<(FormingModel, FormingRun)> + 'a;

/// The iterations into `dir`: `outline-NN.csv` and `iteration-NN/` (the blank's mesh
/// `blank.msh` and the forming run's files) per iteration, the history row by row; `report`
/// hears of each iteration as it ends. A forming run that stops is the error, naming its
/// iteration; the files so far are kept.
pub fn iterate(
    scenario: &Scenario,
    trim: &TrimLine,
    settings: &OutlineSettings,
    dir: &Path,
    runner: &mut FormingRunner<'_>,
    report: &mut dyn FnMut(&IterationRecord),
) -> anyhow::Result<OutlineResult> {
    let size = element_size(scenario).map_err(|e| anyhow::anyhow!(e))?;
    let trim = trim.resampled(TRIM_STEP * size);
    let first_guess = first_guess(scenario, &trim, size);
    let mut outline = outline_around(&first_guess.0, settings.margin)
        .map_err(|e| anyhow::anyhow!("the first guess ({}): {e}", first_guess.1))?;
    let mut history_csv = CsvStream::create(&dir.join(HISTORY_CSV), &HISTORY_COLUMNS)?;
    let mut history: Vec<IterationRecord> = Vec::new();
    let mut converged = false;
    for k in 1..=settings.iterations.max(1) {
        let start = Instant::now();
        write_outline_csv(&dir.join(outline_csv_name(k)), &outline)?;
        let blank =
            mesh_outline(&outline, size).map_err(|e| anyhow::anyhow!("iteration {k}: {e}"))?;
        let folder = dir.join(format!("iteration-{k:02}"));
        let s = scenario_on(scenario, &blank, &folder)?;
        let (forming, run) = runner(&s, &folder)?;
        let state = match run.outcome {
            Ok(state) => state,
            Err(e) => {
                return Err(anyhow::Error::from(e).context(format!(
                    "iteration {k}: the forming run of the blank of {} stopped (its files are \
                     in {})",
                    outline_csv_name(k),
                    folder.display()
                )))
            }
        };
        let mapped = flat_from_formed(
            &forming.model.mesh.nodes,
            &state.positions,
            &forming.model.mesh.cells,
            &trim.points,
            trim.in_plan,
        );
        let edge = blank.edge_polygon();
        let coverage = coverage(&edge, &mapped, settings.margin);
        let record = IterationRecord {
            iteration: k,
            outline: outline.clone(),
            edge,
            mapped,
            area: blank.mesh.total_area(),
            wall_seconds: start.elapsed().as_secs_f64(),
            folder,
            coverage,
        };
        history_csv.write_row(&[
            k as f64,
            record.coverage.error,
            record.coverage.min,
            record.coverage.max,
            record.area,
            record.wall_seconds,
        ])?;
        report(&record);
        converged = record.coverage.error < settings.tolerance;
        let next = outline_around(&record.mapped, settings.margin);
        history.push(record);
        if converged || k == settings.iterations {
            break;
        }
        outline = next.map_err(|e| anyhow::anyhow!("iteration {k}: {e}"))?;
    }
    let covers = |r: &IterationRecord| r.coverage.min >= settings.margin - settings.tolerance;
    let chosen = if converged {
        history.len() - 1
    } else {
        (0..history.len())
            .filter(|&k| covers(&history[k]))
            .min_by(|&a, &b| {
                history[a]
                    .coverage
                    .error
                    .total_cmp(&history[b].coverage.error)
            })
            .unwrap_or(history.len() - 1)
    };
    let covered = covers(&history[chosen]);
    Ok(OutlineResult {
        first_guess,
        history,
        chosen,
        converged,
        covered,
    })
}

/// `outline-NN.csv`: the outline run in iteration `k`.
pub fn outline_csv_name(k: usize) -> String {
    format!("outline-{k:02}.csv")
}

/// The scenario with its blank read from `blank` written as `folder/blank.msh`.
fn scenario_on(
    scenario: &Scenario,
    blank: &OutlineMesh,
    folder: &Path,
) -> anyhow::Result<Scenario> {
    create_folder(folder)?;
    let path = folder.join("blank.msh");
    crate::mesh::gmsh::write_msh(&path, &blank.mesh)?;
    let mut s = scenario.clone();
    s.blank.shape = BlankShape::File {
        mesh: path,
        element_set: None,
    };
    Ok(s)
}

/// The outline as CSV `x,y` (mm), closed: the first point repeated at the end.
pub fn write_outline_csv(path: &Path, outline: &[Vector2<f64>]) -> anyhow::Result<()> {
    let file = crate::io::product_file::create(path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    let rows = outline.iter().chain(outline.first()).map(|p| [p.x, p.y]);
    let mut out = std::io::BufWriter::new(file);
    write_csv(&mut out, &["x", "y"], rows)
        .with_context(|| format!("cannot write {}", path.display()))?;
    std::io::Write::flush(&mut out).with_context(|| format!("cannot write {}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_margins_of_points_inside_and_outside_a_square_edge() {
        let edge = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(10.0, 0.0),
            Vector2::new(10.0, 10.0),
            Vector2::new(0.0, 10.0),
        ];
        let mapped = [Vector2::new(5.0, 2.0), Vector2::new(5.0, 11.0)];
        let c = coverage(&edge, &mapped, 3.0);
        assert_eq!(c.margins, [2.0, -1.0]);
        assert_eq!((c.min, c.max, c.error), (-1.0, 2.0, 4.0));
    }

    #[test]
    fn the_outline_around_a_clockwise_square() {
        let cw = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(0.0, 10.0),
            Vector2::new(10.0, 10.0),
            Vector2::new(10.0, 0.0),
        ];
        let out = outline_around(&cw, 2.0).unwrap();
        assert!((polygon::signed_area(&out) - 196.0).abs() < 1e-9);
    }
}
