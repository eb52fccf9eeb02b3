//! Strings from inputs (ids, surface and model names, a parser's echo of a line) shown in
//! messages: a file can hold escape sequences that rewrite a terminal, newlines that forge
//! lines of output, or a megabyte on one line. Every such string passes through [`escaped`]
//! before it is put into a message.

use std::fmt::Write;

/// A dependency parser's error as a message may carry it: it may quote the input it failed
/// on (a line, a token), so it is escaped and cut like any string from an input.
pub fn parser_error(error: impl std::fmt::Display) -> String {
    escaped(&error.to_string(), 300)
}

/// `text` with its control characters (C0, DEL, C1, and the Unicode format characters that
/// reorder or hide text) written as escapes, cut after `limit` characters with a note of how
/// much was left out.
pub fn escaped(text: &str, limit: usize) -> String {
    escape(text, limit, false)
}

/// [`escaped`] in quotes, its own quotes and backslashes escaped, at most 80 characters: how
/// an id or a name appears in a message.
pub fn quoted(text: &str) -> String {
    format!("\"{}\"", escape(text, 80, true))
}

fn escape(text: &str, limit: usize, quoting: bool) -> String {
    let mut shown = String::with_capacity(text.len().min(limit * 4));
    for (count, c) in text.chars().enumerate() {
        if count == limit {
            let cut = text.char_indices().nth(limit).map_or(text.len(), |(i, _)| i);
            let _ = write!(shown, "… ({} more bytes)", text.len() - cut);
            break;
        }
        if c.is_control() || is_format_control(c) || (quoting && matches!(c, '"' | '\\')) {
            shown.extend(c.escape_default());
        } else {
            shown.push(c);
        }
    }
    shown
}

/// Bidirectional overrides and isolates, zero-width characters, the byte-order mark.
fn is_format_control(c: char) -> bool {
    matches!(c, '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{2069}' | '\u{feff}')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_long_text_is_cut() {
        assert_eq!(escaped("a\u{1b}[2Jb\nc\u{202e}d\u{7f}", 100), "a\\u{1b}[2Jb\\nc\\u{202e}d\\u{7f}");
        assert_eq!(escaped("é😀", 100), "é😀");
        assert_eq!(escaped(&"x".repeat(1000), 10), format!("{}… (990 more bytes)", "x".repeat(10)));
        assert_eq!(quoted("h\"1\\\n"), r#""h\"1\\\n""#);
    }
}
