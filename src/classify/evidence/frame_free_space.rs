//! The frame saw through the place the mirror image would be.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::decide::returns_along;
use crate::classify::rule::Rule;

/// Mirrored through the landmark, a reflection lands on a real surface; if
/// every beam around the image's direction returned from farther away, the
/// frame saw through that place, and the point is real.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrameFreeSpace {
    /// Probability that the beams around a true reflection's image all pass
    /// it (the image falls between rings, the mirrored surface is thin).
    pub error: f64,
    /// A return this much farther than the image proves the place free, m
    /// (range noise) ...
    pub margin: f64,
    /// ... plus this share of the image's range (an error in the plane's
    /// orientation moves images in proportion to their range).
    pub margin_ratio: f64,
}

impl Default for FrameFreeSpace {
    fn default() -> Self {
        Self {
            error: 0.03,
            margin: 0.1,
            margin_ratio: 0.01,
        }
    }
}

impl EvidenceTest for FrameFreeSpace {
    fn name(&self) -> &str {
        "frame-free-space"
    }

    fn rule(&self) -> Rule {
        Rule::FrameFreeSpace
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let (_, far) = returns_along(point.scan, point.sensor, point.frame, &point.mirrored, 1)?;
        let range = point.mirrored.coords.norm();
        (far > range + self.margin + self.margin_ratio * range).then(|| -outcome_weight(self.error))
    }
}
