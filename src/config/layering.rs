//! Layering a configuration file over its built-in, key by key, and
//! naming the keys it has wrong (with the closest valid one).

/// Tables whose tag key selects a variant with its own keys (an internally
/// tagged enum): a file that changes the tag replaces the whole table instead
/// of merging into it, so the other variant's keys are not carried over.
const TAGGED_TABLES: &[(&str, &str)] = &[("backend.robust", "kind")];

/// How a configuration file was layered: the built-in under it and the keys
/// it set, so a user can see what a file changes (`specular config`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layering {
    /// The built-in configuration the file layers over (`extends`, default
    /// `"default"`).
    pub extends: &'static str,
    /// Dotted paths of the values the file set (e.g.
    /// `plane_map.decision.space_margin`), sorted.
    pub keys: Vec<String>,
}

impl Layering {
    /// A one-line TOML comment saying what the file extends and which keys it
    /// set (at most ten named, then a count).
    pub fn comment(&self) -> String {
        const SHOWN: usize = 10;
        let keys = if self.keys.is_empty() {
            "no keys".to_string()
        } else if self.keys.len() <= SHOWN {
            self.keys.join(", ")
        } else {
            format!(
                "{} and {} more",
                self.keys[..SHOWN].join(", "),
                self.keys.len() - SHOWN
            )
        };
        format!(
            "# extends the built-in \"{}\"; set by the file: {keys}",
            self.extends
        )
    }
}

/// `prefix.key`, or `key` at the top level.
fn key_path(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Layer `over` onto `base`: a key in `over` replaces the value in `base`,
/// except that tables present in both merge recursively (a tagged table
/// whose tag changes is replaced whole, see [`TAGGED_TABLES`]).
pub(super) fn merge(base: &mut toml::Table, over: toml::Table, prefix: &str) {
    for (key, value) in over {
        let path = key_path(prefix, &key);
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(o)) if !tag_changes(&path, b, &o) => {
                merge(b, o, &path)
            }
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

/// Whether `over` selects another variant of the tagged table at `path`.
fn tag_changes(path: &str, base: &toml::Table, over: &toml::Table) -> bool {
    TAGGED_TABLES
        .iter()
        .any(|(p, tag)| *p == path && over.get(*tag).is_some_and(|t| Some(t) != base.get(*tag)))
}

/// Dotted paths of the non-table values in `table`.
pub(super) fn leaf_paths(table: &toml::Table, prefix: &str, out: &mut Vec<String>) {
    for (key, value) in table {
        let path = key_path(prefix, key);
        match value {
            toml::Value::Table(t) => leaf_paths(t, &path, out),
            _ => out.push(path),
        }
    }
}

/// One message per key of `file` that `known` (the default configuration's
/// table at the same path) does not have, each suggesting the closest known
/// key of that table, or listing them when none is close.
pub(super) fn unknown_keys(file: &toml::Table, known: &toml::Table, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    for (key, value) in file {
        let path = key_path(prefix, key);
        match (known.get(key), value) {
            (None, _) => {
                let closest = known
                    .keys()
                    .map(|k| (edit_distance(key, k), k))
                    .min_by_key(|(d, _)| *d);
                let hint = match closest {
                    Some((d, k)) if d <= (key.chars().count() / 3).max(2) => {
                        format!("did you mean `{}`?", key_path(prefix, k))
                    }
                    _ => format!(
                        "valid keys here: {}",
                        known.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                };
                out.push(format!("unknown key `{path}` ({hint})"));
            }
            (Some(toml::Value::Table(k)), toml::Value::Table(f)) => {
                out.extend(unknown_keys(f, k, &path))
            }
            _ => {}
        }
    }
    out
}

/// Edit distance between two keys: insertions, deletions, substitutions and
/// transpositions of adjacent characters each count one (optimal string
/// alignment), so `space_tset` is one edit from `space_test`.
pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    // d[i][j]: distance between a[..i] and b[..j].
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for (j, cell) in d[0].iter_mut().enumerate() {
        *cell = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            let mut v = (d[i - 1][j] + 1)
                .min(d[i][j - 1] + 1)
                .min(d[i - 1][j - 1] + cost);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                v = v.min(d[i - 2][j - 2] + 1);
            }
            d[i][j] = v;
        }
    }
    d[a.len()][b.len()]
}
