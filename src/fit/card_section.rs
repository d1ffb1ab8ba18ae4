//! The `[matrix]` section of a material card written from a fit, and its replacement in an
//! existing card's text (fits that set single keys use [`super::card_key`]). The replacement is
//! textual so that the rest of the card, comments included, stays exactly as it was.

use super::card_key::{header_name, toml_float};
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
