//! The text formats read with a dependency's parser (TOML scenes and header attributes, JSON
//! hypothesis files): each behind the panic boundary (error.rs, `guard_parser`), and with
//! errors that say where and why without echoing the offending line, which an input can make
//! megabytes long and fill with terminal escapes.

use crate::error::{guard_parser, Error, Result};
use crate::untrusted::{escaped, parser_error};
use serde::de::DeserializeOwned;

/// TOML text parsed into `T`; errors are `Error::Scene`, with the line.
pub fn parse_toml<T: DeserializeOwned>(text: &str) -> Result<T> {
    guard_parser("the TOML text", "the toml parser", || {
        toml::from_str(text).map_err(|e| {
            let at = e.span().map(|span| format!("line {}: ", line_of(text, span.start)));
            // The parser gives some errors (a NUL in a comment) no message of their own.
            let message = match e.message().trim() {
                "" => "not valid TOML (a character the format does not allow there?)",
                message => message,
            };
            Error::Scene(format!("{}{}", at.unwrap_or_default(), escaped(message, 300)))
        })
    })
}

/// JSON text parsed into `T`; errors are `Error::Scene`, with the line and column.
pub fn parse_json<T: DeserializeOwned>(text: &str) -> Result<T> {
    guard_parser("the JSON text", "serde_json", || {
        serde_json::from_str(text).map_err(|e| Error::Scene(parser_error(e)))
    })
}

/// The line (from 1) holding byte `offset` of `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())].iter().filter(|&&b| b == b'\n').count() + 1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Doc {
        a: u32,
    }

    #[test]
    fn an_error_names_the_line_without_echoing_it() {
        let long = format!("a = 1\nunknown = [{}\u{1b}[2J]\n", "1, ".repeat(100_000));
        let e = parse_toml::<Doc>(&long).unwrap_err().to_string();
        assert!(e.starts_with("invalid scene: line 2: "), "{e}");
        assert!(e.len() < 500 && !e.contains('\u{1b}'), "{} bytes: {}", e.len(), &e[..e.len().min(300)]);
        let e = parse_toml::<Doc>("a = 1\n# a \0 in a comment\n").unwrap_err().to_string();
        assert_eq!(e, "invalid scene: line 2: not valid TOML (a character the format does not allow there?)");
        let e = parse_json::<Doc>(&format!("{{\"a\": 1, \"b{}\": 2}}", "x".repeat(100_000))).unwrap_err().to_string();
        assert!(e.len() < 500 && e.contains("unknown field"), "{} bytes", e.len());
    }
}
