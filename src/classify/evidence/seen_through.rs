//! Where the point was measured, beams seen through the same glass passed
//! (nothing real is there, so it is a mirror image), or a surface was seen
//! through it (3DRef labels whatever lands there real).

use serde::{Deserialize, Serialize};

use super::seen_space::CLEARANCE_RATIO;
use super::{rate_weight, BehindPoint, EvidenceTest};
use crate::classify::rule::Rule;
use crate::classify::space::Occupancy;

/// The measured position lies in space that the beams of confirmed
/// transmissions (real echoes behind a pane, their mirror images refuted by
/// the space seen directly) crossed on their way through the glass: no
/// surface there, so the echo came back from the pane's mirror side. A
/// ceiling reflected in a window with the street behind it is the case:
/// the transmitted beams to the buildings across the street cross where
/// the ceiling's image lies, and no other test speaks for it.
///
/// Where a surface was seen through the glass in the voxel of the measured
/// position ([`BehindPoint::on_surface_seen_through`](super::BehindPoint)), the point is
/// labelled real whatever its path: a floor that runs on behind a glass
/// partition is its own mirror image, and its reflection lands on it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeenThrough {
    /// Share of the reflections behind a landmark whose measured position
    /// the beams seen through glass crossed (probability).
    pub reflection_rate: f64,
    /// Share of the real points behind a landmark whose measured position
    /// they crossed: a confirmed transmission that was a reflection, plane
    /// and pose errors moving a beam across a real surface (probability).
    pub real_rate: f64,
    /// Share of the reflections behind a landmark measured on a surface
    /// seen through it (probability).
    pub surface_reflection_rate: f64,
    /// Share of the real points behind a landmark measured on a surface
    /// seen through it (probability).
    pub surface_real_rate: f64,
}

/// The values of `configs/default.toml`.
impl Default for SeenThrough {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.seen_through")
    }
}

impl EvidenceTest for SeenThrough {
    fn name(&self) -> &str {
        "seen-through"
    }

    fn rule(&self) -> Rule {
        Rule::SeenThrough
    }

    fn is_likelihood_ratio(&self) -> bool {
        true
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        if point.on_surface_seen_through {
            return Some(rate_weight(
                self.surface_reflection_rate,
                self.surface_real_rate,
            ));
        }
        let space = point.space.filter(|_| point.single_pane)?;
        let clearance = CLEARANCE_RATIO * point.range;
        (space.through_occupancy_clear_of(&point.position, clearance)? == Occupancy::Free)
            .then(|| rate_weight(self.reflection_rate, self.real_rate))
    }
}
