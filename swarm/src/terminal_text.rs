//! Text from users and parsers made fit for one line on a terminal: [`printable`] escapes every
//! control character, [`one_line`] folds a parser's message of several lines into one, and
//! [`toml_error`] says where in a TOML file an error stands.

use std::fmt::Write as _;

/// A TOML error in one line: where (line, column and the line's text) and what.
#[must_use]
pub fn toml_error(text: &str, e: &toml::de::Error) -> String {
    let Some(span) = e.span() else {
        return one_line(e.message());
    };
    let before = &text[..span.start.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    let source: String = text
        .lines()
        .nth(line - 1)
        .unwrap_or_default()
        .trim()
        .chars()
        .take(60)
        .collect();
    format!(
        "line {line}, column {column} (`{source}`): {}",
        one_line(e.message())
    )
}

/// `text` safe to show on a terminal, in one line: every control character (ESC, newline,
/// carriage return, tab, backspace, DEL, the C1 controls such as CSI), every Unicode format
/// character (general category Cf: the bidirectional controls such as U+202E, the zero-width
/// characters, the byte-order mark, the tag characters) and the line and paragraph separators
/// are written as escapes (`\e`, `\n`, `\r`, `\t`, `\u{9b}`, `\u{202e}`), so no text from a
/// file or an argument can move the cursor, recolour or retitle the terminal, reorder what is
/// shown, hide characters, or break a one-line message into lines. Everything else is kept as
/// it is.
///
/// This is the one place where text that came from a user is made printable: every message
/// that echoes a path, a value, a line of a file or a message built from them goes through
/// it (the error line `h8swarm` prints, `sweep merge`'s and `sweep run`'s lists, `emu`'s
/// reports).
#[must_use]
pub fn printable(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\u{1b}' => out.push_str("\\e"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() || is_format_char(c) => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
            c => out.push(c),
        }
    }
    out
}

pub use robot_board::symbols::is_format_char;

/// A number as messages show it: as Rust prints it, but in exponent form when it is very
/// large or very small (`1e308`, `1e-320`), never hundreds of digits.
#[must_use]
pub fn number(v: f64) -> String {
    let a = v.abs();
    if v.is_finite() && a != 0.0 && !(1e-6..1e15).contains(&a) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A message of several lines (the TOML parser's, with its source excerpt) in one: the
/// excerpt's lines dropped, the rest joined by `: `, and what is left made [`printable`].
#[must_use]
pub fn one_line(text: &str) -> String {
    let joined = text
        .lines()
        .map(str::trim)
        .filter(|l| {
            !l.is_empty()
                && !l.starts_with('|')
                && !l.starts_with("TOML parse error")
                && !l
                    .split_once('|')
                    .is_some_and(|(n, _)| n.trim().chars().all(|c| c.is_ascii_digit()))
        })
        .collect::<Vec<_>>()
        .join(": ");
    printable(&short_numbers(&joined))
}

/// `text` with every written-out number of more than 20 characters (a parser's `1e308` as
/// 309 digits) put in [`number`]'s exponent form.
#[must_use]
pub fn short_numbers(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find(|c: char| c.is_ascii_digit()) {
        out.push_str(&rest[..start]);
        let tail = &rest[start..];
        let len = tail
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(tail.len());
        let token = &tail[..len];
        match token.parse::<f64>() {
            Ok(v) if len > 20 => out.push_str(&number(v)),
            _ => out.push_str(token),
        }
        rest = &tail[len..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn printable_text_has_no_control_characters_left() {
        assert_eq!(printable("plain `x` = 1.5"), "plain `x` = 1.5");
        assert_eq!(printable("a\u{1b}]0;title\u{7}b"), "a\\e]0;title\\u{7}b");
        assert_eq!(printable("two\nlines\r\t"), "two\\nlines\\r\\t");
        assert_eq!(
            printable("\u{9b}31m\u{202e}x\u{7f}"),
            "\\u{9b}31m\\u{202e}x\\u{7f}"
        );
        assert_eq!(printable("Ω é"), "Ω é");
        // Format characters: a right-to-left override, zero-width ones, a byte-order mark, a
        // tag, the line separator.
        assert_eq!(
            printable("a\u{202e}b\u{200b}c\u{2060}d\u{feff}e\u{e0041}f\u{2028}g"),
            "a\\u{202e}b\\u{200b}c\\u{2060}d\\u{feff}e\\u{e0041}f\\u{2028}g"
        );
        for c in (0u32..0x110000).filter_map(char::from_u32) {
            let p = printable(&c.to_string());
            assert!(
                !p.chars().any(|c| c.is_control() || is_format_char(c)),
                "U+{:04X}",
                u32::from(c)
            );
        }
        // A TOML error with a source excerpt is one printable line.
        assert_eq!(
            one_line("TOML parse error at line 1\n  |\n1 | a\u{1b}\n  |\n bad \u{1b}[2J"),
            "bad \\e[2J"
        );
    }

    #[test]
    fn numbers_in_messages_are_short() {
        assert_eq!(number(0.45), "0.45");
        assert_eq!(number(1e308), "1e308");
        assert_eq!(number(1e-320), "1e-320");
        assert_eq!(number(-2.5e20), "-2.5e20");
        assert_eq!(number(0.0), "0");
        assert_eq!(number(f64::NAN), "NaN");
        assert_eq!(number(123_456.0), "123456");
        let long = format!(
            "invalid type: floating point `1{}`, expected u32",
            "0".repeat(308)
        );
        assert_eq!(
            short_numbers(&long),
            "invalid type: floating point `1e308`, expected u32"
        );
        let tiny = format!("`x` = 0.{}1 at line 12", "0".repeat(319));
        assert_eq!(short_numbers(&tiny), "`x` = 1e-320 at line 12");
        assert_eq!(
            short_numbers("line 3, column 7: 1.5 and 20"),
            "line 3, column 7: 1.5 and 20"
        );
    }
}
