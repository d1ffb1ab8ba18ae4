//! The `[matrix]` section of a material card written from a fit, and its replacement in an
//! existing card's text; the `[fabric] shear` key likewise. The replacement is textual so that the rest of the card, comments
//! included, stays exactly as it was.

use super::card_key::header_name;
use super::matrix::{Eta1, TemperatureFit};

/// The `[matrix]` section (header, provenance comments, the four tables) for `fits`, which are
/// in increasing temperature. `provenance` lines become comments.
pub fn matrix_section(fits: &[TemperatureFit], provenance: &[String]) -> String {
    let mut text = String::from("[matrix]\n");
    for line in provenance {
        text.push_str(&format!("# {line}\n"));
    }
    let standard_errors =
        |f: &dyn Fn(&TemperatureFit) -> String| fits.iter().map(f).collect::<Vec<_>>().join(", ");
    text.push_str(&format!(
        "# Standard errors: c10 [{}] MPa; eta1 [{}] MPa·s (\"card\": kept from the input card, \
         a single rate at that temperature).\n",
        standard_errors(&|f| format!("{:.2e}", f.c10_standard_error)),
        standard_errors(&|f| match f.eta1 {
            Eta1::Fitted { standard_error, .. } => format!("{standard_error:.2e}"),
            Eta1::FromCard { .. } => "card".into(),
        }),
    ));
    let row = |key: &str, value: &dyn Fn(&TemperatureFit) -> f64| {
        let values: Vec<String> = fits.iter().map(|f| toml_float(value(f))).collect();
        format!("{key} = [{}]\n", values.join(", "))
    };
    text.push_str(&row("temperature", &|f| f.temperature));
    text.push_str(&row("c10", &|f| f.c10));
    text.push_str(&row("d1", &|f| f.d1));
    text.push_str(&row("eta1", &|f| f.eta1.value()));
    text
}

/// `v` to 6 significant digits, always a TOML float (`280.0`, `0.000294`, `1.25e-3`).
fn toml_float(v: f64) -> String {
    let rounded: f64 = format!("{v:.5e}").parse().unwrap_or(v);
    format!("{rounded:?}")
}

/// `card` with its `[matrix]` section (from its header to the next table header) replaced by
/// `section`, or with `section` appended when it has none.
pub fn replace_matrix_section(card: &str, section: &str) -> String {
    let lines: Vec<&str> = card.lines().collect();
    let Some(start) = lines.iter().position(|l| header_name(l) == Some("matrix")) else {
        let separator = if card.ends_with('\n') || card.is_empty() {
            "\n"
        } else {
            "\n\n"
        };
        return format!("{card}{separator}{section}");
    };
    let end = (start + 1..lines.len())
        .find(|&i| header_name(lines[i]).is_some())
        .unwrap_or(lines.len());
    let mut out: Vec<String> = lines[..start].iter().map(|l| l.to_string()).collect();
    out.push(section.trim_end().to_string());
    if end < lines.len() {
        out.push(String::new());
        out.extend(lines[end..].iter().map(|l| l.to_string()));
    }
    out.join("\n") + "\n"
}

/// `card` with the `shear = [...]` key of its `[fabric]` section (one line or a bracketed
/// value over several) replaced by `provenance` comment lines and `shear = [coefficients]`;
/// every other line is kept as it was. `None` when the card has no `[fabric] shear` key.
pub fn replace_fabric_shear(
    card: &str,
    coefficients: &[f64],
    provenance: &[String],
) -> Option<String> {
    let lines: Vec<&str> = card.lines().collect();
    let start = lines
        .iter()
        .position(|l| header_name(l) == Some("fabric"))?;
    let end = (start + 1..lines.len())
        .find(|&i| header_name(lines[i]).is_some())
        .unwrap_or(lines.len());
    let key = (start + 1..end).find(|&i| key_name(lines[i]) == Some("shear"))?;
    let mut depth = 0i32;
    let mut last = key;
    for (i, line) in lines.iter().enumerate().take(end).skip(key) {
        let code = line.split('#').next().unwrap_or("");
        depth += code.matches('[').count() as i32 - code.matches(']').count() as i32;
        last = i;
        if depth <= 0 {
            break;
        }
    }
    // A previous fit's provenance right above the key goes with it.
    let mut first = key;
    while first > start + 1 && is_shear_provenance(lines[first - 1]) {
        first -= 1;
    }
    let values: Vec<String> = coefficients.iter().map(|&c| toml_float(c)).collect();
    let mut out: Vec<String> = lines[..first].iter().map(|l| l.to_string()).collect();
    out.extend(provenance.iter().map(|l| format!("# {l}")));
    out.push(format!("shear = [{}]", values.join(", ")));
    out.extend(lines[last + 1..].iter().map(|l| l.to_string()));
    Some(out.join("\n") + "\n")
}

/// The comment lines `fit shear` writes above the key (see `cli::fit`).
fn is_shear_provenance(line: &str) -> bool {
    line.starts_with("# Fitted by `thermostamp fit shear`")
        || line.starts_with("# Standard errors [")
}

/// The key of a `key = value` line, if it is one.
fn key_name(line: &str) -> Option<&str> {
    let code = line.split('#').next()?;
    let (key, _) = code.split_once('=')?;
    let key = key.trim();
    (!key.is_empty() && key.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')).then_some(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_only_the_fabric_shear_key() {
        let card = "name = \"x\"\nshear = 1\n[fabric]\n# about shear\nwarp = [1.0]\nshear = [0.1,\n  0.2] # old\ncompression_fraction = 1e-3\n[bending]\nshear = 3\n";
        let out = replace_fabric_shear(card, &[0.5, 0.25], &["fitted".into()]).unwrap();
        assert_eq!(
            out,
            "name = \"x\"\nshear = 1\n[fabric]\n# about shear\nwarp = [1.0]\n# fitted\nshear = [0.5, 0.25]\ncompression_fraction = 1e-3\n[bending]\nshear = 3\n"
        );
        assert_eq!(
            replace_fabric_shear("[fabric]\nwarp = 1\n", &[1.0], &[]),
            None
        );
    }

    #[test]
    fn replaces_only_the_matrix_section() {
        let card = "name = \"x\"\n[layers]\na = 1\n\n[matrix]\n# old\nc10 = [1.0,\n  2.0]\n\n[fabric]\nb = 2\n";
        let out = replace_matrix_section(card, "[matrix]\nc10 = [3.0]\n");
        assert_eq!(
            out,
            "name = \"x\"\n[layers]\na = 1\n\n[matrix]\nc10 = [3.0]\n\n[fabric]\nb = 2\n"
        );
        let last = replace_matrix_section(
            "[fabric]\nb = 2\n[matrix]\nc10 = 1\n",
            "[matrix]\nc10 = [3.0]\n",
        );
        assert_eq!(last, "[fabric]\nb = 2\n[matrix]\nc10 = [3.0]\n");
        let none = replace_matrix_section("[fabric]\nb = 2\n", "[matrix]\nc10 = [3.0]\n");
        assert_eq!(none, "[fabric]\nb = 2\n\n[matrix]\nc10 = [3.0]\n");
    }

    #[test]
    fn floats_are_toml_floats() {
        assert_eq!(toml_float(280.0), "280.0");
        assert_eq!(toml_float(0.000294123456), "0.000294123");
        assert_eq!(toml_float(1.0 / 750.0), "0.00133333");
    }
}
