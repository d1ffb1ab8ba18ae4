//! The keywords that describe more than nodes, elements and sets: the part/assembly structure,
//! orientations and sections.

use super::super::lexer::{canonical, unquote, DataLine, Deck, Keyword};
use super::resolve::frame;
use super::{parse_number, required, Axes, Model, Orientation, Section, Thickness};
use crate::mesh::MeshFileError;
use nalgebra::Vector3;

type Result<T> = std::result::Result<T, MeshFileError>;

impl Model {
    pub(super) fn structure(
        &mut self,
        deck: &Deck,
        keyword: &Keyword,
        data: &[&DataLine],
    ) -> Result<()> {
        let s = &mut self.structure;
        let loc = keyword.loc;
        match keyword.name.as_str() {
            "PART" => {
                let name = keyword.param("NAME").unwrap_or("").to_string();
                if let Some((first, first_loc)) = &s.part {
                    return Err(deck.error(
                        loc,
                        format!(
                            "a second *PART ('{name}'; '{first}' at {}): only a single part, or \
                             a flat deck without *PART, is supported",
                            deck.place(*first_loc, loc)
                        ),
                    ));
                }
                if let Some(flat) = s.flat {
                    return Err(deck.error(
                        loc,
                        format!(
                            "*PART after nodes or elements outside any part ({}): only a single \
                             part, or a flat deck without *PART, is supported",
                            deck.place(flat, loc)
                        ),
                    ));
                }
                s.part = Some((name, loc));
                s.in_part = true;
            }
            "END PART" => s.in_part = false,
            "ASSEMBLY" | "END ASSEMBLY" => {}
            "INSTANCE" => {
                let name = keyword.param("NAME").unwrap_or("").to_string();
                if let Some((first, first_loc)) = &s.instance {
                    return Err(deck.error(
                        loc,
                        format!(
                            "a second *INSTANCE ('{name}'; '{first}' at {}): only a single \
                             instance of a single part is supported",
                            deck.place(*first_loc, loc)
                        ),
                    ));
                }
                let part = keyword.param("PART").unwrap_or("");
                match &s.part {
                    Some((p, _)) if canonical(p) == canonical(part) => {}
                    _ => {
                        return Err(deck.error(
                            loc,
                            format!(
                                "*INSTANCE '{name}' of part '{part}', which is not the deck's \
                                 part: only a single instance of a single part is supported"
                            ),
                        ))
                    }
                }
                // data lines: a translation, then a rotation (axis points and an angle)
                for (n, line) in data.iter().enumerate() {
                    let values = line
                        .fields
                        .iter()
                        .map(|f| parse_number(deck, f, "instance transform", line.loc, Some(0.0)))
                        .collect::<Result<Vec<f64>>>()?;
                    let identity = match n {
                        0 => values.iter().all(|v| *v == 0.0),
                        1 => values.get(6).is_none_or(|angle| *angle == 0.0),
                        _ => false,
                    };
                    if !identity {
                        return Err(deck.error(
                            line.loc,
                            "an *INSTANCE with a translation or rotation: instance transforms \
                             are not supported (place the part in its final position)",
                        ));
                    }
                }
                s.instance = Some((name, loc));
                s.in_instance = true;
            }
            _ => s.in_instance = false, // END INSTANCE
        }
        Ok(())
    }

    pub(super) fn orientation(
        &mut self,
        deck: &Deck,
        keyword: &Keyword,
        data: &[&DataLine],
    ) -> Result<()> {
        let loc = keyword.loc;
        let name = canonical(required(deck, keyword, "NAME")?);
        let system = keyword.param("SYSTEM").map(canonical);
        if system.as_deref().is_some_and(|s| s != "RECTANGULAR") {
            return Err(deck.error(
                loc,
                format!(
                    "*ORIENTATION, SYSTEM={}: only SYSTEM=RECTANGULAR (the default) is \
                     supported (not CYLINDRICAL, SPHERICAL, Z RECTANGULAR or USER)",
                    keyword.param("SYSTEM").unwrap_or("")
                ),
            ));
        }
        let definition = keyword.param("DEFINITION").map(canonical);
        if definition.as_deref().is_some_and(|d| d != "COORDINATES") {
            return Err(deck.error(
                loc,
                format!(
                    "*ORIENTATION, DEFINITION={}: only DEFINITION=COORDINATES (the default: \
                     points a, b and c, or a distribution of them) is supported",
                    keyword.param("DEFINITION").unwrap_or("")
                ),
            ));
        }
        if keyword.has("LOCAL DIRECTIONS") {
            return Err(deck.error(loc, "*ORIENTATION, LOCAL DIRECTIONS is not supported"));
        }
        let Some(first) = data.first() else {
            return Err(deck.error(
                loc,
                "*ORIENTATION needs a data line: a1, a2, a3, b1, b2, b3[, c1, c2, c3] or the name \
                 of a distribution",
            ));
        };
        let fields: Vec<&String> = first.fields.iter().collect();
        let axes = if fields.len() == 1
            && !fields[0].starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c))
        {
            Axes::Distribution(canonical(unquote(fields[0])))
        } else {
            if !(6..=9).contains(&fields.len()) {
                return Err(deck.error(
                    first.loc,
                    format!(
                        "*ORIENTATION: {} values, expected a1, a2, a3, b1, b2, b3[, c1, c2, c3]",
                        fields.len()
                    ),
                ));
            }
            let mut v = [0.0; 9];
            for (k, f) in fields.iter().enumerate() {
                v[k] = parse_number(deck, f, "*ORIENTATION", first.loc, Some(0.0))?;
            }
            let c = Vector3::new(v[6], v[7], v[8]);
            let a = Vector3::new(v[0], v[1], v[2]) - c;
            let b = Vector3::new(v[3], v[4], v[5]) - c;
            let (e1, e2) = frame(a, b).ok_or_else(|| {
                deck.error(
                    first.loc,
                    "*ORIENTATION: points a and b are collinear with the origin c (or a is at c)",
                )
            })?;
            Axes::Fixed(e1, e2)
        };
        let mut rotation = 0.0;
        if let Some(second) = data.get(1) {
            let l = second.loc;
            let axis = match second.fields.first().map(|f| f.trim()) {
                None | Some("") => 1,
                Some(text) => match text.parse::<u8>() {
                    Ok(a @ 1..=3) => a,
                    _ => {
                        return Err(deck.error(
                            l,
                            format!("*ORIENTATION: local axis '{text}' is not 1, 2 or 3"),
                        ))
                    }
                },
            };
            let angle = match second.fields.get(1) {
                None => 0.0,
                Some(text) if text.starts_with(|c: char| c.is_ascii_alphabetic()) => {
                    return Err(deck.error(
                        l,
                        "*ORIENTATION: an additional rotation given by a distribution is not \
                         supported (give the angle in degrees)",
                    ))
                }
                Some(text) => parse_number(deck, text, "*ORIENTATION angle", l, Some(0.0))?,
            };
            if axis != 3 && angle != 0.0 {
                return Err(deck.error(
                    l,
                    format!(
                        "*ORIENTATION: an additional rotation about local axis {axis}: only \
                         rotations about axis 3 (the shell normal: the ply angle) are supported"
                    ),
                ));
            }
            rotation = angle.to_radians();
        }
        if let Some(extra) = data.get(2) {
            return Err(deck.error(extra.loc, "*ORIENTATION takes at most two data lines"));
        }
        if let Some(first) = self.orientations.get(&name) {
            return Err(deck.error(
                loc,
                format!(
                    "orientation '{}' is defined twice (first at {})",
                    keyword.param("NAME").unwrap_or(""),
                    deck.place(first.loc, loc)
                ),
            ));
        }
        self.orientations.insert(
            name,
            Orientation {
                axes,
                rotation,
                loc,
            },
        );
        Ok(())
    }

    pub(super) fn section(
        &mut self,
        deck: &Deck,
        keyword: &Keyword,
        data: &[&DataLine],
    ) -> Result<()> {
        let loc = keyword.loc;
        let elset = canonical(required(deck, keyword, "ELSET")?);
        let orientation = keyword
            .param("ORIENTATION")
            .filter(|o| !o.is_empty())
            .map(canonical);
        let thickness = if let Some(d) = keyword.param("SHELL THICKNESS").filter(|d| !d.is_empty())
        {
            Thickness::Distribution(canonical(d))
        } else if keyword.has("COMPOSITE") || keyword.has("NODAL THICKNESS") {
            self.notes.push(format!(
                "*{} of '{}' ({} line {}): {}, so its elements have no thickness",
                keyword.name,
                keyword.param("ELSET").unwrap_or(""),
                deck.file(loc),
                loc.line,
                if keyword.has("COMPOSITE") {
                    "the layers of a composite section are not read"
                } else {
                    "NODAL THICKNESS is not read"
                },
            ));
            Thickness::Unknown
        } else {
            match data
                .first()
                .and_then(|d| d.fields.first().map(|f| (f, d.loc)))
            {
                Some((text, l)) if !text.is_empty() => {
                    let t = parse_number(deck, text, "section thickness", l, None)?;
                    if t <= 0.0 {
                        return Err(deck.error(l, format!("section thickness {t} is not positive")));
                    }
                    Thickness::Value(t)
                }
                _ => Thickness::Unknown,
            }
        };
        self.sections.push(Section {
            elset,
            orientation,
            thickness,
            loc,
        });
        Ok(())
    }
}
