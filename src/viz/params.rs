//! What the outputs for people are made of: the voxel that thins the
//! accumulated PLY maps and the height slice the top-down map draws. The
//! defaults are `configs/default.toml`'s.

use serde::{Deserialize, Serialize};

use super::topdown::HeightSlice;

/// Output settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputParams {
    /// Voxel size used to thin the accumulated PLY maps, m (0 keeps every
    /// point).
    pub map_voxel: f64,
    /// The top-down map (`topdown.png`) draws the points from this height
    /// above the floor, m (`-inf`: no lower bound): the floor left out.
    pub topdown_min_height: f64,
    /// ... up to this height above the floor, m (`inf`: no upper bound):
    /// the ceiling left out.
    pub topdown_max_height: f64,
}

impl OutputParams {
    /// The heights drawn in the top-down map.
    pub fn topdown_slice(&self) -> HeightSlice {
        HeightSlice {
            min: self.topdown_min_height,
            max: self.topdown_max_height,
        }
    }
}

impl Default for OutputParams {
    /// `[output]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("output")
    }
}
