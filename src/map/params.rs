//! The plane-map stage's parameters: which merger fuses observations, which
//! landmarks are reliable enough to classify against, and how a reflective
//! landmark is bounded. The merger, evidence and pane parameters it
//! composes live with their own code ([`super::merge`], [`super::evidence`],
//! [`super::panes`]); the defaults are `configs/default.toml`'s.

use serde::{Deserialize, Serialize};

use super::{EvidenceParams, GhostParams, LandmarkSelection, MergeParams, PaneParams};

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
#[serde(deny_unknown_fields)]
pub struct MapParams {
    /// The merger: the paper's weighted average, the only one (no key).
    #[serde(skip, default = "weighted_average")]
    pub merger: MergerName,
    /// Landmarks observed fewer times (frames) are not used for
    /// classification (paper: 10).
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
    /// Landmarks that are reflections of seen surfaces in other glass
    /// (tested once the sequence's surfaces are known).
    pub ghosts: GhostParams,
}

impl MapParams {
    /// The landmark selection these parameters describe.
    pub fn selection(&self) -> LandmarkSelection {
        LandmarkSelection {
            min_observations: self.min_observations,
            min_found_ratio: self.min_found_ratio,
            visibility_range: self.visibility_range,
            field: None,
        }
    }
}

/// The merger of every configuration: the paper's weighted average.
fn weighted_average() -> MergerName {
    MergerName::WeightedAverage
}

impl Default for MapParams {
    /// `[map]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("map")
    }
}
