//! The README and the book under docs/ hold together: every relative link between them (and to
//! the repository's files) resolves, anchors included, every page of the book is listed in
//! its index, and the README stays a front page (at most 300 lines). Their Rust code is
//! compiled and run as doc tests (src/lib.rs). CPU only: this reads Markdown.

use std::collections::HashSet;
use std::fs;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// README.md and every Markdown page directly under docs/.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md")];
    let mut book: Vec<PathBuf> = fs::read_dir(root().join("docs"))
        .expect("docs/ is readable")
        .map(|entry| entry.expect("a docs/ entry").path())
        .filter(|path| path.extension().is_some_and(|e| e == "md"))
        .collect();
    book.sort();
    pages.extend(book);
    pages
}

/// The page's lines outside fenced code blocks, with inline code spans removed.
fn prose(text: &str) -> Vec<String> {
    let mut in_fence = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        // Drop what lies between pairs of backticks.
        let kept: String = line.split('`').step_by(2).collect::<Vec<_>>().join("");
        lines.push(kept);
    }
    assert!(!in_fence, "a code fence is never closed");
    lines
}

/// Link targets, `[text](target)` and `![alt](target)`, outside code.
fn links(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for line in prose(text) {
        let mut rest = line.as_str();
        while let Some(start) = rest.find("](") {
            let after = &rest[start + 2..];
            let end = after.find(')').unwrap_or_else(|| panic!("an unclosed link in {line:?}"));
            found.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    found
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces as hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a page's headings (code spans keep their text in GitHub's anchors).
fn anchors(text: &str) -> HashSet<String> {
    let mut in_fence = false;
    let mut anchors = HashSet::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
        } else if !in_fence && line.starts_with('#') {
            anchors.insert(slug(line.trim_start_matches('#')));
        }
    }
    anchors
}

#[test]
fn every_link_between_the_pages_resolves() {
    let mut checked = 0;
    let mut broken = Vec::new();
    for page in pages() {
        let text = fs::read_to_string(&page).unwrap();
        let dir = page.parent().unwrap();
        for target in links(&text) {
            if target.starts_with("http://") || target.starts_with("https://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path, anchor) = match target.split_once('#') {
                Some((path, anchor)) => (path, Some(anchor)),
                None => (target.as_str(), None),
            };
            let file = if path.is_empty() { page.clone() } else { dir.join(path) };
            let shown = format!("{}: {target}", page.strip_prefix(root()).unwrap().display());
            if !file.exists() {
                broken.push(format!("{shown} (no such file)"));
                continue;
            }
            if let Some(anchor) = anchor {
                let linked = fs::read_to_string(&file).unwrap_or_default();
                if !anchors(&linked).contains(anchor) {
                    broken.push(format!("{shown} (no heading with this anchor)"));
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
    assert!(checked > 50, "only {checked} links were found: is the parser broken?");
}

#[test]
fn the_book_index_lists_every_page() {
    let index = fs::read_to_string(root().join("docs/README.md")).unwrap();
    let listed: HashSet<String> = links(&index).into_iter().map(|t| t.split('#').next().unwrap().to_string()).collect();
    let unlisted: Vec<String> = pages()
        .iter()
        .filter(|p| p.parent() == Some(root().join("docs").as_path()))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .filter(|name| name != "README.md" && !listed.contains(name))
        .collect();
    assert!(unlisted.is_empty(), "docs/README.md does not list {unlisted:?}");
}

#[test]
fn the_readme_is_a_front_page() {
    let lines = fs::read_to_string(root().join("README.md")).unwrap().lines().count();
    assert!(lines <= 300, "README.md has {lines} lines: move reference material into docs/");
}

#[test]
fn anchors_follow_githubs_rule() {
    assert_eq!(slug(" The paper's ambiguities, and what was decided"), "the-papers-ambiguities-and-what-was-decided");
    assert_eq!(slug("Coincident faces: the tie rule"), "coincident-faces-the-tie-rule");
    assert_eq!(
        slug("Four runs of 2026-11-26 (the lavapipe figures of performance.md)"),
        "four-runs-of-2026-11-26-the-lavapipe-figures-of-performancemd"
    );
}

/// Every file under `dir` (recursively) whose name ends in one of `extensions`.
fn files_under(dir: &std::path::Path, extensions: &[&str], out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("a readable folder").flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_under(&path, extensions, out);
        } else if path.extension().is_some_and(|e| extensions.iter().any(|x| e == *x)) {
            out.push(path);
        }
    }
}

/// The repository paths a text names (`src/…`, `shaders/…`, `tests/…`, `tools/…`, `docs/…`),
/// leaving out patterns (`effect_*.comp`, `effect_NAME.comp`).
fn paths_named(text: &str) -> Vec<String> {
    let mut paths = Vec::new();
    for (at, _) in text.match_indices('/') {
        let start = text[..at]
            .char_indices()
            .rev()
            .find(|&(_, c)| !(c.is_ascii_alphanumeric() || c == '_'))
            .map_or(0, |(i, c)| i + c.len_utf8());
        let before = text[..start].chars().next_back();
        let root = &text[start..at];
        if !["src", "shaders", "tests", "tools", "docs"].contains(&root)
            || before.is_some_and(|c| c == '/' || c == '.' || c.is_alphanumeric())
        {
            continue;
        }
        let rest: String =
            text[at..].chars().take_while(|c| c.is_ascii_alphanumeric() || "_./-*".contains(*c)).collect();
        let path = format!("{root}{}", rest.trim_end_matches(['.', '-']));
        if !path.contains('*') && !path.contains("NAME") {
            paths.push(path);
        }
    }
    paths
}

/// Comments and pages name files by their paths; a file moved or renamed must take them along.
#[test]
fn every_repository_path_the_docs_and_comments_name_exists() {
    let mut texts = pages();
    texts.push(root().join("build.rs"));
    for (dir, extensions) in [
        ("src", &["rs"][..]),
        ("shaders", &["glsl", "comp", "vert", "frag"]),
        ("tests", &["rs"]),
        ("tools", &["rs", "sh", "md"]),
    ] {
        files_under(&root().join(dir), extensions, &mut texts);
    }
    let mut missing = Vec::new();
    for file in &texts {
        let text = fs::read_to_string(file).expect("a readable file");
        for path in paths_named(&text) {
            if !root().join(&path).exists() {
                missing.push(format!("{}: {path}", file.strip_prefix(root()).unwrap().display()));
            }
        }
    }
    assert!(texts.len() > 100, "the sources were read");
    assert!(missing.is_empty(), "paths that name no file:\n{}", missing.join("\n"));
    assert_eq!(
        paths_named("see src/render/mod.rs, not xsrc/a.rs nor shaders/stages/effect_*.comp."),
        ["src/render/mod.rs"]
    );
}
