//! The library's modules import in one direction: no cycle among the top-level modules of
//! `src/`, and none among the files of any one folder (`src/render/`, `src/verify/`, …). A
//! module that imports from another which imports it back is one concept split in two, or a
//! definition in the wrong file; this test names the cycle when one comes back.
//!
//! It reads the sources: every `crate::…` and `super::…` path outside comments and test
//! modules (in `use` declarations, braces expanded, and inline) is an edge from the file to
//! the module it names. The binary (`src/main.rs`, `src/cli/`) is another crate and is left
//! out.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module's path below the crate: `["render", "raster", "draw"]` for src/render/raster/draw.rs.
type ModulePath = Vec<String>;

fn module_of(file: &Path, src: &Path) -> ModulePath {
    let relative = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: ModulePath = relative.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib")) {
        parts.pop();
    }
    parts
}

fn library_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "cli") {
                library_files(&path, out);
            }
        } else if path.extension().is_some_and(|e| e == "rs") && path.file_name().is_some_and(|n| n != "main.rs") {
            out.push(path);
        }
    }
}

/// The code of a file without its comments, strings and `#[cfg(test)]` module.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(at) => &text[..at],
        None => text,
    };
    let mut code = String::with_capacity(text.len());
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => {
                for c in chars.by_ref() {
                    if c == '\n' {
                        code.push('\n');
                        break;
                    }
                }
            }
            '/' if chars.peek() == Some(&'*') => {
                let mut last = ' ';
                for c in chars.by_ref() {
                    if last == '*' && c == '/' {
                        break;
                    }
                    last = c;
                }
            }
            // A character literal of a double quote opens no string.
            '\'' if text_at_quote_literal(&mut chars) => code.push_str("' '"),
            '"' => {
                let mut escaped = false;
                for c in chars.by_ref() {
                    if c == '"' && !escaped {
                        break;
                    }
                    escaped = c == '\\' && !escaped;
                }
                code.push_str("\"\"");
            }
            _ => code.push(c),
        }
    }
    code
}

/// Whether the characters after a `'` are `"'` (the literal `'"'`), which it then consumes.
fn text_at_quote_literal(chars: &mut std::iter::Peekable<std::str::Chars>) -> bool {
    let mut ahead = chars.clone();
    if ahead.next() == Some('"') && ahead.next() == Some('\'') {
        chars.next();
        chars.next();
        return true;
    }
    false
}

/// Every path a piece of code names from `crate::` or `super::`, `use` trees expanded.
fn paths_named(code: &str) -> Vec<String> {
    let mut paths = Vec::new();
    for statement in code.split(';') {
        match use_tree(statement) {
            Some(tree) => expand(&tree, "", &mut paths),
            None => paths.extend(inline_paths(statement)),
        }
    }
    paths.retain(|p| p.starts_with("crate::") || p.starts_with("super::"));
    // `Item as Alias` names Item.
    paths.iter().map(|p| p.split('@').next().unwrap_or(p).to_string()).collect()
}

/// The tree of a `use` declaration (`pub`, `pub(crate)` … included, attributes before it
/// skipped), without whitespace.
fn use_tree(statement: &str) -> Option<String> {
    let at = statement.lines().position(|line| {
        let line = line.trim_start();
        line.starts_with("use ") || line.starts_with("pub use ") || line.starts_with("pub(")
    })?;
    let statement = statement.lines().skip(at).collect::<Vec<_>>().join("\n");
    let statement = statement.trim();
    let tree = statement
        .strip_prefix("use ")
        .or_else(|| statement.strip_prefix("pub use "))
        .or_else(|| statement.split_once(") use ").map(|(_, rest)| rest))?;
    // `Item as Alias` keeps its two names apart: `Item@Alias`.
    Some(tree.replace(" as ", "@").split_whitespace().collect())
}

/// What a folder's module (`mod.rs`, `lib.rs`) brings in with `use`, which its children
/// may name through it (`super::Buffer`): (folder, name) → the path it stands for, from the
/// crate's root.
fn reexports(files: &[PathBuf], src: &Path) -> BTreeMap<(ModulePath, String), String> {
    let mut names = BTreeMap::new();
    for file in files.iter().filter(|f| f.file_name().is_some_and(|n| n == "mod.rs" || n == "lib.rs")) {
        let folder = module_of(file, src);
        let mut paths = Vec::new();
        for statement in code_of(&std::fs::read_to_string(file).unwrap()).split(';') {
            if let Some(tree) = use_tree(statement) {
                expand(&tree, "", &mut paths);
            }
        }
        for path in paths {
            let (path, name) = match path.split_once('@') {
                Some((path, alias)) => (path.to_string(), alias.to_string()),
                None => (path.clone(), path.rsplit("::").next().unwrap().to_string()),
            };
            let absolute = match path.strip_prefix("crate::") {
                Some(rest) => rest.to_string(),
                None if path.starts_with("super::") || path.starts_with("std::") => continue,
                None => [folder.join("::"), path.clone()]
                    .iter()
                    .filter(|s| !s.is_empty())
                    .cloned()
                    .collect::<Vec<_>>()
                    .join("::"),
            };
            names.insert((folder.clone(), name), format!("crate::{absolute}"));
        }
    }
    names
}

fn expand(tree: &str, prefix: &str, out: &mut Vec<String>) {
    match tree.find('{') {
        None => out.push(format!("{prefix}{tree}")),
        Some(open) => {
            let head = format!("{prefix}{}", &tree[..open]);
            let inner = &tree[open + 1..tree.rfind('}').unwrap()];
            let mut depth = 0;
            let mut start = 0;
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand(&inner[start..i], &head, out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            if !inner[start..].is_empty() {
                expand(&inner[start..], &head, out);
            }
        }
    }
}

fn inline_paths(code: &str) -> Vec<String> {
    let mut found = Vec::new();
    for root in ["crate::", "super::"] {
        let mut rest = code;
        while let Some(at) = rest.find(root) {
            let before = rest[..at].chars().next_back();
            let path: String =
                rest[at..].chars().take_while(|c| c.is_alphanumeric() || *c == '_' || *c == ':').collect();
            if !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':') {
                found.push(path.trim_end_matches(':').to_string());
            }
            rest = &rest[at + root.len()..];
        }
    }
    found
}

/// The module a path names, resolved from `from` (the naming file's module) to the longest
/// prefix that is a module of the crate, and through what a folder's module brings in.
fn resolve(path: &str, from: &ModulePath, modules: &BTreeSet<ModulePath>, reexports: &Reexports) -> ModulePath {
    let target = resolve_modules(path, from, modules);
    let named = path.rsplit("::").next().unwrap_or("");
    match reexports.get(&(target.clone(), named.to_string())) {
        Some(original) if original != path => resolve(original, &Vec::new(), modules, &BTreeMap::new()),
        _ => target,
    }
}

type Reexports = BTreeMap<(ModulePath, String), String>;

fn resolve_modules(path: &str, from: &ModulePath, modules: &BTreeSet<ModulePath>) -> ModulePath {
    let mut segments: Vec<&str> = path.split("::").collect();
    // `super` of a folder's mod.rs (module ["render"]) is the folder's parent, as it is of a
    // file's module.
    let mut base: ModulePath = match segments[0] {
        "crate" => Vec::new(),
        _ => from[..from.len() - 1].to_vec(),
    };
    segments.remove(0);
    while segments.first() == Some(&"super") {
        base.pop();
        segments.remove(0);
    }
    let mut target = base;
    for segment in segments {
        let mut longer = target.clone();
        longer.push(segment.to_string());
        if !modules.contains(&longer) {
            break;
        }
        target = longer;
    }
    target
}

/// The first cycle of `edges`, as the nodes along it.
fn find_cycle(edges: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        on_path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = on_path.iter().position(|n| n == node) {
            let mut cycle = on_path[at..].to_vec();
            cycle.push(node.to_string());
            return Some(cycle);
        }
        if done.contains(node) {
            return None;
        }
        on_path.push(node.to_string());
        for next in edges.get(node).into_iter().flatten() {
            if let Some(cycle) = visit(next, edges, on_path, done) {
                return Some(cycle);
            }
        }
        on_path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = BTreeSet::new();
    edges.keys().find_map(|node| visit(node, edges, &mut Vec::new(), &mut done))
}

#[test]
fn no_module_imports_one_that_imports_it_back() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    library_files(&src, &mut files);
    let modules: BTreeSet<ModulePath> = files.iter().map(|f| module_of(f, &src)).collect();
    let reexports = reexports(&files, &src);
    // Edges between siblings: the top-level modules (parent []) and each folder's files.
    let mut levels: BTreeMap<ModulePath, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    let mut imports = 0;
    for file in &files {
        let from = module_of(file, &src);
        for path in paths_named(&code_of(&std::fs::read_to_string(file).unwrap())) {
            let to = resolve(&path, &from, &modules, &reexports);
            imports += 1;
            // The nearest common folder, and the two children of it on each side.
            let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common < from.len() && common < to.len() {
                let edges = levels.entry(from[..common].to_vec()).or_default();
                edges.entry(from[common].clone()).or_default().insert(to[common].clone());
            }
        }
    }
    assert!(imports > 200, "the sources were read: {imports} paths");
    assert!(levels.contains_key(&vec!["render".to_string()]), "render/'s files import each other");
    for (folder, edges) in &levels {
        let place = if folder.is_empty() { "src/".to_string() } else { format!("src/{}/", folder.join("/")) };
        if let Some(cycle) = find_cycle(edges) {
            panic!("modules of {place} import in a circle: {}", cycle.join(" → "));
        }
    }
}

#[test]
fn the_reader_sees_a_cycle_where_there_is_one() {
    // Two files of one folder naming each other, through `use` trees and inline paths alike.
    let modules: BTreeSet<ModulePath> =
        [vec![], vec!["a".into()], vec!["a".into(), "x".into()], vec!["a".into(), "y".into()]].into_iter().collect();
    let x = paths_named(&code_of(
        "use super::{y::{One, Two}, other};\n// use super::z;\nconst Q: char = '\"';\n#[allow(unused)]\nuse super::y as why;\n",
    ));
    let y = paths_named(&code_of("fn f() { let s = \"crate::q\"; crate::a::x::f(); }\n"));
    let resolve_all = |paths: &[String], from: &[&str]| -> Vec<ModulePath> {
        let from: ModulePath = from.iter().map(|s| s.to_string()).collect();
        paths.iter().map(|p| resolve(p, &from, &modules, &BTreeMap::new())).collect()
    };
    assert_eq!(resolve_all(&x, &["a", "x"]), [vec!["a", "y"], vec!["a", "y"], vec!["a"], vec!["a", "y"]]);
    assert_eq!(resolve_all(&y, &["a", "y"]), [vec!["a", "x"]]);
    let mut edges = BTreeMap::new();
    edges.insert("x".to_string(), BTreeSet::from(["y".to_string()]));
    edges.insert("y".to_string(), BTreeSet::from(["x".to_string()]));
    assert_eq!(find_cycle(&edges), Some(vec!["x".into(), "y".into(), "x".into()]));
    edges.remove("y");
    assert_eq!(find_cycle(&edges), None);
}
