//! What the mesh-file readers (Gmsh, Abaqus) give back, how they fail, and how a blank read
//! from a file is checked to be one sheet.

use super::conformity::{self, Defect, Item, Naming};
use super::{six_digits, Mesh, MeshError, FOLDED};
use std::path::Path;

/// A mesh read from a file: one cell per triangle or quadrilateral of the file, the sets, and
/// what the reader noticed on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshImport {
    pub mesh: Mesh,
    /// Per cell, whether it is a rigid element (Abaqus `R3D3`/`R3D4`): such cells can describe
    /// a tool, never the blank.
    pub rigid: Vec<bool>,
    /// Things the user should know, one line each: keywords or element types that were read
    /// but not used, nodes dropped, ...
    pub notes: Vec<String>,
    /// Where each node and cell is written in the file, for messages about them.
    pub origin: Origin,
}

impl MeshImport {
    /// The import of the element set `name` alone ([`Mesh::restricted_to`]), with the places of
    /// its nodes and cells.
    pub fn restricted_to(&self, name: &str) -> Result<MeshImport, MeshError> {
        let (mesh, kept) = self.mesh.restricted_to(name)?;
        let origin = self.origin.restricted(&self.mesh, &mesh, &kept);
        Ok(MeshImport {
            rigid: kept.iter().map(|&t| self.rigid[t]).collect(),
            mesh,
            notes: self.notes.clone(),
            origin,
        })
    }

    /// The mesh as a blank: no rigid element, and one sheet ([`conformity::check`]), its cells
    /// numbered against their neighbours turned round. Also returns the reader's notes, and
    /// what was turned and the pieces where there is more than one.
    pub fn into_blank(self) -> Result<(Mesh, Vec<String>), MeshFileError> {
        let MeshImport {
            mut mesh,
            rigid,
            mut notes,
            origin,
        } = self;
        if let Some(t) = rigid.iter().position(|&r| r) {
            return Err(origin.error_at(
                Item::Cell(t),
                "is a rigid element (R3D3/R3D4): a blank is made of shell or membrane elements \
                 (name the blank's elements with blank.element_set, or read rigid elements as a \
                 tool)",
            ));
        }
        let sheet = conformity::check(&mesh).map_err(|d| origin.defect(&d))?;
        // the notes are printed after the name of the file read first
        let names = origin.names(Some(0));
        if !sheet.turned.is_empty() {
            notes.push(format!(
                "{} of {} elements were numbered against their neighbours and were turned round \
                 to agree with them (first: {}): every shared edge now runs once each way, the \
                 numbering kept being that of most of the area",
                sheet.turned.len(),
                mesh.cells.len(),
                first_few(sheet.turned.iter().map(|&t| names.name_at(Item::Cell(t))))
            ));
        }
        if sheet.pieces.len() > 1 {
            notes.push(format!(
                "the blank is {} pieces that share no edge, each formed on its own: {}",
                sheet.pieces.len(),
                first_few(sheet.pieces.iter().map(|p| {
                    let first = names.name_at(Item::Cell(p.first));
                    match p.cells {
                        1 => format!("{first} alone"),
                        n => format!("{first} and {} more", n - 1),
                    }
                }))
            ));
        }
        sheet.orient(&mut mesh);
        Ok((mesh, notes))
    }
}

/// Up to five items, and "..." for more.
fn first_few(items: impl ExactSizeIterator<Item = String>) -> String {
    let more = if items.len() > 5 { "; ..." } else { "" };
    format!("{}{more}", items.take(5).collect::<Vec<_>>().join("; "))
}

/// Where a node or an element is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum At {
    Line(usize),
    /// In binary data (Gmsh): the byte's offset in the file.
    Byte(usize),
}

/// One node or element of a file: its label and where it is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    /// The file's label for it (Gmsh tag, Abaqus label).
    pub label: u64,
    /// Its file: an index into [`Origin::files`] (an Abaqus deck includes others).
    pub file: usize,
    pub at: At,
}

/// Where the nodes and cells of a mesh read from a file are written, so that a fault found
/// after reading is reported as the readers report theirs: the file, the line, the label.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Origin {
    /// The files, the one read first.
    pub files: Vec<String>,
    /// Per node of the mesh.
    pub nodes: Vec<Place>,
    /// Per cell of the mesh.
    pub cells: Vec<Place>,
}

/// Names of an origin's items, places given relative to the file of `here`.
struct Names<'a> {
    origin: &'a Origin,
    here: Option<usize>,
}

impl Naming for Names<'_> {
    fn name(&self, item: Item) -> String {
        match (item, self.origin.place(item)) {
            (Item::Node(_), Some(p)) => format!("node {}", p.label),
            (Item::Cell(_), Some(p)) => format!("element {}", p.label),
            (_, None) => conformity::ByIndex.name(item),
        }
    }

    fn name_at(&self, item: Item) -> String {
        let name = self.name(item);
        match self.origin.place(item) {
            Some(&Place { file, at, .. }) => {
                let file = match self.here {
                    Some(here) if here == file => String::new(),
                    _ => format!("{} ", self.origin.file(file)),
                };
                match at {
                    At::Line(line) => format!("{name} ({file}line {line})"),
                    At::Byte(byte) => format!("{name} ({file}byte {byte})"),
                }
            }
            None => name,
        }
    }
}

impl Origin {
    fn place(&self, item: Item) -> Option<&Place> {
        match item {
            Item::Node(n) => self.nodes.get(n),
            Item::Cell(t) => self.cells.get(t),
        }
    }

    fn file(&self, index: usize) -> &str {
        self.files.get(index).map_or("", String::as_str)
    }

    fn names(&self, here: Option<usize>) -> Names<'_> {
        Names { origin: self, here }
    }

    /// `predicate` of `item` (`element 7 is ...`), placed at its line (or byte).
    pub fn error_at(&self, item: Item, predicate: &str) -> MeshFileError {
        let place = self.place(item);
        let message = format!("{} {predicate}", self.names(None).name(item));
        match place {
            Some(&Place {
                file,
                at: At::Line(line),
                ..
            }) => MeshFileError::at_line(self.file(file), line, message),
            Some(&Place {
                file,
                at: At::Byte(byte),
                ..
            }) => MeshFileError::in_file(
                self.file(file),
                format!("{message} (byte {byte} of the file)"),
            ),
            None => MeshFileError::in_file(self.file(0), message),
        }
    }

    /// A defect of [`conformity`], at its subject's place, the other items named with theirs.
    pub fn defect(&self, defect: &Defect) -> MeshFileError {
        let subject = defect.subject();
        let here = self.place(subject).map(|p| p.file);
        self.error_at(subject, &defect.predicate(&self.names(here)))
    }

    /// What [`Mesh::validate`] found, at the node or element concerned.
    pub fn mesh_error(&self, error: &MeshError) -> MeshFileError {
        let (item, predicate) = match *error {
            MeshError::Degenerate { triangle, area } => (
                Item::Cell(triangle),
                format!(
                    "is degenerate (area {} mm^2: its corners are on one line or at one point)",
                    six_digits(area)
                ),
            ),
            MeshError::Folded { element } => (Item::Cell(element), FOLDED.to_string()),
            MeshError::NonFinite { node } => {
                (Item::Node(node), "has a non-finite coordinate".to_string())
            }
            MeshError::BadWarpDirection { triangle } => (
                Item::Cell(triangle),
                "has a zero or non-finite warp direction".to_string(),
            ),
            _ => return MeshFileError::in_file(self.file(0), error.to_string()),
        };
        self.error_at(item, &predicate)
    }

    /// The origin of `sub`, the cells `kept` of `full` ([`Mesh::restricted_to`]).
    fn restricted(&self, full: &Mesh, sub: &Mesh, kept: &[usize]) -> Origin {
        let mut nodes = vec![None; sub.nodes.len()];
        for (cell, &t) in sub.cells.iter().zip(kept) {
            for (&n, &m) in cell.nodes().iter().zip(full.cells[t].nodes()) {
                nodes[n] = self.nodes.get(m).copied();
            }
        }
        // all or nothing: an origin without places names by index
        Origin {
            files: self.files.clone(),
            nodes: nodes.into_iter().collect::<Option<_>>().unwrap_or_default(),
            cells: kept
                .iter()
                .map(|&t| self.cells.get(t).copied())
                .collect::<Option<_>>()
                .unwrap_or_default(),
        }
    }
}

/// Why a mesh file could not be read or written: the file, the line where there is one, and
/// what was expected there.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", line.map(|l| format!(": line {l}")).unwrap_or_default())]
pub struct MeshFileError {
    pub file: String,
    pub line: Option<usize>,
    pub message: String,
}

impl MeshFileError {
    pub fn in_file(file: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            line: None,
            message: message.into(),
        }
    }

    pub fn at_line(file: impl Into<String>, line: usize, message: impl Into<String>) -> Self {
        Self {
            file: file.into(),
            line: Some(line),
            message: message.into(),
        }
    }
}

/// Reads a mesh file by its extension: `.msh` (Gmsh 4.1, ASCII or binary) or `.inp` (Abaqus).
pub fn read_mesh_file(path: &Path) -> Result<MeshImport, MeshFileError> {
    let extension = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    match extension.as_deref() {
        Some("msh") => super::gmsh::read_msh(path),
        Some("inp") => super::abaqus::read_inp(path),
        _ => Err(MeshFileError::in_file(
            path.display().to_string(),
            "unknown mesh format: the blank and tool meshes read are Gmsh .msh (4.1) and \
             Abaqus .inp files (and STL for tools)",
        )),
    }
}
