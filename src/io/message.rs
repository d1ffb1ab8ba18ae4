//! How an error reads: one line, its numbers rounded, a cause said once. The command line
//! prints errors so, and a study records a failed case's reason so, whichever front end ran it.

use crate::limits::{shown, SHOWN_DIGITS};

/// The message on one line, without a cause repeated by its context, and with every number
/// written with many digits rounded to [`SHOWN_DIGITS`] significant ones (`1e300`, not 301
/// digits).
pub fn tidy_message(message: &str) -> String {
    let words: Vec<String> = message.split_whitespace().map(round_long_numbers).collect();
    drop_repeated_causes(&words.join(" "))
}

/// Numbers of `word` written with more than [`SHOWN_DIGITS`] + 6 digits rounded to
/// [`SHOWN_DIGITS`]; names with digits in them (`run_2026.csv`, `node12`) are left alone.
fn round_long_numbers(word: &str) -> String {
    let mut out = String::with_capacity(word.len());
    let chars: Vec<char> = word.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        let starts_number = chars[i].is_ascii_digit()
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || "_./\\".contains(chars[i - 1])));
        if !starts_number {
            out.push(chars[i]);
            i += 1;
            continue;
        }
        let end = number_end(&chars, i);
        let token: String = chars[i..end].iter().collect();
        let followed_by_name = chars
            .get(end)
            .is_some_and(|c| c.is_alphabetic() || *c == '_');
        match token.parse::<f64>() {
            Ok(x) if !followed_by_name && written_digits(&token) > SHOWN_DIGITS + 6 => {
                out.push_str(&shown(x))
            }
            _ => out.push_str(&token),
        }
        i = end;
    }
    out
}

/// End of the decimal number (`123`, `1.5`, `2.5e-7`) starting at `start`.
fn number_end(chars: &[char], start: usize) -> usize {
    let digits_from = |mut i: usize| {
        while chars.get(i).is_some_and(char::is_ascii_digit) {
            i += 1;
        }
        i
    };
    let mut end = digits_from(start);
    if chars.get(end) == Some(&'.') && chars.get(end + 1).is_some_and(char::is_ascii_digit) {
        end = digits_from(end + 1);
    }
    if matches!(chars.get(end), Some('e' | 'E')) {
        let sign = usize::from(matches!(chars.get(end + 1), Some('-' | '+')));
        if chars.get(end + 1 + sign).is_some_and(char::is_ascii_digit) {
            end = digits_from(end + 1 + sign);
        }
    }
    end
}

/// Digits written in the mantissa of `token` (leading zeros too: `0.000...01` is as long to
/// read as any other).
fn written_digits(token: &str) -> usize {
    let mantissa = token.split(['e', 'E']).next().unwrap_or(token);
    let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
    digits.len()
}

/// anyhow's `{:#}` joins contexts and causes with `: `; a cause that a context already
/// quotes in full is said once.
fn drop_repeated_causes(message: &str) -> String {
    let parts: Vec<&str> = message.split(": ").collect();
    let mut kept: Vec<&str> = Vec::with_capacity(parts.len());
    for (k, part) in parts.iter().enumerate() {
        let rest = parts[k..].join(": ");
        let said_before = kept.join(": ");
        if k > 0 && rest.len() >= 10 && said_before.contains(&rest) {
            break;
        }
        kept.push(part);
    }
    kept.join(": ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_rounded_and_names_left_alone() {
        let huge = format!("blank.width = {} must be", 1e300);
        assert_eq!(tidy_message(&huge), "blank.width = 1e300 must be");
        let tiny = format!("x = {}", 1.0e-300);
        assert_eq!(tidy_message(&tiny), "x = 1e-300");
        assert_eq!(tidy_message("v = 0.30000000000000004 mm"), "v = 0.3 mm");
        assert_eq!(tidy_message("at 12345.678 s"), "at 12345.678 s");
        let name = "results_123456789012345678/x.csv: run 1234567890123456789x";
        assert_eq!(tidy_message(name), name);
        assert_eq!(
            tidy_message("f = 1.2345678901234567e-12 N"),
            "f = 1.23457e-12 N"
        );
    }

    #[test]
    fn a_cause_quoted_by_its_context_is_said_once() {
        let message = "cannot write a.csv: No space left on device: No space left on device";
        assert_eq!(
            tidy_message(message),
            "cannot write a.csv: No space left on device"
        );
        let distinct = "a.toml: line 3: bad value";
        assert_eq!(tidy_message(distinct), distinct);
    }
}
