//! STL files of rigid tools: read (ASCII or binary) into a [`TriangleSurface`], write binary or
//! ASCII.
//!
//! - **Orientation.** STL orders each facet's corners counter-clockwise seen from outside, which
//!   is the [`TriangleSurface`] convention when "outside" is the blank's side: export tools with
//!   their normals towards the blank. The normal stored in a facet is ignored on reading (many
//!   exporters write zeros) and recomputed from the corners on writing.
//! - **Vertices.** Corners with bit-identical coordinates (after `-0.0 -> 0.0`) are merged into
//!   one vertex, in order of first appearance; no tolerance is applied, so a file whose facets do
//!   not share exact corners stays unwelded rather than being silently distorted.
//! - **Format detection.** A file whose length is exactly `84 + 50 n`, with `n` the facet count
//!   of the binary header, is binary (binary files whose 80-byte header starts with `solid`, as
//!   some exporters write, are therefore read correctly); otherwise a file starting with `solid`
//!   is ASCII; anything else is an error.
//! - **Precision.** Binary STL holds `f32`: writing rounds coordinates to about 7 significant
//!   digits. ASCII is written with the shortest decimal that reads back to the same `f64`, so an
//!   ASCII round trip is exact.
//! - **Robustness.** Reading never panics and allocates at most in proportion to the input:
//!   arbitrary bytes give an [`StlError`].
//!
//! Binary reading and writing use the `stl_io` crate; ASCII is parsed here so that errors can
//! name the line and what was expected there.

use super::surface::TriangleSurface;
use nalgebra::Vector3;
use std::collections::HashMap;
use std::io::Write;
use std::path::Path;

/// Why an STL file could not be read or written. `file` is the path (or the name given to
/// [`parse_stl`]); facet indices are 0-based, in file order.
#[derive(Debug, thiserror::Error)]
pub enum StlError {
    #[error("{file}: {source}")]
    Io {
        file: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: line {line}: expected {expected}, found {found}")]
    Ascii {
        file: String,
        line: usize,
        expected: String,
        found: String,
    },
    #[error("{file}: not a valid binary STL: {reason}")]
    Binary { file: String, reason: String },
    #[error("{file}: facet {facet} has a coordinate that is not a finite number")]
    NonFinite { file: String, facet: usize },
    #[error("{file}: facet {facet} is degenerate: {reason}")]
    Degenerate {
        file: String,
        facet: usize,
        reason: String,
    },
    #[error("{file}: the file holds no facets")]
    Empty { file: String },
    #[error("{file}: cannot write the surface: {reason}")]
    InvalidSurface { file: String, reason: String },
}

/// Size of the binary header (80 bytes of free text and the `u32` facet count).
const BINARY_HEADER: usize = 84;
/// Size of one binary facet: normal and three corners as `f32`, and a `u16` attribute.
const BINARY_FACET: usize = 50;
/// A facet is degenerate when `|(b - a) x (c - a)| <= DEGENERATE_SINE * (longest edge)^2`: its
/// smallest angle is below about `f32::EPSILON` rad, so the facet's normal is rounding noise (at
/// `f32`, the precision of binary STL).
const DEGENERATE_SINE: f64 = f32::EPSILON as f64;
/// Longest excerpt of an offending line quoted in an error.
const QUOTE_CHARS: usize = 40;

/// Reads an STL file, ASCII or binary (see the module documentation for the detection rule).
pub fn read_stl(path: &Path) -> Result<TriangleSurface, StlError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|source| StlError::Io {
        file: file.clone(),
        source,
    })?;
    parse_stl(&bytes, &file)
}

/// Parses the bytes of an STL file; `file` names it in errors.
pub fn parse_stl(bytes: &[u8], file: &str) -> Result<TriangleSurface, StlError> {
    let facets = if is_binary(bytes) {
        binary_facets(bytes, file)?
    } else if bytes.trim_ascii_start().starts_with(b"solid") {
        ascii_facets(bytes, file)?
    } else {
        return Err(binary_error(
            file,
            binary_size_mismatch(bytes)
                + " (and it does not start with `solid`, so it is not ASCII STL either)",
        ));
    };
    surface_from_facets(&facets, file)
}

/// Writes `surface` as binary STL (80-byte zero header, `f32` coordinates).
pub fn write_stl_binary(path: &Path, surface: &TriangleSurface) -> Result<(), StlError> {
    let file = path.display().to_string();
    write_to_file(path, |w| write_binary(w, surface, &file))
}

/// Writes `surface` as ASCII STL with solid name `name` (whitespace and control characters in
/// it are replaced by `_`, since the name must be one token on the `solid` line).
pub fn write_stl_ascii(path: &Path, surface: &TriangleSurface, name: &str) -> Result<(), StlError> {
    let file = path.display().to_string();
    write_to_file(path, |w| write_ascii(w, surface, name, &file))
}

/// Writes `surface` as binary STL to `writer`; `file` names the destination in errors.
pub fn write_binary<W: Write>(
    writer: &mut W,
    surface: &TriangleSurface,
    file: &str,
) -> Result<(), StlError> {
    check_writable(surface, file)?;
    if u32::try_from(surface.triangles.len()).is_err() {
        return Err(StlError::InvalidSurface {
            file: file.to_string(),
            reason: format!(
                "{} triangles do not fit in the u32 count of binary STL",
                surface.triangles.len()
            ),
        });
    }
    let facets = surface.triangles.iter().map(|t| {
        let corners = t.map(|i| surface.vertices[i]);
        stl_io::Triangle {
            normal: stl_io::Normal::new(to_f32(&facet_normal(&corners))),
            vertices: corners.map(|v| stl_io::Vertex::new(to_f32(&v))),
        }
    });
    stl_io::write_stl(writer, facets).map_err(|source| io_error(file, source))
}

/// Writes `surface` as ASCII STL to `writer`; `file` names the destination in errors.
pub fn write_ascii<W: Write>(
    writer: &mut W,
    surface: &TriangleSurface,
    name: &str,
    file: &str,
) -> Result<(), StlError> {
    check_writable(surface, file)?;
    let name = solid_name(name);
    let mut w = std::io::BufWriter::new(writer);
    let result = (|| -> std::io::Result<()> {
        writeln!(w, "solid {name}")?;
        for t in &surface.triangles {
            let corners = t.map(|i| surface.vertices[i]);
            let n = facet_normal(&corners);
            writeln!(w, "  facet normal {:e} {:e} {:e}", n.x, n.y, n.z)?;
            writeln!(w, "    outer loop")?;
            for v in corners {
                writeln!(w, "      vertex {:e} {:e} {:e}", v.x, v.y, v.z)?;
            }
            writeln!(w, "    endloop")?;
            writeln!(w, "  endfacet")?;
        }
        writeln!(w, "endsolid {name}")?;
        w.flush()
    })();
    result.map_err(|source| io_error(file, source))
}

fn write_to_file(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> Result<(), StlError>,
) -> Result<(), StlError> {
    let mut f = std::fs::File::create(path)
        .map_err(|source| io_error(&path.display().to_string(), source))?;
    write(&mut f)
}

fn io_error(file: &str, source: std::io::Error) -> StlError {
    StlError::Io {
        file: file.to_string(),
        source,
    }
}

fn binary_error(file: &str, reason: String) -> StlError {
    StlError::Binary {
        file: file.to_string(),
        reason,
    }
}

/// Triangles must index existing vertices (the fields of a [`TriangleSurface`] are public).
fn check_writable(surface: &TriangleSurface, file: &str) -> Result<(), StlError> {
    let n = surface.vertices.len();
    match surface
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i >= n))
    {
        Some(k) => Err(StlError::InvalidSurface {
            file: file.to_string(),
            reason: format!("triangle {k} refers to a vertex past the {n} vertices"),
        }),
        None => Ok(()),
    }
}

/// Unit normal `(b - a) x (c - a)` of a facet, zero for a degenerate one.
fn facet_normal([a, b, c]: &Facet) -> Vector3<f64> {
    (b - a)
        .cross(&(c - a))
        .try_normalize(0.0)
        .unwrap_or_else(Vector3::zeros)
}

fn to_f32(v: &Vector3<f64>) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn solid_name(name: &str) -> String {
    let name: String = name
        .chars()
        .map(|c| {
            if c.is_whitespace() || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    if name.is_empty() {
        "tool".to_string()
    } else {
        name
    }
}

/// Facet count stated by a binary header, when there is one.
fn binary_count(bytes: &[u8]) -> Option<usize> {
    let count = bytes.get(80..BINARY_HEADER)?;
    Some(u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as usize)
}

/// The binary detection rule: the length is exactly that announced by the header.
fn is_binary(bytes: &[u8]) -> bool {
    binary_count(bytes).is_some_and(|n| {
        n.checked_mul(BINARY_FACET)
            .and_then(|body| body.checked_add(BINARY_HEADER))
            == Some(bytes.len())
    })
}

fn binary_size_mismatch(bytes: &[u8]) -> String {
    match binary_count(bytes) {
        None => format!(
            "{} bytes is shorter than the {BINARY_HEADER}-byte header",
            bytes.len()
        ),
        Some(n) => format!(
            "the header announces {n} facets, i.e. {} bytes, but the file has {}",
            BINARY_HEADER as u128 + BINARY_FACET as u128 * n as u128,
            bytes.len()
        ),
    }
}

/// Corners of the facets of a binary STL whose size has been checked by [`is_binary`].
fn binary_facets(bytes: &[u8], file: &str) -> Result<Vec<Facet>, StlError> {
    // stl_io takes a header starting with "solid " for ASCII: blank it, since the size already
    // says the file is binary.
    let mut data = bytes.to_vec();
    data[..80].fill(0);
    let mut cursor = std::io::Cursor::new(data);
    let reader =
        stl_io::create_stl_reader(&mut cursor).map_err(|e| binary_error(file, e.to_string()))?;
    let mut facets = Vec::new();
    for (facet, triangle) in reader.enumerate() {
        let triangle = triangle.map_err(|e| binary_error(file, format!("facet {facet}: {e}")))?;
        let corners = triangle
            .vertices
            .map(|v| Vector3::new(v[0] as f64, v[1] as f64, v[2] as f64));
        if corners.iter().any(|c| !c.iter().all(|x| x.is_finite())) {
            return Err(StlError::NonFinite {
                file: file.to_string(),
                facet,
            });
        }
        facets.push(corners);
    }
    Ok(facets)
}

/// The lines of a file (split at `\n`) with their 0-based indices.
type NumberedLines<'a> = std::iter::Enumerate<std::slice::Split<'a, u8, fn(&u8) -> bool>>;

/// The corners of one facet, counter-clockwise seen from the blank.
type Facet = [Vector3<f64>; 3];

/// The non-blank lines of an ASCII STL, split into tokens, with 1-based line numbers.
struct Statements<'a> {
    lines: NumberedLines<'a>,
    file: &'a str,
}

/// One non-blank line: its number, its tokens, and its text (for error messages).
struct Statement<'a> {
    line: usize,
    tokens: Vec<&'a str>,
    text: &'a str,
}

impl<'a> Statements<'a> {
    fn new(bytes: &'a [u8], file: &'a str) -> Self {
        let newline: fn(&u8) -> bool = |b| *b == b'\n';
        Statements {
            lines: bytes.split(newline).enumerate(),
            file,
        }
    }

    /// Next non-blank line, `None` at the end of the file.
    fn next(&mut self) -> Result<Option<Statement<'a>>, StlError> {
        for (i, raw) in self.lines.by_ref() {
            let text = std::str::from_utf8(raw).map_err(|_| StlError::Ascii {
                file: self.file.to_string(),
                line: i + 1,
                expected: "UTF-8 text".to_string(),
                found: "bytes that are not UTF-8".to_string(),
            })?;
            let tokens: Vec<&str> = text.split_whitespace().collect();
            if !tokens.is_empty() {
                return Ok(Some(Statement {
                    line: i + 1,
                    tokens,
                    text: text.trim(),
                }));
            }
        }
        Ok(None)
    }

    /// Next non-blank line, which must exist: at the end of the file, an error saying that
    /// `expected` was expected.
    fn expect_some(&mut self, expected: &str, last_line: usize) -> Result<Statement<'a>, StlError> {
        self.next()?.ok_or_else(|| StlError::Ascii {
            file: self.file.to_string(),
            line: last_line + 1,
            expected: expected.to_string(),
            found: "the end of the file".to_string(),
        })
    }

    /// Next line, which must consist of exactly the keywords `words`.
    fn expect_keywords(&mut self, words: &[&str], last_line: usize) -> Result<usize, StlError> {
        let expected = format!("`{}`", words.join(" "));
        let s = self.expect_some(&expected, last_line)?;
        if s.tokens != words {
            return Err(self.unexpected(&s, &expected));
        }
        Ok(s.line)
    }

    fn unexpected(&self, s: &Statement, expected: &str) -> StlError {
        StlError::Ascii {
            file: self.file.to_string(),
            line: s.line,
            expected: expected.to_string(),
            found: quote(s.text),
        }
    }
}

/// `text` in backquotes, cut to [`QUOTE_CHARS`] characters.
fn quote(text: &str) -> String {
    match text.char_indices().nth(QUOTE_CHARS) {
        Some((cut, _)) => format!("`{}...`", &text[..cut]),
        None => format!("`{text}`"),
    }
}

/// Corners of the facets of an ASCII STL:
///
/// ```text
/// solid [name]
///   facet normal ni nj nk      (repeated)
///     outer loop
///       vertex x y z           (three times)
///     endloop
///   endfacet
/// endsolid [name]
/// ```
///
/// Several solids may follow each other; their facets are put together.
fn ascii_facets(bytes: &[u8], file: &str) -> Result<Vec<Facet>, StlError> {
    let mut lines = Statements::new(bytes, file);
    let mut facets = Vec::new();
    let mut statement = lines.expect_some("`solid`", 0)?;
    loop {
        if statement.tokens[0] != "solid" {
            return Err(lines.unexpected(&statement, "`solid` or the end of the file"));
        }
        ascii_solid(&mut lines, statement.line, &mut facets)?;
        match lines.next()? {
            None => return Ok(facets),
            Some(next) => statement = next,
        }
    }
}

/// The facets of one solid, after its `solid` line `start`, up to and including `endsolid`.
fn ascii_solid(
    lines: &mut Statements,
    start: usize,
    facets: &mut Vec<Facet>,
) -> Result<(), StlError> {
    const EXPECTED: &str = "`facet normal` or `endsolid`";
    let mut last = start;
    loop {
        let s = lines.expect_some(EXPECTED, last)?;
        match s.tokens[0] {
            "endsolid" => return Ok(()),
            "facet" => {
                let (corners, end) = ascii_facet(lines, &s)?;
                facets.push(corners);
                last = end;
            }
            _ => return Err(lines.unexpected(&s, EXPECTED)),
        }
    }
}

/// One facet, from its `facet normal` line `header` to `endfacet`; returns the corners and the
/// number of the `endfacet` line. The stated normal must be three numbers but is not used.
fn ascii_facet(lines: &mut Statements, header: &Statement) -> Result<(Facet, usize), StlError> {
    const HEADER: &str = "`facet normal ni nj nk` with three numbers";
    let t = &header.tokens;
    if t.len() != 5 || t[1] != "normal" || t[2..].iter().any(|x| x.parse::<f64>().is_err()) {
        return Err(lines.unexpected(header, HEADER));
    }
    let mut last = lines.expect_keywords(&["outer", "loop"], header.line)?;
    let mut corners = [Vector3::zeros(); 3];
    for corner in &mut corners {
        const VERTEX: &str = "`vertex x y z` with three finite numbers";
        let s = lines.expect_some(VERTEX, last)?;
        *corner = parse_vertex(&s.tokens).ok_or_else(|| lines.unexpected(&s, VERTEX))?;
        last = s.line;
    }
    let last = lines.expect_keywords(&["endloop"], last)?;
    let last = lines.expect_keywords(&["endfacet"], last)?;
    Ok((corners, last))
}

fn parse_vertex(tokens: &[&str]) -> Option<Vector3<f64>> {
    if tokens.len() != 4 || tokens[0] != "vertex" {
        return None;
    }
    let mut v = Vector3::zeros();
    for (c, token) in v.iter_mut().zip(&tokens[1..]) {
        *c = token.parse::<f64>().ok().filter(|x| x.is_finite())?;
    }
    Some(v)
}

/// Merges bit-identical corners into vertices and checks that no facet is degenerate.
fn surface_from_facets(facets: &[Facet], file: &str) -> Result<TriangleSurface, StlError> {
    if facets.is_empty() {
        return Err(StlError::Empty {
            file: file.to_string(),
        });
    }
    let mut index_of: HashMap<[u64; 3], usize> = HashMap::new();
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(facets.len());
    for (facet, corners) in facets.iter().enumerate() {
        check_facet(corners).map_err(|reason| StlError::Degenerate {
            file: file.to_string(),
            facet,
            reason,
        })?;
        let triangle = corners.map(|c| {
            // Adding 0.0 turns -0.0 into 0.0, so both signs of zero merge.
            let key = [c.x + 0.0, c.y + 0.0, c.z + 0.0].map(f64::to_bits);
            *index_of.entry(key).or_insert_with(|| {
                vertices.push(c);
                vertices.len() - 1
            })
        });
        triangles.push(triangle);
    }
    Ok(TriangleSurface {
        vertices,
        triangles,
    })
}

/// Why a facet is degenerate: coincident corners, or corners (nearly) on one line.
fn check_facet([a, b, c]: &Facet) -> Result<(), String> {
    for (i, j, p, q) in [(0, 1, a, b), (1, 2, b, c), (2, 0, c, a)] {
        if p == q {
            return Err(format!("corners {i} and {j} coincide"));
        }
    }
    let longest = [
        (b - a).norm_squared(),
        (c - b).norm_squared(),
        (a - c).norm_squared(),
    ]
    .into_iter()
    .fold(0.0, f64::max);
    if (b - a).cross(&(c - a)).norm() <= DEGENERATE_SINE * longest {
        return Err("its corners lie on one line (zero area)".to_string());
    }
    Ok(())
}
