//! Frame directories and frame-to-pose matching by timestamp.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use super::StampedPose;
use crate::Result;

/// A frame file found in a directory.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameEntry {
    /// Path to the `.ply` file.
    pub path: PathBuf,
    /// File stem (the prediction file is named after it).
    pub name: String,
    /// Timestamp parsed from the stem, seconds.
    pub stamp: f64,
}

/// All `*.ply` frames in `dir`, sorted by timestamp. Errors when the
/// directory is unreadable, holds no frame, or a stem is not a timestamp.
pub fn list_frames(dir: &Path) -> Result<Vec<FrameEntry>> {
    todo!("{}", dir.display())
}

/// The pose of each frame: the pose whose timestamp is nearest, which must lie
/// within `tolerance` seconds. Never by position in a list. `poses_path` names
/// the pose file in errors.
pub fn match_poses(
    frames: &[FrameEntry],
    poses: &[StampedPose],
    tolerance: f64,
    poses_path: &Path,
) -> Result<Vec<Isometry3<f64>>> {
    todo!(
        "{} {} {} {}",
        frames.len(),
        poses.len(),
        tolerance,
        poses_path.display()
    )
}
