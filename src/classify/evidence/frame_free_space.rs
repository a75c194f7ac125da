//! The frame saw through the place the mirror image would be.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::decide::returns_along;
use crate::classify::rule::Rule;

/// Mirrored through the landmark, a reflection lands on a real surface; if
/// every beam around the image's direction returned from farther away, the
/// frame saw through that place, and the point is real.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameFreeSpace {
    /// Probability that the beams around a true reflection's image all pass
    /// it (the image falls between rings, the mirrored surface is thin).
    pub error: f64,
    /// A return this much farther than the image proves the place free, m
    /// (range noise), plus a share `MARGIN_RATIO` (0.01) of the image's range.
    pub margin: f64,
}

/// The free-space margin grows by this share of the image's range: an
/// error in the plane's orientation moves images in proportion.
pub const MARGIN_RATIO: f64 = 0.01;

/// The values of `configs/default.toml`.
impl Default for FrameFreeSpace {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.frame_free_space")
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
        (far > range + self.margin + MARGIN_RATIO * range).then(|| -outcome_weight(self.error))
    }
}
