//! Which echo of a dual-return beam the point is.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;

/// On a beam whose two returns both lie behind the landmark, well apart,
/// the near one is likelier the reflection (the glass sent part of the beam
/// back into the room, where it met something nearer than what lies behind)
/// and the far one the transmitted echo.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EchoOrder {
    /// Probability that the order points the wrong way.
    pub error: f64,
}

/// Two returns at least this far apart are distinct echoes, m (the dual
/// returns' separation of the detector).
const MIN_GAP: f64 = 0.1;

/// The values of `configs/default.toml`.
impl Default for EchoOrder {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.echo_order")
    }
}

impl EvidenceTest for EchoOrder {
    fn name(&self) -> &str {
        "echo-order"
    }

    fn rule(&self) -> Rule {
        Rule::DualReturn
    }

    fn tells_the_path(&self) -> bool {
        true
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let other = point.scan.partner(point.index)?;
        let other_range = point.frame.points[other].range();
        // Both behind the landmark's crossing, and distinct.
        if other_range <= point.crossing + MIN_GAP || (other_range - point.range).abs() <= MIN_GAP {
            return None;
        }
        let w = outcome_weight(self.error);
        Some(if point.range < other_range { w } else { -w })
    }
}
