//! A mesh as an Abaqus deck that CalculiX reads as well: nodes, S3 and S4R elements, sets, and per
//! element the warp and weft directions (an orientation) and the thickness (a shell section).

use crate::mesh::{Mesh, MeshFileError};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Per element, what a forming run gives a structural analysis: the current warp direction
/// (any length; written as the local 1-axis of the element's material orientation), the
/// current weft direction (written as the orientation's second point, which fixes the 1–2
/// plane: Abaqus and CalculiX take the local 2-axis normal to the warp in the plane of the
/// two, so the weft is kept in the deck exactly; `None`: the 2-axis normal to the warp in the
/// element) and the current thickness (mm).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementOutput {
    pub warp: Vec<Vector3<f64>>,
    pub weft: Option<Vec<Vector3<f64>>>,
    pub thickness: Vec<f64>,
}

/// The material the written `*SHELL SECTION`s refer to: the user defines it.
pub const MATERIAL_NAME: &str = "PREPREG";
/// Element `n`'s own element set is `THERMOSTAMP_E<n>`, its orientation `THERMOSTAMP_O<n>`:
/// a section per element is the form of per-element thickness and orientation that both
/// Abaqus and CalculiX read (CalculiX ignores `SHELL THICKNESS=` distributions and applies only
/// the default line of an orientation `*DISTRIBUTION`).
pub const SECTION_SET_PREFIX: &str = "THERMOSTAMP_E";
pub const ORIENTATION_PREFIX: &str = "THERMOSTAMP_O";
/// The widest numeric field that Abaqus (and CalculiX) read in a data line.
pub const MAX_FIELD: usize = 20;

/// Whether `name` is one of the per-element section sets this writer writes (any case).
pub(in crate::mesh::abaqus) fn is_section_set(name: &str) -> bool {
    name.len() > SECTION_SET_PREFIX.len()
        && name.is_char_boundary(SECTION_SET_PREFIX.len())
        && name[..SECTION_SET_PREFIX.len()].eq_ignore_ascii_case(SECTION_SET_PREFIX)
        && name[SECTION_SET_PREFIX.len()..]
            .bytes()
            .all(|b| b.is_ascii_digit())
}

/// `x` in at most [`MAX_FIELD`] characters: the shortest form that reads back to the same
/// `f64` where it fits (`1.0`, `-79.99483755371092`, `1e-7`), else scientific notation with
/// as many significant digits as fit (at least 13; 15 for exponents of one digit), so that the
/// value read back is within half a unit of the last digit written. `x` is finite.
pub fn abaqus_number(x: f64) -> String {
    let shortest = format!("{x:?}");
    if shortest.len() <= MAX_FIELD {
        return shortest;
    }
    let scientific = format!("{x:e}");
    if scientific.len() <= MAX_FIELD {
        return scientific;
    }
    let mut digits = 16;
    loop {
        let text = format!("{x:.digits$e}");
        if text.len() <= MAX_FIELD || digits == 0 {
            return without_trailing_zeros(&text);
        }
        digits -= 1;
    }
}

/// `2.500e-300` as `2.5e-300`: rounding to fewer digits can leave zeros at the end.
fn without_trailing_zeros(scientific: &str) -> String {
    match scientific.split_once('e') {
        Some((mantissa, exponent)) if mantissa.contains('.') => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            format!("{mantissa}e{exponent}")
        }
        _ => scientific.to_string(),
    }
}

/// Numbers of a data line, each in at most [`MAX_FIELD`] characters.
fn numbers(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| abaqus_number(*v))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes `mesh` to `path` as an Abaqus input file (see [`write_inp_to`]). Nothing is written
/// when the mesh or `elements` is not valid, nor through a symbolic link at `path`
/// ([`crate::io::product_file`]).
pub fn write_inp(
    path: &Path,
    mesh: &Mesh,
    elements: Option<&ElementOutput>,
) -> Result<(), MeshFileError> {
    let file = path.display().to_string();
    let mut bytes = Vec::new();
    write_inp_to(&mut bytes, &file, mesh, elements)?;
    crate::io::product_file::write(path, &bytes)
        .map_err(|e| MeshFileError::in_file(&file, format!("cannot write: {e}")))
}

/// Writes `mesh` as an Abaqus input file to `out` (`file` names it in errors): `*HEADING`,
/// `*NODE`, `*ELEMENT, TYPE=S3` (triangles) and `TYPE=S4R` (quadrilaterals), a block per run
/// of cells of one kind, the node and element sets, and, where there are warp directions
/// (`elements`, else `mesh.warp_directions`) or thicknesses, per element its own element set, `*ORIENTATION` (local 1-axis along the warp) and `*SHELL SECTION` (its
/// thickness) with material [`MATERIAL_NAME`]. Every number is written by [`abaqus_number`]
/// and no data line has more than 16 entries, so that Abaqus and CalculiX read the deck alike.
pub fn write_inp_to<W: Write>(
    mut out: W,
    file: &str,
    mesh: &Mesh,
    elements: Option<&ElementOutput>,
) -> Result<(), MeshFileError> {
    let error = |message: String| MeshFileError::in_file(file, message);
    mesh.validate()
        .map_err(|e| error(format!("the mesh is not valid: {e}")))?;
    let count = mesh.cells.len();
    let warp: Option<&[Vector3<f64>]> = match elements {
        Some(e) => Some(&e.warp),
        None => mesh.warp_directions.as_deref(),
    };
    let thickness: Option<&[f64]> = elements.map(|e| e.thickness.as_slice());
    let weft: Option<&[Vector3<f64>]> = elements.and_then(|e| e.weft.as_deref());
    if let Some(e) = elements {
        let wefts = e.weft.as_ref().map_or(count, Vec::len);
        if e.warp.len() != count || e.thickness.len() != count || wefts != count {
            return Err(error(format!(
                "{} warp directions, {wefts} weft directions and {} thicknesses for {count} \
                 elements",
                e.warp.len(),
                e.thickness.len()
            )));
        }
        if let Some(t) = e
            .thickness
            .iter()
            .position(|t| !(t.is_finite() && *t > 0.0))
        {
            return Err(error(format!(
                "element {t}: thickness {} is not positive",
                e.thickness[t]
            )));
        }
    }
    let node_sets = names(&mesh.node_sets, "node").map_err(error)?;
    let element_sets = names(&mesh.element_sets, "element").map_err(error)?;
    let with_sections = warp.is_some() || thickness.is_some();
    no_section_set_names(mesh).map_err(error)?;

    let mut text = String::new();
    let count_nodes = mesh.nodes.len();
    // writing to a String cannot fail
    let _ = writeln!(
        text,
        "** Written by thermostamp {}: {count_nodes} nodes, {count} shell elements ({}).",
        env!("CARGO_PKG_VERSION"),
        element_kinds(mesh)
    );
    if with_sections {
        let _ = writeln!(
            text,
            "** To run it in Abaqus or CalculiX, define *MATERIAL, NAME={MATERIAL_NAME} (the \
             shell sections\n** at the end refer to it) and a step, or include this file in a \
             deck that does."
        );
    } else {
        let _ = writeln!(
            text,
            "** To run it in Abaqus or CalculiX, add a shell section on the elements, its \
             material and a step,\n** or include this file in a deck that does."
        );
    }
    let _ = writeln!(
        text,
        "*HEADING\nthermostamp blank: {count_nodes} nodes, {count} elements"
    );
    text.push_str("*NODE\n");
    for (n, x) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(text, "{}, {}", n + 1, numbers(&[x.x, x.y, x.z]));
    }
    // a block per run of cells of one kind, so that the reader (file order) keeps their order
    for (t, cell) in mesh.cells.iter().enumerate() {
        if t == 0 || mesh.cells[t - 1].is_quad() != cell.is_quad() {
            let kind = if cell.is_quad() { "S4R" } else { "S3" };
            let _ = writeln!(text, "*ELEMENT, TYPE={kind}");
        }
        let labels: Vec<String> = cell.nodes().iter().map(|n| (n + 1).to_string()).collect();
        let _ = writeln!(text, "{}, {}", t + 1, labels.join(", "));
    }
    for (name, members) in node_sets.iter().map(|(n, s)| (n, &mesh.node_sets[*s])) {
        let _ = writeln!(text, "*NSET, NSET={name}");
        write_labels(&mut text, members);
    }
    for (name, members) in element_sets
        .iter()
        .map(|(n, s)| (n, &mesh.element_sets[*s]))
    {
        let _ = writeln!(text, "*ELSET, ELSET={name}");
        write_labels(&mut text, members);
    }
    if with_sections {
        write_sections(&mut text, mesh, (warp, weft), thickness).map_err(error)?;
    }
    out.write_all(text.as_bytes())
        .map_err(|e| error(format!("cannot write: {e}")))
}

/// A direction per element, where known.
type Directions<'a> = Option<&'a [Vector3<f64>]>;

/// Per element: its element set, its orientation (where there is a warp; its second point
/// the weft where known) and its shell section (with its thickness where known).
fn write_sections(
    text: &mut String,
    mesh: &Mesh,
    (warp, weft): (Directions, Directions),
    thickness: Option<&[f64]>,
) -> Result<(), String> {
    let b_is = if weft.is_some() {
        "the weft: the local 2-axis is normal to a in the plane of a and b, and the \
         shear angle\n** of the fabric is 90 degrees less the angle between a and b"
    } else {
        "in the element, normal to a"
    };
    let _ = writeln!(
        text,
        "** Per element: its own element set, its orientation (local 1-axis a: the warp; b \
         {b_is}) and its shell section (its thickness in mm, 5 integration points)."
    );
    if thickness.is_none() {
        let _ = writeln!(
            text,
            "** The thickness is not known here: give it as the first value of the line after \
             each\n** *SHELL SECTION."
        );
    }
    for (t, cell) in mesh.cells.iter().enumerate() {
        let label = t + 1;
        let _ = writeln!(text, "*ELSET, ELSET={SECTION_SET_PREFIX}{label}\n{label}");
        let mut section =
            format!("*SHELL SECTION, ELSET={SECTION_SET_PREFIX}{label}, MATERIAL={MATERIAL_NAME}");
        if let Some(given) = warp.map(|w| w[t]) {
            let normal = cell.area_vector(&mesh.nodes).normalize();
            // unit axes: a direction of any length is written (and read back) alike
            let a = (given / given.amax()).normalize();
            let b = normal.cross(&a);
            if !(given.iter().all(|c| c.is_finite()) && b.norm() > 1e-10) {
                return Err(format!(
                    "element {t}: warp direction {given:?} is zero, not finite or normal to \
                     the element"
                ));
            }
            let b = match weft.map(|w| w[t]) {
                Some(w) => second_axis_point(t, &a, &w)?,
                None => b,
            };
            let _ = writeln!(
                text,
                "*ORIENTATION, NAME={ORIENTATION_PREFIX}{label}\n{}\n3, 0.0",
                numbers(&[a.x, a.y, a.z, b.x, b.y, b.z])
            );
            let _ = write!(section, ", ORIENTATION={ORIENTATION_PREFIX}{label}");
        }
        let h = thickness.map_or(String::new(), |h| abaqus_number(h[t]));
        let _ = writeln!(text, "{section}\n{h}, 5");
    }
    Ok(())
}

/// The weft `w` as an orientation's second point: unit, and far enough from the warp `a` that
/// the plane of the two is defined (yarns within a degree of each other are no fabric).
fn second_axis_point(t: usize, a: &Vector3<f64>, w: &Vector3<f64>) -> Result<Vector3<f64>, String> {
    let unit = w / w.amax();
    let unit = unit.normalize();
    if !(w.iter().all(|c| c.is_finite()) && a.cross(&unit).norm() > 1e-2_f64.to_radians().sin()) {
        return Err(format!(
            "element {t}: weft direction {w:?} is zero, not finite or along the warp"
        ));
    }
    Ok(unit)
}

/// The element types written, for the first comment line.
fn element_kinds(mesh: &Mesh) -> &'static str {
    let quads = mesh.cells.iter().filter(|c| c.is_quad()).count();
    match quads {
        0 => "3-node S3",
        q if q == mesh.cells.len() => "4-node S4R",
        _ => "3-node S3 and 4-node S4R",
    }
}

/// 16 labels (indices + 1) a line, as Abaqus reads set data.
fn write_labels(text: &mut String, members: &[usize]) {
    for line in members.chunks(16) {
        let labels: Vec<String> = line.iter().map(|i| (i + 1).to_string()).collect();
        text.push_str(&labels.join(", "));
        text.push('\n');
    }
}

/// Whether [`write_inp`] can write the sets of `mesh`: the reason of the first it cannot, so
/// that a run whose formed blank is written at its end refuses such a mesh when it reads it.
pub fn check_set_names(mesh: &Mesh) -> Result<(), String> {
    names(&mesh.node_sets, "node")?;
    names(&mesh.element_sets, "element")?;
    no_section_set_names(mesh)
}

/// No element set may take the name of a per-element section set of the writer.
fn no_section_set_names(mesh: &Mesh) -> Result<(), String> {
    match mesh.element_sets.keys().find(|n| is_section_set(n)) {
        Some(name) => Err(format!(
            "element set '{name}' has the name of the per-element section sets \
             ({SECTION_SET_PREFIX}<n>), which the reader does not keep"
        )),
        None => Ok(()),
    }
}

/// The sets' names as Abaqus labels (quoted where they are not plain names), by the mesh's
/// name; names that Abaqus would take for the same (it ignores case) or cannot hold are
/// refused.
fn names<'m>(
    sets: &'m BTreeMap<String, Vec<usize>>,
    kind: &str,
) -> Result<Vec<(String, &'m str)>, String> {
    let mut seen: BTreeMap<String, &str> = BTreeMap::new();
    let mut out = Vec::with_capacity(sets.len());
    for name in sets.keys() {
        let plain = name.starts_with(|c: char| c.is_ascii_alphabetic())
            && name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        let label = if plain {
            name.clone()
        } else if !name.trim().is_empty()
            && name.trim() == name
            && !name.contains(['"', ',', '\n', '\r'])
        {
            format!("\"{name}\"")
        } else {
            return Err(format!(
                "{kind} set name '{name}' cannot be written as an Abaqus label (a label holds \
                 no comma, double quote or line break, and no space at either end)"
            ));
        };
        if name.chars().count() > 80 {
            return Err(format!(
                "{kind} set name '{name}' is longer than the 80 characters of an Abaqus label"
            ));
        }
        if let Some(other) = seen.insert(name.to_uppercase(), name) {
            return Err(format!(
                "{kind} sets '{other}' and '{name}' differ only in case, which Abaqus ignores"
            ));
        }
        out.push((label, name.as_str()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_fit_twenty_characters_and_keep_what_fits() {
        // the shortest round-trip form where it fits: read back bit for bit
        for x in [
            1.0,
            -79.99483755371092,
            1e-7,
            0.1,
            -5e-324,
            1e300,
            0.0,
            -0.0,
        ] {
            let text = abaqus_number(x);
            assert!(text.len() <= MAX_FIELD, "{text}");
            assert_eq!(
                text.parse::<f64>().unwrap().to_bits(),
                x.to_bits(),
                "{text}"
            );
        }
        // too long in every exact form: as many digits as fit, no trailing zeros
        for (x, written) in [
            (-1.2345678901234567e-300, "-1.234567890123e-300"),
            (-0.00021087190299357247, "-2.10871902993572e-4"),
            (0.00021087190299357247, "2.108719029935725e-4"),
            (-1.999_999_999_999_9e-300, "-2e-300"),
        ] {
            assert_eq!(abaqus_number(x), written);
        }
    }

    #[test]
    fn section_sets_are_recognised_in_any_case_and_only_with_a_number() {
        assert!(is_section_set("THERMOSTAMP_E12"));
        assert!(is_section_set("thermostamp_e3"));
        assert!(!is_section_set("THERMOSTAMP_E"));
        assert!(!is_section_set("THERMOSTAMP_EDGE"));
        assert!(!is_section_set("THERMOSTAMP_É1"));
    }
}
