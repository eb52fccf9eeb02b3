//! Material libraries (MTL), read for one thing: each material's diffuse colour `Kd`, whose
//! mean is a surface's reflectivity (`[effects.reflectivity]`).
//!
//! tobj's MTL parser panics on colours the format allows (`Kd 0.5`: the green and blue
//! components are optional and equal red when left out), so it is only given text this file
//! has checked: each `newmtl` line, and each `Kd` line rewritten with its three components.
//! Colours given as a spectral file (`Kd spectral …`) or in CIE XYZ (`Kd xyz …`), and every
//! other statement, are left out: they do not change a reflectivity the product reads. A `Kd`
//! of one to three numbers that are not finite and at least 0 (`nan`, `inf`, `-5`), or of
//! other words, is refused, naming the library, its line and its material: taken as given or
//! left out, it would change the image without a word. (Above 1 is allowed: the format says
//! such a value raises the reflectivity, whose mean the reflectivity effect caps at 1.)

use super::text_lines;
use crate::error::{guard_parser, Error, Result};
use crate::untrusted::quoted;
use std::path::Path;

/// The `newmtl` and `Kd` statements of MTL text, normalised for tobj; `path` names the
/// library in a refusal.
pub(super) fn checked_library(text: &str, path: &Path) -> Result<String> {
    let mut checked = String::new();
    let mut material = String::new();
    for (n, line) in text_lines(text.trim_start_matches('\u{feff}')).enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.splitn(2, char::is_whitespace);
        match (words.next(), words.next().map(str::trim).filter(|rest| !rest.is_empty())) {
            (Some("newmtl"), Some(name)) => {
                checked.push_str("newmtl ");
                checked.push_str(name);
                checked.push('\n');
                material = name.to_string();
            }
            (Some("Kd"), Some(rest)) if !rest.starts_with("spectral") && !rest.starts_with("xyz") => {
                let [r, g, b] = rgb(rest).ok_or_else(|| {
                    let at = format!("line {}, material {}", n + 1, quoted(&material));
                    Error::file(path, format!("{at}: Kd {} must be 1 to 3 finite numbers, at least 0", quoted(rest)))
                })?;
                checked.push_str(&format!("Kd {r:?} {g:?} {b:?}\n"));
            }
            _ => {}
        }
    }
    Ok(checked)
}

/// `r [g [b]]` as three finite components of at least 0, the missing ones equal to r (the MTL
/// format).
fn rgb(text: &str) -> Option<[f32; 3]> {
    let values: Vec<f32> = text.split_whitespace().map(str::parse).collect::<Result<_, _>>().ok()?;
    match values[..] {
        [r] => Some([r, r, r]),
        [r, g] => Some([r, g, r]),
        [r, g, b] => Some([r, g, b]),
        _ => None,
    }
    .filter(|c| c.iter().all(|v| v.is_finite() && *v >= 0.0))
}

/// The materials of checked library text (see [`checked_library`]), through tobj; `name`
/// names the library in messages.
pub(super) fn parse_checked_library(checked: &str, name: &str) -> Result<tobj::MTLLoadResult> {
    guard_parser(name, "tobj's MTL parser", || Ok(tobj::load_mtl_buf(&mut checked.as_bytes())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn optional_colour_components_take_red_and_other_forms_are_left_out() {
        let text = "\u{feff}newmtl grey\r\nKd 0.5\r\nKs 1 1\nnewmtl two\nKd 0.2 0.4 # comment\n\
                    newmtl full\nKd 0.1 0.2 0.3\nnewmtl odd\nKd spectral grey.rfl\nKd xyz 1 1 1\nnewmtl\n";
        let checked = checked_library(text, Path::new("t.mtl")).unwrap();
        assert_eq!(
            checked,
            "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl two\nKd 0.2 0.4 0.2\nnewmtl full\nKd 0.1 0.2 0.3\nnewmtl odd\n"
        );
        let (materials, _) = parse_checked_library(&checked, "t.mtl").unwrap().unwrap();
        let diffuse: Vec<_> = materials.iter().map(|m| (m.name.as_str(), m.diffuse)).collect();
        assert_eq!(
            diffuse,
            [
                ("grey", Some([0.5, 0.5, 0.5])),
                ("two", Some([0.2, 0.4, 0.2])),
                ("full", Some([0.1, 0.2, 0.3])),
                ("odd", None)
            ]
        );
    }

    #[test]
    fn a_kd_that_is_no_reflectance_is_refused_by_line_and_material() {
        for kd in ["nan 0 0", "inf", "-5", "0.5 -0.1", "1e39 0 0", "1 0 0 0", "bright", "0,8"] {
            let text = format!("newmtl first\nKd 0.5\nnewmtl \"odd\"\n\nKd {kd}\n");
            let e = checked_library(&text, Path::new("m.mtl")).unwrap_err().to_string();
            let expected = format!(
                "m.mtl: line 5, material \"\\\"odd\\\"\": Kd \"{kd}\" must be 1 to 3 finite numbers, at least 0"
            );
            assert_eq!(e, expected);
        }
        let bright = "newmtl edges\nKd 0 1 0.25\nnewmtl bright\nKd 1.2 1.0000001 8e-1\n";
        assert!(checked_library(bright, Path::new("m.mtl")).is_ok());
    }

    #[test]
    fn tobj_alone_panics_on_a_grey_kd() {
        // The reason for checked_library: if tobj stops panicking here, the rewrite can go.
        let outcome = std::panic::catch_unwind(|| tobj::load_mtl_buf(&mut "newmtl g\nKd 0.5\n".as_bytes()));
        assert!(outcome.is_err());
    }
}
