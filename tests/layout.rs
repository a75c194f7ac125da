//! The house rules of the source tree (issue 19), checked so they stay
//! true: no source file over 650 lines, and no two modules of the library
//! that import each other (an import circle). Module-level `use` items of
//! `crate::` and `super::` paths are read as written, outside `#[cfg(test)]`
//! blocks; a module importing its own ancestor or descendant (a re-export
//! through `mod.rs`) is not a circle.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Longest source file allowed, lines.
const MAX_LINES: usize = 650;

/// Every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn no_source_file_is_over_650_lines() {
    let mut long = Vec::new();
    for dir in ["src", "tests", "benches", "paper/reproduce/src"] {
        for file in rust_files(&root().join(dir)) {
            let lines = std::fs::read_to_string(&file).unwrap().lines().count();
            if lines > MAX_LINES {
                long.push(format!("{} ({lines} lines)", file.display()));
            }
        }
    }
    assert!(long.is_empty(), "over {MAX_LINES} lines: {long:?}");
}

/// The module path of a file under `src/` (`a::b` for `src/a/b.rs` and
/// `src/a/b/mod.rs`; empty for `lib.rs` and `main.rs`).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    if parts == ["lib"] || parts == ["main"] {
        parts.clear();
    }
    parts
}

/// The paths of the module-level `use` items of `text` (up to the first
/// `#[cfg(test)]`), as written, without the `use` and the `;`.
fn use_paths(text: &str) -> Vec<String> {
    let body = text.split("#[cfg(test)]").next().unwrap_or("");
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in body.lines() {
        let t = line.trim_start();
        if let Some(acc) = current.as_mut() {
            acc.push_str(t);
        } else if line.starts_with("use ")
            || line.starts_with("pub use ")
            || line.starts_with("pub(crate) use ")
        {
            current = Some(t.split_once("use ").unwrap().1.to_string());
        }
        if current.as_ref().is_some_and(|acc| acc.ends_with(';')) {
            out.push(current.take().unwrap().trim_end_matches(';').to_string());
        }
    }
    out
}

/// `a::{b::C, d}` as `a::b::C` and `a::d` (nested groups too).
fn expand(path: &str) -> Vec<String> {
    let Some(open) = path.find('{') else {
        return vec![path.replace(' ', "")];
    };
    let (prefix, rest) = path.split_at(open);
    let mut depth = 0;
    let mut items = Vec::new();
    let mut start = 1;
    for (i, c) in rest.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    items.push(&rest[start..i]);
                    break;
                }
            }
            ',' if depth == 1 => {
                items.push(&rest[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items
        .into_iter()
        .filter(|item| !item.trim().is_empty())
        .flat_map(|item| expand(&format!("{prefix}{}", item.trim())))
        .collect()
}

#[test]
fn no_two_library_modules_import_each_other() {
    let src = root().join("src");
    let files = rust_files(&src);
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_of(&src, f)).collect();
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for file in &files {
        let me = module_of(&src, file);
        let text = std::fs::read_to_string(file).unwrap();
        for path in use_paths(&text).iter().flat_map(|p| expand(p)) {
            let mut segments: Vec<&str> = path.split("::").map(str::trim).collect();
            let mut target: Vec<String> = match segments.first() {
                Some(&"crate") => {
                    segments.remove(0);
                    Vec::new()
                }
                Some(&"super") => {
                    let mut base = me.clone();
                    while segments.first() == Some(&"super") {
                        segments.remove(0);
                        base.pop();
                    }
                    base
                }
                Some(&"self") => {
                    segments.remove(0);
                    me.clone()
                }
                _ => continue,
            };
            // The longest prefix of the path that is a module of the crate.
            let mut found = None;
            for s in segments {
                target.push(s.to_string());
                if modules.contains(&target) {
                    found = Some(target.clone());
                }
            }
            let Some(dep) = found else { continue };
            let related = dep.starts_with(&me) || me.starts_with(&dep);
            if !related {
                edges.entry(me.clone()).or_default().insert(dep);
            }
        }
    }
    let mut circles = Vec::new();
    for (a, deps) in &edges {
        for b in deps {
            if a < b && edges.get(b).is_some_and(|d| d.contains(a)) {
                circles.push(format!("{} <-> {}", a.join("::"), b.join("::")));
            }
        }
    }
    // The checker must see the crate's imports at all.
    assert!(
        edges.len() > 20,
        "only {} modules with imports found",
        edges.len()
    );
    assert!(
        circles.is_empty(),
        "modules importing each other: {circles:?}"
    );
}
