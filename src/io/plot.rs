//! PNG line plots (force–displacement curves and the like).
//!
//! Text is drawn with Liberation Sans, embedded in the binary (`assets/fonts/`), so plots
//! render the same on a machine with no system fonts and no fontconfig, as CI is. The picture
//! is drawn into memory and encoded with the `png` crate, so that every I/O failure can name
//! the file.

use plotters::chart::SeriesAnno;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::{register_font, FontStyle};
use std::fs::File;
use std::io::BufWriter;
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

/// One curve: `points` are `(x, y)` in the caller's units.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub style: LineStyle,
}

impl Series {
    pub fn new(label: impl Into<String>, points: Vec<(f64, f64)>, style: LineStyle) -> Self {
        Self {
            label: label.into(),
            points,
            style,
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

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("plot '{title}': no points to draw")]
    Empty { title: String },
    #[error("plot '{title}': none of its {count} points is finite")]
    NoFinitePoints { title: String, count: usize },
    #[error("plot '{title}': {width} x {height} pixels is not a usable size (from {MIN_WIDTH} x {MIN_HEIGHT} to {MAX_SIDE} x {MAX_SIDE})")]
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
/// Largest side accepted: keeps the in-memory RGB buffer (3 bytes a pixel) below 200 MB.
const MAX_SIDE: u32 = 8192;

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

/// Fraction of the data span added on each side of the axes, so curves do not touch the frame.
const MARGIN: f64 = 0.04;

/// Writes the plot as a PNG of `width` x `height` pixels (e.g. 900 x 600).
pub fn write_png(path: &Path, plot: &LinePlot, width: u32, height: u32) -> Result<(), PlotError> {
    check_size(plot, width, height)?;
    let series = finite_series(plot)?;
    register_embedded_font()?;
    let mut rgb = vec![255u8; 3 * width as usize * height as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, (width, height)).into_drawing_area();
        draw(&root, plot, &series).map_err(|message| PlotError::Draw {
            title: plot.title.clone(),
            message,
        })?;
    }
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

/// plotters keeps fonts in a process-wide table; registering once is enough.
fn register_embedded_font() -> Result<(), PlotError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok = *REGISTERED
        .get_or_init(|| register_font(FONT_FAMILY, FontStyle::Normal, FONT_BYTES).is_ok());
    if ok {
        Ok(())
    } else {
        Err(PlotError::Font)
    }
}

/// Draws frame, grid, curves and legend; `series` holds the finite points of `plot.series`.
fn draw(
    root: &DrawingArea<BitMapBackend, Shift>,
    plot: &LinePlot,
    series: &[Vec<(f64, f64)>],
) -> Result<(), String> {
    let (width, height) = root.dim_in_pixel();
    let scale = (f64::from(width) / DESIGN_SIZE.0).min(f64::from(height) / DESIGN_SIZE.1);
    let px = |design: f64| (design * scale).round().max(1.0) as u32;
    let font = |design: f64| (FONT_FAMILY, f64::from(px(design)));

    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let all = series.iter().flatten().copied();
    let x_range = padded_range(all.clone().map(|(x, _)| x));
    let y_range = padded_range(all.map(|(_, y)| y));

    let mut chart = ChartBuilder::on(root)
        .caption(&plot.title, font(24.0))
        .margin(px(16.0))
        .x_label_area_size(px(56.0))
        .y_label_area_size(px(88.0))
        .build_cartesian_2d(x_range.clone(), y_range.clone())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(&plot.x_label)
        .y_desc(&plot.y_label)
        .axis_desc_style(font(18.0))
        .label_style(font(15.0))
        .x_labels(10)
        .y_labels(8)
        .bold_line_style(RGBColor(215, 215, 215).stroke_width(1))
        .light_line_style(RGBColor(240, 240, 240).stroke_width(1))
        .axis_style(BLACK.stroke_width(1))
        .draw()
        .map_err(|e| e.to_string())?;

    let line_width = px(2.0);
    for (index, (meta, points)) in plot.series.iter().zip(series).enumerate() {
        let color = PALETTE[index % PALETTE.len()];
        let style = color.stroke_width(line_width);
        let legend_size = px(24.0) as i32;
        let drawn = match meta.style {
            LineStyle::Solid => chart.draw_series(LineSeries::new(points.iter().copied(), style)),
            LineStyle::Dashed => chart.draw_series(DashedLineSeries::new(
                points.iter().copied(),
                px(10.0),
                px(6.0),
                style,
            )),
            LineStyle::Markers => chart.draw_series(
                points
                    .iter()
                    .map(|&p| Circle::new(p, px(3.5), color.filled())),
            ),
        }
        .map_err(|e| e.to_string())?;
        set_legend(drawn, &meta.label, meta.style, legend_size, style);
    }

    if plot.series.len() > 1 {
        let corner = emptiest_corner(series, &x_range, &y_range);
        chart
            .configure_series_labels()
            .position(corner)
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
    (mid - half).max(f64::MIN)..(mid + half).min(f64::MAX)
}

/// The corner of the plotting area (a quarter of its width by a third of its height) that
/// holds the fewest points, where the legend hides the least of the curves.
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

fn encode_png(path: &Path, rgb: &[u8], width: u32, height: u32) -> Result<(), PlotError> {
    let io_error = |source| PlotError::Io {
        path: path.to_path_buf(),
        source,
    };
    let encode_error = |source| PlotError::Encode {
        path: path.to_path_buf(),
        source,
    };
    let file = File::create(path).map_err(io_error)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(encode_error)?;
    writer.write_image_data(rgb).map_err(encode_error)?;
    writer.finish().map_err(encode_error)
}
