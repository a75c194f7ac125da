//! At the height of a floor or ceiling that runs on behind the glass: 3DRef
//! labels a point behind glass by whether a surface of the scene lies where
//! it was measured, and such a floor is one.

use serde::{Deserialize, Serialize};

use super::{outcome_weight, BehindPoint, EvidenceTest};
use crate::classify::levels::index_near;
use crate::classify::rule::Rule;

/// A point behind glass at the height of a floor or ceiling seen directly
/// ([`crate::classify::levels::Levels`]) that runs on behind its landmark
/// (`BoundedPlane::levels_behind`: transmissions confirmed by the seen
/// space end there) lies on that surface: real where measured. The floor's
/// own reflection lands there too, and 3DRef labels it an Obstacle as
/// well. Behind a mirror every point is a reflection, the floor's image
/// included, so the test weighs by the landmark's probability of being
/// glass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LevelSurface {
    /// Probability that a point the test calls real is a reflection (the
    /// floor runs on behind part of the pane only, an object's mirror image
    /// lands at the floor's height where no floor is).
    pub error: f64,
    /// Within this height of a level, m (range noise, the floor's
    /// flatness; 3DRef's labels give a surface 0.15 m).
    pub tolerance: f64,
}

/// The values of `configs/default.toml`.
impl Default for LevelSurface {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.level_surface")
    }
}

impl EvidenceTest for LevelSurface {
    fn name(&self) -> &str {
        "level-surface"
    }

    fn rule(&self) -> Rule {
        Rule::LevelSurface
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let space = point.space?;
        let z = space.height(&point.position);
        index_near(&point.landmark.levels_behind, z, self.tolerance)?;
        let glass = 1.0 - point.landmark.mirror_probability.unwrap_or(0.0);
        Some(-glass * outcome_weight(self.error))
    }
}
