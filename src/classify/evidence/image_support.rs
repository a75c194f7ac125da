//! The mirror image lands on an observed surface.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::decide::returns_along;
use crate::classify::rule::Rule;

/// Mirrored through the landmark, a reflection lands on a real surface: a
/// return of the frame at that range along the image's beam, or an observed
/// surface within a radius.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSupport {
    /// Probability that the image of a real point lands on an observed
    /// surface by chance (cluttered rooms, surfaces perpendicular to the
    /// glass that are their own mirror image).
    pub error: f64,
    /// An observed surface within this radius of the image supports it, m.
    /// An image this near the point itself is supported by the point's own
    /// surface: no evidence.
    pub radius: f64,
}

/// A return within this range of the image along its beam supports it, m
/// (range noise and the plane's error).
const RANGE_TOLERANCE: f64 = 0.1;

/// The values of `configs/default.toml`.
impl Default for ImageSupport {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.image_support")
    }
}

impl EvidenceTest for ImageSupport {
    fn name(&self) -> &str {
        "image-support"
    }

    fn rule(&self) -> Rule {
        Rule::Support
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        if (point.mirrored - point.position).norm() <= self.radius {
            return None;
        }
        let image_range = point.mirrored.coords.norm();
        let on_beam = returns_along(point.scan, point.sensor, point.frame, &point.mirrored, 1)
            .is_some_and(|(closest, _)| (closest - image_range).abs() <= RANGE_TOLERANCE);
        let nearby = || {
            point
                .support
                .is_some_and(|s| s.near(&point.mirrored, self.radius))
        };
        (on_beam || nearby()).then(|| outcome_weight(self.error))
    }
}
