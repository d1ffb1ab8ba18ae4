//! What the records of a deck mean: nodes, elements, sets, orientations, sections and
//! distributions, resolved into a [`Mesh`] once the whole deck is read.

mod lookup;
mod resolve;
mod sections;

use super::lexer::{canonical, unquote, DataLine, Deck, Keyword, Loc, Record};
use super::AbaqusMesh;
use crate::mesh::MeshFileError;
use nalgebra::Vector3;
use std::collections::HashMap;

/// The element types read: name, corner nodes, rigid (each one cell of the mesh: a triangle
/// or a quadrilateral).
pub const ELEMENT_TYPES: [(&str, usize, bool); 9] = [
    ("S3", 3, false),
    ("S3R", 3, false),
    ("M3D3", 3, false),
    ("S4", 4, false),
    ("S4R", 4, false),
    ("M3D4", 4, false),
    ("M3D4R", 4, false),
    ("R3D3", 3, true),
    ("R3D4", 4, true),
];

fn supported_types() -> String {
    ELEMENT_TYPES
        .iter()
        .map(|(name, _, _)| *name)
        .collect::<Vec<_>>()
        .join(", ")
}

type Result<T> = std::result::Result<T, MeshFileError>;

struct Node {
    label: u64,
    position: Vector3<f64>,
    loc: Loc,
}

struct Element {
    label: u64,
    kind: usize,
    nodes: Vec<u64>,
    loc: Loc,
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum SetKind {
    Node,
    Element,
}

impl SetKind {
    fn word(self) -> &'static str {
        match self {
            SetKind::Node => "node",
            SetKind::Element => "element",
        }
    }
}

enum Member {
    Label(u64),
    /// `GENERATE`: first, last, step (step > 0, first <= last).
    Range(u64, u64, u64),
    Set(String),
    /// `*NSET, ELSET=`: the nodes of an element set.
    NodesOf(String),
}

/// One definition of (or addition to) a set.
struct SetEvent {
    kind: SetKind,
    name: String,
    internal: bool,
    members: Vec<(Member, Loc)>,
}

/// A local 1-axis and 2-axis, or a distribution that gives them per element.
enum Axes {
    Fixed(Vector3<f64>, Vector3<f64>),
    Distribution(String),
}

struct Orientation {
    axes: Axes,
    /// Additional rotation about the local 3-axis (radians).
    rotation: f64,
    loc: Loc,
}

enum Thickness {
    Unknown,
    Value(f64),
    Distribution(String),
}

struct Section {
    elset: String,
    orientation: Option<String>,
    thickness: Thickness,
    loc: Loc,
}

struct Distribution {
    location: Option<String>,
    table: Option<String>,
    lines: Vec<DataLine>,
    loc: Loc,
}

struct Table {
    types: Vec<String>,
}

/// The part/assembly structure seen so far.
#[derive(Default)]
struct Structure {
    part: Option<(String, Loc)>,
    in_part: bool,
    instance: Option<(String, Loc)>,
    in_instance: bool,
    /// Nodes or elements read outside any part.
    flat: Option<Loc>,
}

#[derive(Default)]
struct Model {
    nodes: Vec<Node>,
    node_index: HashMap<u64, usize>,
    elements: Vec<Element>,
    element_index: HashMap<u64, usize>,
    sets: Vec<SetEvent>,
    orientations: HashMap<String, Orientation>,
    sections: Vec<Section>,
    distributions: HashMap<String, Distribution>,
    tables: HashMap<String, Table>,
    structure: Structure,
    ignored: Vec<(String, Loc)>,
    notes: Vec<String>,
    normals_ignored: bool,
}

/// Reads the records of `deck` and builds the mesh.
pub(super) fn interpret(deck: &Deck) -> Result<AbaqusMesh> {
    let mut model = Model::default();
    let records = &deck.records;
    let mut i = 0;
    if let Some(Record::Data(line)) = records.first() {
        return Err(deck.error(line.loc, "a data line before any keyword"));
    }
    while i < records.len() {
        let Record::Keyword(keyword) = &records[i] else {
            i += 1;
            continue;
        };
        let mut end = i + 1;
        while matches!(records.get(end), Some(Record::Data(_))) {
            end += 1;
        }
        let data: Vec<&DataLine> = records[i + 1..end]
            .iter()
            .filter_map(|r| match r {
                Record::Data(d) => Some(d),
                Record::Keyword(_) => None,
            })
            .collect();
        model.keyword(deck, keyword, &data)?;
        i = end;
    }
    model.finish(deck)
}

fn parse_label(deck: &Deck, text: &str, what: &str, loc: Loc) -> Result<u64> {
    match text.trim().parse::<u64>() {
        Ok(label) if label > 0 => Ok(label),
        _ => Err(deck.error(
            loc,
            format!("'{text}' is not a {what} label (a positive integer)"),
        )),
    }
}

/// A number as Abaqus writes it (`1.`, `.5`, `1.5E+02`, `1.5D+02`); blank is `default`.
fn parse_number(
    deck: &Deck,
    text: &str,
    what: &str,
    loc: Loc,
    default: Option<f64>,
) -> Result<f64> {
    let t = text.trim();
    if t.is_empty() {
        if let Some(value) = default {
            return Ok(value);
        }
    }
    let value = t.replace(['d', 'D'], "e").parse::<f64>();
    match value {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(deck.error(loc, format!("{what}: '{t}' is not a finite number"))),
    }
}

fn required<'k>(deck: &Deck, keyword: &'k Keyword, key: &str) -> Result<&'k str> {
    match keyword.param(key) {
        Some(v) if !v.is_empty() => Ok(v),
        _ => Err(deck.error(keyword.loc, format!("*{} needs {key}=", keyword.name))),
    }
}

impl Model {
    fn keyword(&mut self, deck: &Deck, keyword: &Keyword, data: &[&DataLine]) -> Result<()> {
        match keyword.name.as_str() {
            "NODE" => self.node(deck, keyword, data),
            "ELEMENT" => self.element(deck, keyword, data),
            "NSET" => self.set(deck, keyword, data, SetKind::Node),
            "ELSET" => self.set(deck, keyword, data, SetKind::Element),
            "ORIENTATION" => self.orientation(deck, keyword, data),
            "SHELL SECTION" | "MEMBRANE SECTION" => self.section(deck, keyword, data),
            "DISTRIBUTION" => {
                let name = canonical(required(deck, keyword, "NAME")?);
                let distribution = Distribution {
                    location: keyword.param("LOCATION").map(canonical),
                    table: keyword.param("TABLE").map(canonical),
                    lines: data.iter().map(|d| (*d).clone()).collect(),
                    loc: keyword.loc,
                };
                if let Some(first) = self.distributions.insert(name.clone(), distribution) {
                    return Err(deck.error(
                        keyword.loc,
                        format!(
                            "distribution '{name}' is defined twice (first at {})",
                            deck.place(first.loc, keyword.loc)
                        ),
                    ));
                }
                Ok(())
            }
            "DISTRIBUTION TABLE" => {
                let name = canonical(required(deck, keyword, "NAME")?);
                let types = data
                    .iter()
                    .flat_map(|d| d.fields.iter())
                    .filter(|f| !f.is_empty())
                    .map(|f| canonical(f))
                    .collect();
                self.tables.insert(name, Table { types });
                Ok(())
            }
            "PART" | "END PART" | "ASSEMBLY" | "END ASSEMBLY" | "INSTANCE" | "END INSTANCE" => {
                self.structure(deck, keyword, data)
            }
            _ => {
                self.ignored.push((keyword.name.clone(), keyword.loc));
                Ok(())
            }
        }
    }

    /// Nodes and elements belong to the single part, or to a flat deck.
    fn check_mesh_place(&mut self, deck: &Deck, keyword: &Keyword) -> Result<()> {
        let s = &mut self.structure;
        if s.part.is_some() && (!s.in_part || s.in_instance) {
            return Err(deck.error(
                keyword.loc,
                format!(
                    "*{} outside the *PART: only the nodes and elements of a single part, or \
                     of a flat deck without *PART, are supported",
                    keyword.name
                ),
            ));
        }
        if s.part.is_none() && s.flat.is_none() {
            s.flat = Some(keyword.loc);
        }
        Ok(())
    }

    /// Strips the instance prefix (`Part-1-1.`) of a member in the assembly.
    fn local<'t>(&self, text: &'t str) -> &'t str {
        if let Some((instance, _)) = &self.structure.instance {
            if let Some((prefix, rest)) = text.split_once('.') {
                if canonical(unquote(prefix)) == canonical(instance) {
                    return rest;
                }
            }
        }
        text
    }

    fn node(&mut self, deck: &Deck, keyword: &Keyword, data: &[&DataLine]) -> Result<()> {
        self.check_mesh_place(deck, keyword)?;
        if let Some(system) = keyword.param("SYSTEM") {
            if canonical(system) != "R" {
                return Err(deck.error(
                    keyword.loc,
                    format!(
                        "*NODE, SYSTEM={system}: only rectangular coordinates (SYSTEM=R, the \
                         default) are supported"
                    ),
                ));
            }
        }
        let mut labels = Vec::with_capacity(data.len());
        for line in data {
            let loc = line.loc;
            let Some(first) = line.fields.first() else {
                continue;
            };
            let label = parse_label(deck, first, "node", loc)?;
            if line.fields.len() > 7 {
                return Err(deck.error(
                    loc,
                    format!(
                        "node {label}: {} values after the label, at most 3 coordinates and 3 \
                         normal components",
                        line.fields.len() - 1
                    ),
                ));
            }
            if line.fields.len() > 4 {
                self.normals_ignored = true;
            }
            let mut x = Vector3::zeros();
            for (k, field) in line.fields.iter().skip(1).take(3).enumerate() {
                x[k] = parse_number(deck, field, &format!("node {label}"), loc, Some(0.0))?;
            }
            if let Some(&first) = self.node_index.get(&label) {
                return Err(deck.error(
                    loc,
                    format!(
                        "node {label} is defined twice (first at {})",
                        deck.place(self.nodes[first].loc, loc)
                    ),
                ));
            }
            self.node_index.insert(label, self.nodes.len());
            self.nodes.push(Node {
                label,
                position: x,
                loc,
            });
            labels.push((Member::Label(label), loc));
        }
        if let Some(name) = keyword.param("NSET").filter(|n| !n.is_empty()) {
            self.sets.push(SetEvent {
                kind: SetKind::Node,
                name: name.to_string(),
                internal: false,
                members: labels,
            });
        }
        Ok(())
    }

    fn element(&mut self, deck: &Deck, keyword: &Keyword, data: &[&DataLine]) -> Result<()> {
        self.check_mesh_place(deck, keyword)?;
        let Some(type_name) = keyword.param("TYPE").filter(|t| !t.is_empty()) else {
            return Err(deck.error(
                keyword.loc,
                format!("*ELEMENT needs TYPE= (supported: {})", supported_types()),
            ));
        };
        let type_name = canonical(type_name);
        let Some(kind) = ELEMENT_TYPES.iter().position(|(n, _, _)| *n == type_name) else {
            return Err(deck.error(
                keyword.loc,
                format!(
                    "element type {type_name} is not supported (supported: {}; the blank is \
                     a shell or membrane surface)",
                    supported_types()
                ),
            ));
        };
        let corners = ELEMENT_TYPES[kind].1;
        let mut labels = Vec::with_capacity(data.len());
        let mut k = 0;
        while k < data.len() {
            // an element's line ending with a comma goes on on the next line
            let loc = data[k].loc;
            let mut fields: Vec<&str> = data[k].fields.iter().map(String::as_str).collect();
            while data[k].continued && fields.len() < 1 + corners && k + 1 < data.len() {
                k += 1;
                fields.extend(data[k].fields.iter().map(String::as_str));
            }
            k += 1;
            let Some(first) = fields.first() else {
                continue;
            };
            let label = parse_label(deck, first, "element", loc)?;
            if fields.len() != 1 + corners {
                return Err(deck.error(
                    loc,
                    format!(
                        "element {label}: {type_name} has {corners} nodes, the line gives {}",
                        fields.len() - 1
                    ),
                ));
            }
            let nodes = fields[1..]
                .iter()
                .map(|f| parse_label(deck, f, "node", loc))
                .collect::<Result<Vec<u64>>>()?;
            if let Some(&first) = self.element_index.get(&label) {
                return Err(deck.error(
                    loc,
                    format!(
                        "element {label} is defined twice (first at {})",
                        deck.place(self.elements[first].loc, loc)
                    ),
                ));
            }
            self.element_index.insert(label, self.elements.len());
            self.elements.push(Element {
                label,
                kind,
                nodes,
                loc,
            });
            labels.push((Member::Label(label), loc));
        }
        if let Some(name) = keyword.param("ELSET").filter(|n| !n.is_empty()) {
            self.sets.push(SetEvent {
                kind: SetKind::Element,
                name: name.to_string(),
                internal: false,
                members: labels,
            });
        }
        Ok(())
    }

    fn set(
        &mut self,
        deck: &Deck,
        keyword: &Keyword,
        data: &[&DataLine],
        kind: SetKind,
    ) -> Result<()> {
        let key = match kind {
            SetKind::Node => "NSET",
            SetKind::Element => "ELSET",
        };
        let name = required(deck, keyword, key)?.to_string();
        if let Some(instance) = keyword.param("INSTANCE") {
            match &self.structure.instance {
                Some((i, _)) if canonical(i) == canonical(instance) => {}
                _ => {
                    return Err(deck.error(
                        keyword.loc,
                        format!(
                            "*{}, INSTANCE={instance}: no such instance (only a single instance \
                             of a single part is supported)",
                            keyword.name
                        ),
                    ))
                }
            }
        }
        let mut members = Vec::new();
        if kind == SetKind::Node {
            if let Some(elset) = keyword.param("ELSET").filter(|e| !e.is_empty()) {
                members.push((Member::NodesOf(canonical(elset)), keyword.loc));
            }
        }
        let generate = keyword.has("GENERATE");
        for line in data {
            let loc = line.loc;
            if generate {
                let values: Vec<&String> = line.fields.iter().filter(|f| !f.is_empty()).collect();
                if !(2..=3).contains(&values.len()) {
                    return Err(deck.error(
                        loc,
                        format!(
                            "GENERATE takes 'first, last[, step]', the line gives {} values",
                            values.len()
                        ),
                    ));
                }
                let what = kind.word();
                let first = parse_label(deck, self.local(values[0]), what, loc)?;
                let last = parse_label(deck, self.local(values[1]), what, loc)?;
                let step = match values.get(2) {
                    Some(s) => s.trim().parse::<u64>().map_err(|_| {
                        deck.error(
                            loc,
                            format!("GENERATE step '{s}' is not a positive integer"),
                        )
                    })?,
                    None => 1,
                };
                if step == 0 {
                    return Err(deck.error(loc, "GENERATE with step 0"));
                }
                if first > last {
                    return Err(deck.error(
                        loc,
                        format!("GENERATE from {first} down to {last}: the first label must not exceed the last"),
                    ));
                }
                members.push((Member::Range(first, last, step), loc));
                continue;
            }
            for field in line.fields.iter().filter(|f| !f.is_empty()) {
                let field = self.local(field);
                let member =
                    if field.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
                        Member::Label(parse_label(deck, field, kind.word(), loc)?)
                    } else {
                        Member::Set(canonical(unquote(field)))
                    };
                members.push((member, loc));
            }
        }
        self.sets.push(SetEvent {
            kind,
            name,
            internal: keyword.has("INTERNAL"),
            members,
        });
        Ok(())
    }
}
