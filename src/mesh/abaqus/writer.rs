//! A mesh as an Abaqus deck: nodes, S3R elements, sets, and per element the warp direction
//! (an orientation from a distribution) and the thickness (a shell thickness distribution).

use crate::mesh::{Mesh, MeshFileError};
use nalgebra::Vector3;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// Per triangle, what a forming run gives a structural analysis: the current warp direction
/// (any length; written as the local 1-axis of the element's material orientation) and the
/// current thickness (mm).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementOutput {
    pub warp: Vec<Vector3<f64>>,
    pub thickness: Vec<f64>,
}

/// The material the written `*SHELL SECTION` refers to: the user defines it.
pub const MATERIAL_NAME: &str = "PREPREG";
/// The written names of the distributions and orientation.
pub const WARP_TABLE: &str = "THERMOSTAMP_WARP_TABLE";
pub const WARP_DISTRIBUTION: &str = "THERMOSTAMP_WARP";
pub const ORIENTATION_NAME: &str = "THERMOSTAMP_ORIENTATION";
pub const THICKNESS_TABLE: &str = "THERMOSTAMP_THICKNESS_TABLE";
pub const THICKNESS_DISTRIBUTION: &str = "THERMOSTAMP_THICKNESS";

/// Writes `mesh` to `path` as an Abaqus input file (see [`write_inp_to`]). Nothing is written
/// when the mesh or `elements` is not valid.
pub fn write_inp(
    path: &Path,
    mesh: &Mesh,
    elements: Option<&ElementOutput>,
) -> Result<(), MeshFileError> {
    let file = path.display().to_string();
    let mut bytes = Vec::new();
    write_inp_to(&mut bytes, &file, mesh, elements)?;
    std::fs::write(path, bytes)
        .map_err(|e| MeshFileError::in_file(&file, format!("cannot write: {e}")))
}

/// Writes `mesh` as an Abaqus input file to `out` (`file` names it in errors): `*HEADING`,
/// `*NODE`, `*ELEMENT, TYPE=S3R`, the node and element sets, and, where there are warp
/// directions (`elements`, else `mesh.warp_directions`) or thicknesses, per element a
/// `*DISTRIBUTION` of the local 1-axis behind an `*ORIENTATION` and a `*DISTRIBUTION` of the
/// shell thickness, both used by a `*SHELL SECTION` on every element with material
/// [`MATERIAL_NAME`]. Coordinates, directions and thicknesses are written in the shortest form
/// that reads back to the same `f64`.
pub fn write_inp_to<W: Write>(
    mut out: W,
    file: &str,
    mesh: &Mesh,
    elements: Option<&ElementOutput>,
) -> Result<(), MeshFileError> {
    let error = |message: String| MeshFileError::in_file(file, message);
    mesh.validate()
        .map_err(|e| error(format!("the mesh is not valid: {e}")))?;
    let count = mesh.triangles.len();
    let warp: Option<&[Vector3<f64>]> = match elements {
        Some(e) => Some(&e.warp),
        None => mesh.warp_directions.as_deref(),
    };
    let thickness: Option<&[f64]> = elements.map(|e| e.thickness.as_slice());
    if let Some(e) = elements {
        if e.warp.len() != count || e.thickness.len() != count {
            return Err(error(format!(
                "{} warp directions and {} thicknesses for {count} triangles",
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
                "triangle {t}: thickness {} is not positive",
                e.thickness[t]
            )));
        }
    }
    let node_sets = names(&mesh.node_sets, "node").map_err(error)?;
    let element_sets = names(&mesh.element_sets, "element").map_err(error)?;

    let mut text = String::new();
    let count_nodes = mesh.nodes.len();
    // writing to a String cannot fail
    let _ = writeln!(
        text,
        "** Written by thermostamp {}: {count_nodes} nodes, {count} 3-node shell elements (S3R).",
        env!("CARGO_PKG_VERSION")
    );
    if warp.is_some() || thickness.is_some() {
        let _ = writeln!(
            text,
            "** To run it in Abaqus, define *MATERIAL, NAME={MATERIAL_NAME} (the shell section at \
             the end refers to it) and a step, or include this file in a deck that does."
        );
    } else {
        let _ = writeln!(
            text,
            "** To run it in Abaqus, add a shell section on the elements, its material and a step, \
             or include this file in a deck that does."
        );
    }
    let _ = writeln!(
        text,
        "*HEADING\nthermostamp blank: {count_nodes} nodes, {count} elements"
    );
    text.push_str("*NODE\n");
    for (n, x) in mesh.nodes.iter().enumerate() {
        let _ = writeln!(text, "{}, {:?}, {:?}, {:?}", n + 1, x.x, x.y, x.z);
    }
    text.push_str("*ELEMENT, TYPE=S3R\n");
    for (t, [a, b, c]) in mesh.triangles.iter().enumerate() {
        let _ = writeln!(text, "{}, {}, {}, {}", t + 1, a + 1, b + 1, c + 1);
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
    if warp.is_none() && thickness.is_none() {
        out.write_all(text.as_bytes())
            .map_err(|e| error(format!("cannot write: {e}")))?;
        return Ok(());
    }

    // every element, for the section: internal, so that reading the file back gives the
    // mesh's own element sets only
    let mut all = "_THERMOSTAMP_BLANK".to_string();
    let mut k = 1;
    while mesh
        .element_sets
        .keys()
        .any(|n| n.eq_ignore_ascii_case(&all))
    {
        k += 1;
        all = format!("_THERMOSTAMP_BLANK_{k}");
    }
    let _ = writeln!(
        text,
        "*ELSET, ELSET={all}, INTERNAL, GENERATE\n1, {count}, 1"
    );
    let mut section = format!("*SHELL SECTION, ELSET={all}, MATERIAL={MATERIAL_NAME}");
    if let Some(warp) = warp {
        let _ = writeln!(
            text,
            "** Warp direction per element: the local 1-axis is a, the 1-2 plane holds b (in the \
             element, normal to a)."
        );
        let _ = writeln!(
            text,
            "*DISTRIBUTION TABLE, NAME={WARP_TABLE}\nCOORD3D, COORD3D"
        );
        let _ = writeln!(
            text,
            "*DISTRIBUTION, NAME={WARP_DISTRIBUTION}, LOCATION=ELEMENT, TABLE={WARP_TABLE}"
        );
        text.push_str(", 1.0, 0.0, 0.0, 0.0, 1.0, 0.0\n");
        for (t, a) in warp.iter().enumerate() {
            let [p, q, r] = mesh.triangles[t].map(|n| mesh.nodes[n]);
            let normal = (q - p).cross(&(r - p)).normalize();
            let b = normal.cross(a);
            if !(a.iter().all(|c| c.is_finite()) && b.norm() > 1e-10 * a.norm()) {
                return Err(error(format!(
                    "triangle {t}: warp direction {a:?} is zero, not finite or normal to the \
                     triangle"
                )));
            }
            let _ = writeln!(
                text,
                "{}, {:?}, {:?}, {:?}, {:?}, {:?}, {:?}",
                t + 1,
                a.x,
                a.y,
                a.z,
                b.x,
                b.y,
                b.z
            );
        }
        let _ = writeln!(
            text,
            "*ORIENTATION, NAME={ORIENTATION_NAME}\n{WARP_DISTRIBUTION}\n3, 0.0"
        );
        let _ = write!(section, ", ORIENTATION={ORIENTATION_NAME}");
    }
    let mut section_data = ", 5".to_string();
    if let Some(thickness) = thickness {
        let _ = writeln!(text, "** Shell thickness per element (mm).");
        let _ = writeln!(text, "*DISTRIBUTION TABLE, NAME={THICKNESS_TABLE}\nLENGTH");
        let _ = writeln!(
            text,
            "*DISTRIBUTION, NAME={THICKNESS_DISTRIBUTION}, LOCATION=ELEMENT, \
             TABLE={THICKNESS_TABLE}"
        );
        let mean = thickness.iter().sum::<f64>() / count as f64;
        let _ = writeln!(text, ", {mean:?}");
        for (t, h) in thickness.iter().enumerate() {
            let _ = writeln!(text, "{}, {h:?}", t + 1);
        }
        let _ = write!(section, ", SHELL THICKNESS={THICKNESS_DISTRIBUTION}");
        section_data = format!("{mean:?}, 5");
    } else {
        let _ = writeln!(
            text,
            "** The thickness is not known here: give it as the first value of the line after \
             *SHELL SECTION."
        );
    }
    let _ = writeln!(text, "{section}\n{section_data}");
    out.write_all(text.as_bytes())
        .map_err(|e| error(format!("cannot write: {e}")))
}

/// 16 labels (indices + 1) a line, as Abaqus reads set data.
fn write_labels(text: &mut String, members: &[usize]) {
    for line in members.chunks(16) {
        let labels: Vec<String> = line.iter().map(|i| (i + 1).to_string()).collect();
        text.push_str(&labels.join(", "));
        text.push('\n');
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
                "{kind} set name '{name}' cannot be written as an Abaqus label"
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
