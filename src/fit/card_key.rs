//! One key of one section of a material card replaced in the card's text, for fits that set a
//! few keys of a section (`warp_tension`, `weft_tension`, `shear` of `[fabric]`) rather than a
//! whole section (see [`super::card_section`]). Only the value and the fit's provenance
//! comments above it change (the value may span several lines, as an array can); everything
//! else, the user's comments included, stays byte for byte.

/// How the provenance a fit writes above a key begins (its first comment line, after `# `).
/// A re-fit recognises its earlier provenance by it and replaces it instead of stacking a
/// second one, so running a fit on its own output gives the same card.
pub const FIT_MARKER: &str = "Fitted by `thermostamp fit";

/// `card` with the value of `key` in the table `[section]` replaced by `value` (TOML text,
/// e.g. `[4.0e4, 2.0e6]`), and `provenance` lines (without `#`; the first one starting with
/// [`FIT_MARKER`]) put as comments just above the key. Dropped with the old value: a comment
/// after it on its last line, and an earlier fit's provenance (the comment lines above the key
/// from the nearest one starting with [`FIT_MARKER`] down). A key the section lacks is added
/// at the end of the section. Errors: no such section, or a value that does not end (an
/// unclosed array).
pub fn replace_key(
    card: &str,
    section: &str,
    key: &str,
    value: &str,
    provenance: &[String],
) -> Result<String, String> {
    let (start, end) = section_span(card, section)
        .ok_or_else(|| format!("the card has no [{section}] section"))?;
    let comment: String = provenance.iter().map(|l| format!("# {l}\n")).collect();
    let Some((line_start, value_start)) = key_position(card, start, end, key) else {
        let insert_at = end_of_content(card, start, end);
        let separator = if card[..insert_at].ends_with('\n') {
            ""
        } else {
            "\n"
        };
        return Ok(format!(
            "{}{separator}{comment}{key} = {value}\n{}",
            &card[..insert_at],
            &card[insert_at..]
        ));
    };
    let value_end = value_end(card, value_start)
        .ok_or_else(|| format!("[{section}] {key}: the value does not end"))?;
    Ok(format!(
        "{}{comment}{}{value}{}",
        &card[..earlier_provenance(card, start, line_start)],
        &card[line_start..value_start],
        &card[trailing_comment_end(card, value_end)..]
    ))
}

/// `card` without the line(s) of `key = ...` in `[section]` (a fit that no longer uses a term
/// drops its key); the comments around it stay. A card without the key is returned as it is.
pub fn remove_key(card: &str, section: &str, key: &str) -> Result<String, String> {
    let (start, end) = section_span(card, section)
        .ok_or_else(|| format!("the card has no [{section}] section"))?;
    let Some((line_start, value_start)) = key_position(card, start, end, key) else {
        return Ok(card.to_string());
    };
    let value_end = value_end(card, value_start)
        .ok_or_else(|| format!("[{section}] {key}: the value does not end"))?;
    let kept_from = trailing_comment_end(card, value_end);
    let line_end = card[kept_from..]
        .find('\n')
        .map_or(card.len(), |i| kept_from + i + 1);
    let rest = if card[kept_from..line_end].trim().is_empty() {
        line_end
    } else {
        kept_from
    };
    Ok(format!("{}{}", &card[..line_start], &card[rest..]))
}

/// Start of the provenance an earlier fit wrote above the key line at `key_line` (which is in
/// the section body starting at `start`), or `key_line` when there is none: among the comment
/// lines directly above the key, the nearest one starting with [`FIT_MARKER`]. Comments above
/// it are the user's and stay.
fn earlier_provenance(card: &str, start: usize, key_line: usize) -> usize {
    let above = &card[start..key_line];
    line_offsets(above)
        .into_iter()
        .rev()
        .take_while(|&(s, e)| above[s..e].trim_start().starts_with('#'))
        .find(|&(s, e)| is_fit_marker(&above[s..e]))
        .map_or(key_line, |(s, _)| start + s)
}

/// Whether `line` is the first comment line of a fit's provenance.
fn is_fit_marker(line: &str) -> bool {
    line.trim_start()
        .strip_prefix('#')
        .is_some_and(|comment| comment.trim_start().starts_with(FIT_MARKER))
}

/// Where the text after the value ending at `value_end` is kept from: the end of its line
/// (before the newline) when only spaces and a comment follow the value, which then go with
/// it; `value_end` otherwise.
fn trailing_comment_end(card: &str, value_end: usize) -> usize {
    let line_end = card[value_end..]
        .find('\n')
        .map_or(card.len(), |i| value_end + i);
    let rest = card[value_end..line_end].trim_end_matches('\r');
    let after = rest.trim_start();
    if after.is_empty() || after.starts_with('#') {
        value_end + rest.len()
    } else {
        value_end
    }
}

/// `v` to 6 significant digits, always a TOML float (`280.0`, `0.000294`, `1.25e-3`).
pub fn toml_float(v: f64) -> String {
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    format!("{rounded:?}")
}

/// `[a, b, ...]`, each a [`toml_float`]: the value of a fitted coefficient key.
pub fn toml_array(values: &[f64]) -> String {
    let floats: Vec<String> = values.iter().map(|&v| toml_float(v)).collect();
    format!("[{}]", floats.join(", "))
}

/// Byte range of the body of `[section]`: from after its header line to the start of the next
/// table header (or the end).
fn section_span(card: &str, section: &str) -> Option<(usize, usize)> {
    let lines = line_offsets(card);
    let header = lines
        .iter()
        .position(|&(s, e)| header_name(&card[s..e]) == Some(section))?;
    let start = lines[header].1;
    let end = lines[header + 1..]
        .iter()
        .find(|&&(s, e)| header_name(&card[s..e]).is_some())
        .map_or(card.len(), |&(s, _)| s);
    Some((start, end))
}

/// `(start, end)` of each line, the end including its newline.
fn line_offsets(text: &str) -> Vec<(usize, usize)> {
    let mut offsets = Vec::new();
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        offsets.push((start, start + line.len()));
        start += line.len();
    }
    offsets
}

/// Start of the line of `key = ...` in `card[start..end]` and the start of its value.
fn key_position(card: &str, start: usize, end: usize, key: &str) -> Option<(usize, usize)> {
    let mut offset = start;
    for line in card[start..end].split_inclusive('\n') {
        let indent = line.len() - line.trim_start().len();
        let rest = &line[indent..];
        if let Some(after) = rest.strip_prefix(key) {
            let spaces = after.len() - after.trim_start().len();
            if let Some(value) = after[spaces..].strip_prefix('=') {
                let blank = value.len() - value.trim_start().len();
                let value_at = offset + indent + key.len() + spaces + 1 + blank;
                return Some((offset, value_at));
            }
        }
        offset += line.len();
    }
    None
}

/// End of the TOML value starting at `start`: past the matching `]` (or `}`) of an array or
/// inline table, skipping strings and comments; a plain value ends before a comment or the end
/// of its line, trailing spaces excluded.
fn value_end(card: &str, start: usize) -> Option<usize> {
    let bytes = card.as_bytes();
    if !matches!(bytes.get(start), Some(b'[') | Some(b'{')) {
        let line_end = card[start..].find('\n').map_or(card.len(), |i| start + i);
        let plain = &card[start..line_end];
        let plain = plain.split('#').next().unwrap_or("").trim_end();
        return Some(start + plain.len());
    }
    let mut depth = 0usize;
    let mut i = start;
    while i < bytes.len() {
        match bytes[i] {
            b'[' | b'{' => depth += 1,
            b']' | b'}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(i + 1);
                }
            }
            b'#' => i += card[i..].find('\n').unwrap_or(card.len() - i),
            quote @ (b'"' | b'\'') => {
                i += 1 + card[i + 1..].find(quote as char)?;
            }
            _ => {}
        }
        i += 1;
    }
    None
}

/// Where a new key goes: after the last non-blank line of the section body.
fn end_of_content(card: &str, start: usize, end: usize) -> usize {
    let body = &card[start..end];
    let trimmed = body.trim_end();
    if trimmed.is_empty() {
        return start;
    }
    let content_end = start + trimmed.len();
    card[content_end..end]
        .find('\n')
        .map_or(end, |i| content_end + i + 1)
}

/// The name of a TOML table header line (`[name]` or `[[name]]`, a comment may follow).
pub(super) fn header_name(line: &str) -> Option<&str> {
    let line = line.split('#').next()?.trim();
    let inner = line.strip_prefix('[')?.strip_suffix(']')?;
    let inner = inner
        .strip_prefix('[')
        .and_then(|s| s.strip_suffix(']'))
        .unwrap_or(inner)
        .trim();
    let is_key = |c: char| c.is_ascii_alphanumeric() || "_-.\" ".contains(c);
    (!inner.is_empty() && inner.chars().all(is_key)).then_some(inner)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A key's line goes, with its trailing comment; its neighbours and a key of a longer name
    /// that starts like it stay; a missing key leaves the card as it is.
    #[test]
    fn a_removed_key_takes_its_line_only() {
        let card = "[fabric]\nshear = [1.0]\nshear_friction = 0.5 # k0\nshear_friction_onset = 2.0\n[bending]\nwarp = 1.0\n";
        let removed = remove_key(card, "fabric", "shear_friction").unwrap();
        assert_eq!(
            removed,
            "[fabric]\nshear = [1.0]\nshear_friction_onset = 2.0\n[bending]\nwarp = 1.0\n"
        );
        assert_eq!(remove_key(card, "fabric", "shear_locking").unwrap(), card);
        assert_eq!(remove_key(card, "bending", "shear").unwrap(), card);
        assert!(remove_key(card, "matrix", "c10").is_err());
    }

    const CARD: &str = "[layers]\nwarp_tension = 1\n\n[fabric]\n# A_k\nwarp_tension = [4.0e4,\n  2.0e6] # MPa\nweft_tension = [1.0]\nshear = [0.25] # c_k\n\n[bending]\nwarp = 1.0\n";

    /// Provenance as a fit writes it: the marker line, then details.
    fn fitted(run: &str) -> Vec<String> {
        vec![
            format!("{FIT_MARKER} shear` to {run}.csv"),
            format!("Standard errors of {run}"),
        ]
    }

    #[test]
    fn replaces_only_the_value_of_the_key_in_its_section() {
        let out = replace_key(CARD, "fabric", "weft_tension", "[5.0]", &[]).unwrap();
        assert_eq!(
            out,
            CARD.replace("weft_tension = [1.0]", "weft_tension = [5.0]")
        );
        let out = replace_key(CARD, "bending", "warp", "2.0", &[]).unwrap();
        assert_eq!(out, CARD.replace("warp = 1.0", "warp = 2.0"));
        let out = replace_key("[a]\n  k=1.0   \n", "a", "k", "2.0", &[]).unwrap();
        assert_eq!(out, "[a]\n  k=2.0\n");
    }

    #[test]
    fn a_multi_line_array_and_its_trailing_comment_are_replaced() {
        let out = replace_key(CARD, "fabric", "warp_tension", "[5.0, 6.0]", &[]).unwrap();
        assert_eq!(
            out,
            CARD.replace("[4.0e4,\n  2.0e6] # MPa", "[5.0, 6.0]"),
            "{out}"
        );
        let out = replace_key(CARD, "fabric", "shear", "[1.0, 2.0]", &fitted("a")).unwrap();
        assert_eq!(
            out,
            CARD.replace(
                "shear = [0.25] # c_k",
                "# Fitted by `thermostamp fit shear` to a.csv\n# Standard errors of a\nshear = [1.0, 2.0]"
            )
        );
        let crlf = "[a]\r\nk = [1, # one\r\n  2] # two\r\nm = 3\r\n";
        let out = replace_key(crlf, "a", "k", "[4]", &[]).unwrap();
        assert_eq!(out, "[a]\r\nk = [4]\r\nm = 3\r\n");
    }

    /// Fitting a fit's output again gives what fitting the original once gives.
    #[test]
    fn a_re_fit_replaces_the_earlier_provenance_instead_of_stacking_it() {
        for key in ["shear", "warp_tension", "compression_fraction"] {
            let once = replace_key(CARD, "fabric", key, "[2.0]", &fitted("b")).unwrap();
            let first = replace_key(CARD, "fabric", key, "[1.0]", &fitted("a")).unwrap();
            let twice = replace_key(&first, "fabric", key, "[2.0]", &fitted("b")).unwrap();
            assert_eq!(twice, once, "{key}");
            let again = replace_key(&once, "fabric", key, "[2.0]", &fitted("b")).unwrap();
            assert_eq!(again, once, "{key}");
        }
    }

    #[test]
    fn user_comments_above_the_provenance_and_other_keys_provenance_stay() {
        let card = "[fabric]\n# Fitted by `thermostamp fit fabric-tension` w\nwarp = [1.0]\n# user note\n# Fitted by `thermostamp fit shear` old\n# Standard errors old\nshear = [1.0]\n";
        let out = replace_key(card, "fabric", "shear", "[2.0]", &fitted("new")).unwrap();
        assert_eq!(
            out,
            "[fabric]\n# Fitted by `thermostamp fit fabric-tension` w\nwarp = [1.0]\n# user note\n# Fitted by `thermostamp fit shear` to new.csv\n# Standard errors of new\nshear = [2.0]\n"
        );
        // A user comment with no fit's marker, right above the key, is not provenance.
        let out = replace_key(CARD, "fabric", "warp_tension", "[3.0]", &fitted("a")).unwrap();
        assert!(out.contains("# A_k\n# Fitted by"), "{out}");
    }

    #[test]
    fn a_missing_key_is_added_and_a_missing_section_is_an_error() {
        let out = replace_key(CARD, "fabric", "compression_fraction", "0.01", &[]).unwrap();
        assert_eq!(
            out,
            CARD.replace("# c_k\n", "# c_k\ncompression_fraction = 0.01\n")
        );
        let out = replace_key("[fabric]\na = 1", "fabric", "b", "2", &["fit".into()]).unwrap();
        assert_eq!(out, "[fabric]\na = 1\n# fit\nb = 2\n");
        assert!(replace_key(CARD, "matrix", "c10", "[1.0]", &[])
            .unwrap_err()
            .contains("no [matrix] section"));
        assert!(
            replace_key("[fabric]\nshear = [1.0,\n", "fabric", "shear", "[2.0]", &[])
                .unwrap_err()
                .contains("does not end")
        );
    }

    #[test]
    fn floats_are_toml_floats() {
        assert_eq!(toml_float(280.0), "280.0");
        assert_eq!(toml_float(0.000294123456), "0.000294123");
        assert_eq!(toml_float(1.0 / 750.0), "0.00133333");
        assert_eq!(toml_array(&[1.0, 2.5e-7]), "[1.0, 2.5e-7]");
        assert_eq!(toml_array(&[]), "[]");
    }
}
