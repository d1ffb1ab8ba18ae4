//! The deck read, what it means: labels resolved to indices, sets in the order of their
//! definitions, each element's section with its orientation and thickness, one cell per
//! element (triangles and quadrilaterals as they are), nodes of no element dropped, and the mesh
//! validated.

use super::super::lexer::{Deck, Loc};
use super::super::writer::{is_section_set, SECTION_SET_PREFIX};
use super::super::AbaqusMesh;
use super::lookup::{IndexSet, Resolved, Use};
use super::{supported_types, Axes, Model, Thickness, ELEMENT_TYPES};
use crate::mesh::conformity::check_elements;
use crate::mesh::{At, Cell, Mesh, MeshError, MeshFileError, MeshImport, Origin, Place};
use nalgebra::Vector3;
use std::collections::{BTreeMap, HashMap, HashSet};

type Result<T> = std::result::Result<T, MeshFileError>;

/// Per element: the warp reference (local 1-axis) and thickness of its section.
struct Properties {
    warp: Vec<Option<Vector3<f64>>>,
    thickness: Vec<Option<f64>>,
}

/// "3 nodes ..." / "1 node ...".
fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Up to ten labels, and "..." for more.
fn some_labels(labels: impl Iterator<Item = u64>, total: usize) -> String {
    let shown: Vec<String> = labels.take(10).map(|l| l.to_string()).collect();
    let more = if total > shown.len() { ", ..." } else { "" };
    format!("{}{more}", shown.join(", "))
}

impl Model {
    /// Resolves labels, sets, sections, orientations and thicknesses and builds the mesh.
    pub(super) fn finish(mut self, deck: &Deck) -> Result<AbaqusMesh> {
        // cell `e` is element `e`
        let cells = self.cells(deck)?;
        let (node_sets, element_sets) = self.resolve_sets(deck, &cells)?;
        let properties = self.properties(deck, &element_sets)?;

        // nodes used by no element are dropped
        let mut used = vec![false; self.nodes.len()];
        for &n in cells.iter().flat_map(Cell::nodes) {
            used[n] = true;
        }
        let mut new_index = vec![usize::MAX; self.nodes.len()];
        let mut kept = Vec::with_capacity(self.nodes.len());
        for (n, _) in self.nodes.iter().enumerate().filter(|(n, _)| used[*n]) {
            new_index[n] = kept.len();
            kept.push(n);
        }
        let orphans = self.nodes.len() - kept.len();
        if orphans > 0 {
            let in_sets: HashSet<usize> = node_sets
                .values()
                .flat_map(|s| s.order.iter().copied())
                .filter(|&n| !used[n])
                .collect();
            let labels = (0..self.nodes.len())
                .filter(|&n| !used[n])
                .map(|n| self.nodes[n].label);
            self.notes.push(format!(
                "{} used by no element dropped ({} of them in node sets only; labels {})",
                count(orphans, "node", "nodes"),
                in_sets.len(),
                some_labels(labels, orphans)
            ));
        }

        let mut mesh_node_sets = BTreeMap::new();
        let mut mesh_element_sets = BTreeMap::new();
        let mut internal = Vec::new();
        for set in node_sets.into_values() {
            if set.internal {
                internal.push(set.name);
                continue;
            }
            let members: Vec<usize> = set
                .order
                .iter()
                .filter(|&&n| used[n])
                .map(|&n| new_index[n])
                .collect();
            if members.len() < set.order.len() {
                self.notes.push(format!(
                    "node set '{}': {} of its {} nodes belong to no element and were dropped",
                    set.name,
                    set.order.len() - members.len(),
                    set.order.len()
                ));
            }
            mesh_node_sets.insert(set.name, members);
        }
        let mut section_sets = 0;
        for set in element_sets.into_values() {
            if set.internal {
                internal.push(set.name);
                continue;
            }
            if is_section_set(&set.name) {
                section_sets += 1;
                continue;
            }
            mesh_element_sets.insert(set.name, set.order);
        }
        if !internal.is_empty() {
            internal.sort();
            self.notes.push(format!(
                "internal sets (INTERNAL: Abaqus/CAE's own) used but not kept: {}",
                internal.join(", ")
            ));
        }
        if section_sets > 0 {
            self.notes.push(format!(
                "{section_sets} per-element section sets ({SECTION_SET_PREFIX}<n>, as thermostamp \
                 writes them) used but not kept"
            ));
        }

        let rigid: Vec<bool> = (0..cells.len()).map(|e| self.rigid(e)).collect();
        let warp_directions = self.warp_directions(&properties);
        let thickness = properties.thickness;
        let notes = self.notes(deck);
        let mesh = Mesh {
            nodes: kept.iter().map(|&n| self.nodes[n].position).collect(),
            cells: cells.iter().map(|c| c.map(|n| new_index[n])).collect(),
            node_sets: mesh_node_sets,
            element_sets: mesh_element_sets,
            warp_directions,
        };
        let place = |label: u64, loc: Loc| Place {
            label,
            file: loc.file,
            at: At::Line(loc.line),
        };
        let origin = Origin {
            files: deck.files.clone(),
            nodes: kept
                .iter()
                .map(|&n| place(self.nodes[n].label, self.nodes[n].loc))
                .collect(),
            cells: self
                .elements
                .iter()
                .map(|e| place(e.label, e.loc))
                .collect(),
        };
        check_elements(&mesh).map_err(|d| origin.defect(&d))?;
        mesh.validate().map_err(|e| match e {
            MeshError::Empty => MeshFileError::in_file(
                origin.files.first().cloned().unwrap_or_default(),
                format!("no elements (supported types: {})", supported_types()),
            ),
            other => origin.mesh_error(&other),
        })?;
        Ok(AbaqusMesh {
            import: MeshImport {
                mesh,
                rigid,
                notes,
                origin,
            },
            thickness,
        })
    }

    fn rigid(&self, e: usize) -> bool {
        ELEMENT_TYPES[self.elements[e].kind].2
    }

    /// One cell per element, on node indices, its nodes in the element's order (which gives
    /// the normal).
    fn cells(&self, deck: &Deck) -> Result<Vec<Cell>> {
        self.elements
            .iter()
            .map(|e| {
                let nodes = e
                    .nodes
                    .iter()
                    .map(|label| {
                        self.node_index.get(label).copied().ok_or_else(|| {
                            deck.error(
                                e.loc,
                                format!(
                                    "element {} refers to node {label}, which is not defined",
                                    e.label
                                ),
                            )
                        })
                    })
                    .collect::<Result<Vec<usize>>>()?;
                match *nodes.as_slice() {
                    [a, b, c] => Ok(Cell::Triangle([a, b, c])),
                    [a, b, c, d] => Ok(Cell::Quad([a, b, c, d])),
                    _ => Err(deck.error(
                        e.loc,
                        format!("element {} has {} nodes, not 3 or 4", e.label, nodes.len()),
                    )),
                }
            })
            .collect()
    }

    /// Each element's section, then its orientation's local 1-axis (after the additional
    /// rotation) and its thickness.
    fn properties(
        &self,
        deck: &Deck,
        element_sets: &HashMap<String, IndexSet>,
    ) -> Result<Properties> {
        let mut section_of: Vec<Option<usize>> = vec![None; self.elements.len()];
        for (s, section) in self.sections.iter().enumerate() {
            let set = element_sets.get(&section.elset).ok_or_else(|| {
                deck.error(
                    section.loc,
                    format!(
                        "the section's element set '{}' is not defined",
                        section.elset
                    ),
                )
            })?;
            for &e in &set.order {
                if let Some(first) = section_of[e] {
                    return Err(deck.error(
                        section.loc,
                        format!(
                            "element {} already has a section (at {})",
                            self.elements[e].label,
                            deck.place(self.sections[first].loc, section.loc)
                        ),
                    ));
                }
                section_of[e] = Some(s);
            }
        }
        let mut cache: HashMap<String, Resolved> = HashMap::new();
        let mut properties = Properties {
            warp: vec![None; self.elements.len()],
            thickness: vec![None; self.elements.len()],
        };
        for (e, s) in section_of.iter().enumerate() {
            let Some(section) = s.map(|s| &self.sections[s]) else {
                continue;
            };
            if let Some(name) = &section.orientation {
                let o = self.orientations.get(name).ok_or_else(|| {
                    deck.error(section.loc, format!("orientation '{name}' is not defined"))
                })?;
                let (e1, e2) = match &o.axes {
                    Axes::Fixed(e1, e2) => (*e1, *e2),
                    Axes::Distribution(d) => {
                        let v = self.distribution_value(
                            deck,
                            &mut cache,
                            element_sets,
                            (d, Use::Orientation, o.loc),
                            e,
                        )?;
                        let a = Vector3::new(v[0], v[1], v[2]);
                        let b = Vector3::new(v[3], v[4], v[5]);
                        frame(a, b).ok_or_else(|| {
                            deck.error(
                                o.loc,
                                format!(
                                    "distribution '{d}': the points a and b of element {} are \
                                     collinear with the origin",
                                    self.elements[e].label
                                ),
                            )
                        })?
                    }
                };
                properties.warp[e] = Some(e1 * o.rotation.cos() + e2 * o.rotation.sin());
            }
            properties.thickness[e] = match &section.thickness {
                Thickness::Unknown => None,
                Thickness::Value(t) => Some(*t),
                Thickness::Distribution(d) => {
                    let t = self.distribution_value(
                        deck,
                        &mut cache,
                        element_sets,
                        (d, Use::Thickness, section.loc),
                        e,
                    )?[0];
                    if t <= 0.0 {
                        return Err(deck.error(
                            section.loc,
                            format!(
                                "distribution '{d}': thickness {t} of element {} is not positive",
                                self.elements[e].label
                            ),
                        ));
                    }
                    Some(t)
                }
            };
        }
        Ok(properties)
    }

    /// Per element, its local 1-axis: `None` where no element has an orientation, the global x
    /// axis (with a note) for the elements without one where others have one.
    fn warp_directions(&mut self, properties: &Properties) -> Option<Vec<Vector3<f64>>> {
        let warp = &properties.warp;
        if warp.iter().all(Option::is_none) {
            return None;
        }
        let bare: Vec<usize> = (0..warp.len())
            .filter(|&e| warp[e].is_none() && !self.rigid(e))
            .collect();
        if !bare.is_empty() {
            let deformable = (0..warp.len()).filter(|&e| !self.rigid(e)).count();
            self.notes.push(format!(
                "{} of {deformable} shell and membrane elements have no orientation (elements \
                 {}): their warp reference is the global x axis, projected onto each element as \
                 Abaqus does for shells without one",
                bare.len(),
                some_labels(bare.iter().map(|&e| self.elements[e].label), bare.len())
            ));
        }
        Some(warp.iter().map(|w| w.unwrap_or_else(Vector3::x)).collect())
    }

    /// The notes: what was flagged, read as structure, ignored.
    fn notes(&mut self, deck: &Deck) -> Vec<String> {
        let mut notes = Vec::new();
        let rigid = (0..self.elements.len()).filter(|&e| self.rigid(e)).count();
        if rigid > 0 {
            notes.push(format!(
                "{} (R3D3/R3D4): flagged rigid",
                count(rigid, "rigid element", "rigid elements")
            ));
        }
        if let Some((part, _)) = &self.structure.part {
            notes.push(match &self.structure.instance {
                Some((instance, _)) => format!("part '{part}' read (instance '{instance}')"),
                None => format!("part '{part}' read (it has no *INSTANCE)"),
            });
        }
        if self.normals_ignored {
            notes.push("node normals given on *NODE lines ignored".to_string());
        }
        notes.append(&mut self.notes);
        if !self.ignored.is_empty() {
            notes.push(ignored_note(deck, &self.ignored));
        }
        notes
    }
}

/// The unit local 1- and 2-axes of a rectangular system with the local 1-axis along `a` and
/// `b` in the 1-2 plane; `None` when `a` and `b` are (nearly) collinear.
pub(super) fn frame(a: Vector3<f64>, b: Vector3<f64>) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let (na, nb) = (a.norm(), b.norm());
    let normal = a.cross(&b);
    if !(na > 0.0 && nb > 0.0 && normal.norm() > 1e-10 * na * nb && normal.norm().is_finite()) {
        return None;
    }
    let e1 = a / na;
    let e3 = normal.normalize();
    Some((e1, e3.cross(&e1)))
}

/// "ignored keywords: *HEADING (line 1), *MATERIAL (line 40, line 52), *ELASTIC (b.inp line 3)".
fn ignored_note(deck: &Deck, ignored: &[(String, Loc)]) -> String {
    let mut order: Vec<&str> = Vec::new();
    let mut places: HashMap<&str, Vec<String>> = HashMap::new();
    let main = Loc { file: 0, line: 0 };
    for (name, loc) in ignored {
        if !places.contains_key(name.as_str()) {
            order.push(name);
        }
        places.entry(name).or_default().push(deck.place(*loc, main));
    }
    let items: Vec<String> = order
        .iter()
        .map(|name| format!("*{name} ({})", places[name].join(", ")))
        .collect();
    format!(
        "ignored keywords (not part of the mesh): {}",
        items.join(", ")
    )
}
