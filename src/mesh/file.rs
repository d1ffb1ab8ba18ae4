//! What the mesh-file readers (Gmsh, Abaqus) give back, and how they fail.

use super::Mesh;
use std::path::Path;

/// A mesh read from a file: the triangles (quadrilaterals split in two), the sets, and what
/// the reader noticed on the way.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshImport {
    pub mesh: Mesh,
    /// Per triangle, whether it comes from a rigid element (Abaqus `R3D3`/`R3D4`): such
    /// triangles can describe a tool, never the blank.
    pub rigid: Vec<bool>,
    /// Things the user should know, one line each: quadrilaterals split, keywords or element
    /// types that were read but not used, ...
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

/// Diagonals whose squared lengths differ by less than this share are taken as equal, and the
/// quadrilateral is split from its first corner: on square cells rounding would otherwise pick
/// the diagonal at random (and differently for the 16-digit ASCII and the binary copy of one
/// mesh), where a regular pattern is what the bending patch wants (docs/forming.md, "Bending").
const EQUAL_DIAGONALS: f64 = 1e-9;

/// The two triangles of the quadrilateral `quad` (corners in order round it), split along its
/// shorter diagonal, both keeping the quadrilateral's orientation; equal diagonals (within
/// `EQUAL_DIAGONALS`) from the first corner. **Choice:** the shorter diagonal gives the
/// better-shaped pair; the solver's elements are triangles (see docs/meshes.md).
pub fn split_quadrilateral(nodes: &[nalgebra::Vector3<f64>], quad: [usize; 4]) -> [[usize; 3]; 2] {
    let [a, b, c, d] = quad;
    let ac = (nodes[c] - nodes[a]).norm_squared();
    let bd = (nodes[d] - nodes[b]).norm_squared();
    if ac <= bd * (1.0 + EQUAL_DIAGONALS) {
        [[a, b, c], [a, c, d]]
    } else {
        [[a, b, d], [b, c, d]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn quadrilaterals_split_along_the_shorter_diagonal_keeping_their_orientation() {
        let nodes = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(2.5, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let area = |t: [usize; 3]| {
            let [a, b, c] = t.map(|i| nodes[i]);
            (b - a).cross(&(c - a)).z
        };
        for quad in [[0, 1, 2, 3], [1, 2, 3, 0]] {
            let pair = split_quadrilateral(&nodes, quad);
            assert!(pair.iter().all(|&t| area(t) > 0.0), "{pair:?}");
            assert!((area(pair[0]) + area(pair[1]) - 2.0 * 2.25).abs() < 1e-12);
            // the diagonal 1-3 (length sqrt(5)) is shorter than 0-2 (sqrt(7.25))
            assert!(
                pair.iter().all(|t| t.contains(&1) && t.contains(&3)),
                "{pair:?}"
            );
        }
    }
}
