//! Abaqus input files (`.inp`) in and out: the blank's mesh (shell, membrane and rigid
//! elements, node and element sets) with its material orientations and shell thicknesses.
//! What is read, what is refused and what is written: docs/meshes.md, "Abaqus (.inp)".
//!
//! **Choice:** the parser is this crate's own; crates.io has no maintained `.inp` reader (one
//! 0.1.0 crate, `abaqus_inp`, for MCNP meshes), and none reads orientations or distributions.

mod lexer;
mod reader;
mod writer;

pub use lexer::IncludeReader;
pub use reader::ELEMENT_TYPES;
pub use writer::{
    abaqus_number, check_set_names, write_inp, write_inp_to, ElementOutput, MATERIAL_NAME,
    MAX_FIELD, ORIENTATION_PREFIX, SECTION_SET_PREFIX,
};

use super::{MeshFileError, MeshImport};
use std::path::Path;

/// A mesh read from a deck with, per cell (element), the shell or membrane thickness (mm) of its
/// element's section where the deck gives one.
#[derive(Clone, Debug, PartialEq)]
pub struct AbaqusMesh {
    pub import: MeshImport,
    pub thickness: Vec<Option<f64>>,
}

/// Reads the Abaqus input file `path` (and the files it includes).
pub fn read_inp(path: &Path) -> Result<MeshImport, MeshFileError> {
    read_inp_with_thickness(path).map(|m| m.import)
}

/// [`read_inp`], with the thickness of each element.
pub fn read_inp_with_thickness(path: &Path) -> Result<AbaqusMesh, MeshFileError> {
    let text = read_text(path).map_err(|e| {
        MeshFileError::in_file(path.display().to_string(), format!("cannot read: {e}"))
    })?;
    parse_inp(&text, path, &mut read_text)
}

/// Reads the deck `text`, the contents of `file` (which names it in errors and locates the
/// files it includes), reading included files through `read_include`.
pub fn parse_inp(
    text: &str,
    file: &Path,
    read_include: &mut IncludeReader<'_>,
) -> Result<AbaqusMesh, MeshFileError> {
    let deck = lexer::lex(text, file, read_include)?;
    reader::interpret(&deck)
}

/// A file's text; bytes that are not UTF-8 (comments in Latin-1, say) replaced.
fn read_text(path: &Path) -> std::io::Result<String> {
    std::fs::read(path).map(|bytes| String::from_utf8_lossy(&bytes).into_owned())
}
