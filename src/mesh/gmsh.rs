//! Gmsh `.msh` files (format 4.1, ASCII and binary) in and out: the sheet's 3-node triangles
//! and 4-node quadrangles (one cell each), physical groups as node and element sets. The rules
//! are in docs/meshes.md, "Gmsh (.msh)".
//!
//! **Choice:** a parser of our own, not the `mshio` crate (0.4.2, the newest): `mshio` panics
//! on some headers (`4.1 1 3`, an oversized data-size), does not read `$PhysicalNames`, gives
//! no line numbers, and brings in nom 5 with lexical-core 0.7 (advisory RUSTSEC-2023-0086),
//! num 0.3 and syn 1. What is needed here (four sections) is small enough to read with care:
//! every count read from the file is checked against what is left of it before memory is
//! set aside, and every failure is a [`MeshFileError`] naming the line (ASCII text) or the
//! byte (binary data).

use super::conformity::check_elements;
use super::{At, Cell, Mesh, MeshFileError, MeshImport, Origin, Place};
use nalgebra::Vector3;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// What the reader takes, for error messages.
const SUPPORTED: &str = "this reader takes 3-node triangles (type 2) and 4-node quadrangles \
    (type 3) for the sheet, 2-node lines (type 1) and points (type 15) for node sets, and skips \
    linear and higher-order volume elements; mesh with first-order elements (Mesh.ElementOrder = 1)";

/// Reads a Gmsh MSH 4.1 file (ASCII or binary). See [`parse_msh`].
pub fn read_msh(path: &Path) -> Result<MeshImport, MeshFileError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path)
        .map_err(|e| MeshFileError::in_file(&file, format!("cannot read the file: {e}")))?;
    parse_msh(&bytes, &file)
}

/// Reads the bytes of a Gmsh MSH 4.1 file (ASCII or binary, either byte order); `file` names it
/// in errors and notes.
///
/// The sheet is the file's 3-node triangles and 4-node quadrangles, one cell each, in file
/// order, with the nodes they use renumbered from 0 in file order (nodes no triangle or
/// quadrangle uses are left out, with a note). Physical groups become
/// sets: a surface group gives an element set and a node set of its elements' nodes, a curve
/// or point group a node set of its line or point elements' nodes. Sets are sorted, without
/// repeats. The orientation of the elements is kept; a surface whose elements are not
/// consistently oriented gets a note naming the first offending element.
pub fn parse_msh(bytes: &[u8], file: &str) -> Result<MeshImport, MeshFileError> {
    let raw = RawFile::parse(bytes, file)?;
    let lines = Lines::new(bytes, raw.text_end);
    raw.into_import(file, &lines)
}

/// Writes `mesh` as an ASCII Gmsh MSH 4.1 file. See [`write_msh_to`].
pub fn write_msh(path: &Path, mesh: &Mesh) -> Result<(), MeshFileError> {
    let file = path.display().to_string();
    let io = |e: std::io::Error| MeshFileError::in_file(&file, format!("cannot write: {e}"));
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(io)?);
    write_msh_to(&mut out, mesh, &file)?;
    out.flush().map_err(io)
}

/// Writes `mesh` as ASCII Gmsh MSH 4.1 to `out` (`file` names it in errors).
///
/// Nodes get tags 1, 2, ... in index order, written in the shortest form that reads back to
/// the same `f64`; cells are 3-node triangles (type 2) and 4-node quadrangles (type 3)
/// tagged 1, 2, ... in order. Each element set
/// is a physical surface group of that name; each node set is a physical point group of that
/// name holding one point element per node, except a node set that is exactly (sorted, no
/// repeats) the nodes of the element set of the same name, which the reader rebuilds from the
/// surface group. [`parse_msh`] of the result gives back the same nodes, cells and sets
/// for a mesh whose sets are sorted, without repeats and not empty, whose nodes all belong to
/// cells, and whose element sets each have a node set of their name or none (the reader
/// then adds one).
pub fn write_msh_to<W: Write>(mut out: W, mesh: &Mesh, file: &str) -> Result<(), MeshFileError> {
    mesh.validate()
        .map_err(|e| MeshFileError::in_file(file, format!("cannot write an invalid mesh: {e}")))?;
    for name in mesh.node_sets.keys().chain(mesh.element_sets.keys()) {
        if name.is_empty() || name.contains(['"', '\n', '\r']) {
            return Err(MeshFileError::in_file(
                file,
                format!(
                    "set name {name:?} cannot be written: MSH physical names are non-empty \
                     and hold no double quote or line break"
                ),
            ));
        }
    }
    let text = msh_text(mesh);
    out.write_all(text.as_bytes())
        .map_err(|e| MeshFileError::in_file(file, format!("cannot write: {e}")))
}

// ---------------------------------------------------------------------------------------------
// Reading: the cursor over the bytes.

#[derive(Clone, Copy, Debug, PartialEq)]
enum Encoding {
    Ascii,
    Binary { little_endian: bool, size_t: usize },
}

struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    file: &'a str,
    encoding: Encoding,
    /// Offsets below this are text, whose line numbers mean something; errors beyond it name
    /// the byte instead.
    text_end: usize,
    /// The section being read, for messages.
    section: &'static str,
}

/// A token for a message: quoted, escaped, at most 40 characters.
fn show(token: &[u8]) -> String {
    let text = String::from_utf8_lossy(&token[..token.len().min(40)]);
    let more = if token.len() > 40 { "..." } else { "" };
    format!("{:?}{more}", text)
}

impl<'a> Cursor<'a> {
    fn new(bytes: &'a [u8], file: &'a str) -> Self {
        Self {
            bytes,
            pos: 0,
            file,
            encoding: Encoding::Ascii,
            text_end: usize::MAX,
            section: "$MeshFormat",
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len().saturating_sub(self.pos)
    }

    /// An error at byte `at`: with its line where that is text, else with the byte.
    fn error(&self, at: usize, message: impl Into<String>) -> MeshFileError {
        let message = message.into();
        if at < self.text_end {
            // at the end of the file: the last line
            let at = at.min(self.bytes.len().saturating_sub(1));
            let line = 1 + self.bytes[..at].iter().filter(|&&b| b == b'\n').count();
            MeshFileError::at_line(self.file, line, message)
        } else {
            MeshFileError::in_file(self.file, format!("{message} (byte {at} of the file)"))
        }
    }

    fn ended(&self, what: &str) -> MeshFileError {
        let message = match self.encoding {
            Encoding::Binary { .. } if self.pos >= self.text_end => format!(
                "binary data cut short in the {} section: the file ends where {what} was \
                 expected",
                self.section
            ),
            _ => format!(
                "the file ends in the {} section, where {what} was expected",
                self.section
            ),
        };
        self.error(self.bytes.len(), message)
    }

    fn skip_whitespace(&mut self) {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    /// The next whitespace-delimited token and where it starts.
    fn token(&mut self) -> Option<(usize, &'a [u8])> {
        self.skip_whitespace();
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| (start, &self.bytes[start..self.pos]))
    }

    /// Where the next number starts (after white space in text).
    fn mark(&mut self) -> usize {
        if self.encoding == Encoding::Ascii {
            self.skip_whitespace();
        }
        self.pos
    }

    /// A number written in text, whatever the encoding.
    fn text_number<T: std::str::FromStr>(
        &mut self,
        what: &str,
        kind: &str,
    ) -> Result<T, MeshFileError> {
        let (at, token) = self.token().ok_or_else(|| self.ended(what))?;
        std::str::from_utf8(token)
            .ok()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| {
                let hint = if token.starts_with(b"$") {
                    " (the section ends before the counts in it are reached)"
                } else {
                    ""
                };
                self.error(
                    at,
                    format!("expected {what} ({kind}), found {}{hint}", show(token)),
                )
            })
    }

    fn text_int(&mut self, what: &str) -> Result<i32, MeshFileError> {
        self.text_number(what, "an integer")
    }

    fn text_count(&mut self, what: &str) -> Result<usize, MeshFileError> {
        self.text_number(what, "a non-negative integer")
    }

    /// `n` bytes of binary data.
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], MeshFileError> {
        if self.remaining() < n {
            return Err(self.error(
                self.pos,
                format!(
                    "binary data cut short in the {} section: {what} needs {n} bytes, {} are left",
                    self.section,
                    self.remaining()
                ),
            ));
        }
        let slice = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(slice)
    }

    /// A `size_t` of the format.
    fn size(&mut self, what: &str) -> Result<u64, MeshFileError> {
        match self.encoding {
            Encoding::Ascii => self.text_number(what, "a non-negative integer"),
            Encoding::Binary {
                little_endian,
                size_t,
            } => {
                let b = self.take(size_t, what)?;
                Ok(match (size_t, little_endian) {
                    (4, true) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u64,
                    (4, false) => u32::from_be_bytes([b[0], b[1], b[2], b[3]]) as u64,
                    (_, true) => {
                        u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
                    }
                    (_, false) => {
                        u64::from_be_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]])
                    }
                })
            }
        }
    }

    /// A count (`size_t`) that fits in memory indices.
    fn count(&mut self, what: &str) -> Result<usize, MeshFileError> {
        let at = self.mark();
        let n = self.size(what)?;
        usize::try_from(n).map_err(|_| self.error(at, format!("{what} {n} is too large")))
    }

    /// An `int` of the format (4 bytes in binary).
    fn int(&mut self, what: &str) -> Result<i32, MeshFileError> {
        match self.encoding {
            Encoding::Ascii => self.text_int(what),
            Encoding::Binary { little_endian, .. } => {
                let b = self.take(4, what)?;
                let b = [b[0], b[1], b[2], b[3]];
                Ok(if little_endian {
                    i32::from_le_bytes(b)
                } else {
                    i32::from_be_bytes(b)
                })
            }
        }
    }

    /// A `double` of the format (8 bytes in binary).
    fn double(&mut self, what: &str) -> Result<f64, MeshFileError> {
        match self.encoding {
            Encoding::Ascii => self.text_number(what, "a number"),
            Encoding::Binary { little_endian, .. } => {
                let b = self.take(8, what)?;
                let b = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
                Ok(if little_endian {
                    f64::from_le_bytes(b)
                } else {
                    f64::from_be_bytes(b)
                })
            }
        }
    }

    /// Room to set aside for `count` items of at least `item_bytes` bytes each: no more than
    /// what is left of the file can hold.
    fn capacity(&self, count: usize, item_bytes: usize) -> usize {
        count.min(self.remaining() / item_bytes.max(1))
    }

    /// The smallest number of bytes one of `numbers` numbers takes (a digit in text).
    fn number_bytes(&self, size: usize) -> usize {
        match self.encoding {
            Encoding::Ascii => 1,
            Encoding::Binary { .. } => size,
        }
    }

    /// After a section header: the rest of its line, so that binary data starts right after.
    fn end_header_line(&mut self, header: &str) -> Result<(), MeshFileError> {
        while self.pos < self.bytes.len() && matches!(self.bytes[self.pos], b' ' | b'\t' | b'\r') {
            self.pos += 1;
        }
        match self.bytes.get(self.pos) {
            None => Ok(()),
            Some(b'\n') => {
                self.pos += 1;
                Ok(())
            }
            Some(_) => Err(self.error(
                self.pos,
                format!("expected the end of the line after {header}"),
            )),
        }
    }

    /// Binary data starts here: line numbers beyond mean nothing.
    fn begin_binary(&mut self) {
        if let Encoding::Binary { .. } = self.encoding {
            self.text_end = self.text_end.min(self.pos);
        }
    }

    /// The `$End...` line closing the section `name`.
    fn expect_end(&mut self, name: &str) -> Result<(), MeshFileError> {
        let end = format!("$End{name}");
        match self.token() {
            Some((_, token)) if token == end.as_bytes() => Ok(()),
            Some((at, token)) => Err(self.error(
                at,
                format!(
                    "expected {end}, found {} (the section holds more than the counts in it \
                     say, or is cut short)",
                    show(token)
                ),
            )),
            None => Err(self.error(
                self.bytes.len(),
                format!("the file ends before {end} closes the ${name} section"),
            )),
        }
    }

    /// Skips a section that is not read: up to the line that starts with `$End<name>`.
    fn skip_section(&mut self, name: &str, header_at: usize) -> Result<(), MeshFileError> {
        let end = format!("$End{name}");
        let end = end.as_bytes();
        let start = self.pos;
        let mut i = start;
        while i + end.len() <= self.bytes.len() {
            if (i == start || self.bytes[i - 1] == b'\n')
                && self.bytes[i..].starts_with(end)
                && self
                    .bytes
                    .get(i + end.len())
                    .is_none_or(|b| b.is_ascii_whitespace())
            {
                self.pos = i + end.len();
                return Ok(());
            }
            i += 1;
        }
        Err(self.error(
            header_at,
            format!("the ${name} section is never closed: no line starts with $End{name}"),
        ))
    }
}

// ---------------------------------------------------------------------------------------------
// Reading: the sections.

/// How a Gmsh element type is taken.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Triangle,
    Quadrangle,
    Line,
    Point,
    /// Skipped, with a note.
    Volume,
}

/// Kind, number of nodes and dimension of the element types read (or skipped).
fn element_type(t: i32) -> Option<(Kind, usize, i32)> {
    Some(match t {
        1 => (Kind::Line, 2, 1),
        2 => (Kind::Triangle, 3, 2),
        3 => (Kind::Quadrangle, 4, 2),
        15 => (Kind::Point, 1, 0),
        4 => (Kind::Volume, 4, 3),
        5 => (Kind::Volume, 8, 3),
        6 => (Kind::Volume, 6, 3),
        7 => (Kind::Volume, 5, 3),
        11 => (Kind::Volume, 10, 3),
        12 => (Kind::Volume, 27, 3),
        13 => (Kind::Volume, 18, 3),
        14 => (Kind::Volume, 14, 3),
        17 => (Kind::Volume, 20, 3),
        18 => (Kind::Volume, 15, 3),
        19 => (Kind::Volume, 13, 3),
        29 => (Kind::Volume, 20, 3),
        30 => (Kind::Volume, 35, 3),
        31 => (Kind::Volume, 56, 3),
        92 => (Kind::Volume, 64, 3),
        93 => (Kind::Volume, 125, 3),
        _ => return None,
    })
}

/// Gmsh's name of some element types that are not read, for the error message.
fn element_type_name(t: i32) -> Option<&'static str> {
    Some(match t {
        8 => "3-node second-order line",
        9 => "6-node second-order triangle",
        10 => "9-node second-order quadrangle",
        16 => "8-node second-order quadrangle",
        20 => "9-node third-order incomplete triangle",
        21 => "10-node third-order triangle",
        22 => "12-node fourth-order incomplete triangle",
        23 => "15-node fourth-order triangle",
        24 => "15-node fifth-order incomplete triangle",
        25 => "21-node fifth-order triangle",
        26 => "4-node third-order line",
        27 => "5-node fourth-order line",
        28 => "6-node fifth-order line",
        _ => return None,
    })
}

/// One node of the file.
struct RawNode {
    tag: u64,
    x: Vector3<f64>,
    /// Where its coordinates start.
    at: usize,
}

/// One triangle, quadrangle, line or point of the file, its nodes as indices into the file's
/// nodes.
struct RawElement {
    tag: u64,
    kind: Kind,
    /// Entity dimension and tag.
    entity: (i32, i32),
    nodes: [usize; 4],
    /// Where its tag is.
    at: usize,
}

impl RawElement {
    fn nodes(&self) -> &[usize] {
        let n = match self.kind {
            Kind::Triangle => 3,
            Kind::Quadrangle => 4,
            Kind::Line => 2,
            Kind::Point | Kind::Volume => 1,
        };
        &self.nodes[..n]
    }
}

#[derive(Default)]
struct RawFile {
    /// Physical names by (dimension, tag).
    names: BTreeMap<(i32, i32), String>,
    /// Physical tags of each entity, by (dimension, tag); `None` without `$Entities`.
    entities: Option<HashMap<(i32, i32), Vec<i32>>>,
    nodes: Vec<RawNode>,
    has_nodes: bool,
    elements: Vec<RawElement>,
    has_elements: bool,
    /// Skipped volume elements, by type.
    volumes: BTreeMap<i32, usize>,
    notes: Vec<String>,
    /// Where binary data starts (the end of the file in ASCII).
    text_end: usize,
}

impl RawFile {
    fn parse(bytes: &[u8], file: &str) -> Result<Self, MeshFileError> {
        let mut c = Cursor::new(bytes, file);
        mesh_format(&mut c)?;
        let mut raw = RawFile::default();
        let mut node_index: HashMap<u64, usize> = HashMap::new();
        let mut seen: HashMap<String, usize> = HashMap::new();
        let mut skipped: Vec<String> = Vec::new();
        loop {
            c.section = "file's top level (between sections)";
            let Some((at, token)) = c.token() else { break };
            if !token.starts_with(b"$") || token.len() < 2 {
                return Err(c.error(
                    at,
                    format!(
                        "expected a section header such as $Nodes, found {}",
                        show(token)
                    ),
                ));
            }
            let name = String::from_utf8_lossy(&token[1..]).into_owned();
            let line_of = |c: &Cursor, at| c.error(at, "").line;
            if let Some(&first) = seen.get(&name) {
                if name != "Comments" && !skipped.contains(&name) {
                    let where_first = line_of(&c, first)
                        .map(|l| format!(" (the first is at line {l})"))
                        .unwrap_or_default();
                    return Err(c.error(
                        at,
                        format!(
                            "a second ${name} section{where_first}: files with a repeated \
                             section are not read"
                        ),
                    ));
                }
            }
            seen.insert(name.clone(), at);
            c.end_header_line(&format!("${name}"))?;
            match name.as_str() {
                "MeshFormat" => {
                    return Err(c.error(at, "a second $MeshFormat section"));
                }
                "PhysicalNames" => {
                    c.section = "$PhysicalNames";
                    raw.names = physical_names(&mut c)?;
                }
                "Entities" => {
                    c.section = "$Entities";
                    c.begin_binary();
                    raw.entities = Some(entities(&mut c)?);
                }
                "PartitionedEntities" => {
                    return Err(c.error(
                        at,
                        "partitioned meshes ($PartitionedEntities) are not read: save the \
                         mesh unpartitioned",
                    ));
                }
                "Nodes" => {
                    c.section = "$Nodes";
                    c.begin_binary();
                    raw.nodes = nodes(&mut c, &mut node_index)?;
                    raw.has_nodes = true;
                }
                "Elements" => {
                    if !raw.has_nodes {
                        return Err(c.error(at, "the $Elements section comes before $Nodes"));
                    }
                    c.section = "$Elements";
                    c.begin_binary();
                    elements(&mut c, &node_index, &mut raw)?;
                    raw.has_elements = true;
                }
                _ => {
                    c.begin_binary();
                    c.skip_section(&name, at)?;
                    if name != "Comments" {
                        skipped.push(name);
                    }
                }
            }
        }
        raw.text_end = c.text_end.min(bytes.len());
        if !raw.has_nodes || !raw.has_elements {
            let missing = if raw.has_nodes { "$Elements" } else { "$Nodes" };
            return Err(MeshFileError::in_file(
                file,
                format!("the file has no {missing} section"),
            ));
        }
        if !skipped.is_empty() {
            raw.notes.push(format!(
                "sections not read: {}",
                skipped
                    .iter()
                    .map(|s| format!("${s}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        Ok(raw)
    }
}

/// `$MeshFormat`: version 4.1, ASCII or binary, and the byte order of binary files.
fn mesh_format(c: &mut Cursor) -> Result<(), MeshFileError> {
    if c.bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        c.pos = 3; // a UTF-8 byte-order mark
    }
    match c.token() {
        Some((_, b"$MeshFormat")) => {}
        Some((at, token)) => {
            return Err(c.error(
                at,
                format!(
                    "not a Gmsh MSH file: it must begin with $MeshFormat, found {}",
                    show(token)
                ),
            ))
        }
        None => {
            return Err(c.error(
                0,
                "the file is empty: a Gmsh MSH file begins with $MeshFormat",
            ))
        }
    }
    let (at, version) = c.token().ok_or_else(|| c.ended("the format version"))?;
    let value = std::str::from_utf8(version)
        .ok()
        .and_then(|s| s.parse::<f64>().ok());
    if !value.is_some_and(|v| (v - 4.1).abs() < 1e-9) {
        return Err(c.error(
            at,
            format!(
                "MSH format version {} is not read: this reader reads version 4.1 only, ASCII \
                 or binary (Gmsh 4.1 and later write it; set Mesh.MshFileVersion = 4.1)",
                show(version)
            ),
        ));
    }
    let at = c.mark();
    let file_type = c.text_int("the file type (0 ASCII, 1 binary)")?;
    let size_at = c.mark();
    let data_size = c.text_count("the data size (the bytes of a size_t)")?;
    match file_type {
        0 => c.encoding = Encoding::Ascii,
        1 => {
            if data_size != 4 && data_size != 8 {
                return Err(c.error(
                    size_at,
                    format!("data size {data_size} in a binary file: it must be 4 or 8"),
                ));
            }
            c.end_header_line("the format line")?;
            let one = c.take(4, "the byte-order check (the integer 1)")?;
            let one = [one[0], one[1], one[2], one[3]];
            let little_endian = if i32::from_le_bytes(one) == 1 {
                true
            } else if i32::from_be_bytes(one) == 1 {
                false
            } else {
                return Err(c.error(
                    c.pos - 4,
                    format!(
                        "the byte-order check after the format line should be the integer 1 \
                         in 4 bytes, found {one:02x?}"
                    ),
                ));
            };
            c.encoding = Encoding::Binary {
                little_endian,
                size_t: data_size,
            };
        }
        other => {
            return Err(c.error(
                at,
                format!("file type {other}: it must be 0 (ASCII) or 1 (binary)"),
            ))
        }
    }
    c.expect_end("MeshFormat")
}

/// `$PhysicalNames` (text in binary files too): names by (dimension, tag).
fn physical_names(c: &mut Cursor) -> Result<BTreeMap<(i32, i32), String>, MeshFileError> {
    let count = c.text_count("the number of physical names")?;
    let mut names = BTreeMap::new();
    for _ in 0..count {
        let at = {
            c.skip_whitespace();
            c.pos
        };
        let dimension = c.text_int("the dimension of a physical group")?;
        if !(0..=3).contains(&dimension) {
            return Err(c.error(
                at,
                format!("physical group dimension {dimension}: it must be 0, 1, 2 or 3"),
            ));
        }
        let tag = c.text_int("the tag of a physical group")?;
        while c.pos < c.bytes.len() && matches!(c.bytes[c.pos], b' ' | b'\t') {
            c.pos += 1;
        }
        if c.bytes.get(c.pos) != Some(&b'"') {
            return Err(c.error(
                c.pos,
                "expected the name of the physical group in double quotes",
            ));
        }
        let start = c.pos + 1;
        let length = c.bytes[start..]
            .iter()
            .position(|&b| b == b'"' || b == b'\n')
            .filter(|&n| c.bytes[start + n] == b'"')
            .ok_or_else(|| {
                c.error(
                    c.pos,
                    "the name of the physical group is not closed by a double quote on its line",
                )
            })?;
        let name = String::from_utf8_lossy(&c.bytes[start..start + length]).into_owned();
        c.pos = start + length + 1;
        if names.insert((dimension, tag), name).is_some() {
            return Err(c.error(
                at,
                format!("physical group {tag} of dimension {dimension} is named twice"),
            ));
        }
    }
    c.expect_end("PhysicalNames")?;
    Ok(names)
}

/// `$Entities`: the physical tags of each point, curve, surface and volume.
fn entities(c: &mut Cursor) -> Result<HashMap<(i32, i32), Vec<i32>>, MeshFileError> {
    let mut counts = [0usize; 4];
    for (count, what) in counts.iter_mut().zip([
        "the number of points",
        "the number of curves",
        "the number of surfaces",
        "the number of volumes",
    ]) {
        *count = c.count(what)?;
    }
    let mut physical = HashMap::new();
    for (dimension, &count) in (0..).zip(counts.iter()) {
        for _ in 0..count {
            let at = c.mark();
            let tag = c.int("an entity tag")?;
            let box_values = if dimension == 0 { 3 } else { 6 };
            for _ in 0..box_values {
                c.double("a coordinate of the entity's bounding box")?;
            }
            let n = c.count("the number of physical tags of the entity")?;
            let mut tags = Vec::with_capacity(c.capacity(n, c.number_bytes(4)));
            for _ in 0..n {
                tags.push(c.int("a physical tag")?);
            }
            if dimension > 0 {
                let n = c.count("the number of bounding entities")?;
                for _ in 0..n {
                    c.int("a bounding entity tag")?;
                }
            }
            if physical.insert((dimension, tag), tags).is_some() {
                return Err(c.error(
                    at,
                    format!("entity {tag} of dimension {dimension} is listed twice"),
                ));
            }
        }
    }
    c.expect_end("Entities")?;
    Ok(physical)
}

/// `$Nodes`: tags and coordinates, in file order; `index` maps tags to positions.
fn nodes(c: &mut Cursor, index: &mut HashMap<u64, usize>) -> Result<Vec<RawNode>, MeshFileError> {
    let blocks = c.count("the number of entity blocks")?;
    let header_at = c.mark();
    let total = c.count("the number of nodes")?;
    c.size("the smallest node tag")?;
    c.size("the largest node tag")?;
    let mut nodes: Vec<RawNode> = Vec::new();
    let mut tags: Vec<(usize, u64)> = Vec::new();
    for _ in 0..blocks {
        let block_at = c.mark();
        let dimension = c.int("the entity dimension of a node block")?;
        if !(0..=3).contains(&dimension) {
            return Err(c.error(
                block_at,
                format!("entity dimension {dimension}: it must be 0, 1, 2 or 3"),
            ));
        }
        c.int("the entity tag of a node block")?;
        let parametric_at = c.mark();
        let parametric = match c.int("the parametric flag of a node block")? {
            0 => 0,
            1 => dimension as usize,
            other => {
                return Err(c.error(
                    parametric_at,
                    format!("parametric flag {other}: it must be 0 or 1"),
                ))
            }
        };
        let count_at = c.mark();
        let n = c.count("the number of nodes in the block")?;
        if n > total - nodes.len() {
            return Err(c.error(
                count_at,
                format!(
                    "the node blocks hold more nodes than the {total} the section's header says"
                ),
            ));
        }
        tags.clear();
        tags.reserve(c.capacity(n, c.number_bytes(8)));
        for _ in 0..n {
            let at = c.mark();
            tags.push((at, c.size("a node tag")?));
        }
        nodes.reserve(c.capacity(n, 3 * c.number_bytes(8)));
        for &(tag_at, tag) in &tags {
            let at = c.mark();
            let x = c.double("the x coordinate of a node")?;
            let y = c.double("the y coordinate of a node")?;
            let z = c.double("the z coordinate of a node")?;
            for _ in 0..parametric {
                c.double("a parametric coordinate of a node")?;
            }
            if ![x, y, z].iter().all(|v| v.is_finite()) {
                return Err(c.error(
                    at,
                    format!("node {tag} has a non-finite coordinate ({x}, {y}, {z})"),
                ));
            }
            if index.insert(tag, nodes.len()).is_some() {
                return Err(c.error(tag_at, format!("node tag {tag} appears twice")));
            }
            nodes.push(RawNode {
                tag,
                x: Vector3::new(x, y, z),
                at,
            });
        }
    }
    if nodes.len() != total {
        return Err(c.error(
            header_at,
            format!(
                "the section's header says {total} nodes, its blocks hold {}",
                nodes.len()
            ),
        ));
    }
    c.expect_end("Nodes")?;
    Ok(nodes)
}

/// `$Elements`: triangles, quadrangles, lines and points kept, volumes counted, other types
/// refused.
fn elements(
    c: &mut Cursor,
    node_index: &HashMap<u64, usize>,
    raw: &mut RawFile,
) -> Result<(), MeshFileError> {
    let blocks = c.count("the number of entity blocks")?;
    let header_at = c.mark();
    let total = c.count("the number of elements")?;
    c.size("the smallest element tag")?;
    c.size("the largest element tag")?;
    let mut read = 0usize;
    let mut element_nodes = Vec::new();
    for _ in 0..blocks {
        let block_at = c.mark();
        let dimension = c.int("the entity dimension of an element block")?;
        let entity = c.int("the entity tag of an element block")?;
        let type_at = c.mark();
        let element = c.int("the element type of an element block")?;
        let (kind, per_element, type_dimension) = element_type(element).ok_or_else(|| {
            let name = element_type_name(element)
                .map(|n| format!(" ({n})"))
                .unwrap_or_default();
            c.error(
                type_at,
                format!("element type {element}{name} is not supported: {SUPPORTED}"),
            )
        })?;
        if dimension != type_dimension {
            return Err(c.error(
                block_at,
                format!(
                    "an element block of an entity of dimension {dimension} holds elements of \
                     type {element}, which are of dimension {type_dimension}"
                ),
            ));
        }
        let count_at = c.mark();
        let n = c.count("the number of elements in the block")?;
        if n > total - read {
            return Err(c.error(
                count_at,
                format!(
                    "the element blocks hold more elements than the {total} the section's \
                     header says"
                ),
            ));
        }
        if kind != Kind::Volume {
            let room = c.capacity(n, (1 + per_element) * c.number_bytes(8));
            raw.elements.reserve(room);
        }
        for _ in 0..n {
            let at = c.mark();
            let tag = c.size("an element tag")?;
            element_nodes.clear();
            for _ in 0..per_element {
                let node_at = c.mark();
                let node = c.size("a node tag of an element")?;
                let &i = node_index.get(&node).ok_or_else(|| {
                    c.error(
                        node_at,
                        format!("element {tag} refers to node {node}, which $Nodes does not list"),
                    )
                })?;
                element_nodes.push(i);
            }
            if kind == Kind::Volume {
                *raw.volumes.entry(element).or_default() += 1;
            } else {
                let mut nodes = [0usize; 4];
                nodes[..per_element].copy_from_slice(&element_nodes);
                raw.elements.push(RawElement {
                    tag,
                    kind,
                    entity: (dimension, entity),
                    nodes,
                    at,
                });
            }
        }
        read += n;
    }
    if read != total {
        return Err(c.error(
            header_at,
            format!("the section's header says {total} elements, its blocks hold {read}"),
        ));
    }
    c.expect_end("Elements")
}

// ---------------------------------------------------------------------------------------------
// Reading: from the file's contents to the mesh.

/// What a physical group of the file holds.
#[derive(Default)]
struct Members {
    /// Cells (surface groups).
    elements: Vec<usize>,
    /// Nodes, renumbered.
    nodes: Vec<usize>,
    /// Nodes of its elements that lie on no triangle or quadrangle.
    off_sheet: usize,
}

/// One physical group of the file.
struct Group {
    dimension: i32,
    tag: i32,
    name: String,
    members: Members,
}

fn dimension_word(dimension: i32) -> &'static str {
    match dimension {
        0 => "point",
        1 => "curve",
        2 => "surface",
        _ => "volume",
    }
}

impl RawFile {
    fn into_import(mut self, file: &str, lines: &Lines) -> Result<MeshImport, MeshFileError> {
        let mut notes = std::mem::take(&mut self.notes);
        // cells from the surface elements, in file order
        let mut cells: Vec<Cell> = Vec::new();
        let mut cell_element: Vec<usize> = Vec::new();
        for (e, element) in self.elements.iter().enumerate() {
            let [a, b, c, d] = element.nodes;
            match element.kind {
                Kind::Triangle => cells.push(Cell::Triangle([a, b, c])),
                Kind::Quadrangle => cells.push(Cell::Quad([a, b, c, d])),
                Kind::Line | Kind::Point | Kind::Volume => continue,
            }
            cell_element.push(e);
        }
        let volumes: usize = self.volumes.values().sum();
        if cells.is_empty() {
            let other = self
                .elements
                .iter()
                .filter(|e| matches!(e.kind, Kind::Line | Kind::Point))
                .count();
            return Err(MeshFileError::in_file(
                file,
                format!(
                    "the file has no triangles (type 2) or quadrangles (type 3) to make a sheet \
                     of ({other} lines and points, {volumes} volume elements)"
                ),
            ));
        }
        if volumes > 0 {
            let types = self
                .volumes
                .iter()
                .map(|(t, n)| format!("{n} of type {t}"))
                .collect::<Vec<_>>()
                .join(", ");
            notes.push(format!(
                "{volumes} volume elements skipped ({types}): the sheet is the surface elements"
            ));
        }
        // the nodes the cells use, renumbered in file order
        let mut new_index: Vec<Option<usize>> = vec![None; self.nodes.len()];
        for &n in cells.iter().flat_map(Cell::nodes) {
            new_index[n] = Some(0);
        }
        let mut nodes = Vec::new();
        let mut file_node = Vec::new(); // new index -> position in the file
        let mut dropped = Vec::new();
        for (i, slot) in new_index.iter_mut().enumerate() {
            if slot.is_some() {
                *slot = Some(nodes.len());
                nodes.push(self.nodes[i].x);
                file_node.push(i);
            } else {
                dropped.push(self.nodes[i].tag);
            }
        }
        if !dropped.is_empty() {
            let first = dropped
                .iter()
                .take(5)
                .map(|t| t.to_string())
                .collect::<Vec<_>>()
                .join(", ");
            let more = if dropped.len() > 5 { ", ..." } else { "" };
            notes.push(format!(
                "{} nodes used by no triangle or quadrangle left out (tags {first}{more})",
                dropped.len()
            ));
        }
        let renumber = |i: usize| new_index[i].unwrap_or(usize::MAX);
        let cells: Vec<Cell> = cells.iter().map(|c| c.map(renumber)).collect();

        // physical groups
        let entities = self.entities.take();
        if entities.is_none() && !self.names.is_empty() {
            notes.push(
                "$PhysicalNames without $Entities: the groups' elements are unknown, no sets"
                    .to_string(),
            );
        }
        let mut unknown_entities = BTreeSet::new();
        let groups_of = |element: &RawElement, unknown: &mut BTreeSet<(i32, i32)>| -> Vec<i32> {
            match &entities {
                None => Vec::new(),
                Some(map) => match map.get(&element.entity) {
                    Some(tags) => tags.iter().map(|t| t.wrapping_abs()).collect(),
                    None => {
                        unknown.insert(element.entity);
                        Vec::new()
                    }
                },
            }
        };
        let name_of = |dimension: i32, tag: i32| {
            self.names
                .get(&(dimension, tag))
                .cloned()
                .unwrap_or_else(|| format!("physical {tag}"))
        };
        // (dimension, tag) -> element members (cells) and node members (new indices)
        let mut members: BTreeMap<(i32, i32), Members> = BTreeMap::new();
        for (t, &e) in cell_element.iter().enumerate() {
            for tag in groups_of(&self.elements[e], &mut unknown_entities) {
                let entry = members.entry((2, tag)).or_default();
                entry.elements.push(t);
                entry.nodes.extend_from_slice(cells[t].nodes());
            }
        }
        for element in &self.elements {
            if !matches!(element.kind, Kind::Line | Kind::Point) {
                continue;
            }
            for tag in groups_of(element, &mut unknown_entities) {
                let entry = members.entry((element.entity.0, tag)).or_default();
                for &n in element.nodes() {
                    match new_index[n] {
                        Some(i) => entry.nodes.push(i),
                        None => entry.off_sheet += 1,
                    }
                }
            }
        }
        if !unknown_entities.is_empty() {
            let list = unknown_entities
                .iter()
                .map(|(d, t)| format!("{} {t}", dimension_word(*d)))
                .collect::<Vec<_>>()
                .join(", ");
            notes.push(format!(
                "elements of entities that $Entities does not list belong to no physical group: \
                 {list}"
            ));
        }
        for &(dimension, tag) in self.names.keys() {
            if dimension < 3 && !members.contains_key(&(dimension, tag)) {
                notes.push(format!(
                    "physical {} group '{}' ({tag}) has no elements in the file: no set",
                    dimension_word(dimension),
                    name_of(dimension, tag)
                ));
            }
        }
        // by name
        let mut by_name: BTreeMap<String, Vec<Group>> = BTreeMap::new();
        for ((dimension, tag), members) in members {
            let name = name_of(dimension, tag);
            by_name.entry(name.clone()).or_default().push(Group {
                dimension,
                tag,
                name,
                members,
            });
        }
        let sorted = |mut v: Vec<usize>| {
            v.sort_unstable();
            v.dedup();
            v
        };
        let describe = |list: &[&Group]| {
            list.iter()
                .map(|g| format!("{} {}", dimension_word(g.dimension), g.tag))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut element_sets = BTreeMap::new();
        let mut node_sets = BTreeMap::new();
        for (name, groups) in &by_name {
            let surfaces: Vec<&Group> = groups.iter().filter(|g| g.dimension == 2).collect();
            let lower: Vec<&Group> = groups.iter().filter(|g| g.dimension < 2).collect();
            if !surfaces.is_empty() {
                let elements = surfaces
                    .iter()
                    .flat_map(|g| g.members.elements.iter().copied());
                element_sets.insert(name.clone(), sorted(elements.collect()));
            }
            // curve and point groups say which nodes; a surface group alone gives its elements'
            let node_groups = if lower.is_empty() { &surfaces } else { &lower };
            let mut set = Vec::new();
            for g in node_groups {
                set.extend(g.members.nodes.iter().copied());
                if g.members.off_sheet > 0 {
                    notes.push(format!(
                        "physical {} group '{}': {} of its element nodes lie on no triangle or \
                         quadrangle and are left out of the node set",
                        dimension_word(g.dimension),
                        g.name,
                        g.members.off_sheet
                    ));
                }
            }
            let set = sorted(set);
            if groups.len() > 1 {
                let rule = if surfaces.is_empty() || lower.is_empty() {
                    format!("the sets are their union ({})", describe(node_groups))
                } else {
                    format!(
                        "the element set is the surface groups' ({}), the node set the curve \
                         and point groups' ({}) alone",
                        describe(&surfaces),
                        describe(&lower)
                    )
                };
                notes.push(format!(
                    "{} physical groups are named '{name}': {rule}",
                    groups.len()
                ));
            }
            if set.is_empty() {
                notes.push(format!(
                    "no node set '{name}': none of its nodes lies on a triangle or quadrangle"
                ));
            } else {
                node_sets.insert(name.clone(), set);
            }
        }

        if let Some(note) = orientation_note(
            &cells,
            |t| self.elements[cell_element[t]].tag,
            |n| self.nodes[file_node[n]].tag,
        ) {
            notes.push(note);
        }

        let rigid = vec![false; cells.len()];
        let place = |label: u64, at: usize| Place {
            label,
            file: 0,
            at: lines.at(at),
        };
        let origin = Origin {
            files: vec![file.to_string()],
            nodes: file_node
                .iter()
                .map(|&i| place(self.nodes[i].tag, self.nodes[i].at))
                .collect(),
            cells: cell_element
                .iter()
                .map(|&e| place(self.elements[e].tag, self.elements[e].at))
                .collect(),
        };
        let mesh = Mesh {
            nodes,
            cells,
            node_sets,
            element_sets,
            warp_directions: None,
        };
        check_elements(&mesh).map_err(|d| origin.defect(&d))?;
        mesh.validate().map_err(|e| origin.mesh_error(&e))?;
        Ok(MeshImport {
            mesh,
            rigid,
            notes,
            origin,
        })
    }
}

/// The line of a place in the text of a file, or its byte in binary data.
struct Lines {
    /// Offsets of the line ends in the text.
    ends: Vec<usize>,
    text_end: usize,
}

impl Lines {
    fn new(bytes: &[u8], text_end: usize) -> Self {
        let ends = (0..text_end).filter(|&i| bytes[i] == b'\n').collect();
        Self { ends, text_end }
    }

    /// As [`Cursor::error`] counts: one more than the line ends before `at`.
    fn at(&self, at: usize) -> At {
        if at < self.text_end {
            At::Line(1 + self.ends.partition_point(|&end| end < at))
        } else {
            At::Byte(at)
        }
    }
}

/// A note when the cells are not consistently oriented (an edge run twice the same way) or an
/// edge is shared by more than two cells; `element` gives the Gmsh tag of a cell, `node` the
/// Gmsh tag of a node.
fn orientation_note(
    cells: &[Cell],
    element: impl Fn(usize) -> u64,
    node: impl Fn(usize) -> u64,
) -> Option<String> {
    // undirected edge -> (first cell, its direction a < b, uses)
    let mut edges: HashMap<(usize, usize), (usize, bool, usize)> = HashMap::new();
    let mut first: Option<String> = None;
    let mut inconsistent = 0usize;
    let mut shared = 0usize;
    for (t, cell) in cells.iter().enumerate() {
        for (a, b) in cell.edges() {
            let key = (a.min(b), a.max(b));
            let forward = a < b;
            let entry = edges.entry(key).or_insert((t, forward, 0));
            entry.2 += 1;
            let problem = if entry.2 == 3 {
                shared += 1;
                Some("is shared by more than two elements")
            } else if entry.2 == 2 && entry.0 != t && entry.1 == forward {
                inconsistent += 1;
                Some("runs the same way in both elements on it")
            } else {
                None
            };
            if let (Some(problem), None) = (problem, &first) {
                first = Some(format!(
                    "element {} and element {}: their edge from node {} to node {} {problem}",
                    element(entry.0),
                    element(t),
                    node(a),
                    node(b)
                ));
            }
        }
    }
    first.map(|first| {
        format!(
            "the elements are not consistently oriented ({inconsistent} edges run the same \
             way in both their elements, {shared} are shared by more than two): first at \
             {first}; Gmsh orients each surface by its geometry, so surfaces meeting at an \
             edge may disagree"
        )
    })
}

// ---------------------------------------------------------------------------------------------
// Writing.

/// The shortest text that reads back to the same `f64`.
fn number(x: f64) -> String {
    format!("{x:?}")
}

fn msh_text(mesh: &Mesh) -> String {
    let mut s = String::new();
    let triangle_count = mesh.cells.len();
    // surface entities: one per distinct combination of element sets
    let element_names: Vec<&String> = mesh.element_sets.keys().collect();
    let mut membership: Vec<Vec<usize>> = vec![Vec::new(); triangle_count];
    for (k, members) in mesh.element_sets.values().enumerate() {
        for &t in members {
            if membership[t].last() != Some(&k) {
                membership[t].push(k);
            }
        }
    }
    for m in &mut membership {
        m.sort_unstable();
        m.dedup();
    }
    let mut signatures: Vec<&Vec<usize>> = Vec::new();
    let mut entity_of: HashMap<&Vec<usize>, usize> = HashMap::new();
    let triangle_entity: Vec<usize> = membership
        .iter()
        .map(|m| {
            *entity_of.entry(m).or_insert_with(|| {
                signatures.push(m);
                signatures.len()
            })
        })
        .collect();
    // node sets written as point groups: not those the reader rebuilds from a surface group
    let written_node_sets: Vec<(&String, &Vec<usize>)> = mesh
        .node_sets
        .iter()
        .filter(|(name, members)| {
            let Some(elements) = mesh.element_sets.get(*name) else {
                return true;
            };
            let mut derived: Vec<usize> = elements
                .iter()
                .flat_map(|&t| mesh.cells[t].nodes().to_vec())
                .collect();
            derived.sort_unstable();
            derived.dedup();
            derived != **members
        })
        .collect();
    let points: Vec<(usize, &Vec<usize>)> = written_node_sets
        .iter()
        .enumerate()
        .filter(|(_, (_, members))| !members.is_empty())
        .map(|(j, (_, members))| (j + 1, *members))
        .collect();

    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    let names = written_node_sets.len() + element_names.len();
    if names > 0 {
        let _ = writeln!(s, "$PhysicalNames\n{names}");
        for (j, (name, _)) in written_node_sets.iter().enumerate() {
            let _ = writeln!(s, "0 {} \"{name}\"", j + 1);
        }
        for (k, name) in element_names.iter().enumerate() {
            let _ = writeln!(s, "2 {} \"{name}\"", k + 1);
        }
        s.push_str("$EndPhysicalNames\n");
    }

    let _ = writeln!(s, "$Entities\n{} 0 {} 0", points.len(), signatures.len());
    for (tag, members) in &points {
        let x = mesh.nodes[members[0]];
        let _ = writeln!(
            s,
            "{tag} {} {} {} 1 {tag}",
            number(x.x),
            number(x.y),
            number(x.z)
        );
    }
    let mut boxes = vec![
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY)
        );
        signatures.len()
    ];
    for (t, &e) in triangle_entity.iter().enumerate() {
        let (lo, hi) = &mut boxes[e - 1];
        for &n in mesh.cells[t].nodes() {
            *lo = lo.inf(&mesh.nodes[n]);
            *hi = hi.sup(&mesh.nodes[n]);
        }
    }
    for (e, (signature, (lo, hi))) in signatures.iter().zip(&boxes).enumerate() {
        let _ = write!(
            s,
            "{} {} {} {} {} {} {} {}",
            e + 1,
            number(lo.x),
            number(lo.y),
            number(lo.z),
            number(hi.x),
            number(hi.y),
            number(hi.z),
            signature.len()
        );
        for k in signature.iter() {
            let _ = write!(s, " {}", k + 1);
        }
        s.push_str(" 0\n");
    }
    s.push_str("$EndEntities\n");

    let n = mesh.nodes.len();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n2 1 0 {n}");
    for i in 1..=n {
        let _ = writeln!(s, "{i}");
    }
    for x in &mesh.nodes {
        let _ = writeln!(s, "{} {} {}", number(x.x), number(x.y), number(x.z));
    }
    s.push_str("$EndNodes\n");

    // runs of consecutive cells of one kind on the same entity, then the point groups
    let mut runs: Vec<(usize, usize)> = Vec::new(); // (entity, first cell)
    for (t, &e) in triangle_entity.iter().enumerate() {
        let same_kind = |r: &(usize, usize)| mesh.cells[r.1].is_quad() == mesh.cells[t].is_quad();
        if runs.last().map(|r| r.0) != Some(e) || !runs.last().is_some_and(same_kind) {
            runs.push((e, t));
        }
    }
    let point_elements: usize = points.iter().map(|(_, m)| m.len()).sum();
    let total = triangle_count + point_elements;
    let _ = writeln!(
        s,
        "$Elements\n{} {total} 1 {total}",
        runs.len() + points.len()
    );
    for (r, &(entity, start)) in runs.iter().enumerate() {
        let end = runs.get(r + 1).map_or(triangle_count, |next| next.1);
        // Gmsh element types: 2 the 3-node triangle, 3 the 4-node quadrangle
        let kind = if mesh.cells[start].is_quad() { 3 } else { 2 };
        let _ = writeln!(s, "2 {entity} {kind} {}", end - start);
        for t in start..end {
            let labels: Vec<String> = mesh.cells[t]
                .nodes()
                .iter()
                .map(|n| (n + 1).to_string())
                .collect();
            let _ = writeln!(s, "{} {}", t + 1, labels.join(" "));
        }
    }
    let mut tag = triangle_count;
    for (entity, members) in &points {
        let _ = writeln!(s, "0 {entity} 15 {}", members.len());
        for &node in members.iter() {
            tag += 1;
            let _ = writeln!(s, "{tag} {}", node + 1);
        }
    }
    s.push_str("$EndElements\n");
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_orientation_check_names_the_first_element_against_its_neighbour() {
        let triangles = |list: &[[usize; 3]]| list.iter().map(|&t| Cell::Triangle(t)).collect();
        // a square of two triangles, the second flipped
        let good: Vec<Cell> = triangles(&[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(
            orientation_note(&good, |t| t as u64 + 10, |n| n as u64 + 100),
            None
        );
        let bad: Vec<Cell> = triangles(&[[0, 1, 2], [0, 3, 2]]);
        let note = orientation_note(&bad, |t| t as u64 + 10, |n| n as u64 + 100).unwrap();
        assert!(note.contains("element 10 and element 11"), "{note}");
        assert!(note.contains("node 102 to node 100"), "{note}");
        // three triangles on one edge
        let fan: Vec<Cell> = triangles(&[[0, 1, 2], [1, 0, 3], [1, 0, 4]]);
        let note = orientation_note(&fan, |t| t as u64 + 1, |n| n as u64 + 1).unwrap();
        assert!(note.contains("more than two"), "{note}");
    }

    #[test]
    fn the_orientation_check_runs_round_every_edge_of_a_quadrangle() {
        // two quadrangles side by side on the edge 1-4, and a triangle on the edge 4-5
        let good = [
            Cell::Quad([0, 1, 4, 3]),
            Cell::Quad([1, 2, 5, 4]),
            Cell::Triangle([4, 5, 6]),
        ];
        assert_eq!(
            orientation_note(&good, |t| t as u64 + 1, |n| n as u64),
            None
        );
        // the second quadrangle numbered the other way round
        let bad = [Cell::Quad([0, 1, 4, 3]), Cell::Quad([1, 4, 5, 2])];
        let note = orientation_note(&bad, |t| t as u64 + 1, |n| n as u64).unwrap();
        assert!(note.contains("element 1 and element 2"), "{note}");
        assert!(note.contains("node 1 to node 4"), "{note}");
        // a triangle on the quadrangle's edge from 5 to 4 running it the same way
        let same = [Cell::Quad([1, 2, 5, 4]), Cell::Triangle([5, 4, 6])];
        let note = orientation_note(&same, |t| t as u64 + 1, |n| n as u64).unwrap();
        assert!(note.contains("node 5 to node 4"), "{note}");
    }

    #[test]
    fn numbers_are_written_to_read_back_bit_for_bit() {
        for x in [
            0.1,
            -0.0,
            1e-7,
            1.0 / 3.0,
            123_456_789.123_456_79,
            1e300,
            -2.5e-310,
            80.0,
        ] {
            let text = number(x);
            let back: f64 = text.parse().unwrap();
            assert_eq!(back.to_bits(), x.to_bits(), "{text}");
        }
    }
}
