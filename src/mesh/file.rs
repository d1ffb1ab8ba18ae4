//! What the mesh-file readers (Gmsh, Abaqus) give back, and how they fail.

use super::Mesh;
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
