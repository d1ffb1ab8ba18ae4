//! Sets and distributions: labels and names looked up, in the order of their definitions.

use super::super::lexer::{canonical, unquote, Deck, Loc};
use super::{parse_label, parse_number, Member, Model, SetKind};
use crate::mesh::{Cell, MeshFileError};
use std::collections::{HashMap, HashSet};

type Result<T> = std::result::Result<T, MeshFileError>;

impl Model {
    /// The sets, resolved in the order of their definitions (a set refers to the sets defined
    /// before it): node indices and element indices, in the order first given.
    pub(super) fn resolve_sets(
        &self,
        deck: &Deck,
        cells: &[Cell],
    ) -> Result<(HashMap<String, IndexSet>, HashMap<String, IndexSet>)> {
        let mut node_sets: HashMap<String, IndexSet> = HashMap::new();
        let mut element_sets: HashMap<String, IndexSet> = HashMap::new();
        for event in &self.sets {
            let key = canonical(&event.name);
            let (index, count) = match event.kind {
                SetKind::Node => (&self.node_index, self.nodes.len()),
                SetKind::Element => (&self.element_index, self.elements.len()),
            };
            let mut set = match event.kind {
                SetKind::Node => node_sets.remove(&key),
                SetKind::Element => element_sets.remove(&key),
            }
            .unwrap_or_else(|| IndexSet::new(event.name.clone()));
            set.internal |= event.internal;
            let word = event.kind.word();
            for (member, loc) in &event.members {
                let unknown = |label: u64| {
                    deck.error(
                        *loc,
                        format!("{word} set '{}': {word} {label} is not defined", event.name),
                    )
                };
                match member {
                    Member::Label(label) => {
                        set.insert(*index.get(label).ok_or_else(|| unknown(*label))?);
                    }
                    Member::Range(first, last, step) => {
                        // every generated label must exist: at most `count` + 1 are looked at
                        let mut label = *first;
                        let mut seen = 0usize;
                        while label <= *last {
                            set.insert(*index.get(&label).ok_or_else(|| unknown(label))?);
                            seen += 1;
                            if seen > count {
                                return Err(unknown(label));
                            }
                            match label.checked_add(*step) {
                                Some(next) => label = next,
                                None => break,
                            }
                        }
                    }
                    Member::Set(name) if *name == key => {} // the set itself: nothing to add
                    Member::Set(name) => {
                        let sets = match event.kind {
                            SetKind::Node => &node_sets,
                            SetKind::Element => &element_sets,
                        };
                        let other = sets.get(name).ok_or_else(|| {
                            deck.error(
                                *loc,
                                format!(
                                    "{word} set '{}': '{name}' is neither a label nor a {word} \
                                     set defined before",
                                    event.name
                                ),
                            )
                        })?;
                        let members = other.order.clone();
                        for m in members {
                            set.insert(m);
                        }
                    }
                    Member::NodesOf(elset) => {
                        let other = element_sets.get(elset).ok_or_else(|| {
                            deck.error(
                                *loc,
                                format!(
                                    "node set '{}': element set '{elset}' is not defined",
                                    event.name
                                ),
                            )
                        })?;
                        for &e in &other.order {
                            for &n in cells[e].nodes() {
                                set.insert(n);
                            }
                        }
                    }
                }
            }
            match event.kind {
                SetKind::Node => node_sets.insert(key, set),
                SetKind::Element => element_sets.insert(key, set),
            };
        }
        Ok((node_sets, element_sets))
    }

    /// The values of distribution `name`, used as `usage` at `used_at`, for element `e`.
    pub(super) fn distribution_value<'c>(
        &self,
        deck: &Deck,
        cache: &'c mut HashMap<String, Resolved>,
        element_sets: &HashMap<String, IndexSet>,
        (name, usage, used_at): (&str, Use, Loc),
        e: usize,
    ) -> Result<&'c [f64]> {
        if !cache.contains_key(name) {
            let resolved = self.resolve_distribution(deck, element_sets, name, usage, used_at)?;
            cache.insert(name.to_string(), resolved);
        }
        let Some(resolved) = cache.get(name) else {
            return Err(deck.error(used_at, format!("distribution '{name}' is not defined")));
        };
        if resolved.usage != usage {
            return Err(deck.error(
                used_at,
                format!("distribution '{name}' is used both for orientations and thicknesses"),
            ));
        }
        match resolved.values.get(&e).or(resolved.default.as_ref()) {
            Some(v) => Ok(v),
            None => Err(deck.error(
                used_at,
                format!(
                    "distribution '{name}' has no value for element {} and no default (a first \
                     data line with a blank label)",
                    self.elements[e].label
                ),
            )),
        }
    }

    fn resolve_distribution(
        &self,
        deck: &Deck,
        element_sets: &HashMap<String, IndexSet>,
        name: &str,
        usage: Use,
        used_at: Loc,
    ) -> Result<Resolved> {
        let d = self
            .distributions
            .get(name)
            .ok_or_else(|| deck.error(used_at, format!("distribution '{name}' is not defined")))?;
        if d.location.as_deref() != Some("ELEMENT") {
            return Err(deck.error(
                d.loc,
                format!("distribution '{name}': only LOCATION=ELEMENT is supported here"),
            ));
        }
        let (expected, count, what): (&[&str], usize, &str) = match usage {
            Use::Orientation => (&["COORD3D", "COORD3D"], 6, "an orientation"),
            Use::Thickness => (&["LENGTH"], 1, "a shell thickness"),
        };
        let table_name = d.table.as_deref().unwrap_or("");
        let table = self.tables.get(table_name).ok_or_else(|| {
            deck.error(
                d.loc,
                format!("distribution '{name}': distribution table '{table_name}' is not defined"),
            )
        })?;
        if table.types != expected {
            return Err(deck.error(
                d.loc,
                format!(
                    "distribution '{name}' is used for {what}, so its table '{table_name}' must \
                     be '{}', not '{}'",
                    expected.join(", "),
                    table.types.join(", ")
                ),
            ));
        }
        let mut resolved = Resolved {
            usage,
            default: None,
            values: HashMap::new(),
        };
        for (k, line) in d.lines.iter().enumerate() {
            let Some(target) = line.fields.first() else {
                continue;
            };
            if line.fields.len() != 1 + count {
                return Err(deck.error(
                    line.loc,
                    format!(
                        "distribution '{name}': {count} values expected after the label, the \
                         line gives {}",
                        line.fields.len() - 1
                    ),
                ));
            }
            let values = line.fields[1..]
                .iter()
                .map(|f| parse_number(deck, f, &format!("distribution '{name}'"), line.loc, None))
                .collect::<Result<Vec<f64>>>()?;
            let target = self.local(target);
            if target.is_empty() {
                if k != 0 {
                    return Err(deck.error(
                        line.loc,
                        "a blank label (the default values) is allowed on the first line only",
                    ));
                }
                resolved.default = Some(values);
            } else if target.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
                let label = parse_label(deck, target, "element", line.loc)?;
                let e = self.element_index.get(&label).ok_or_else(|| {
                    deck.error(
                        line.loc,
                        format!("distribution '{name}': element {label} is not defined"),
                    )
                })?;
                resolved.values.insert(*e, values);
            } else {
                let set = element_sets
                    .get(&canonical(unquote(target)))
                    .ok_or_else(|| {
                        deck.error(
                            line.loc,
                            format!("distribution '{name}': element set '{target}' is not defined"),
                        )
                    })?;
                for &e in &set.order {
                    resolved.values.insert(e, values.clone());
                }
            }
        }
        Ok(resolved)
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Use {
    Orientation,
    Thickness,
}

pub(super) struct Resolved {
    usage: Use,
    default: Option<Vec<f64>>,
    values: HashMap<usize, Vec<f64>>,
}

/// Members in the order first given, each once.
pub(super) struct IndexSet {
    pub(super) name: String,
    pub(super) internal: bool,
    pub(super) order: Vec<usize>,
    members: HashSet<usize>,
}

impl IndexSet {
    fn new(name: String) -> Self {
        Self {
            name,
            internal: false,
            order: Vec::new(),
            members: HashSet::new(),
        }
    }

    fn insert(&mut self, i: usize) {
        if self.members.insert(i) {
            self.order.push(i);
        }
    }
}
