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

/// Longest function allowed in `src/classify/`, lines from its `fn` line to
/// its closing brace.
const MAX_FUNCTION_LINES: usize = 80;

/// `text` with its comments and the contents of its string and character
/// literals blanked (newlines kept, so line numbers stay): what is left
/// are the braces of the code alone.
fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                out.push(' ');
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            // Block comments nest.
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    out.push_str("  ");
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    out.push_str("  ");
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && matches!(next, Some('"') | Some('#'))
            && (i == 0 || !(chars[i - 1].is_alphanumeric() || chars[i - 1] == '_'))
        {
            // A raw string: r"...", r#"..."#.
            let mut j = i + 1;
            while chars.get(j) == Some(&'#') {
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            let hashes = j - i - 1;
            out.extend(std::iter::repeat_n(' ', j + 1 - i));
            i = j + 1;
            while i < chars.len() {
                if chars[i] == '"' && (1..=hashes).all(|k| chars.get(i + k) == Some(&'#')) {
                    out.extend(std::iter::repeat_n(' ', hashes + 1));
                    i += hashes + 1;
                    break;
                }
                out.push(blank(chars[i]));
                i += 1;
            }
        } else if c == '"' {
            out.push(' ');
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    out.push(' ');
                    i += 1;
                }
                if i < chars.len() {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
            out.push(' ');
            i += 1;
        } else if c == '\'' {
            // A character literal ('{', '\n', '\u{7b}'), not a lifetime.
            let end = if next == Some('\\') {
                (i + 2..chars.len()).find(|&k| chars[k] == '\'')
            } else if chars.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match end {
                Some(end) => {
                    out.extend(std::iter::repeat_n(' ', end + 1 - i));
                    i = end + 1;
                }
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The name of the function a line of code starts (`fn`, after any
/// visibility and `const`, `async`, `unsafe` or `extern` qualifiers).
fn starts_function(line: &str) -> Option<&str> {
    let mut rest = line.trim_start();
    if let Some(r) = rest.strip_prefix("pub") {
        let r = r.trim_start();
        rest = match r.strip_prefix('(') {
            Some(inner) => inner.split_once(')')?.1.trim_start(),
            None => r,
        };
    }
    loop {
        let before = rest;
        for qualifier in ["const ", "async ", "unsafe ", "extern "] {
            if let Some(r) = rest.strip_prefix(qualifier) {
                rest = r.trim_start();
            }
        }
        if before == rest {
            break;
        }
    }
    let name = rest.strip_prefix("fn ")?.trim_start();
    let end = name
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(name.len());
    (end > 0).then_some(&name[..end])
}

/// The line (0-based) of the brace that closes the block opened by the
/// first `{` at or after line `start` of `lines` (bracket depth 0); `None`
/// for a declaration without a body (a `;` first).
fn block_end(lines: &[&str], start: usize) -> Option<usize> {
    let mut brackets = 0i32;
    let mut braces = 0i32;
    for (n, line) in lines.iter().enumerate().skip(start) {
        for c in line.chars() {
            match c {
                '(' | '[' => brackets += 1,
                ')' | ']' => brackets -= 1,
                ';' if braces == 0 && brackets == 0 => return None,
                '{' => braces += 1,
                '}' => {
                    braces -= 1;
                    if braces == 0 {
                        return Some(n);
                    }
                }
                _ => {}
            }
        }
    }
    None
}

/// The module files declared `#[cfg(test)] mod name;` in `text`, a file of
/// the module directory `dir`.
fn test_module_files(dir: &Path, text: &str) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut after_cfg_test = false;
    for line in text.lines().map(str::trim) {
        if line == "#[cfg(test)]" {
            after_cfg_test = true;
            continue;
        }
        if after_cfg_test {
            let decl = line
                .trim_start_matches("pub(crate) ")
                .trim_start_matches("pub ");
            if let Some(name) = decl.strip_prefix("mod ").and_then(|r| r.strip_suffix(';')) {
                out.push(dir.join(format!("{name}.rs")));
                out.push(dir.join(name));
            }
        }
        after_cfg_test = line.starts_with("#[") && after_cfg_test;
    }
    out
}

/// Every function of the library code in `files`, as (file, first line
/// (1-based), name, lines), outside `#[cfg(test)]` items, test module
/// files and `tests/` folders.
fn functions(files: &[PathBuf]) -> Vec<(PathBuf, usize, String, usize)> {
    let mut test_paths: Vec<PathBuf> = Vec::new();
    for file in files {
        let dir = match file.file_name().and_then(|n| n.to_str()) {
            Some("mod.rs") | Some("lib.rs") | Some("main.rs") => file.parent().unwrap().into(),
            _ => file.with_extension(""),
        };
        let text = std::fs::read_to_string(file).unwrap();
        test_paths.extend(test_module_files(&dir, &text));
    }
    let mut out = Vec::new();
    for file in files {
        let in_tests = file.components().any(|c| c.as_os_str() == "tests")
            || test_paths.iter().any(|t| file.starts_with(t));
        if in_tests {
            continue;
        }
        let code = code_only(&std::fs::read_to_string(file).unwrap());
        let lines: Vec<&str> = code.lines().collect();
        let mut n = 0;
        let mut cfg_test = false;
        while n < lines.len() {
            let line = lines[n].trim();
            if line.starts_with("#[cfg(test)]") {
                cfg_test = true;
            } else if cfg_test && !line.is_empty() && !line.starts_with("#[") {
                // The whole item under `#[cfg(test)]` is test code.
                cfg_test = false;
                if let Some(end) = block_end(&lines, n) {
                    n = end;
                }
            } else if let Some(name) = starts_function(line) {
                if let Some(end) = block_end(&lines, n) {
                    out.push((file.clone(), n + 1, name.to_string(), end - n + 1));
                }
            }
            n += 1;
        }
    }
    out
}

#[test]
fn no_function_in_classify_is_over_80_lines() {
    let found = functions(&rust_files(&root().join("src/classify")));
    // The scanner must see the module's functions at all.
    assert!(found.len() > 100, "only {} functions found", found.len());
    let long: Vec<String> = found
        .iter()
        .filter(|(.., lines)| *lines > MAX_FUNCTION_LINES)
        .map(|(file, line, name, lines)| {
            format!("{}:{line} fn {name} ({lines} lines)", file.display())
        })
        .collect();
    assert!(
        long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines: {long:#?}"
    );
}

/// The function scanner: literals and comments hide their braces, nested
/// and qualified functions are found, test items are skipped.
#[test]
fn the_function_scanner_counts_lines_to_the_closing_brace() {
    let dir = std::env::temp_dir().join(format!("layout-scan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("sample.rs");
    let text = r##"
/// A doc comment with a { brace.
pub(crate) fn first(x: [u8; 2]) -> char {
    let s = "}}}"; // }
    let r = r#"}"#;
    /* { nested /* } */ { */
    let _ = |a: &'static str| a;
    '}'
}

const unsafe fn second() {}

trait T {
    fn declared(&self);
}

#[cfg(test)]
mod tests {
    fn hidden() {
    }
}
"##;
    std::fs::write(&file, text).unwrap();
    let found = functions(std::slice::from_ref(&file));
    std::fs::remove_dir_all(&dir).unwrap();
    let summary: Vec<(usize, &str, usize)> = found
        .iter()
        .map(|(_, line, name, lines)| (*line, name.as_str(), *lines))
        .collect();
    assert_eq!(summary, [(3, "first", 7), (11, "second", 1)]);
}
