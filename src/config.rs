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
//! the closest valid key. [`Config::default`] is `configs/default.toml`; the
//! sections' own `Default` impls serve unit tests and are never what a
//! missing key falls back to.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::backend::BackendParams;
use crate::classify::single_scan::SingleScanParams;
use crate::classify::PlaneMapParams;
use crate::frontend::ExtractorParams;
use crate::map::{EvidenceParams, MergeParams, PaneParams};
use crate::reflect::DetectorParams;
use crate::slam::SlamParams;
use crate::{Error, Result};

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

/// Input handling.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InputParams {
    /// A frame is matched to the pose with the nearest timestamp, which must
    /// be within this many seconds.
    pub pose_tolerance: f64,
    /// A frame with no pose within `pose_tolerance` gets one interpolated
    /// between the poses before and after it (SLERP) when they are at most
    /// this many seconds apart; beyond, the run stops naming the frame
    /// (0: never interpolate).
    pub pose_interpolation_gap: f64,
    /// Frames read from files are kept in memory after their first read,
    /// up to this many megabytes of points, so later passes over the
    /// sequence do not parse them again; beyond it frames are re-read at
    /// every pass (memory stays bounded whatever the sequence length).
    pub frame_cache_mb: f64,
}

impl InputParams {
    /// How frames find their poses.
    pub fn pose_matching(&self) -> crate::io::PoseMatching {
        crate::io::PoseMatching {
            tolerance: self.pose_tolerance,
            max_gap: self.pose_interpolation_gap,
        }
    }
}

impl Default for InputParams {
    fn default() -> Self {
        Self {
            pose_tolerance: 0.01,
            pose_interpolation_gap: 0.0,
            frame_cache_mb: crate::pipeline::sequence::DEFAULT_FRAME_CACHE_MB,
        }
    }
}

/// Map mergers selectable by name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MergerName {
    /// The paper's weighted average of plane parameters with hull union.
    WeightedAverage,
}

/// How a reflective landmark's extent on its infinite plane is bounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryMode {
    /// The convex hull of the fused candidate hulls (the paper).
    Hull,
    /// The hull, overridden cell by cell by the transparency evidence grid.
    EvidenceGrid,
    /// Separate panes found in the evidence, each bounded by a convex
    /// polygon fitted as a linear program.
    Panes,
}

/// The global plane map.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MapParams {
    /// The merger.
    pub merger: MergerName,
    /// Landmarks observed fewer times are not used for classification
    /// (paper: 10).
    pub min_observations: usize,
    /// Landmarks found in fewer than this share of the frames that had them
    /// in view (front side, within `visibility_range`) are not used: chance
    /// alignments of reflections or of points behind glass are fitted now
    /// and then, a real pane in most frames that see it (0: no test, the
    /// paper).
    pub min_found_ratio: f64,
    /// Distance from a landmark's boundary within which a frame counts as
    /// having it in view, m.
    pub visibility_range: f64,
    /// Matching and weighting thresholds.
    pub merge: MergeParams,
    /// How reflective landmarks are bounded.
    pub boundary: BoundaryMode,
    /// Transparency evidence (evidence-grid and panes boundaries).
    pub evidence: EvidenceParams,
    /// Pane segmentation and boundary fitting (panes boundary).
    pub panes: PaneParams,
}

impl MapParams {
    /// The landmark selection these parameters describe.
    pub fn selection(&self) -> crate::map::LandmarkSelection {
        crate::map::LandmarkSelection {
            min_observations: self.min_observations,
            min_found_ratio: self.min_found_ratio,
            visibility_range: self.visibility_range,
        }
    }
}

impl Default for MapParams {
    fn default() -> Self {
        Self {
            merger: MergerName::WeightedAverage,
            min_observations: 10,
            min_found_ratio: 0.0,
            visibility_range: 10.0,
            merge: MergeParams::default(),
            boundary: BoundaryMode::Hull,
            evidence: EvidenceParams::default(),
            panes: PaneParams::default(),
        }
    }
}

/// Output settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputParams {
    /// Voxel size used to thin the accumulated PLY maps, m (0 keeps every
    /// point).
    pub map_voxel: f64,
    /// The top-down map (`topdown.png`) draws the points from this height
    /// above the floor, m (`-inf`: no lower bound): the floor left out.
    pub topdown_min_height: f64,
    /// ... up to this height above the floor, m (`inf`: no upper bound):
    /// the ceiling left out.
    pub topdown_max_height: f64,
}

impl OutputParams {
    /// The heights drawn in the top-down map.
    pub fn topdown_slice(&self) -> crate::viz::topdown::HeightSlice {
        crate::viz::topdown::HeightSlice {
            min: self.topdown_min_height,
            max: self.topdown_max_height,
        }
    }
}

impl Default for OutputParams {
    fn default() -> Self {
        Self {
            map_voxel: 0.03,
            topdown_min_height: 0.3,
            topdown_max_height: 2.0,
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
    ("default", include_str!("../configs/default.toml")),
    ("paper", include_str!("../configs/paper.toml")),
];

/// The built-in a configuration file layers over when it does not say.
const DEFAULT_BASE: &str = "default";

/// The top-level key of a configuration file naming the built-in it layers
/// over.
const EXTENDS: &str = "extends";

/// Tables whose tag key selects a variant with its own keys (an internally
/// tagged enum): a file that changes the tag replaces the whole table instead
/// of merging into it, so the other variant's keys are not carried over.
const TAGGED_TABLES: &[(&str, &str)] = &[
    ("backend.robust", "kind"),
    ("slam.loop_closure.robust", "kind"),
];

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
        let mut known = builtin_table(DEFAULT_BASE);
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

    fn validate(&self) -> std::result::Result<(), String> {
        let d = &self.detector;
        let positive = [
            ("detector.dual_gap", d.dual_gap),
            ("detector.ransac.distance", d.ransac.distance),
            (
                "single_scan.decision.glass_distance",
                self.single_scan.decision.glass_distance,
            ),
            ("input.pose_tolerance", self.input.pose_tolerance),
            (
                "plane_map.decision.glass_distance",
                self.plane_map.decision.glass_distance,
            ),
            ("plane_map.support_voxel", self.plane_map.support_voxel),
            ("extractor.ransac.distance", self.extractor.ransac.distance),
            (
                "extractor.ground.ransac.distance",
                self.extractor.ground.ransac.distance,
            ),
            ("extractor.normals.max_gap", self.extractor.normals.max_gap),
            ("extractor.min_area", self.extractor.min_area),
            (
                "slam.rejector.inlier_offset",
                self.slam.rejector.inlier_offset,
            ),
            (
                "slam.frame_matching.max_centroid_distance",
                self.slam.frame_matching.max_centroid_distance,
            ),
            ("slam.rpe_segment", self.slam.rpe_segment),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("{name} must be positive, got {v}"));
            }
        }
        let gap = self.input.pose_interpolation_gap;
        if !(gap >= 0.0 && gap.is_finite()) {
            return Err(format!(
                "input.pose_interpolation_gap must be >= 0 (0: never interpolate), got {gap}"
            ));
        }
        if !(d.ransac.probability > 0.0 && d.ransac.probability < 1.0) {
            return Err(format!(
                "detector.ransac.probability must be in (0, 1), got {}",
                d.ransac.probability
            ));
        }
        if d.ransac.max_iterations == 0 || d.max_planes == 0 {
            return Err(
                "detector.ransac.max_iterations and detector.max_planes must be at least 1".into(),
            );
        }
        for (name, dec) in [
            ("single_scan", &self.single_scan.decision),
            ("plane_map", &self.plane_map.decision),
        ] {
            if dec.behind_distance < dec.glass_distance {
                return Err(format!(
                    "{name}.decision.behind_distance must be >= glass_distance"
                ));
            }
        }
        for (name, r) in [
            ("extractor.ransac", &self.extractor.ransac),
            ("extractor.ground.ransac", &self.extractor.ground.ransac),
        ] {
            if !(r.probability > 0.0 && r.probability < 1.0) || r.max_iterations == 0 {
                return Err(format!(
                    "{name}: probability must be in (0, 1) and max_iterations at least 1"
                ));
            }
        }
        if self.extractor.min_points < 3 {
            return Err("extractor.min_points must be at least 3".into());
        }
        for (name, v) in [
            (
                "slam.frame_matching.min_normal_cos",
                self.slam.frame_matching.min_normal_cos,
            ),
            (
                "slam.map_matching.min_normal_cos",
                self.slam.map_matching.min_normal_cos,
            ),
            (
                "slam.map_matching.min_overlap",
                self.slam.map_matching.min_overlap,
            ),
        ] {
            if !(v > 0.0 && v <= 1.0) {
                return Err(format!("{name} must be in (0, 1], got {v}"));
            }
        }
        if !(self.slam.gauss_newton.degeneracy_threshold >= 0.0)
            || !(self.slam.rejector.min_eigenvalue >= 0.0)
        {
            return Err(
                "slam.gauss_newton.degeneracy_threshold and slam.rejector.min_eigenvalue must be >= 0"
                    .into(),
            );
        }
        if self.map.min_observations == 0 {
            return Err("map.min_observations must be at least 1".into());
        }
        if !(self.output.map_voxel >= 0.0) {
            return Err("output.map_voxel must be >= 0".into());
        }
        if !(self.output.topdown_min_height < self.output.topdown_max_height) {
            return Err(
                "output.topdown_min_height must be below output.topdown_max_height (-inf and inf: no bound)"
                    .into(),
            );
        }
        self.slam.loop_closure.validate()?;
        self.backend.validate().map_err(|e| e.to_string())?;
        Ok(())
    }
}

/// A built-in configuration as a TOML table.
fn builtin_table(name: &str) -> toml::Table {
    let (_, text) = BUILTIN
        .iter()
        .find(|(n, _)| *n == name)
        .expect("a built-in configuration name");
    toml::from_str(text).expect("the embedded built-in configurations are valid TOML")
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
fn merge(base: &mut toml::Table, over: toml::Table, prefix: &str) {
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
fn leaf_paths(table: &toml::Table, prefix: &str, out: &mut Vec<String>) {
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
fn unknown_keys(file: &toml::Table, known: &toml::Table, prefix: &str) -> Vec<String> {
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
fn edit_distance(a: &str, b: &str) -> usize {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse() {
        for name in Config::builtin_names() {
            Config::resolve(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }

    #[test]
    fn round_trips_through_toml() {
        let c = Config::resolve("default").unwrap();
        let again = Config::from_toml(&c.to_toml(), Path::new("x")).unwrap();
        assert_eq!(c, again);
    }

    #[test]
    fn unknown_keys_and_bad_values_are_errors() {
        let e = Config::from_toml("sensorr = 1", Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("c.toml") && e.contains("sensorr"), "{e}");
        let e = Config::from_toml("[detector]\ndual_gap = -1.0", Path::new("c.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("detector.dual_gap must be positive"), "{e}");
    }

    /// Dotted paths of every value in a table.
    fn paths(table: &toml::Table) -> Vec<String> {
        let mut out = Vec::new();
        leaf_paths(table, "", &mut out);
        out.sort();
        out
    }

    #[test]
    fn default_is_the_default_file() {
        let parsed: Config = toml::from_str(include_str!("../configs/default.toml"))
            .expect("configs/default.toml parses");
        assert_eq!(Config::default(), parsed);
        assert_eq!(Config::default(), Config::resolve("default").unwrap());
        assert_eq!(Config::default().method, Method::PlaneOptimized);
    }

    /// Every built-in states every key the configuration has, so none is
    /// filled from a section's `Default` impl.
    #[test]
    fn builtins_are_complete() {
        let Ok(toml::Value::Table(serialised)) = toml::Value::try_from(Config::default()) else {
            panic!("the configuration serialises to a table");
        };
        let all = paths(&serialised);
        for name in Config::builtin_names() {
            assert_eq!(paths(&builtin_table(name)), all, "configs/{name}.toml");
        }
    }

    #[test]
    fn an_empty_file_is_the_default() {
        let c = Config::from_toml("", Path::new("empty.toml")).unwrap();
        assert_eq!(c, Config::default());
        let (_, layering) = Config::from_toml_layered("", Path::new("empty.toml")).unwrap();
        assert_eq!(layering.extends, "default");
        assert!(layering.keys.is_empty());
        let c = Config::from_toml("extends = \"paper\"", Path::new("p.toml")).unwrap();
        assert_eq!(c, Config::resolve("paper").unwrap());
    }

    #[test]
    fn a_file_changes_only_its_keys() {
        let text = "seed = 7\n[plane_map.decision]\nspace_margin = 0.3\n[map.panes.fit]\nsolver = \"joint-lp\"";
        let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
        let mut want = Config {
            seed: 7,
            ..Config::default()
        };
        want.plane_map.decision.space_margin = 0.3;
        want.map.panes.fit.solver = crate::map::boundary_fit::BoundarySolver::JointLp;
        assert_eq!(c, want);
        assert_eq!(
            layering.keys,
            [
                "map.panes.fit.solver",
                "plane_map.decision.space_margin",
                "seed"
            ]
        );
        assert!(
            layering.comment().contains("\"default\""),
            "{}",
            layering.comment()
        );

        let text = "extends = \"paper\"\n[plane_map.decision]\nspace_margin = 0.3";
        let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
        let mut want = Config::resolve("paper").unwrap();
        want.plane_map.decision.space_margin = 0.3;
        assert_eq!(c, want);
        assert_eq!(layering.extends, "paper");
    }

    #[test]
    fn changing_a_tagged_table_variant_replaces_it() {
        let c =
            Config::from_toml("[backend.robust]\nkind = \"none\"", Path::new("c.toml")).unwrap();
        assert_eq!(c.backend.robust, crate::backend::RobustKernel::None);
        let c = Config::from_toml(
            "[backend.robust]\nkind = \"cauchy\"\nk = 2.0",
            Path::new("c.toml"),
        )
        .unwrap();
        assert_eq!(
            c.backend.robust,
            crate::backend::RobustKernel::Cauchy { k: 2.0 }
        );
        let c = Config::from_toml("[backend.robust]\nk = 2.0", Path::new("c.toml")).unwrap();
        assert_eq!(
            c.backend.robust,
            crate::backend::RobustKernel::Huber { k: 2.0 }
        );
    }

    #[test]
    fn misspelt_keys_suggest_the_closest() {
        let e = Config::from_toml(
            "[plane_map.decision]\nspace_tset = true",
            Path::new("my.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("my.toml: "), "{e}");
        assert!(e.contains("`plane_map.decision.space_tset`"), "{e}");
        assert!(
            e.contains("did you mean `plane_map.decision.space_test`?"),
            "{e}"
        );
        let e = Config::from_toml("[plane_mapp]\nhull_margin = 1.0", Path::new("my.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("did you mean `plane_map`?"), "{e}");
        let e = Config::from_toml("[input]\nzzz = 1", Path::new("my.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("valid keys here: frame_cache_mb, pose_interpolation_gap, pose_tolerance"),
            "{e}"
        );
        let e = Config::from_toml("extend = \"paper\"", Path::new("my.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("did you mean `extends`?"), "{e}");
        let e = Config::from_toml("extends = \"papr\"", Path::new("my.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("my.toml") && e.contains("default, paper"), "{e}");
    }

    #[test]
    fn edit_distances() {
        assert_eq!(edit_distance("space_tset", "space_test"), 1);
        assert_eq!(edit_distance("sensorr", "sensor"), 1);
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }
}
