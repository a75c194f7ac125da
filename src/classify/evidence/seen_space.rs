//! The space seen directly over the sequence: a hypothesis whose endpoint
//! lies in space seen free, or whose path beyond the landmark runs through a
//! seen surface, is refuted.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::decide::leg_refuted;
use crate::classify::rule::Rule;
use crate::classify::space::SensorFrameSpace;
use crate::classify::SurfaceSupport;

/// Both hypotheses against the space seen directly: where it was measured
/// seen free favours the Reflection; its mirror image seen free (or the
/// reflected path through a seen surface) favours it being real.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeenSpace {
    /// Probability that the seen space refutes a true hypothesis (pose and
    /// plane errors, objects thinner than a voxel, people moving).
    pub error: f64,
    /// Paths are tested from this far off the plane to this far before
    /// their endpoint, m (frames and wall strips around a pane, the surface
    /// the endpoint lies on).
    pub margin: f64,
}

/// A position is seen free only if no seen surface lies within this share
/// of its range (at least a voxel): the plane's angular error (about a
/// degree) moves mirror images in proportion to their range.
pub const CLEARANCE_RATIO: f64 = 0.02;

/// A path towards a surface observed within this radius of its endpoint is
/// not refuted by a voxel it clips on the way, m (the paper's support
/// radius, √0.1 m).
pub const SUPPORT_RADIUS: f64 = 0.316;

/// The values of `configs/default.toml`.
impl Default for SeenSpace {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.seen_space")
    }
}

impl SeenSpace {
    /// Whether the hypothesis "the echo came from `end`", reached by a leg
    /// that leaves the plane at `x`, is refuted by the seen space.
    pub(crate) fn refuted(
        &self,
        space: &SensorFrameSpace<'_>,
        support: Option<&dyn SurfaceSupport>,
        normal: &nalgebra::Vector3<f64>,
        x: &Point3<f64>,
        end: &Point3<f64>,
        range: f64,
    ) -> bool {
        leg_refuted(
            space,
            support,
            normal,
            x,
            end,
            (self.margin, CLEARANCE_RATIO * range, SUPPORT_RADIUS),
        )
    }
}

impl EvidenceTest for SeenSpace {
    fn name(&self) -> &str {
        "seen-space"
    }

    fn rule(&self) -> Rule {
        Rule::RealRefuted
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let space = point.space.filter(|_| point.single_pane)?;
        let x = point.crossing_point();
        let normal = point.landmark.plane.normal;
        let w = outcome_weight(self.error);
        let real_refuted = self.refuted(
            space,
            point.support,
            &normal,
            &x,
            &point.position,
            point.range,
        );
        let image_refuted = self.refuted(
            space,
            point.support,
            &normal,
            &x,
            &point.mirrored,
            point.range,
        );
        match (real_refuted, image_refuted) {
            (true, false) => Some(w),
            (false, true) => Some(-w),
            _ => None,
        }
    }
}
