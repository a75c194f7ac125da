//! A surface seen directly where the point was measured.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;
use crate::classify::space::Occupancy;

/// Where the point was measured, a surface was seen directly from elsewhere
/// in the sequence: it is likely real. A mirror image lands near some
/// observed surface far more often than exactly on one.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeenSurface {
    /// Probability that a reflection lands exactly on a voxel seen occupied
    /// (a floor or ceiling continuing behind the glass is its own mirror
    /// image).
    pub error: f64,
}

/// The values of `configs/default.toml`.
impl Default for SeenSurface {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.seen_surface")
    }
}

impl EvidenceTest for SeenSurface {
    fn name(&self) -> &str {
        "seen-surface"
    }

    fn rule(&self) -> Rule {
        Rule::SeenSurface
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let space = point.space.filter(|_| point.single_pane)?;
        (space.occupancy(&point.position) == Occupancy::Occupied)
            .then(|| -outcome_weight(self.error))
    }
}
