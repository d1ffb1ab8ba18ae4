//! PNG line plots (force–displacement curves and the like).
//!
//! Text is drawn with Liberation Sans, embedded in the binary (`assets/fonts/`), so plots
//! render the same on a machine with no system fonts and no fontconfig, as CI is. The picture
//! is drawn into memory and encoded with the `png` crate, so that every I/O failure can name
//! the file.

use ab_glyph::FontRef;
use backend::PlotBackend;
use plotters::chart::SeriesAnno;
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineStyle {
    Solid,
    Dashed,
    /// A filled circle at each point, no line: for measured data or sparse samples.
    Markers,
}

/// One curve: `points` are `(x, y)` in the caller's units. An empty label leaves the series
/// out of the legend.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub style: LineStyle,
    /// Index into the palette; by default the series' own index, so that a caller can give
    /// data and model of the same case one colour.
    pub colour: Option<usize>,
}

impl Series {
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, style: LineStyle) -> Self {
        Self {
            label: label.into(),
            points,
            style,
            colour: None,
        }
    }

    /// The same series drawn in palette colour `index`.
    pub fn with_colour(self, index: usize) -> Self {
        Self {
            colour: Some(index),
            ..self
        }
    }
}

/// A plot of one or more series on shared axes. Labels carry their units, e.g. `"u (mm)"`.
#[derive(Clone, Debug, PartialEq)]
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// A line plot with a second y axis on the right for series of another quantity (e.g. forces
/// on the left, a displacement on the right); the right axis's series take the palette's
/// colours after the left's.
#[derive(Clone, Debug, PartialEq)]
pub struct TwinPlot {
    pub plot: LinePlot,
    /// The right axis's label, with units.
    pub right_label: String,
    pub right: Vec<Series>,
}

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("plot '{title}': no points to draw")]
    Empty { title: String },
    #[error("plot '{title}': none of its {count} points is finite")]
    NoFinitePoints { title: String, count: usize },
    #[error("plot '{title}': {width} x {height} px is outside {MIN_WIDTH} x {MIN_HEIGHT}..{MAX_SIDE} x {MAX_SIDE}")]
    Size {
        title: String,
        width: u32,
        height: u32,
    },
    #[error("plot '{title}': drawing failed: {message}")]
    Draw { title: String, message: String },
    #[error("the embedded plot font cannot be read")]
    Font,
    #[error("{}: cannot write the plot: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: cannot encode the plot as PNG: {source}", path.display())]
    Encode {
        path: PathBuf,
        source: png::EncodingError,
    },
}

/// Smallest picture that still has room for the title, labels and a legible plotting area.
const MIN_WIDTH: u32 = 240;
const MIN_HEIGHT: u32 = 180;
/// Largest side accepted: keeps the supersampled RGB buffer (3 bytes a pixel) near 200 MB.
const MAX_SIDE: u32 = 4096;

/// plotters draws lines and markers without anti-aliasing; drawing at this many times the
/// size and averaging each block of pixels smooths curves that would otherwise look stepped.
const SUPERSAMPLE: u32 = 2;

/// The size the text and margins are designed for; other sizes scale them.
const DESIGN_SIZE: (f64, f64) = (900.0, 600.0);

/// Tableau 10: distinct hues that stay apart for the common colour-vision deficiencies.
/// Series past the tenth reuse them in order.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The family name the embedded font is registered under; plotters' own defaults use it too.
const FONT_FAMILY: &str = "sans-serif";
const FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/LiberationSans-Regular.ttf");

/// A tick closer to zero than this many steps is zero, off by rounding.
const ZERO_TICK: f64 = 1e-6;

/// Fraction of the data span added on each side of the axes, so curves do not touch the frame.
const MARGIN: f64 = 0.04;

/// Writes the plot as a PNG of `width` x `height` pixels (e.g. 900 x 600).
pub fn write_png(path: &Path, plot: &LinePlot, width: u32, height: u32) -> Result<(), PlotError> {
    write_lines(path, plot, None, (width, height))
}

/// Writes the plot with its second axis as a PNG of `width` x `height` pixels.
pub fn write_twin_png(
    path: &Path,
    twin: &TwinPlot,
    width: u32,
    height: u32,
) -> Result<(), PlotError> {
    let right = LinePlot {
        series: twin.right.clone(),
        y_label: twin.right_label.clone(),
        ..twin.plot.clone()
    };
    write_lines(path, &twin.plot, Some(&right), (width, height))
}

/// The line plot `plot`, with `right`'s series on a second axis where given.
fn write_lines(
    path: &Path,
    plot: &LinePlot,
    right: Option<&LinePlot>,
    (width, height): (u32, u32),
) -> Result<(), PlotError> {
    check_size(plot, width, height)?;
    let series = finite_series(plot)?;
    let right = match right {
        Some(r) => Some((r, finite_series(r)?)),
        None => None,
    };
    let font = embedded_font()?;
    let (fine_width, fine_height) = (SUPERSAMPLE * width, SUPERSAMPLE * height);
    let mut fine = vec![255u8; 3 * fine_width as usize * fine_height as usize];
    {
        let bitmap = BitMapBackend::with_buffer(&mut fine, (fine_width, fine_height));
        let root = PlotBackend { bitmap, font }.into_drawing_area();
        let right = right.as_ref().map(|(r, s)| (*r, s.as_slice()));
        draw(&root, plot, &series, right).map_err(|message| PlotError::Draw {
            title: plot.title.clone(),
            message,
        })?;
    }
    let rgb = downsample(&fine, fine_width as usize, SUPERSAMPLE as usize);
    encode_png(path, &rgb, width, height)
}

fn check_size(plot: &LinePlot, width: u32, height: u32) -> Result<(), PlotError> {
    if (MIN_WIDTH..=MAX_SIDE).contains(&width) && (MIN_HEIGHT..=MAX_SIDE).contains(&height) {
        Ok(())
    } else {
        Err(PlotError::Size {
            title: plot.title.clone(),
            width,
            height,
        })
    }
}

/// The points of each series with non-finite ones dropped (a series may end up empty);
/// an error when nothing at all is left to draw.
fn finite_series(plot: &LinePlot) -> Result<Vec<Vec<(f64, f64)>>, PlotError> {
    let count: usize = plot.series.iter().map(|s| s.points.len()).sum();
    if count == 0 {
        return Err(PlotError::Empty {
            title: plot.title.clone(),
        });
    }
    let finite: Vec<Vec<(f64, f64)>> = plot
        .series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .copied()
                .filter(|(x, y)| x.is_finite() && y.is_finite())
                .collect()
        })
        .collect();
    if finite.iter().all(Vec::is_empty) {
        return Err(PlotError::NoFinitePoints {
            title: plot.title.clone(),
            count,
        });
    }
    Ok(finite)
}

/// The embedded font, parsed once and registered once with plotters, which keeps fonts in a
/// process-wide table and sizes legends with it.
fn embedded_font() -> Result<FontRef<'static>, PlotError> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| {
        let font = FontRef::try_from_slice(FONT_BYTES).ok()?;
        register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES).ok()?;
        Some(font)
    })
    .clone()
    .ok_or(PlotError::Font)
}

/// Sizes drawn as on a [`DESIGN_SIZE`] picture, scaled to the actual one.
struct DesignScale {
    scale: f64,
}

impl DesignScale {
    fn of(root: &DrawingArea<PlotBackend, Shift>) -> Self {
        let (width, height) = root.dim_in_pixel();
        Self {
            scale: (f64::from(width) / DESIGN_SIZE.0).min(f64::from(height) / DESIGN_SIZE.1),
        }
    }

    /// A length of `design` pixels on the design picture, at least one pixel.
    fn px(&self, design: f64) -> u32 {
        (design * self.scale).round().max(1.0) as u32
    }

    /// The embedded font at `design` points on the design picture.
    fn font(&self, design: f64) -> (&'static str, f64) {
        (FONT_FAMILY, f64::from(self.px(design)))
    }
}

/// Draws frame, grid, curves and legend; `series` holds the finite points of `plot.series`,
/// `right` a second plot's series and their finite points for the axis on the right.
fn draw(
    root: &DrawingArea<PlotBackend, Shift>,
    plot: &LinePlot,
    series: &[Vec<(f64, f64)>],
    right: Option<(&LinePlot, &[Points])>,
) -> Result<(), String> {
    let (width, height) = root.dim_in_pixel();
    let design = DesignScale::of(root);
    let (px, font) = (|d: f64| design.px(d), |d: f64| design.font(d));

    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let right_points = right.map_or(&[][..], |(_, points)| points);
    let all = series.iter().chain(right_points).flatten().copied();
    // About one tick every 110 design pixels across and 85 up, room for labels like "-1.5e-6".
    let ticks =
        |pixels: u32, spacing: f64| (f64::from(pixels) / design.scale / spacing).clamp(3.0, 12.0);
    let x_axis = Axis::new(
        padded_range(all.clone().map(|(x, _)| x)),
        ticks(width, 110.0),
    );
    let y_ticks = ticks(height, 85.0);
    let y_axis = Axis::new(
        padded_range(series.iter().flatten().map(|&(_, y)| y)),
        y_ticks,
    );
    // the right axis: its series' span, or (unused) the left's
    let y_right = match right {
        Some((_, points)) => Axis::new(padded_range(points.iter().flatten().map(|p| p.1)), y_ticks),
        None => Axis::new(y_axis.range.clone(), y_ticks),
    };

    // Room beside the plot for the widest tick label, the tick marks and the rotated label.
    let tick_style = TextStyle::from(font(15.0).into_font());
    let widest = |axis: &Axis| {
        axis.major
            .iter()
            .map(|v| root.estimate_text_size(&axis.format_ext(v), &tick_style))
            .try_fold(0, |widest, size| size.map(|(w, _)| widest.max(w)))
            .map_err(|e| e.to_string())
    };
    let widest_tick = widest(&y_axis)?;
    let right_room = match right {
        Some(_) => widest(&y_right)? + px(44.0),
        None => 0,
    };
    // the legend's corner judged on all curves, the right's scaled onto the left axis
    let onto_left = |(x, y): (f64, f64)| {
        let (r, l) = (&y_right.range, &y_axis.range);
        (
            x,
            l.start + (y - r.start) / (r.end - r.start) * (l.end - l.start),
        )
    };
    let mut placed: Vec<Vec<(f64, f64)>> = series.to_vec();
    placed.extend(
        right_points
            .iter()
            .map(|s| s.iter().copied().map(onto_left).collect()),
    );
    let legend_corner = emptiest_corner(&placed, &x_axis.range, &y_axis.range);
    let x_right = Axis::new(x_axis.range.clone(), ticks(width, 110.0));

    let body = titled(root, &plot.title, &design)?;
    let mut chart = ChartBuilder::on(&body)
        .margin(px(16.0))
        .x_label_area_size(px(56.0))
        .y_label_area_size(widest_tick + px(44.0))
        .right_y_label_area_size(right_room)
        .build_cartesian_2d(x_axis, y_axis)
        .map_err(|e| e.to_string())?
        .set_secondary_coord(x_right, y_right);
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .axis_desc_style(font(18.0))
        .label_style(font(15.0))
        .set_all_tick_mark_size(px(5.0))
        .bold_line_style(RGBColor(220, 220, 220).stroke_width(px(1.0)))
        .light_line_style(RGBColor(240, 240, 240).stroke_width(px(1.0)))
        .axis_style(BLACK.stroke_width(px(1.0)))
        .draw()
        .map_err(|e| e.to_string())?;
    if let Some((right_plot, _)) = right {
        chart
            .configure_secondary_axes()
            .y_desc(&right_plot.y_label)
            .axis_desc_style(font(18.0))
            .label_style(font(15.0))
            .axis_style(BLACK.stroke_width(px(1.0)))
            .draw()
            .map_err(|e| e.to_string())?;
    }

    let line_width = px(2.5);
    let legend_size = px(24.0) as i32;
    let curve = |index: usize, meta: &Series, points: &[(f64, f64)]| {
        let color = PALETTE[meta.colour.unwrap_or(index) % PALETTE.len()];
        // A line through a single point (or the same point repeated) would draw nothing:
        // show that point as a dot.
        let shape = if points.windows(2).all(|pair| pair[0] == pair[1]) {
            LineStyle::Markers
        } else {
            meta.style
        };
        (color, shape)
    };
    // one curve onto the left axis (`draw_series`) or the right one (`draw_secondary_series`):
    // the two take different coordinates, so the same body serves both through a macro
    macro_rules! draw_curves {
        ($draw:ident, $metas:expr, $points:expr, $first:expr) => {
            for (index, (meta, points)) in $metas.iter().zip($points).enumerate() {
                let (color, shape) = curve($first + index, meta, points);
                let style = color.stroke_width(line_width);
                let drawn = match shape {
                    LineStyle::Solid => chart.$draw(LineSeries::new(points.iter().copied(), style)),
                    LineStyle::Dashed => chart.$draw(DashedLineSeries::new(
                        points.iter().copied(),
                        px(10.0),
                        px(6.0),
                        style,
                    )),
                    LineStyle::Markers => chart.$draw(
                        points
                            .iter()
                            .map(|&p| Circle::new(p, px(3.5), color.filled())),
                    ),
                }
                .map_err(|e| e.to_string())?;
                if !meta.label.is_empty() {
                    set_legend(drawn, &meta.label, meta.style, legend_size, style);
                }
            }
        };
    }
    draw_curves!(draw_series, plot.series, series, 0);
    let right_series = right.map_or(&[][..], |(r, _)| r.series.as_slice());
    draw_curves!(
        draw_secondary_series,
        right_series,
        right_points,
        plot.series.len()
    );

    // Close the frame on the top and right, where plotters draws no axis.
    let (columns, rows) = chart.plotting_area().get_pixel_range();
    root.draw(&Rectangle::new(
        [(columns.start, rows.start), (columns.end - 1, rows.end - 1)],
        BLACK.stroke_width(px(1.0)),
    ))
    .map_err(|e| e.to_string())?;

    if plot.series.len() + right_series.len() > 1 {
        chart
            .configure_series_labels()
            .position(legend_corner)
            .margin(px(12.0))
            .legend_area_size(px(30.0))
            .label_font(font(15.0))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}

/// Draws `title` centred at the top of `root`, a line of text per line of it, the first
/// larger; returns the area below it. An empty title takes no room.
fn titled<'b>(
    root: &DrawingArea<PlotBackend<'b>, Shift>,
    title: &str,
    design: &DesignScale,
) -> Result<DrawingArea<PlotBackend<'b>, Shift>, String> {
    let width = root.dim_in_pixel().0 as i32;
    let mut y = design.px(10.0) as i32;
    for (k, line) in title.lines().enumerate() {
        let size = if k == 0 { 22.0 } else { 17.0 };
        let style =
            TextStyle::from(design.font(size).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
        root.draw(&Text::new(line.to_string(), (width / 2, y), style))
            .map_err(|e| e.to_string())?;
        y += design.px(1.35 * size) as i32;
    }
    Ok(root
        .clone()
        .shrink((0, y), (width as u32, root.dim_in_pixel().1 - y as u32)))
}

/// Gives the series its legend entry: a short stretch of its line, or one of its dots.
fn set_legend<'a, DB: DrawingBackend + 'a>(
    anno: &mut SeriesAnno<'a, DB>,
    label: &str,
    style: LineStyle,
    length: i32,
    line: ShapeStyle,
) {
    anno.label(label);
    match style {
        LineStyle::Solid => {
            anno.legend(move |(x, y)| PathElement::new(vec![(x, y), (x + length, y)], line))
        }
        LineStyle::Dashed => anno.legend(move |(x, y)| {
            let dash = length * 2 / 5;
            EmptyElement::at((x, y))
                + PathElement::new(vec![(0, 0), (dash, 0)], line)
                + PathElement::new(vec![(length - dash, 0), (length, 0)], line)
        }),
        LineStyle::Markers => anno.legend(move |(x, y)| {
            let radius = (line.stroke_width * 7 / 4).max(2);
            Circle::new((x + length / 2, y), radius, line.color.filled())
        }),
    };
}

/// The span of `values` widened by `MARGIN` on each side; a single value (one point, or a
/// constant series) gets a span of ±5 % of its size, or ±1 around zero.
fn padded_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    // Halves, so that the span of two huge values of opposite sign does not overflow.
    let mid = lo / 2.0 + hi / 2.0;
    let half = hi / 2.0 - lo / 2.0;
    let half = if half > 0.0 {
        half * (1.0 + 2.0 * MARGIN)
    } else if mid != 0.0 {
        0.05 * mid.abs()
    } else {
        1.0
    };
    let range = (mid - half).max(f64::MIN)..(mid + half).min(f64::MAX);
    if range.start < range.end {
        range
    } else {
        // Values so small (subnormal) that 5 % of them rounds to nothing.
        -1.0..1.0
    }
}

/// One axis of the chart: its range, and ticks at round numbers `step` apart with finer ones
/// for a light grid. It writes its own tick labels, so that they carry the decimals the step
/// needs (plotters' default writes 2e-7 as "0.0").
struct Axis {
    range: std::ops::Range<f64>,
    step: f64,
    /// Labels in scientific notation: the axis reaches 1e5, or stays below 1e-3.
    scientific: bool,
    /// Decimals of every label (of the mantissa, in scientific notation).
    decimals: usize,
    major: Vec<f64>,
    minor: Vec<f64>,
}

impl Axis {
    /// Ticks at multiples of 1, 2 or 5 times a power of ten, about `target` of them.
    fn new(range: std::ops::Range<f64>, target: f64) -> Self {
        // Halves, as in `padded_range`, so that a span near f64::MAX does not overflow.
        let raw = (range.end / 2.0 - range.start / 2.0) / (target / 2.0);
        let magnitude = 10f64.powf(raw.log10().floor());
        // The round step that gives the number of ticks closest to the target.
        let (step, parts) = [(1.0, 5.0), (2.0, 4.0), (5.0, 5.0), (10.0, 5.0)]
            .into_iter()
            .map(|(mantissa, parts)| (mantissa * magnitude, parts))
            .min_by(|a, b| (raw / a.0 - 1.0).abs().total_cmp(&(raw / b.0 - 1.0).abs()))
            .unwrap_or((magnitude, 5.0));
        let major = multiples(&range, step);
        let largest = major.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let scientific = largest >= 1e5 || (largest > 0.0 && largest < 1e-3);
        // The same decimals on every label: those the step needs, in scientific notation next
        // to the smallest tick's leading digit.
        let decimals = if scientific {
            major
                .iter()
                .filter(|v| v.abs() >= ZERO_TICK * step)
                .map(|&v| decimals_needed(step / 10f64.powf(exponent_of(v))))
                .max()
                .unwrap_or(0)
        } else {
            decimals_needed(step)
        };
        let minor = multiples(&range, step / parts)
            .into_iter()
            .filter(|v| (v / step - (v / step).round()).abs() > 1e-6)
            .collect();
        Self {
            scientific,
            decimals,
            major,
            minor,
            range,
            step,
        }
    }

    /// A tick value, written as the axis asks.
    fn label(&self, value: f64) -> String {
        let decimals = self.decimals;
        if value.abs() < ZERO_TICK * self.step {
            // A multiple of the step that should be zero but carries a rounding error.
            if self.scientific {
                "0".to_string()
            } else {
                format!("{:.decimals$}", 0.0)
            }
        } else if self.scientific {
            let exponent = exponent_of(value);
            format!("{:.decimals$}e{exponent}", value / 10f64.powf(exponent))
        } else {
            format!("{value:.decimals$}")
        }
    }
}

impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (start, end) = (self.range.start / 2.0, self.range.end / 2.0);
        let fraction = (value / 2.0 - start) / (end - start);
        limit.0 + (fraction * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.minor.clone()
        } else {
            self.major.clone()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.range.clone()
    }
}

impl ValueFormatter<f64> for Axis {
    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

/// The multiples of `step` inside `range` (none for a step that is not a positive number).
fn multiples(range: &std::ops::Range<f64>, step: f64) -> Vec<f64> {
    if !(step > 0.0 && step.is_finite()) {
        return Vec::new();
    }
    let first = (range.start / step).ceil();
    let last = (range.end / step).floor();
    // Multiplying each index, rather than adding steps, keeps rounding errors from piling up.
    (0..)
        .map(|i| (first + f64::from(i)) * step)
        .take_while(|&v| v <= last * step)
        .take(1000)
        .collect()
}

/// The power of ten of `value`'s leading digit. The nudge keeps 1e5, whose logarithm may come
/// out as 4.999..., from reading 10.0e4.
fn exponent_of(value: f64) -> f64 {
    (value.abs().log10() + 1e-9).floor()
}

/// The fewest decimals that write `x` (a tick step, 1, 2 or 5 times a power of ten) exactly.
fn decimals_needed(x: f64) -> usize {
    (0..15)
        .find(|&d| {
            let shifted = x * 10f64.powi(d as i32);
            (shifted - shifted.round()).abs() <= 1e-6 * shifted.abs().max(1.0)
        })
        .unwrap_or(15)
}

/// The corner of the plotting area (45 % of its width by 40 % of its height) that holds the
/// fewest points, where the legend hides the least of the curves.
fn emptiest_corner(
    series: &[Vec<(f64, f64)>],
    x: &std::ops::Range<f64>,
    y: &std::ops::Range<f64>,
) -> SeriesLabelPosition {
    let relative = |v: f64, r: &std::ops::Range<f64>| (v - r.start) / (r.end - r.start);
    let count = |right: bool, top: bool| {
        series
            .iter()
            .flatten()
            .filter(|&&(px, py)| {
                let (u, v) = (relative(px, x), relative(py, y));
                let in_x = if right { u >= 0.55 } else { u <= 0.45 };
                let in_y = if top { v >= 0.6 } else { v <= 0.4 };
                in_x && in_y
            })
            .count()
    };
    // Ties go to the first, in the order people expect a legend.
    [
        (SeriesLabelPosition::UpperRight, count(true, true)),
        (SeriesLabelPosition::UpperLeft, count(false, true)),
        (SeriesLabelPosition::LowerRight, count(true, false)),
        (SeriesLabelPosition::LowerLeft, count(false, false)),
    ]
    .into_iter()
    .min_by_key(|&(_, n)| n)
    .map_or(SeriesLabelPosition::UpperRight, |(corner, _)| corner)
}

/// A map of a cell field: cells (polygons in the plot's x–y, e.g. a part seen from above, a
/// projected view of it, or cases over two parameters) filled with the colour of their value,
/// beside a colour bar; optionally lines over it (tools' outlines), a marked cell (the
/// largest value), a limit marked on the bar, values printed in the cells and a legend.
#[derive(Clone, Debug, PartialEq)]
pub struct MapPlot {
    pub title: String,
    /// Labels of the x and y axes, with units; `None`: no axes (a projected view, whose
    /// coordinates mean nothing to the reader).
    pub axes: Option<(String, String)>,
    /// Whether x and y share one scale (a part) or each fills the plot (a map over two
    /// parameters).
    pub equal_scales: bool,
    /// Label of the colour bar, with units.
    pub value_label: String,
    /// The cells' corners (a polygon each), drawn in this order (a projected view sorts them
    /// far to near), one value per cell; a value that is not finite (no result) is grey.
    pub cells: Vec<Vec<(f64, f64)>>,
    pub values: Vec<f64>,
    /// The colour bar's span; `None`: from 0 to the largest value or the limit, whichever is
    /// higher ([`MapPlot::colour_range`]).
    pub scale: Option<(f64, f64)>,
    /// A value marked on the colour bar (e.g. the locking angle); `None`: none.
    pub limit: Option<Limit>,
    /// Cells drawn with a thick black outline, their colour kept (e.g. the cases of a study
    /// that wrinkled); empty: none.
    pub outlined: Vec<bool>,
    /// Brightness of each cell's colour, 0 to 1 (the light on a projected view); empty: 1.
    pub shade: Vec<f64>,
    /// Text printed in each cell (e.g. its value); empty: none.
    pub cell_labels: Vec<String>,
    /// Ticks of the x and y axes at given places with given labels (e.g. the cases'
    /// parameter values); `None`: round numbers.
    pub ticks: Option<(Ticks, Ticks)>,
    /// Lines drawn over the cells, each with its legend entry.
    pub lines: Vec<MapLine>,
    /// A point marked with a ring and a label (e.g. where the largest value is).
    pub marker: Option<Marker>,
    /// Legend entries for kinds of cell (e.g. wrinkled, failed), beside those of the lines.
    pub legend: Vec<LegendCell>,
    /// Each cell drawn as a dot at its centre, not as its polygon (a scatter of a study's
    /// sampled cases over two parameters, which tile nothing); the dots keep the cells'
    /// colours and outlines.
    pub dots: bool,
    /// The x and y spans of the plotting area; `None`: the box around the cells and lines
    /// (dots at the box's edge would be cut in half: give their spans with a margin).
    pub extent: Option<(std::ops::Range<f64>, std::ops::Range<f64>)>,
}

/// Ticks of an axis: each place and its label.
pub type Ticks = Vec<(f64, String)>;

/// The finite points of a series.
type Points = Vec<(f64, f64)>;

/// A value marked on the colour bar with a line and `label`; with `flags_cells`, cells above
/// it are drawn in [`LIMIT_COLOUR`] (the shear map's cells beyond the locking angle).
#[derive(Clone, Debug, PartialEq)]
pub struct Limit {
    pub value: f64,
    pub label: String,
    pub flags_cells: bool,
}

/// A ring at `at` (plot coordinates) with `label` beside it.
#[derive(Clone, Debug, PartialEq)]
pub struct Marker {
    pub at: (f64, f64),
    pub label: String,
}

/// Line segments in one colour, e.g. a tool's outline, named in the legend.
#[derive(Clone, Debug, PartialEq)]
pub struct MapLine {
    pub label: String,
    pub colour: (u8, u8, u8),
    pub segments: Vec<[(f64, f64); 2]>,
}

/// A legend entry for a kind of cell: a swatch filled with `fill` (white: `None`), outlined
/// in black where `outlined`.
#[derive(Clone, Debug, PartialEq)]
pub struct LegendCell {
    pub label: String,
    pub fill: Option<(u8, u8, u8)>,
    pub outlined: bool,
}

/// Where the map's plotting area lies in the written picture, to find the pixel of a point
/// (e.g. the marked maximum).
#[derive(Clone, Debug, PartialEq)]
pub struct MapFrame {
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
    /// The plotting area in pixels of the written picture.
    columns: std::ops::Range<f64>,
    rows: std::ops::Range<f64>,
}

impl MapFrame {
    /// The pixel (column, row) of the point `(x, y)` of the plot.
    pub fn pixel(&self, (x, y): (f64, f64)) -> (u32, u32) {
        let u = (x - self.x.start) / (self.x.end - self.x.start);
        let v = (y - self.y.start) / (self.y.end - self.y.start);
        let column = self.columns.start + u * (self.columns.end - self.columns.start);
        // rows grow downwards, y upwards
        let row = self.rows.end - v * (self.rows.end - self.rows.start);
        (column.max(0.0) as u32, row.max(0.0) as u32)
    }
}

/// Colour of the flagged cells and of the limit's mark.
pub const LIMIT_COLOUR: RGBColor = RGBColor(230, 0, 200);
/// Colour of the cells without a value.
pub const MISSING_COLOUR: RGBColor = RGBColor(170, 170, 170);

/// Blue (0) through cyan, green and yellow to red (1).
fn colour_scale(t: f64) -> RGBColor {
    let stops = [
        (0.0, (49.0, 54.0, 149.0)),
        (0.25, (69.0, 160.0, 220.0)),
        (0.5, (120.0, 200.0, 120.0)),
        (0.75, (250.0, 210.0, 60.0)),
        (1.0, (200.0, 30.0, 30.0)),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let k = stops.iter().rposition(|s| s.0 <= t).unwrap_or(0).min(3);
    let (t0, c0) = stops[k];
    let (t1, c1) = stops[k + 1];
    let w = (t - t0) / (t1 - t0);
    let mix = |a: f64, b: f64| (a + w * (b - a)).round() as u8;
    RGBColor(mix(c0.0, c1.0), mix(c0.1, c1.1), mix(c0.2, c1.2))
}

impl MapPlot {
    /// A map of `values` over `cells` with equal scales, no axes and nothing drawn over it;
    /// set the other fields to add them.
    pub fn new(
        title: impl Into<String>,
        value_label: impl Into<String>,
        cells: Vec<Vec<(f64, f64)>>,
        values: Vec<f64>,
    ) -> Self {
        Self {
            title: title.into(),
            axes: None,
            equal_scales: true,
            value_label: value_label.into(),
            cells,
            values,
            scale: None,
            limit: None,
            outlined: Vec::new(),
            shade: Vec::new(),
            cell_labels: Vec::new(),
            ticks: None,
            lines: Vec::new(),
            marker: None,
            legend: Vec::new(),
            dots: false,
            extent: None,
        }
    }

    /// The colour bar's span: [`MapPlot::scale`], or from 0 to the largest finite value or
    /// the limit, whichever is higher, so that a part far below the limit uses the whole
    /// scale and one beyond it shows how far. An empty span is widened, so that one value
    /// still maps to a colour.
    pub fn colour_range(&self) -> (f64, f64) {
        let (low, high) = self.scale.unwrap_or_else(|| {
            let largest = self
                .values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max);
            (
                0.0,
                self.limit
                    .as_ref()
                    .map_or(largest, |l| largest.max(l.value)),
            )
        });
        if high > low {
            (low, high)
        } else {
            let half = (1e-3 * low.abs()).max(1e-9);
            (low - half, low + half)
        }
    }

    /// The colour of a cell of `value`: grey without a value, [`LIMIT_COLOUR`] above a limit
    /// that flags cells, else its place on the colour bar.
    pub fn colour_of(&self, value: f64) -> RGBColor {
        let (low, high) = self.colour_range();
        match &self.limit {
            _ if !value.is_finite() => MISSING_COLOUR,
            Some(l) if l.flags_cells && value > l.value => LIMIT_COLOUR,
            _ => colour_scale((value - low) / (high - low)),
        }
    }

    /// The cell's colour darkened by its shade.
    fn shaded_colour(&self, cell: usize) -> RGBColor {
        let RGBColor(r, g, b) = self.colour_of(self.values[cell]);
        let shade = self.shade.get(cell).copied().unwrap_or(1.0).clamp(0.0, 1.0);
        let dim = |c: u8| (f64::from(c) * shade).round() as u8;
        RGBColor(dim(r), dim(g), dim(b))
    }
}

/// Writes the map as a PNG of `width` x `height` pixels; returns where its plotting area lies.
pub fn write_map_png(
    path: &Path,
    map: &MapPlot,
    width: u32,
    height: u32,
) -> Result<MapFrame, PlotError> {
    let title = map.title.clone();
    if map.cells.is_empty() || !map.values.iter().any(|v| v.is_finite()) {
        return Err(PlotError::Empty { title });
    }
    if !((MIN_WIDTH..=MAX_SIDE).contains(&width) && (MIN_HEIGHT..=MAX_SIDE).contains(&height)) {
        return Err(PlotError::Size {
            title,
            width,
            height,
        });
    }
    let font = embedded_font()?;
    let (fine_width, fine_height) = (SUPERSAMPLE * width, SUPERSAMPLE * height);
    let mut fine = vec![255u8; 3 * fine_width as usize * fine_height as usize];
    let frame = {
        let bitmap = BitMapBackend::with_buffer(&mut fine, (fine_width, fine_height));
        let root = PlotBackend { bitmap, font }.into_drawing_area();
        draw_map(&root, map).map_err(|message| PlotError::Draw { title, message })?
    };
    let rgb = downsample(&fine, fine_width as usize, SUPERSAMPLE as usize);
    encode_png(path, &rgb, width, height)?;
    Ok(frame)
}

/// An axis of a map: its range and ticks at given places with their labels.
struct MapAxis {
    range: std::ops::Range<f64>,
    ticks: Vec<(f64, String)>,
}

impl MapAxis {
    /// Ticks at round numbers, about `target` of them, labelled as [`Axis`] labels them.
    fn round(range: std::ops::Range<f64>, target: f64) -> Self {
        let axis = Axis::new(range.clone(), target);
        let ticks = axis.major.iter().map(|&v| (v, axis.label(v))).collect();
        Self { range, ticks }
    }
}

impl Ranged for MapAxis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        let (start, end) = (self.range.start / 2.0, self.range.end / 2.0);
        let fraction = (value / 2.0 - start) / (end - start);
        limit.0 + (fraction * f64::from(limit.1 - limit.0)).round() as i32
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            Vec::new()
        } else {
            self.ticks.iter().map(|t| t.0).collect()
        }
    }

    fn range(&self) -> std::ops::Range<f64> {
        self.range.clone()
    }
}

impl ValueFormatter<f64> for MapAxis {
    fn format_ext(&self, value: &f64) -> String {
        self.ticks
            .iter()
            .min_by(|a, b| (a.0 - value).abs().total_cmp(&(b.0 - value).abs()))
            .map_or_else(String::new, |t| t.1.clone())
    }
}

/// The box around the cells and lines, padded to the drawing area's proportions where the
/// scales are equal.
fn map_extent(map: &MapPlot, aspect: f64) -> (std::ops::Range<f64>, std::ops::Range<f64>) {
    if let Some(extent) = &map.extent {
        return extent.clone();
    }
    let lines = map.lines.iter().flat_map(|l| l.segments.iter().flatten());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in map.cells.iter().flatten().chain(lines) {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let (cx, cy, mut sx, mut sy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0);
    if map.equal_scales {
        if sx / sy < aspect {
            sx = sy * aspect;
        } else {
            sy = sx / aspect;
        }
    }
    // a part gets a margin around it; a map over parameters ends at its cells
    let margin = if map.equal_scales { 0.53 } else { 0.5 };
    let (sx, sy) = (margin * sx.max(1e-12), margin * sy.max(1e-12));
    (cx - sx..cx + sx, cy - sy..cy + sy)
}

/// The entries of the legend strip: the lines', then the kinds of cell.
fn legend_entries(map: &MapPlot) -> Vec<(String, Swatch)> {
    let lines = map
        .lines
        .iter()
        .map(|l| (l.label.clone(), Swatch::Line(l.colour)));
    let cells = map.legend.iter().map(|c| {
        let fill = c.fill.map_or(WHITE, |(r, g, b)| RGBColor(r, g, b));
        (c.label.clone(), Swatch::Cell(fill, c.outlined))
    });
    lines.chain(cells).collect()
}

enum Swatch {
    Line((u8, u8, u8)),
    Cell(RGBColor, bool),
}

/// The map on the left (its legend in a strip under it), the colour bar on the right.
fn draw_map(root: &DrawingArea<PlotBackend, Shift>, map: &MapPlot) -> Result<MapFrame, String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    let width = root.dim_in_pixel().0;
    let design = DesignScale::of(root);
    let (px, font) = (|d: f64| design.px(d), |d: f64| design.font(d));
    root.fill(&WHITE).map_err(text)?;
    let body = titled(root, &map.title, &design)?;
    let (left, right) = body.split_horizontally(width * 4 / 5);
    let legend = legend_entries(map);
    let (left, strip) = if legend.is_empty() {
        (left, None)
    } else {
        let (top, strip) = left.split_vertically(left.dim_in_pixel().1 - px(36.0));
        (top, Some(strip))
    };
    let (w, h) = left.dim_in_pixel();
    let (x_range, y_range) = map_extent(map, f64::from(w) / f64::from(h));
    let (x_axis, y_axis) = match &map.ticks {
        Some((x, y)) => (
            MapAxis {
                range: x_range,
                ticks: x.clone(),
            },
            MapAxis {
                range: y_range,
                ticks: y.clone(),
            },
        ),
        None => (MapAxis::round(x_range, 8.0), MapAxis::round(y_range, 6.0)),
    };
    let axis_room = |size: f64| if map.axes.is_some() { px(size) } else { 0 };
    let mut chart = ChartBuilder::on(&left)
        .margin(px(12.0))
        .x_label_area_size(axis_room(44.0))
        .y_label_area_size(axis_room(64.0))
        .build_cartesian_2d(x_axis, y_axis)
        .map_err(text)?;
    if let Some((x_label, y_label)) = &map.axes {
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .axis_desc_style(font(16.0))
            .label_style(font(13.0))
            .disable_mesh()
            .draw()
            .map_err(text)?;
    }
    if map.dots {
        draw_dots(&mut chart, map, &design)?;
    } else {
        draw_cells(&mut chart, map, &design)?;
    }
    draw_cell_labels(&mut chart, map, font(14.0))?;
    for line in &map.lines {
        let (r, g, b) = line.colour;
        let style = RGBColor(r, g, b).stroke_width(px(2.0));
        chart
            .draw_series(
                line.segments
                    .iter()
                    .map(|s| PathElement::new(s.to_vec(), style)),
            )
            .map_err(text)?;
    }
    if let Some(marker) = &map.marker {
        draw_marker(
            root,
            chart.backend_coord(&marker.at),
            &marker.label,
            &design,
        )?;
    }
    let (columns, rows) = chart.plotting_area().get_pixel_range();
    let fine = |r: std::ops::Range<i32>| {
        f64::from(r.start) / f64::from(SUPERSAMPLE)..f64::from(r.end) / f64::from(SUPERSAMPLE)
    };
    let frame = MapFrame {
        x: chart.x_range(),
        y: chart.y_range(),
        columns: fine(columns),
        rows: fine(rows),
    };
    if let Some(strip) = strip {
        draw_legend(&strip, &legend, &design)?;
    }
    draw_colour_bar(&right, map, &design)?;
    Ok(frame)
}

/// The cells filled with their colours, the outlined ones ringed in black.
fn draw_cells(
    chart: &mut ChartContext<PlotBackend, Cartesian2d<MapAxis, MapAxis>>,
    map: &MapPlot,
    design: &DesignScale,
) -> Result<(), String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    chart
        .draw_series(
            map.cells
                .iter()
                .enumerate()
                .map(|(k, c)| Polygon::new(c.clone(), map.shaded_colour(k).filled())),
        )
        .map_err(text)?;
    chart
        .draw_series(
            map.cells
                .iter()
                .zip(&map.outlined)
                .filter(|(_, &outlined)| outlined)
                .map(|(c, _)| {
                    let mut ring = c.clone();
                    ring.extend(c.first().copied());
                    PathElement::new(ring, BLACK.stroke_width(design.px(3.0)))
                }),
        )
        .map_err(text)?;
    Ok(())
}

/// The centre of a cell: the mean of its corners.
fn centre(cell: &[(f64, f64)]) -> (f64, f64) {
    let n = cell.len().max(1) as f64;
    cell.iter()
        .fold((0.0, 0.0), |(x, y), p| (x + p.0 / n, y + p.1 / n))
}

/// Each cell as a dot at its centre, in its colour with a thin dark edge (so that a pale
/// colour still shows on white), the outlined ones ringed in black.
fn draw_dots(
    chart: &mut ChartContext<PlotBackend, Cartesian2d<MapAxis, MapAxis>>,
    map: &MapPlot,
    design: &DesignScale,
) -> Result<(), String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    let radius = design.px(7.0);
    let edge = RGBColor(60, 60, 60);
    let dots = map.cells.iter().enumerate().map(|(k, c)| (k, centre(c)));
    chart
        .draw_series(dots.clone().flat_map(|(k, at)| {
            [
                Circle::new(at, radius, map.shaded_colour(k).filled()),
                Circle::new(at, radius, edge.stroke_width(design.px(1.0))),
            ]
        }))
        .map_err(text)?;
    chart
        .draw_series(
            dots.filter(|(k, _)| map.outlined.get(*k).copied().unwrap_or(false))
                .map(|(_, at)| {
                    Circle::new(
                        at,
                        radius + design.px(2.5),
                        BLACK.stroke_width(design.px(3.0)),
                    )
                }),
        )
        .map_err(text)?;
    Ok(())
}

/// Each cell's label at its centre, black on light colours and white on dark ones.
fn draw_cell_labels(
    chart: &mut ChartContext<PlotBackend, Cartesian2d<MapAxis, MapAxis>>,
    map: &MapPlot,
    font: (&'static str, f64),
) -> Result<(), String> {
    let labels = map.cells.iter().zip(&map.cell_labels).enumerate();
    let centred = Pos::new(HPos::Center, VPos::Center);
    chart
        .draw_series(labels.map(|(k, (cell, label))| {
            let (x, y) = centre(cell);
            let RGBColor(r, g, b) = map.shaded_colour(k);
            // perceived brightness (ITU-R BT.601 weights)
            let light = 0.299 * f64::from(r) + 0.587 * f64::from(g) + 0.114 * f64::from(b) > 140.0;
            let colour = if light { &BLACK } else { &WHITE };
            Text::new(
                label.clone(),
                (x, y),
                TextStyle::from(font.into_font()).color(colour).pos(centred),
            )
        }))
        .map(|_| ())
        .map_err(|e| e.to_string())
}

/// A ring around the marked point and its label on a white box beside it, in pixels.
fn draw_marker(
    root: &DrawingArea<PlotBackend, Shift>,
    (x, y): (i32, i32),
    label: &str,
    design: &DesignScale,
) -> Result<(), String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    let radius = design.px(9.0) as i32;
    root.draw(&Circle::new(
        (x, y),
        radius,
        BLACK.stroke_width(design.px(2.5)),
    ))
    .map_err(text)?;
    let style =
        TextStyle::from(design.font(16.0).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    let (w, h) = root.estimate_text_size(label, &style).map_err(text)?;
    let (w, h) = (w as i32, h as i32);
    // the label up and to the right of the ring, on a box that keeps it legible over colours
    let (left, middle) = (x + radius + design.px(4.0) as i32, y - radius - h / 2);
    let pad = design.px(3.0) as i32;
    root.draw(&Rectangle::new(
        [
            (left - pad, middle - h / 2 - pad),
            (left + w + pad, middle + h / 2 + pad),
        ],
        ShapeStyle::from(&WHITE.mix(0.85)).filled(),
    ))
    .map_err(text)?;
    root.draw(&Rectangle::new(
        [
            (left - pad, middle - h / 2 - pad),
            (left + w + pad, middle + h / 2 + pad),
        ],
        BLACK.stroke_width(1),
    ))
    .map_err(text)?;
    root.draw(&Text::new(label.to_string(), (left, middle), style))
        .map_err(text)
}

/// The legend strip: a swatch and a label per entry, in a row.
fn draw_legend(
    strip: &DrawingArea<PlotBackend, Shift>,
    entries: &[(String, Swatch)],
    design: &DesignScale,
) -> Result<(), String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    let style =
        TextStyle::from(design.font(14.0).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
    let (swatch_width, gap) = (design.px(26.0) as i32, design.px(8.0) as i32);
    let half = design.px(7.0) as i32;
    let middle = strip.dim_in_pixel().1 as i32 / 2;
    let mut x = design.px(16.0) as i32;
    for (label, swatch) in entries {
        let (x1, top, bottom) = (x + swatch_width, middle - half, middle + half);
        match swatch {
            Swatch::Line((r, g, b)) => strip.draw(&PathElement::new(
                vec![(x, middle), (x1, middle)],
                RGBColor(*r, *g, *b).stroke_width(design.px(2.5)),
            )),
            Swatch::Cell(fill, outlined) => {
                strip
                    .draw(&Rectangle::new([(x, top), (x1, bottom)], fill.filled()))
                    .map_err(text)?;
                let edge = if *outlined {
                    BLACK.stroke_width(design.px(3.0))
                } else {
                    RGBColor(120, 120, 120).stroke_width(1)
                };
                strip.draw(&Rectangle::new([(x, top), (x1, bottom)], edge))
            }
        }
        .map_err(text)?;
        let label_x = x1 + gap;
        strip
            .draw(&Text::new(label.clone(), (label_x, middle), style.clone()))
            .map_err(text)?;
        let (w, _) = strip.estimate_text_size(label, &style).map_err(text)?;
        x = label_x + w as i32 + 3 * gap;
    }
    Ok(())
}

/// The colour bar from the bottom to the top of [`MapPlot::colour_range`], the limit marked
/// by a line across it and its label beside it.
fn draw_colour_bar(
    area: &DrawingArea<PlotBackend, Shift>,
    map: &MapPlot,
    design: &DesignScale,
) -> Result<(), String> {
    let text = |e: DrawingAreaErrorKind<_>| e.to_string();
    let (px, font) = (|d: f64| design.px(d), |d: f64| design.font(d));
    let (low, high) = map.colour_range();
    let mut bar = ChartBuilder::on(area)
        .margin(px(12.0))
        .margin_top(px(48.0))
        .y_label_area_size(px(52.0))
        .x_label_area_size(px(40.0))
        .build_cartesian_2d(0.0..1.0, MapAxis::round(low..high, 8.0))
        .map_err(text)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(&map.value_label)
        .axis_desc_style(font(15.0))
        .label_style(font(13.0))
        .draw()
        .map_err(text)?;
    // the bar on the left of its area, the limit's label on the right
    let (bar_width, steps) = (0.4, 200);
    bar.draw_series((0..steps).map(|k| {
        let at = |k: i32| low + (high - low) * f64::from(k) / f64::from(steps);
        let colour = map.colour_of(0.5 * (at(k) + at(k + 1)));
        Rectangle::new([(0.0, at(k)), (bar_width, at(k + 1))], colour.filled())
    }))
    .map_err(text)?;
    if let Some(limit) = &map.limit {
        bar.draw_series([PathElement::new(
            vec![(0.0, limit.value), (bar_width + 0.08, limit.value)],
            BLACK.stroke_width(px(2.0)),
        )])
        .map_err(text)?;
        let style = TextStyle::from(font(13.0).into_font()).pos(Pos::new(HPos::Left, VPos::Center));
        bar.draw_series([Text::new(
            limit.label.clone(),
            (bar_width + 0.1, limit.value),
            style,
        )])
        .map_err(text)?;
    }
    Ok(())
}

/// Averages each `factor` x `factor` block of the RGB picture `fine`, `fine_width` pixels wide.
fn downsample(fine: &[u8], fine_width: usize, factor: usize) -> Vec<u8> {
    let width = fine_width / factor;
    let height = fine.len() / (3 * fine_width * factor);
    let mut rgb = Vec::with_capacity(3 * width * height);
    for row in 0..height {
        for column in 0..width {
            for channel in 0..3 {
                let sum: usize = (0..factor)
                    .flat_map(|dy| (0..factor).map(move |dx| (dy, dx)))
                    .map(|(dy, dx)| {
                        let (y, x) = (row * factor + dy, column * factor + dx);
                        usize::from(fine[3 * (y * fine_width + x) + channel])
                    })
                    .sum();
                rgb.push(((sum + factor * factor / 2) / (factor * factor)) as u8);
            }
        }
    }
    rgb
}

/// Encodes in memory, then writes the file in one go, so that a failure is about the file;
/// never through a symbolic link ([`super::product_file`]).
fn encode_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<(), PlotError> {
    let encode_error = |source| PlotError::Encode {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    // plots are large flat areas, which the fast encoder packs nearly as well in a fraction of
    // the time: every run writes several (docs/performance.md, "What the outputs cost")
    encoder.set_compression(png::Compression::Fast);
    let mut writer = encoder.write_header().map_err(encode_error)?;
    writer.write_image_data(rgb).map_err(encode_error)?;
    writer.finish().map_err(encode_error)?;
    // through `NAME.tmp` and a rename: a full disk leaves the old picture or none, never half
    super::product_file::replace(path, &bytes).map_err(|source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The drawing backend that draws text with the embedded font.
mod backend {
    use ab_glyph::{point, Font, FontRef, OutlinedGlyph, ScaleFont};
    use plotters::prelude::{BitMapBackend, DrawingBackend};
    use plotters::style::text_anchor::{HPos, VPos};
    use plotters_backend::{BackendColor, BackendStyle, BackendTextStyle, DrawingErrorKind};

    /// plotters' bitmap backend with text drawn here: plotters 0.3.7 places each glyph without
    /// its side bearing, which crowds some letters and spreads others ("dis placement", "0 .0").
    pub(super) struct PlotBackend<'a> {
        pub(super) bitmap: BitMapBackend<'a>,
        pub(super) font: FontRef<'static>,
    }

    type BackendResult =
        Result<(), DrawingErrorKind<<BitMapBackend<'static> as DrawingBackend>::ErrorType>>;

    /// One glyph of a laid-out line: its outline and where its pixels go, relative to the top
    /// left of the line's box.
    struct PlacedGlyph {
        outline: OutlinedGlyph,
        left: i32,
        top: i32,
    }

    impl PlotBackend<'_> {
        /// Lays `text` out on one line at `size` pixels (ascent to descent, as plotters measures
        /// its fonts), with kerning; returns the glyphs and the line's width and height.
        fn layout(&self, text: &str, size: f64) -> (Vec<PlacedGlyph>, u32, u32) {
            let font = self.font.as_scaled(size as f32);
            let mut caret = 0.0f32;
            let mut previous = None;
            let mut glyphs = Vec::new();
            for c in text.chars() {
                let id = font.glyph_id(c);
                if let Some(previous) = previous {
                    caret += font.kern(previous, id);
                }
                previous = Some(id);
                let glyph = id.with_scale_and_position(font.scale(), point(caret, font.ascent()));
                caret += font.h_advance(id);
                if let Some(outline) = font.outline_glyph(glyph) {
                    let bounds = outline.px_bounds();
                    glyphs.push(PlacedGlyph {
                        left: bounds.min.x as i32,
                        top: bounds.min.y as i32,
                        outline,
                    });
                }
            }
            let height = font.ascent() - font.descent();
            (glyphs, caret.ceil() as u32, height.ceil() as u32)
        }
    }

    /// Shapes go to the bitmap backend's own routines, which are faster than the trait's
    /// pixel-by-pixel defaults; text is laid out and drawn with the embedded font.
    impl DrawingBackend for PlotBackend<'_> {
        type ErrorType = <BitMapBackend<'static> as DrawingBackend>::ErrorType;

        fn get_size(&self) -> (u32, u32) {
            self.bitmap.get_size()
        }

        fn ensure_prepared(&mut self) -> BackendResult {
            self.bitmap.ensure_prepared()
        }

        fn present(&mut self) -> BackendResult {
            self.bitmap.present()
        }

        fn draw_pixel(&mut self, point: (i32, i32), color: BackendColor) -> BackendResult {
            self.bitmap.draw_pixel(point, color)
        }

        fn draw_line<S: BackendStyle>(
            &mut self,
            from: (i32, i32),
            to: (i32, i32),
            style: &S,
        ) -> BackendResult {
            self.bitmap.draw_line(from, to, style)
        }

        fn draw_rect<S: BackendStyle>(
            &mut self,
            upper_left: (i32, i32),
            bottom_right: (i32, i32),
            style: &S,
            fill: bool,
        ) -> BackendResult {
            self.bitmap.draw_rect(upper_left, bottom_right, style, fill)
        }

        fn draw_path<S: BackendStyle, I: IntoIterator<Item = (i32, i32)>>(
            &mut self,
            path: I,
            style: &S,
        ) -> BackendResult {
            self.bitmap.draw_path(path, style)
        }

        fn draw_circle<S: BackendStyle>(
            &mut self,
            center: (i32, i32),
            radius: u32,
            style: &S,
            fill: bool,
        ) -> BackendResult {
            self.bitmap.draw_circle(center, radius, style, fill)
        }

        fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = (i32, i32)>>(
            &mut self,
            vert: I,
            style: &S,
        ) -> BackendResult {
            self.bitmap.fill_polygon(vert, style)
        }

        fn draw_text<S: BackendTextStyle>(
            &mut self,
            text: &str,
            style: &S,
            pos: (i32, i32),
        ) -> BackendResult {
            let color = style.color();
            let (glyphs, width, height) = self.layout(text, style.size());
            let (width, height) = (width as i32, height as i32);
            let anchor = style.anchor();
            let dx = match anchor.h_pos {
                HPos::Left => 0,
                HPos::Center => -width / 2,
                HPos::Right => -width,
            };
            let dy = match anchor.v_pos {
                VPos::Top => 0,
                VPos::Center => -height / 2,
                VPos::Bottom => -height,
            };
            let turn = style.transform();
            let mut result = Ok(());
            for glyph in &glyphs {
                glyph.outline.draw(|x, y, coverage| {
                    let (x, y) =
                        turn.transform(glyph.left + x as i32 + dx, glyph.top + y as i32 + dy);
                    let shade = BackendColor {
                        alpha: color.alpha * f64::from(coverage.min(1.0)),
                        rgb: color.rgb,
                    };
                    if result.is_ok() {
                        result = self.bitmap.draw_pixel((pos.0 + x, pos.1 + y), shade);
                    }
                });
            }
            result
        }

        fn estimate_text_size<S: BackendTextStyle>(
            &self,
            text: &str,
            style: &S,
        ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
            let (_, width, height) = self.layout(text, style.size());
            Ok((width, height))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh folder under the system temp dir, unique to this test and process.
    fn temp_folder(test: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("thermostamp-plot-{}-{test}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn plot_of(series: Vec<Series>) -> LinePlot {
        LinePlot {
            title: "Bias extension, T300/PPS at 300 °C".to_string(),
            x_label: "displacement u (mm)".to_string(),
            y_label: "force F (N)".to_string(),
            series,
        }
    }

    fn two_series() -> LinePlot {
        let u: Vec<f64> = (0..=200).map(|i| f64::from(i) * 0.25).collect();
        let model = u.iter().map(|&u| (u, 0.02 * u * u + 0.5 * u)).collect();
        let measured = u
            .iter()
            .step_by(10)
            .map(|&u| (u, 0.021 * u * u + 0.4 * u + 1.0))
            .collect();
        plot_of(vec![
            Series::new("model", model, LineStyle::Solid),
            Series::new("measured", measured, LineStyle::Markers),
        ])
    }

    /// `(width, height)` from the IHDR chunk, after checking the PNG signature.
    fn png_size(bytes: &[u8]) -> (u32, u32) {
        assert!(bytes.len() > 24, "only {} bytes", bytes.len());
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG");
        assert_eq!(&bytes[12..16], b"IHDR");
        let word = |at: usize| u32::from_be_bytes(bytes[at..at + 4].try_into().unwrap());
        (word(16), word(20))
    }

    /// Decoded RGB pixels of the PNG at `path`.
    fn decode(path: &Path) -> (png::OutputInfo, Vec<u8>) {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let mut reader = png::Decoder::new(file).read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        pixels.truncate(info.buffer_size());
        (info, pixels)
    }

    #[test]
    fn writes_a_png_of_the_requested_size_with_curves_and_text() {
        let path = temp_folder("two-series").join("force.png");
        write_png(&path, &two_series(), 900, 600).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(png_size(&bytes), (900, 600));
        let (info, pixels) = decode(&path);
        assert_eq!((info.width, info.height), (900, 600));
        assert_eq!(info.color_type, png::ColorType::Rgb);
        let rgb: Vec<[u8; 3]> = pixels.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
        let count = |c: [u8; 3]| rgb.iter().filter(|&&p| p == c).count();
        let white = count([255, 255, 255]);
        assert!(white > rgb.len() / 2, "mostly white background: {white}");
        assert!(white < rgb.len() * 98 / 100, "something is drawn: {white}");
        // Each series in its own palette colour, and black for text and axes.
        let blue = PALETTE[0];
        let orange = PALETTE[1];
        assert!(count([blue.0, blue.1, blue.2]) > 500, "first series drawn");
        assert!(
            count([orange.0, orange.1, orange.2]) > 200,
            "second series drawn"
        );
        assert!(count([0, 0, 0]) > 500, "axes and text drawn");
    }

    #[test]
    fn text_is_drawn_with_the_embedded_font() {
        let dir = temp_folder("text");
        let mut plot = plot_of(vec![Series::new(
            "one",
            vec![(0.0, 0.0), (1.0, 1.0)],
            LineStyle::Solid,
        )]);
        plot.title = String::new();
        let untitled = dir.join("untitled.png");
        write_png(&untitled, &plot, 400, 300).unwrap();
        plot.title = "A title that must show up as dark pixels".to_string();
        let titled = dir.join("titled.png");
        write_png(&titled, &plot, 400, 300).unwrap();
        // Inked pixels in the band above the plotting area, where only the title goes.
        let ink = |path: &Path| {
            let (_, pixels) = decode(path);
            pixels[..3 * 400 * 20]
                .chunks_exact(3)
                .filter(|p| p.iter().all(|&c| c < 128))
                .count()
        };
        assert_eq!(ink(&untitled), 0);
        assert!(ink(&titled) > 150, "the title is drawn: {}", ink(&titled));
    }

    /// Pixels of exactly the first palette colour: the first series, once drawn.
    fn first_series_pixels(path: &Path) -> usize {
        let (_, pixels) = decode(path);
        let blue = PALETTE[0];
        pixels
            .chunks_exact(3)
            .filter(|p| p == &[blue.0, blue.1, blue.2])
            .count()
    }

    #[test]
    fn degenerate_data_still_plots() {
        let dir = temp_folder("degenerate");
        let cases = [
            ("single", vec![(2.0, 3.0)]),
            ("constant", vec![(0.0, 5.0), (1.0, 5.0), (2.0, 5.0)]),
            ("zero", vec![(0.0, 0.0), (0.0, 0.0)]),
            ("tiny", vec![(0.0, 1e-9), (1e-6, 3e-9)]),
            ("subnormal", vec![(0.0, 5e-324)]),
            ("huge", vec![(-1e300, -1e300), (1e300, 1e300)]),
        ];
        for (name, points) in cases {
            let path = dir.join(format!("{name}.png"));
            let plot = plot_of(vec![Series::new(name, points, LineStyle::Dashed)]);
            write_png(&path, &plot, 300, 200).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(png_size(&std::fs::read(&path).unwrap()), (300, 200));
            assert!(first_series_pixels(&path) > 0, "{name}: the data shows");
        }
    }

    #[test]
    fn empty_and_non_finite_series_beside_a_good_one_are_skipped() {
        let path = temp_folder("partial").join("partial.png");
        let plot = plot_of(vec![
            Series::new(
                "good",
                vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)],
                LineStyle::Solid,
            ),
            Series::new("empty", vec![], LineStyle::Solid),
            Series::new("nan", vec![(f64::NAN, 1.0)], LineStyle::Markers),
        ]);
        write_png(&path, &plot, 900, 600).unwrap();
        assert!(first_series_pixels(&path) > 500);
    }

    #[test]
    fn padded_range_widens_the_data() {
        let r = padded_range([10.0, 0.0, 2.0].into_iter());
        assert!(
            (r.start + 0.4).abs() < 1e-12 && (r.end - 10.4).abs() < 1e-12,
            "{r:?}"
        );
        assert_eq!(padded_range([5.0].into_iter()), 4.75..5.25);
        assert_eq!(padded_range([0.0].into_iter()), -1.0..1.0);
        let r = padded_range([-f64::MAX, f64::MAX].into_iter());
        assert!(r.start.is_finite() && r.end.is_finite() && r.start < r.end);
    }

    #[test]
    fn tick_labels_carry_the_decimals_their_step_needs() {
        let labels = |range, target| {
            let axis = Axis::new(range, target);
            let labels: Vec<String> = axis.major.iter().map(|v| axis.format_ext(v)).collect();
            labels.join(" ")
        };
        assert_eq!(labels(-0.2..52.0, 8.0), "0 5 10 15 20 25 30 35 40 45 50");
        assert_eq!(labels(0.0..2.0, 4.0), "0.0 0.5 1.0 1.5 2.0");
        assert_eq!(
            labels(-4.1e-6..4.3e-6, 8.0),
            "-4e-6 -3e-6 -2e-6 -1e-6 0 1e-6 2e-6 3e-6 4e-6"
        );
        assert_eq!(labels(0.9e5..3.1e5, 4.0), "1.0e5 1.5e5 2.0e5 2.5e5 3.0e5");
        assert_eq!(labels(0.0..1e6, 2.0), "0 5.0e5 1.0e6");
    }

    #[test]
    fn a_plot_without_points_is_an_error_naming_it() {
        let path = temp_folder("empty").join("empty.png");
        let plot = plot_of(vec![Series::new("none", vec![], LineStyle::Solid)]);
        let e = write_png(&path, &plot, 900, 600).unwrap_err();
        assert!(matches!(e, PlotError::Empty { .. }), "{e:?}");
        assert!(e.to_string().contains(&plot.title), "{e}");
        let e = write_png(&path, &plot_of(vec![]), 900, 600).unwrap_err();
        assert!(matches!(e, PlotError::Empty { .. }), "{e:?}");
        assert!(!path.exists());
    }

    #[test]
    fn a_plot_with_only_non_finite_points_is_an_error() {
        let path = temp_folder("nan").join("nan.png");
        let plot = plot_of(vec![
            Series::new("nan", vec![(f64::NAN, f64::NAN); 3], LineStyle::Solid),
            Series::new("inf", vec![(1.0, f64::INFINITY)], LineStyle::Markers),
        ]);
        let e = write_png(&path, &plot, 900, 600).unwrap_err();
        assert!(
            matches!(e, PlotError::NoFinitePoints { count: 4, .. }),
            "{e:?}"
        );
        assert!(e.to_string().contains(&plot.title), "{e}");
        assert!(!path.exists());
    }

    #[test]
    fn unusable_sizes_are_errors() {
        let path = temp_folder("size").join("size.png");
        for (w, h) in [(0, 600), (900, 0), (100, 600), (900, MAX_SIDE + 1)] {
            let e = write_png(&path, &two_series(), w, h).unwrap_err();
            assert!(matches!(e, PlotError::Size { .. }), "{w} x {h}: {e:?}");
        }
    }

    fn square_map(values: Vec<f64>, limit: Option<f64>) -> MapPlot {
        let cells = (0..values.len())
            .map(|k| {
                let x = 10.0 * k as f64;
                vec![(x, 0.0), (x + 10.0, 0.0), (x + 10.0, 10.0), (x, 10.0)]
            })
            .collect();
        let mut map = MapPlot::new("Squares", "value (°)", cells, values);
        map.limit = limit.map(|value| Limit {
            value,
            label: format!("locking {value}°"),
            flags_cells: true,
        });
        map
    }

    /// The scale runs from 0 to the locking angle or the largest value, whichever is higher,
    /// or over a span given; one value still gets a span.
    #[test]
    fn the_colour_scale_runs_to_the_limit_or_the_largest_value() {
        assert_eq!(
            square_map(vec![3.0, 27.7], Some(45.0)).colour_range(),
            (0.0, 45.0)
        );
        assert_eq!(
            square_map(vec![3.0, 52.5, f64::NAN], Some(45.0)).colour_range(),
            (0.0, 52.5)
        );
        assert_eq!(
            square_map(vec![3.0, 27.7], None).colour_range(),
            (0.0, 27.7)
        );
        let mut spanned = square_map(vec![-2.0, 5.0], None);
        spanned.scale = Some((-2.0, 5.0));
        assert_eq!(spanned.colour_range(), (-2.0, 5.0));
        let (lo, hi) = square_map(vec![0.0, 0.0], None).colour_range();
        assert!(lo < 0.0 && hi > 0.0, "{lo} {hi}");
    }

    /// Cells beyond a flagging limit are magenta, cells without a value grey, the rest on
    /// the scale: its ends blue and red.
    #[test]
    fn cells_take_the_colour_of_their_place_on_the_scale() {
        let map = square_map(vec![0.0, 45.0], Some(45.0));
        assert_eq!(map.colour_of(50.0), LIMIT_COLOUR);
        assert_eq!(map.colour_of(f64::NAN), MISSING_COLOUR);
        assert_eq!(map.colour_of(0.0), RGBColor(49, 54, 149));
        assert_eq!(map.colour_of(45.0), RGBColor(200, 30, 30));
        assert_eq!(map.colour_of(22.5), RGBColor(120, 200, 120));
        let mut marked = map.clone();
        marked.limit.as_mut().unwrap().flags_cells = false;
        assert_eq!(marked.colour_of(50.0), RGBColor(200, 30, 30));
    }

    /// The pixel the frame gives for a cell's centre has the cell's colour, lines, a marker,
    /// a legend and printed values drawn beside it.
    #[test]
    fn the_frame_finds_a_cells_pixel_and_its_colour() {
        let path = temp_folder("map").join("map.png");
        let mut map = square_map(vec![5.0, 20.0, 40.0, 50.0], Some(45.0));
        map.axes = Some(("x (mm)".into(), "y (mm)".into()));
        map.cell_labels = vec!["5".into(), "20".into(), "40".into(), "50".into()];
        map.marker = Some(Marker {
            at: (25.0, 5.0),
            label: "max 20°".into(),
        });
        map.lines = vec![MapLine {
            label: "die opening".into(),
            colour: (120, 60, 0),
            segments: vec![[(0.0, -2.0), (40.0, -2.0)]],
        }];
        map.legend = vec![LegendCell {
            label: "failed".into(),
            fill: Some((170, 170, 170)),
            outlined: false,
        }];
        let frame = write_map_png(&path, &map, 800, 500).unwrap();
        let (info, pixels) = decode(&path);
        let at = |(x, y): (f64, f64)| {
            let (column, row) = frame.pixel((x, y));
            let i = 3 * (row * info.width + column) as usize;
            RGBColor(pixels[i], pixels[i + 1], pixels[i + 2])
        };
        // off the printed value, inside each square
        assert_eq!(at((2.0, 2.0)), map.colour_of(5.0));
        assert_eq!(at((12.0, 8.0)), map.colour_of(20.0));
        assert_eq!(at((22.0, 2.0)), map.colour_of(40.0));
        assert_eq!(at((38.0, 8.0)), LIMIT_COLOUR);
    }

    /// A plot with a second axis draws the right axis's series in the next palette colour.
    #[test]
    fn a_twin_plot_draws_both_axes_series() {
        let path = temp_folder("twin").join("twin.png");
        let u: Vec<f64> = (0..=50).map(f64::from).collect();
        let twin = TwinPlot {
            plot: plot_of(vec![Series::new(
                "punch force",
                u.iter().map(|&u| (u, 2.0 * u)).collect(),
                LineStyle::Solid,
            )]),
            right_label: "draw-in (mm)".into(),
            right: vec![Series::new(
                "draw-in",
                u.iter().map(|&u| (u, 0.01 * u * u)).collect(),
                LineStyle::Solid,
            )],
        };
        write_twin_png(&path, &twin, 900, 600).unwrap();
        let (_, pixels) = decode(&path);
        let count = |c: RGBColor| {
            pixels
                .chunks_exact(3)
                .filter(|p| p == &[c.0, c.1, c.2])
                .count()
        };
        assert!(count(PALETTE[0]) > 300, "left series");
        assert!(count(PALETTE[1]) > 300, "right series");
    }

    #[test]
    fn io_errors_name_the_path() {
        let path = temp_folder("io").join("no-such-folder").join("plot.png");
        let e = write_png(&path, &two_series(), 900, 600).unwrap_err();
        assert!(matches!(e, PlotError::Io { .. }), "{e:?}");
        assert!(e.to_string().contains(&path.display().to_string()), "{e}");
    }
}
