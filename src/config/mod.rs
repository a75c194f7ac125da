//! The TOML configuration, with one source of defaults: `configs/default.toml`.
//!
//! Sections mirror the pipeline's stages. Two configurations ship with the
//! crate (embedded in the binary), each a complete file stating every key:
//! `configs/default.toml` (our improved defaults) and `configs/paper.toml`
//! (the paper's method and thresholds), selectable as `--config default` or
//! `--config paper`. Any other `--config` is a path to a TOML file that
//! states only what it changes: it is layered key by key over
//! `configs/default.toml` (tables merge recursively, a key in the file
//! replaces the built-in's value), or over `configs/paper.toml` when it says
//! `extends = "paper"` at the top. An empty file is exactly the default
//! configuration. Unknown keys are errors naming the file, the key path and
//! the closest valid key. [`Config::default`] is `configs/default.toml`, and
//! so is every section's `Default` (its table of that file, read by
//! [`default_section`]); numerical-method constants nobody should tune are
//! `const`s beside the code that uses them, and the sensor's own constants
//! are in its model (`configs/sensors/*.toml`).
//!
//! Each stage owns its plain parameter struct, beside the code that reads
//! it ([`DetectorParams`] in `reflect`, [`MapParams`] in `map`,
//! [`InputParams`] with the sequence, ...); [`Config`] only composes them
//! (the three that once lived here are re-exported, so `config::MapParams`
//! still names the map's). This module reads
//! and checks the files: `layering` puts a file over its built-in and
//! names unknown keys, `validate` checks the values.

mod layering;
#[cfg(test)]
mod tests;
mod validate;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::backend::BackendParams;
use crate::classify::single_scan::SingleScanParams;
use crate::classify::PlaneMapParams;
use crate::frontend::ExtractorParams;
use crate::reflect::DetectorParams;
use crate::slam::SlamParams;
use crate::{Error, Result};

pub use crate::map::{BoundaryMode, MapParams, MergerName};
pub use crate::pipeline::sequence::InputParams;
pub use crate::viz::OutputParams;
pub use layering::Layering;
use layering::{edit_distance, leaf_paths, merge, unknown_keys};

/// Which pipeline `detect` runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Classify every frame against the planes detected in it alone.
    SingleScan,
    /// Fuse planes into a global map with external poses, then classify.
    PlaneOptimized,
}

impl Method {
    /// The method's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::SingleScan => "single-scan",
            Method::PlaneOptimized => "plane-optimized",
        }
    }
}

/// The whole configuration.
///
/// Deserialised only from complete tables (a built-in, or a file layered
/// over one), so no section is filled from its struct's `Default`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// Built-in sensor name or path to a sensor TOML.
    pub sensor: String,
    /// Seed for every randomised step (RANSAC).
    pub seed: u64,
    /// The pipeline `detect` runs unless `--method` says otherwise.
    pub method: Method,
    /// Input handling.
    pub input: InputParams,
    /// Reflective-plane detection in one scan.
    pub detector: DetectorParams,
    /// The single-scan classifier.
    pub single_scan: SingleScanParams,
    /// The global plane map (plane-optimized pipeline).
    pub map: MapParams,
    /// The plane-map classifier (plane-optimized pipeline).
    pub plane_map: PlaneMapParams,
    /// Ordinary and ground plane extraction (Reflection SLAM front end).
    pub extractor: ExtractorParams,
    /// Reflection SLAM: registration, tracking, map maintenance.
    pub slam: SlamParams,
    /// Reflection SLAM's back-end: the pose-plane graph optimisation run
    /// after tracking.
    pub backend: BackendParams,
    /// Output settings.
    pub output: OutputParams,
}

impl Default for Config {
    /// The default configuration: `configs/default.toml`, the one source of
    /// defaults (the same as `Config::resolve("default")`).
    fn default() -> Self {
        Config::resolve("default")
            .expect("the embedded configs/default.toml is a valid configuration")
    }
}

/// Configurations shipped with the crate: complete files, every key stated.
const BUILTIN: &[(&str, &str)] = &[
    ("default", include_str!("../../configs/default.toml")),
    ("paper", include_str!("../../configs/paper.toml")),
];

/// The built-in a configuration file layers over when it does not say.
const DEFAULT_BASE: &str = "default";

/// The top-level key of a configuration file naming the built-in it layers
/// over.
const EXTENDS: &str = "extends";

/// Optional keys (an `Option` each: absent is off) that `configs/default.toml`
/// leaves out, with a value of their type: valid in a configuration file all
/// the same.
const OPTIONAL_KEYS: &[(&str, f64)] = &[
    ("slam.window", 20.0),
    ("slam.keyframe_move", 0.2),
    ("slam.keyframe_turn_deg", 5.0),
    ("backend.odometry_free_translation_sigma", 0.5),
    ("backend.odometry_free_rotation_sigma", 0.1),
];

/// Optional tables (an `Option` each: absent is off) that
/// `configs/default.toml` leaves out, with the built-in that states them:
/// their keys are valid in a configuration file all the same.
const OPTIONAL_TABLES: &[(&str, &str, &str)] = &[("plane_map", "ladder", "paper")];

/// The keys a configuration file may name: the default file's and the
/// optional ones it leaves out.
fn known_keys() -> toml::Table {
    let mut known = builtin_table(DEFAULT_BASE);
    for (parent, name, builtin) in OPTIONAL_TABLES {
        let from = builtin_table(builtin);
        let table = from[*parent][*name].clone();
        if let Some(toml::Value::Table(p)) = known.get_mut(*parent) {
            p.insert((*name).into(), table);
        }
    }
    for (path, value) in OPTIONAL_KEYS {
        let mut table = &mut known;
        let mut keys: Vec<&str> = path.split('.').collect();
        let leaf = keys.pop().expect("a dotted key");
        for key in keys {
            table = table
                .entry(key)
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                .as_table_mut()
                .expect("optional keys lie in tables");
        }
        let value = if value.fract() == 0.0 {
            toml::Value::Integer(*value as i64)
        } else {
            toml::Value::Float(*value)
        };
        table.insert(leaf.into(), value);
    }
    known
}

impl Config {
    /// Names of the built-in configurations.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN.iter().map(|(n, _)| *n).collect()
    }

    /// A built-in configuration by name, or a TOML file by path layered over
    /// a built-in (see [`Config::from_toml`]).
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        if let Some((name, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
            let config: Self =
                toml::from_str(text).map_err(|e| Error::format(*name, e.to_string()))?;
            config.validate().map_err(|m| Error::format(*name, m))?;
            return Ok(config);
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            // Neither a built-in nor a file: say which built-ins there are.
            let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
            let closest = names
                .iter()
                .min_by_key(|n| edit_distance(name_or_path, n))
                .filter(|n| edit_distance(name_or_path, n) <= 3);
            let hint = closest.map_or(String::new(), |n| format!("; did you mean `{n}`?"));
            return Err(Error::Config(format!(
                "`{name_or_path}` is neither a built-in configuration ({}) nor a file{hint}",
                names.join(", ")
            )));
        }
        Self::load(path)
    }

    /// Read a configuration file and layer it over its built-in (see
    /// [`Config::from_toml`]).
    pub fn load(path: &Path) -> Result<Self> {
        Ok(Self::load_layered(path)?.0)
    }

    /// [`Config::load`], also saying what the file extends and which keys it
    /// set.
    pub fn load_layered(path: &Path) -> Result<(Self, Layering)> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_toml_layered(&text, path)
    }

    /// Parse a configuration file's text (`origin` names it in errors),
    /// layer it over `configs/default.toml` (or the built-in its top-level
    /// `extends` names) key by key, and validate the result. Keys unknown to
    /// the default configuration are errors that suggest the closest valid
    /// key.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        Ok(Self::from_toml_layered(text, origin)?.0)
    }

    /// [`Config::from_toml`], also saying what the file extends and which
    /// keys it set.
    pub fn from_toml_layered(text: &str, origin: &Path) -> Result<(Self, Layering)> {
        let mut file: toml::Table =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string()))?;
        let extends = match file.remove(EXTENDS) {
            None => DEFAULT_BASE,
            Some(toml::Value::String(name)) => BUILTIN
                .iter()
                .map(|(n, _)| *n)
                .find(|n| *n == name)
                .ok_or_else(|| {
                    Error::format(
                        origin,
                        format!(
                            "extends = \"{name}\" is not a built-in configuration ({})",
                            Self::builtin_names().join(", ")
                        ),
                    )
                })?,
            Some(other) => {
                return Err(Error::format(
                    origin,
                    format!(
                        "extends must be the name of a built-in configuration ({}), got {other}",
                        Self::builtin_names().join(", ")
                    ),
                ))
            }
        };
        // Known keys: the default configuration's, and `extends` (already
        // taken out of the file) so that a misspelling of it is suggested.
        let mut known = known_keys();
        known.insert(EXTENDS.into(), DEFAULT_BASE.into());
        let unknown = unknown_keys(&file, &known, "");
        if !unknown.is_empty() {
            return Err(Error::format(origin, unknown.join("; ")));
        }
        let mut keys = Vec::new();
        leaf_paths(&file, "", &mut keys);
        keys.sort();
        let mut merged = builtin_table(extends);
        merge(&mut merged, file, "");
        let config: Self = toml::Value::Table(merged)
            .try_into()
            .map_err(|e: toml::de::Error| Error::format(origin, e.to_string()))?;
        config.validate().map_err(|m| Error::format(origin, m))?;
        Ok((config, Layering { extends, keys }))
    }

    /// The configuration as TOML (written beside every run's outputs).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot serialise: {e}\n"))
    }
}

/// The section of `configs/default.toml` at a dotted path (`""` for the
/// whole file, `"slam.points"`), parsed: what the `Default` of every
/// section's struct returns, so the file is the only source of defaults.
///
/// # Panics
///
/// If the embedded default file lacks the section or it does not parse as
/// `T` (a test covers every section).
pub fn default_section<T: serde::de::DeserializeOwned>(path: &str) -> T {
    static TABLE: std::sync::OnceLock<toml::Table> = std::sync::OnceLock::new();
    let mut table = TABLE.get_or_init(|| builtin_table(DEFAULT_BASE));
    for key in path.split('.').filter(|k| !k.is_empty()) {
        table = match table.get(key) {
            Some(toml::Value::Table(t)) => t,
            _ => panic!("configs/default.toml has no section [{path}]"),
        };
    }
    toml::Value::Table(table.clone())
        .try_into()
        .unwrap_or_else(|e| panic!("configs/default.toml [{path}]: {e}"))
}

/// A built-in configuration as a TOML table.
fn builtin_table(name: &str) -> toml::Table {
    let (_, text) = BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .expect("a built-in configuration name");
    toml::from_str(text).expect("the embedded built-in configurations are valid TOML")
}
