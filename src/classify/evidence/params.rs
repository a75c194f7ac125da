//! The weighing's configuration: which tests, and the parameters each owns.

use serde::{Deserialize, Serialize};

use super::{
    Depth, EchoOrder, EchoStrength, FrameFreeSpace, ImageSupport, LevelSurface, SeenSpace,
    SeenSurface, SeenThrough,
};

/// Parameters of the evidence weighing behind reflective landmarks
/// (`[plane_map.weighing]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeighingParams {
    /// The tests weighed, by name: `seen-space`, `seen-surface`,
    /// `image-support`, `frame-free-space`, `depth`, `echo-strength`,
    /// `echo-order`, `level-surface`, `seen-through`.
    pub tests: Vec<String>,
    /// The posterior a class needs to be given; a point whose posterior
    /// falls short either way stays unclassified (probability, 0.5-1).
    pub threshold: f64,
    /// Probability that a point behind glass is a reflection before any
    /// test (behind a mirror every point is one).
    pub reflection_prior: f64,
    /// The seen-space test's parameters.
    pub seen_space: SeenSpace,
    /// The seen-surface test's parameters.
    pub seen_surface: SeenSurface,
    /// The image-support test's parameters.
    pub image_support: ImageSupport,
    /// The frame-free-space test's parameters.
    pub frame_free_space: FrameFreeSpace,
    /// The depth test's parameters.
    pub depth: Depth,
    /// The echo-strength test's parameters.
    pub echo_strength: EchoStrength,
    /// The echo-order test's parameters.
    pub echo_order: EchoOrder,
    /// The level-surface test's parameters.
    pub level_surface: LevelSurface,
    /// The seen-through test's parameters.
    pub seen_through: SeenThrough,
}

/// Every built-in test's name, in the order they are weighed.
pub const TEST_NAMES: [&str; 9] = [
    "seen-space",
    "seen-surface",
    "image-support",
    "frame-free-space",
    "depth",
    "echo-strength",
    "echo-order",
    "level-surface",
    "seen-through",
];

/// The values of `configs/default.toml`.
impl Default for WeighingParams {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing")
    }
}
