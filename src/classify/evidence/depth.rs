//! Deeper behind the landmark than the room in front of it.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;

/// A reflection appears as deep behind the plane as its real object stands
/// in front: a point deeper than everything the frame saw in front of the
/// landmark is likely real.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Depth {
    /// Probability that a reflection lies deeper than the room the frame
    /// saw (its object outside the field of view or occluded).
    pub error: f64,
    /// Deeper than the room by this much, m (range noise).
    pub margin: f64,
}

/// The values of `configs/default.toml`.
impl Default for Depth {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.depth")
    }
}

impl EvidenceTest for Depth {
    fn name(&self) -> &str {
        "depth"
    }

    fn rule(&self) -> Rule {
        Rule::Depth
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        (point.depth() > point.room_depth + self.margin).then(|| -outcome_weight(self.error))
    }
}
