//! ParaView output: `.vtu` frames of the meshed sheet and a `.pvd` collection that
//! strings them into a time series.
//!
//! Files are VTK XML `UnstructuredGrid` (version 1.0, little-endian, `UInt64` headers) with
//! every array inline as base64 binary: exact `Float64` values, a third smaller than ASCII,
//! and read by ParaView and VTK as they are. Triangles are cell type 5 (`VTK_TRIANGLE`),
//! quadrilaterals cell type 9 (`VTK_QUAD`).
//!
//! The writer is hand-written rather than taken from the `vtkio` crate: its newest stable
//! release (0.6.3) depends on `nom` 3 and `quick-xml` 0.22, which Rust already warns "will be
//! rejected by a future version of Rust", and its default features compile the C library
//! liblzma. What this module needs — one element type, no compression, no reading — is a
//! short writer and a base64 encoder.
//!
//! Every file is written to `NAME.tmp` and renamed, so a run that stops mid-write leaves
//! either the old file or the new one, never half of one; a write that fails (a full disk)
//! removes its temporary file.

use crate::mesh::Cell;
use std::fmt::{self, Display, Write as _};
use std::path::{Path, PathBuf};

/// `VTK_TRIANGLE` in the VTK cell type table.
const VTK_TRIANGLE: u8 = 5;
/// `VTK_QUAD` in the VTK cell type table.
const VTK_QUAD: u8 = 9;

/// Values of one field, per point or per cell.
#[derive(Clone, Debug, PartialEq)]
pub enum FieldData {
    Scalar(Vec<f64>),
    /// Components x, y, z (global axes).
    Vector(Vec<[f64; 3]>),
    /// A symmetric in-plane tensor: components xx, yy, xy.
    InPlaneTensor(Vec<[f64; 3]>),
    /// Integer codes, with what each means: `meanings[k]` for code `k`. The meanings go into
    /// the file as a string array `<name>_codes` of the grid's field data ("0 free", ...).
    Codes {
        values: Vec<u32>,
        meanings: Vec<String>,
    },
}

impl FieldData {
    /// The number of points or cells the field has values for.
    pub fn len(&self) -> usize {
        match self {
            FieldData::Scalar(v) => v.len(),
            FieldData::Vector(v) | FieldData::InPlaneTensor(v) => v.len(),
            FieldData::Codes { values, .. } => values.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn components(&self) -> usize {
        self.component_names().len().max(1)
    }

    /// The names ParaView shows for the components (`ComponentName0`, ...); none for scalars.
    fn component_names(&self) -> &'static [&'static str] {
        match self {
            FieldData::Scalar(_) | FieldData::Codes { .. } => &[],
            FieldData::Vector(_) => &["x", "y", "z"],
            FieldData::InPlaneTensor(_) => &["xx", "yy", "xy"],
        }
    }

    /// The floating-point values, component after component, point (or cell) after point.
    fn flat(&self) -> &[f64] {
        match self {
            FieldData::Scalar(v) => v,
            FieldData::Vector(v) | FieldData::InPlaneTensor(v) => v.as_flattened(),
            FieldData::Codes { .. } => &[],
        }
    }
}

/// A named field; the name is what ParaView shows in its colouring menu.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: String,
    pub data: FieldData,
}

/// One frame of a meshed sheet.
#[derive(Clone, Copy, Debug)]
pub struct VtuFrame<'a> {
    pub points: &'a [[f64; 3]],
    pub cells: &'a [Cell],
    pub point_data: &'a [Field],
    pub cell_data: &'a [Field],
}

/// Whether a value belongs to a point or to a cell (an element).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    Point,
    Cell,
}

impl Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Location::Point => "point",
            Location::Cell => "cell",
        })
    }
}

/// Why a frame or a series could not be written.
#[derive(Debug, thiserror::Error)]
pub enum VtkError {
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },
    #[error("field '{field}': {len} values, but the sheet has {expected} {location}s")]
    FieldLength {
        field: String,
        location: Location,
        len: usize,
        expected: usize,
    },
    #[error("field '{field}': two {location} fields have this name")]
    DuplicateField { field: String, location: Location },
    #[error("field '{field}': the value at {location} {index} is not finite ({value})")]
    NonFinite {
        field: String,
        location: Location,
        index: usize,
        value: f64,
    },
    #[error(
        "field '{field}': code {code} at {location} {index}, but only {codes} codes have a meaning"
    )]
    UnknownCode {
        field: String,
        location: Location,
        index: usize,
        code: u32,
        codes: usize,
    },
    #[error("cells: cell {triangle} uses point {point}, but the sheet has {points} points")]
    TriangleIndex {
        triangle: usize,
        point: usize,
        points: usize,
    },
    #[error("time {time}: not a finite number")]
    NonFiniteTime { time: f64 },
    #[error("time {time}: not after the previous frame's time {previous}")]
    TimeNotIncreasing { time: f64, previous: f64 },
}

/// Writes one frame as a VTK XML UnstructuredGrid (.vtu) file.
pub fn write_vtu(path: &Path, frame: &VtuFrame) -> Result<(), VtkError> {
    let document = vtu_document(frame)?;
    write_atomically(path, &document)
}

/// A time series: frames `<dir>/<basename>_0000.vtu, _0001.vtu, ...` and `<dir>/<basename>.pvd`,
/// which ParaView opens as one animated data set. A frame may have further parts beside the
/// sheet (the tools), each its own file `<basename>_0000_<part>.vtu` listed under the same time
/// as part 1, 2, ... of the collection: ParaView and pyvista read such a time as one
/// multiblock data set, the sheet block 0.
#[derive(Clone, Debug)]
pub struct PvdSeries {
    dir: PathBuf,
    basename: String,
    /// Time (as written, [`time_text`]) and file names (relative to `dir`, part 0 first) of
    /// each frame written so far.
    frames: Vec<(f64, Vec<String>)>,
}

impl PvdSeries {
    /// Creates `dir` if missing and writes an empty collection there at once, so that an
    /// unwritable folder stops the run before it starts, and a `.pvd` left by an earlier run
    /// never lists that run's frames beside this one's.
    pub fn new(dir: &Path, basename: &str) -> Result<Self, VtkError> {
        std::fs::create_dir_all(dir).map_err(|source| VtkError::Io {
            path: dir.to_path_buf(),
            action: "create the folder",
            source,
        })?;
        let series = Self {
            dir: dir.to_path_buf(),
            basename: basename.to_string(),
            frames: Vec::new(),
        };
        series.write_pvd()?;
        Ok(series)
    }

    /// Writes the frame and rewrites the `.pvd` at once, so that the files on disk are a valid
    /// collection of the results so far even if the run stops later. Returns the frame's path.
    /// Times must be finite and increasing, as written (ten significant digits). Should the
    /// `.pvd` fail to be written, the frame still counts: the next successful call lists it.
    pub fn add_frame(&mut self, time: f64, frame: &VtuFrame) -> Result<PathBuf, VtkError> {
        self.add_frame_with_parts(time, frame, &[])
    }

    /// [`PvdSeries::add_frame`] with further `parts` of the same time, each `(name, frame)`,
    /// `name` a word (letters, digits, `-`) that ends its file's name.
    pub fn add_frame_with_parts(
        &mut self,
        time: f64,
        frame: &VtuFrame,
        parts: &[(&str, VtuFrame)],
    ) -> Result<PathBuf, VtkError> {
        let time = self.checked_time(time)?;
        let stem = format!("{}_{:04}", self.basename, self.frames.len());
        let name = format!("{stem}.vtu");
        let path = self.dir.join(&name);
        write_vtu(&path, frame)?;
        let mut files = vec![name];
        for (part, frame) in parts {
            let name = format!("{stem}_{part}.vtu");
            write_vtu(&self.dir.join(&name), frame)?;
            files.push(name);
        }
        self.frames.push((time, files));
        self.write_pvd()?;
        Ok(path)
    }

    pub fn pvd_path(&self) -> PathBuf {
        self.dir.join(format!("{}.pvd", self.basename))
    }

    pub fn frame_count(&self) -> usize {
        self.frames.len()
    }

    /// `time` as it will be written, if finite and after the last frame's.
    fn checked_time(&self, time: f64) -> Result<f64, VtkError> {
        if !time.is_finite() {
            return Err(VtkError::NonFiniteTime { time });
        }
        let written = rounded_time(time);
        match self.frames.last() {
            Some(&(previous, _)) if written <= previous => {
                Err(VtkError::TimeNotIncreasing { time, previous })
            }
            _ => Ok(written),
        }
    }

    fn write_pvd(&self) -> Result<(), VtkError> {
        write_atomically(&self.pvd_path(), &pvd_document(&self.frames))
    }
}

/// Significant digits of the times written: a frame's time is a record's, itself a sum of
/// increments, whose last digits are noise (`0.6150000000000001`).
const TIME_DIGITS: usize = 10;

/// `time` rounded to [`TIME_DIGITS`] significant digits.
fn rounded_time(time: f64) -> f64 {
    format!("{time:.*e}", TIME_DIGITS - 1)
        .parse()
        .unwrap_or(time)
}

/// `time` as written in a `.pvd`: [`rounded_time`] in its shortest decimal form (`0.615`).
pub fn time_text(time: f64) -> String {
    format!("{}", rounded_time(time))
}

/// The `.pvd` text listing `frames` (time, relative file names, part 0 first).
fn pvd_document(frames: &[(f64, Vec<String>)]) -> String {
    let mut out = String::from(
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n\
         <Collection>\n",
    );
    for (time, files) in frames {
        for (part, file) in files.iter().enumerate() {
            let _ = writeln!(
                out,
                "<DataSet timestep=\"{}\" part=\"{part}\" file=\"{}\"/>",
                time_text(*time),
                xml_escape(file)
            );
        }
    }
    out.push_str("</Collection>\n</VTKFile>\n");
    out
}

/// The `.vtu` text of `frame`, once it is found consistent.
fn vtu_document(frame: &VtuFrame) -> Result<String, VtkError> {
    check_frame(frame)?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<?xml version=\"1.0\"?>\n\
         <VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" \
         header_type=\"UInt64\">\n\
         <UnstructuredGrid>"
    );
    push_code_meanings(&mut out, frame.point_data.iter().chain(frame.cell_data));
    let _ = writeln!(
        out,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        frame.points.len(),
        frame.cells.len()
    );
    push_points(&mut out, frame.points);
    push_cells(&mut out, frame.cells);
    push_fields(&mut out, "PointData", frame.point_data);
    push_fields(&mut out, "CellData", frame.cell_data);
    out.push_str("</Piece>\n</UnstructuredGrid>\n</VTKFile>\n");
    Ok(out)
}

/// Everything that would make a file ParaView misreads, or a panic here.
fn check_frame(frame: &VtuFrame) -> Result<(), VtkError> {
    check_finite("points", Location::Point, 3, frame.points.as_flattened())?;
    check_cells(frame.cells, frame.points.len())?;
    check_fields(frame.point_data, Location::Point, frame.points.len())?;
    check_fields(frame.cell_data, Location::Cell, frame.cells.len())
}

fn check_cells(cells: &[Cell], points: usize) -> Result<(), VtkError> {
    for (triangle, corners) in cells.iter().enumerate() {
        if let Some(&point) = corners.nodes().iter().find(|&&p| p >= points) {
            return Err(VtkError::TriangleIndex {
                triangle,
                point,
                points,
            });
        }
    }
    Ok(())
}

fn check_fields(fields: &[Field], location: Location, expected: usize) -> Result<(), VtkError> {
    for (i, field) in fields.iter().enumerate() {
        let name = || field.name.clone();
        if fields[..i].iter().any(|f| f.name == field.name) {
            return Err(VtkError::DuplicateField {
                field: name(),
                location,
            });
        }
        if field.data.len() != expected {
            return Err(VtkError::FieldLength {
                field: name(),
                location,
                len: field.data.len(),
                expected,
            });
        }
        check_finite(
            &field.name,
            location,
            field.data.components(),
            field.data.flat(),
        )?;
        if let FieldData::Codes { values, meanings } = &field.data {
            if let Some(index) = values.iter().position(|&c| c as usize >= meanings.len()) {
                return Err(VtkError::UnknownCode {
                    field: name(),
                    location,
                    index,
                    code: values[index],
                    codes: meanings.len(),
                });
            }
        }
    }
    Ok(())
}

/// `values` holds `components` numbers per point or cell; the error names the point or cell.
fn check_finite(
    field: &str,
    location: Location,
    components: usize,
    values: &[f64],
) -> Result<(), VtkError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(at) => Err(VtkError::NonFinite {
            field: field.to_string(),
            location,
            index: at / components,
            value: values[at],
        }),
        None => Ok(()),
    }
}

fn push_points(out: &mut String, points: &[[f64; 3]]) {
    out.push_str("<Points>\n");
    push_data_array(
        out,
        "Float64",
        "Points",
        3,
        &[],
        &f64_bytes(points.as_flattened()),
    );
    out.push_str("</Points>\n");
}

/// Connectivity, end offsets (3, 6, 9, ... for triangles) and cell types, as VTK lays out
/// cells.
fn push_cells(out: &mut String, cells: &[Cell]) {
    let connectivity: Vec<u8> = cells
        .iter()
        .flat_map(|c| c.nodes().iter())
        .flat_map(|&p| (p as i64).to_le_bytes())
        .collect();
    let offsets: Vec<u8> = cells
        .iter()
        .scan(0i64, |end, c| {
            *end += c.nodes().len() as i64;
            Some(*end)
        })
        .flat_map(|end| end.to_le_bytes())
        .collect();
    let types: Vec<u8> = cells
        .iter()
        .map(|c| if c.is_quad() { VTK_QUAD } else { VTK_TRIANGLE })
        .collect();
    out.push_str("<Cells>\n");
    push_data_array(out, "Int64", "connectivity", 1, &[], &connectivity);
    push_data_array(out, "Int64", "offsets", 1, &[], &offsets);
    push_data_array(out, "UInt8", "types", 1, &[], &types);
    out.push_str("</Cells>\n");
}

fn push_fields(out: &mut String, section: &str, fields: &[Field]) {
    let _ = writeln!(out, "<{section}>");
    for field in fields {
        match &field.data {
            FieldData::Codes { values, .. } => {
                let bytes: Vec<u8> = values
                    .iter()
                    .flat_map(|v| (*v as i32).to_le_bytes())
                    .collect();
                push_data_array(out, "Int32", &field.name, 1, &[], &bytes);
            }
            data => push_data_array(
                out,
                "Float64",
                &field.name,
                data.components(),
                data.component_names(),
                &f64_bytes(data.flat()),
            ),
        }
    }
    let _ = writeln!(out, "</{section}>");
}

/// The meanings of every code field, as the grid's field data: for each code `k` of a field
/// `name`, a one-value `Int32` array named `name k meaning` ("contact_status 1 punch") holding
/// `k`. Numbers, not strings: meshio refuses VTK's `String` arrays, and ParaView lists field
/// data by name in its Information panel, where the legend then reads as it should.
fn push_code_meanings<'f>(out: &mut String, fields: impl Iterator<Item = &'f Field>) {
    let legends: Vec<(&str, &[String])> = fields
        .filter_map(|f| match &f.data {
            FieldData::Codes { meanings, .. } => Some((f.name.as_str(), meanings.as_slice())),
            _ => None,
        })
        .collect();
    if legends.is_empty() {
        return;
    }
    out.push_str("<FieldData>\n");
    for (name, meanings) in legends {
        for (k, meaning) in meanings.iter().enumerate() {
            let _ = writeln!(
                out,
                "<DataArray type=\"Int32\" Name=\"{}\" NumberOfTuples=\"1\" \
                 format=\"ascii\">{k}</DataArray>",
                xml_escape(&code_name(name, k, meaning))
            );
        }
    }
    out.push_str("</FieldData>\n");
}

/// The name of the field-data array that says what code `k` of field `name` means.
fn code_name(name: &str, k: usize, meaning: &str) -> String {
    format!("{name} {k} {meaning}")
}

/// One inline binary `DataArray` (with its components' names, if any): base64 of the byte
/// count (`UInt64`) followed by the bytes, encoded as one stream, as VTK itself writes
/// uncompressed data.
fn push_data_array(
    out: &mut String,
    vtk_type: &str,
    name: &str,
    components: usize,
    component_names: &[&str],
    bytes: &[u8],
) {
    let _ = write!(
        out,
        "<DataArray type=\"{vtk_type}\" Name=\"{}\" NumberOfComponents=\"{components}\"",
        xml_escape(name)
    );
    for (k, component) in component_names.iter().enumerate() {
        let _ = write!(out, " ComponentName{k}=\"{}\"", xml_escape(component));
    }
    out.push_str(" format=\"binary\">\n");
    let mut block = (bytes.len() as u64).to_le_bytes().to_vec();
    block.extend_from_slice(bytes);
    push_base64(out, &block);
    out.push_str("\n</DataArray>\n");
}

fn f64_bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Standard base64 (RFC 4648, with `=` padding) of `bytes`, appended to `out`.
fn push_base64(out: &mut String, bytes: &[u8]) {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.reserve(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let triple = u32::from_be_bytes([0, b[0], b[1], b[2]]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(triple >> (18 - 6 * k) & 0x3f) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
}

/// `text` made safe inside a double-quoted XML attribute.
fn xml_escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// Writes `text` to `path` through `path.tmp` and a rename, never through a symbolic link
/// ([`super::product_file::replace`]).
fn write_atomically(path: &Path, text: &str) -> Result<(), VtkError> {
    super::product_file::replace(path, text.as_bytes()).map_err(|source| VtkError::Io {
        path: path.to_path_buf(),
        action: "write the file",
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame_with(point_data: &[Field]) -> Result<String, VtkError> {
        vtu_document(&VtuFrame {
            points: &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            cells: &[Cell::Triangle([0, 1, 2])],
            point_data,
            cell_data: &[],
        })
    }

    #[test]
    fn vectors_carry_component_names_and_codes_their_meanings() {
        let text = frame_with(&[
            Field {
                name: "velocity".into(),
                data: FieldData::Vector(vec![[0.0; 3]; 3]),
            },
            Field {
                name: "status".into(),
                data: FieldData::Codes {
                    values: vec![0, 1, 0],
                    meanings: vec!["free".into(), "punch".into()],
                },
            },
        ])
        .unwrap();
        assert!(text.contains(
            "Name=\"velocity\" NumberOfComponents=\"3\" ComponentName0=\"x\" \
             ComponentName1=\"y\" ComponentName2=\"z\""
        ));
        assert!(text.contains("<DataArray type=\"Int32\" Name=\"status\""));
        // one number a meaning, named by the field, the code and what it means
        for (k, meaning) in ["free", "punch"].iter().enumerate() {
            assert!(text.contains(&format!(
                "<DataArray type=\"Int32\" Name=\"status {k} {meaning}\" NumberOfTuples=\"1\" \
                 format=\"ascii\">{k}</DataArray>"
            )));
        }
    }

    #[test]
    fn times_are_written_to_ten_digits_and_must_increase_as_written() {
        assert_eq!(time_text(0.6150000000000001), "0.615");
        assert_eq!(time_text(0.0), "0");
        assert_eq!(time_text(1.0 / 3.0), "0.3333333333");
        let dir = std::env::temp_dir().join(format!("thermostamp-pvd-{}", std::process::id()));
        let mut series = PvdSeries::new(&dir, "s").unwrap();
        let frame = VtuFrame {
            points: &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            cells: &[Cell::Triangle([0, 1, 2])],
            point_data: &[],
            cell_data: &[],
        };
        series
            .add_frame_with_parts(0.1, &frame, &[("tools", frame)])
            .unwrap();
        assert!(series.add_frame(0.1 + 1e-13, &frame).is_err());
        let pvd = std::fs::read_to_string(series.pvd_path()).unwrap();
        assert!(pvd.contains("timestep=\"0.1\" part=\"0\" file=\"s_0000.vtu\""));
        assert!(pvd.contains("timestep=\"0.1\" part=\"1\" file=\"s_0000_tools.vtu\""));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_code_without_a_meaning_is_refused() {
        let error = frame_with(&[Field {
            name: "status".into(),
            data: FieldData::Codes {
                values: vec![0, 2, 0],
                meanings: vec!["free".into(), "punch".into()],
            },
        }])
        .unwrap_err();
        assert_eq!(
            error.to_string(),
            "field 'status': code 2 at point 1, but only 2 codes have a meaning"
        );
    }
}
