//! The TOML configuration: the single source of defaults.
//!
//! Sections mirror the pipeline's stages; every field has a default, so a
//! config file only states what it changes. Unknown keys are errors. Two
//! configurations ship with the crate (and are embedded in the binary):
//! `configs/default.toml` (our improved defaults) and `configs/paper.toml`
//! (the paper's method and thresholds), selectable as `--config default` or
//! `--config paper`, or any file path.

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
    /// Frames read from files are kept in memory after their first read,
    /// up to this many megabytes of points, so later passes over the
    /// sequence do not parse them again; beyond it frames are re-read at
    /// every pass (memory stays bounded whatever the sequence length).
    pub frame_cache_mb: f64,
}

impl Default for InputParams {
    fn default() -> Self {
        Self {
            pose_tolerance: 0.01,
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
}

impl Default for OutputParams {
    fn default() -> Self {
        Self { map_voxel: 0.03 }
    }
}

/// The whole configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    fn default() -> Self {
        Self {
            sensor: "pandar_qt64".into(),
            seed: 0,
            method: Method::SingleScan,
            input: InputParams::default(),
            detector: DetectorParams::default(),
            single_scan: SingleScanParams::default(),
            map: MapParams::default(),
            plane_map: PlaneMapParams::default(),
            extractor: ExtractorParams::default(),
            slam: SlamParams::default(),
            backend: BackendParams::default(),
            output: OutputParams::default(),
        }
    }
}

/// Configurations shipped with the crate.
const BUILTIN: &[(&str, &str)] = &[
    ("default", include_str!("../configs/default.toml")),
    ("paper", include_str!("../configs/paper.toml")),
];

impl Config {
    /// Names of the built-in configurations.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN.iter().map(|(n, _)| *n).collect()
    }

    /// A built-in configuration by name, or a TOML file by path.
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name_or_path) {
            return Self::from_toml(text, Path::new(name_or_path));
        }
        Self::load(Path::new(name_or_path))
    }

    /// Read a configuration file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_toml(&text, path)
    }

    /// Parse a configuration (`origin` names it in errors) and validate it.
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let config: Self =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string()))?;
        config.validate().map_err(|m| Error::format(origin, m))?;
        Ok(config)
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
        self.backend.validate().map_err(|e| e.to_string())?;
        Ok(())
    }
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
}
