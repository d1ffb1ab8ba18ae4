//! The lines of a deck: comments and blank lines dropped, keyword lines split into a name and
//! parameters, data lines into fields, and the files named by `*INCLUDE, INPUT=` (and by
//! `INPUT=` on the keywords whose data the reader uses) read in their place.

use crate::mesh::MeshFileError;
use std::path::{Component, Path, PathBuf};

/// Reads the text of an included file (the path is the included name joined to the including
/// file's folder).
pub type IncludeReader<'a> = dyn FnMut(&Path) -> std::io::Result<String> + 'a;

/// How deep `*INCLUDE` may nest: deeper is taken for a runaway and refused.
pub(super) const MAX_INCLUDE_DEPTH: usize = 16;

/// How many files one deck may read in all (a file included many times counts each time):
/// more is taken for a runaway and refused.
pub(super) const MAX_FILES: usize = 1000;

/// Keywords whose `INPUT=` parameter names a file holding their data lines, and whose data
/// the reader uses. `INPUT=` on any other keyword is left alone (the keyword is ignored).
const DATA_FROM_FILE: [&str; 5] = ["NODE", "ELEMENT", "NSET", "ELSET", "DISTRIBUTION"];

/// Where a record comes from: the index of the file in [`Deck::files`] and the line (from 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Loc {
    pub file: usize,
    pub line: usize,
}

/// `*NAME, KEY=value, FLAG`: the name upper case with single spaces (`SHELL SECTION`), the
/// keys likewise, the values as written less surrounding quotes.
#[derive(Clone, Debug)]
pub(super) struct Keyword {
    pub name: String,
    pub params: Vec<(String, Option<String>)>,
    pub loc: Loc,
}

impl Keyword {
    /// The value of `key` (upper case): `Some("")` for a flag without a value.
    pub fn param(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_deref().unwrap_or(""))
    }

    pub fn has(&self, key: &str) -> bool {
        self.params.iter().any(|(k, _)| k == key)
    }
}

/// A data line: its comma-separated fields, trimmed (quotes kept, so that a quoted set name is
/// never taken for a label); `continued` when the line ends with a comma.
#[derive(Clone, Debug)]
pub(super) struct DataLine {
    pub fields: Vec<String>,
    pub continued: bool,
    pub loc: Loc,
}

#[derive(Clone, Debug)]
pub(super) enum Record {
    Keyword(Keyword),
    Data(DataLine),
}

/// Every record of a deck and its included files, in reading order.
#[derive(Debug, Default)]
pub(super) struct Deck {
    pub files: Vec<String>,
    pub records: Vec<Record>,
}

impl Deck {
    pub fn error(&self, loc: Loc, message: impl Into<String>) -> MeshFileError {
        MeshFileError::at_line(self.file(loc), loc.line, message)
    }

    pub fn file(&self, loc: Loc) -> &str {
        self.files.get(loc.file).map(String::as_str).unwrap_or("")
    }

    /// `line 12` in the same file as `here`, `b.inp line 12` in another.
    pub fn place(&self, loc: Loc, here: Loc) -> String {
        if loc.file == here.file {
            format!("line {}", loc.line)
        } else {
            format!("{} line {}", self.file(loc), loc.line)
        }
    }
}

/// Splits `text` (the contents of `file`) into records, reading included files through
/// `read`.
pub(super) fn lex(
    text: &str,
    file: &Path,
    read: &mut IncludeReader<'_>,
) -> Result<Deck, MeshFileError> {
    let mut deck = Deck::default();
    let mut stack = vec![normalise(file)];
    lex_file(text, file, false, &mut stack, &mut deck, read)?;
    Ok(deck)
}

fn lex_file(
    text: &str,
    path: &Path,
    data_only: bool,
    stack: &mut Vec<PathBuf>,
    deck: &mut Deck,
    read: &mut IncludeReader<'_>,
) -> Result<(), MeshFileError> {
    let file = deck.files.len();
    deck.files.push(path.display().to_string());
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l)).peekable();
    while let Some((number, raw)) = lines.next() {
        let loc = Loc { file, line: number };
        let line = raw.trim();
        if line.is_empty() || line.starts_with("**") {
            continue;
        }
        if let Some(rest) = line.strip_prefix('*') {
            if data_only {
                return Err(deck.error(
                    loc,
                    "a file read through INPUT= holds data lines only, but this line is a keyword",
                ));
            }
            // a keyword line ending with a comma goes on on the next line, which then starts
            // with a parameter `NAME=` (a data line starts with a number, or names a set)
            let mut keyword_text = rest.to_string();
            while keyword_text.trim_end().ends_with(',') {
                match lines.peek() {
                    Some((_, more)) if more.trim().starts_with("**") => {
                        lines.next();
                    }
                    Some((_, more))
                        if more.trim().starts_with(|c: char| c.is_ascii_alphabetic())
                            && more.contains('=') =>
                    {
                        keyword_text.push_str(more.trim());
                        lines.next();
                    }
                    _ => break,
                }
            }
            let keyword = parse_keyword(&keyword_text, loc).map_err(|m| deck.error(loc, m))?;
            if keyword.name == "INCLUDE" {
                include(&keyword, path, stack, deck, read, false)?;
            } else if DATA_FROM_FILE.contains(&keyword.name.as_str()) && keyword.has("INPUT") {
                let keyword_copy = keyword.clone();
                deck.records.push(Record::Keyword(keyword));
                include(&keyword_copy, path, stack, deck, read, true)?;
            } else {
                deck.records.push(Record::Keyword(keyword));
            }
        } else {
            let (fields, continued) = split_data(line);
            deck.records.push(Record::Data(DataLine {
                fields,
                continued,
                loc,
            }));
        }
    }
    Ok(())
}

/// Reads the file named by `keyword`'s `INPUT=` relative to `including`.
fn include(
    keyword: &Keyword,
    including: &Path,
    stack: &mut Vec<PathBuf>,
    deck: &mut Deck,
    read: &mut IncludeReader<'_>,
    data_only: bool,
) -> Result<(), MeshFileError> {
    let loc = keyword.loc;
    let name = match keyword.param("INPUT") {
        Some(name) if !name.is_empty() => name,
        _ => return Err(deck.error(loc, format!("*{} needs INPUT=file", keyword.name))),
    };
    let target = including
        .parent()
        .map(|folder| folder.join(name))
        .unwrap_or_else(|| PathBuf::from(name));
    let key = normalise(&target);
    if let Some(first) = stack.iter().position(|p| *p == key) {
        let chain: Vec<String> = stack[first..]
            .iter()
            .chain(std::iter::once(&key))
            .map(|p| p.display().to_string())
            .collect();
        return Err(deck.error(loc, format!("*INCLUDE cycle: {}", chain.join(" includes "))));
    }
    if stack.len() > MAX_INCLUDE_DEPTH {
        return Err(deck.error(
            loc,
            format!(
                "included files nest more than {MAX_INCLUDE_DEPTH} deep (at '{}')",
                target.display()
            ),
        ));
    }
    if deck.files.len() >= MAX_FILES {
        return Err(deck.error(
            loc,
            format!(
                "the deck reads more than {MAX_FILES} files (includes included again and again?)"
            ),
        ));
    }
    let text = read(&target).map_err(|e| {
        deck.error(
            loc,
            format!("cannot read '{name}' ({}): {e}", target.display()),
        )
    })?;
    stack.push(key);
    let result = lex_file(&text, &target, data_only, stack, deck, read);
    stack.pop();
    result
}

/// `a/./b/../c.inp` as `a/c.inp`, for recognising a file included twice in a chain.
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for component in path.components() {
        match component {
            Component::CurDir => {}
            Component::ParentDir => {
                if !matches!(out.components().next_back(), Some(Component::Normal(_))) || !out.pop()
                {
                    out.push("..");
                }
            }
            other => out.push(other.as_os_str()),
        }
    }
    out
}

/// Upper case, runs of white space as one space.
pub(super) fn canonical(text: &str) -> String {
    text.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .to_uppercase()
}

/// `"a, b"` without its quotes; anything else trimmed.
pub(super) fn unquote(text: &str) -> &str {
    let t = text.trim();
    t.strip_prefix('"')
        .and_then(|s| s.strip_suffix('"'))
        .unwrap_or(t)
}

/// Splits at commas outside double quotes.
fn split_fields(text: &str) -> Vec<&str> {
    let mut fields = Vec::new();
    let mut start = 0;
    let mut quoted = false;
    for (i, c) in text.char_indices() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => {
                fields.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    fields.push(&text[start..]);
    fields
}

fn parse_keyword(text: &str, loc: Loc) -> Result<Keyword, String> {
    let mut fields = split_fields(text).into_iter();
    let name = canonical(fields.next().unwrap_or(""));
    if name.is_empty() {
        return Err("a keyword line without a keyword".to_string());
    }
    let mut params = Vec::new();
    for field in fields {
        if field.trim().is_empty() {
            continue;
        }
        let (key, value) = match split_once_unquoted(field, '=') {
            Some((k, v)) => (canonical(k), Some(unquote(v).to_string())),
            None => (canonical(field), None),
        };
        if key.is_empty() {
            return Err(format!(
                "*{name}: a parameter without a name ('{}')",
                field.trim()
            ));
        }
        params.push((key, value));
    }
    Ok(Keyword { name, params, loc })
}

fn split_once_unquoted(text: &str, separator: char) -> Option<(&str, &str)> {
    let mut quoted = false;
    for (i, c) in text.char_indices() {
        if c == '"' {
            quoted = !quoted;
        } else if c == separator && !quoted {
            return Some((&text[..i], &text[i + c.len_utf8()..]));
        }
    }
    None
}

fn split_data(line: &str) -> (Vec<String>, bool) {
    let mut fields: Vec<String> = split_fields(line)
        .into_iter()
        .map(|f| f.trim().to_string())
        .collect();
    let continued = line.ends_with(',');
    if continued {
        fields.pop();
    }
    (fields, continued)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    fn lex_files(files: &[(&str, &str)]) -> Result<Deck, MeshFileError> {
        let map: HashMap<PathBuf, String> = files
            .iter()
            .map(|(p, t)| (PathBuf::from(p), t.to_string()))
            .collect();
        let mut read = |p: &Path| {
            map.get(p)
                .cloned()
                .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"))
        };
        lex(files[0].1, Path::new(files[0].0), &mut read)
    }

    #[test]
    fn keywords_parameters_and_data_fields() {
        let deck = lex_files(&[(
            "d/main.inp",
            "** comment\n\n*Shell  Section, elset=\"Blank, A\", Material = M,\n  orientation=Ori-1\n0.31, 5,\n",
        )])
        .unwrap();
        assert_eq!(deck.records.len(), 2);
        let Record::Keyword(k) = &deck.records[0] else {
            panic!("{:?}", deck.records[0])
        };
        assert_eq!(k.name, "SHELL SECTION");
        assert_eq!(k.param("ELSET"), Some("Blank, A"));
        assert_eq!(k.param("MATERIAL"), Some("M"));
        assert_eq!(k.param("ORIENTATION"), Some("Ori-1"));
        assert_eq!(k.loc, Loc { file: 0, line: 3 });
        let Record::Data(d) = &deck.records[1] else {
            panic!()
        };
        assert_eq!(d.fields, ["0.31", "5"]);
        assert!(d.continued);
        assert_eq!(d.loc.line, 5);
    }

    #[test]
    fn a_keyword_line_goes_on_only_onto_a_line_of_parameters() {
        let deck = lex_files(&[(
            "d.inp",
            "*NSET, NSET=A,\nB, C\n*ELSET, ELSET=E,\nGENERATE\n",
        )])
        .unwrap();
        let kinds: Vec<bool> = deck
            .records
            .iter()
            .map(|r| matches!(r, Record::Keyword(_)))
            .collect();
        assert_eq!(kinds, [true, false, true, false]);
    }

    #[test]
    fn includes_are_read_relative_to_the_including_file_and_cycles_are_refused() {
        let deck = lex_files(&[
            ("d/main.inp", "*NODE\n*INCLUDE, INPUT=sub/a.inp\n*END"),
            ("d/sub/a.inp", "1, 0, 0\n*INCLUDE, INPUT=../b.inp\n"),
            ("d/sub/../b.inp", "2, 1, 0\n"),
        ])
        .unwrap();
        assert_eq!(deck.files, ["d/main.inp", "d/sub/a.inp", "d/sub/../b.inp"]);
        assert_eq!(deck.records.len(), 4);
        let e = lex_files(&[
            ("d/main.inp", "*INCLUDE, INPUT=a.inp"),
            ("d/a.inp", "*INCLUDE, INPUT=./main.inp"),
        ])
        .unwrap_err();
        assert_eq!((e.file.as_str(), e.line), ("d/a.inp", Some(1)));
        assert!(e.message.contains("cycle"), "{e}");
        let e = lex_files(&[("d/main.inp", "\n*INCLUDE, INPUT=gone.inp")]).unwrap_err();
        assert_eq!((e.file.as_str(), e.line), ("d/main.inp", Some(2)));
        assert!(e.message.contains("gone.inp"), "{e}");
    }

    #[test]
    fn normalise_resolves_dots() {
        assert_eq!(normalise(Path::new("a/./b/../c.inp")), Path::new("a/c.inp"));
        assert_eq!(normalise(Path::new("../x/../y")), Path::new("../y"));
    }
}
