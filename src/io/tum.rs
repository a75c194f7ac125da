//! TUM trajectory files: `timestamp tx ty tz qx qy qz qw`, one pose per line,
//! each `T_world_sensor`.

use std::path::Path;

use nalgebra::Isometry3;

use crate::Result;

/// A pose with its timestamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Seconds.
    pub stamp: f64,
    /// `T_world_sensor`.
    pub pose: Isometry3<f64>,
}

/// Read a TUM file. Blank lines and `#` comments are skipped.
pub fn read_tum(path: &Path) -> Result<Vec<StampedPose>> {
    todo!("{}", path.display())
}

/// Write a TUM file (atomically).
pub fn write_tum(path: &Path, poses: &[StampedPose]) -> Result<()> {
    todo!("{} {}", path.display(), poses.len())
}
