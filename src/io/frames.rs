//! Frame directories and frame-to-pose matching by timestamp.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use super::StampedPose;
use crate::{Error, Result};

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

/// The stem of a frame file and the timestamp it encodes, e.g.
/// `1689496219.652560.ply` gives `("1689496219.652560", 1689496219.65256)`.
///
/// Frames are named `<timestamp>.ply`; the stem names predictions and the
/// timestamp matches the frame to its pose. Errors (naming the file) when the
/// stem is not a finite number.
pub fn parse_stamp(path: &Path) -> Result<(String, f64)> {
    let bad = || Error::format(path, "file name must be <timestamp>.ply");
    let stem = path.file_stem().and_then(|s| s.to_str()).ok_or_else(bad)?;
    let stamp: f64 = stem.parse().map_err(|_| bad())?;
    if !stamp.is_finite() {
        return Err(bad());
    }
    Ok((stem.to_string(), stamp))
}

/// The directory holding a sequence's frames: `dir` itself, or, for the
/// 3DRef release layout (`raw/seqN/` with the frames in
/// `raw/seqN/raycast/hesai/`), that subdirectory, read in place.
pub fn frame_dir(dir: &Path) -> PathBuf {
    let release = dir.join("raycast").join("hesai");
    if release.is_dir() {
        release
    } else {
        dir.to_path_buf()
    }
}

/// The pose file of the 3DRef release layout (`raw/seqN/hesai_pose.txt`)
/// when `dir` is such a sequence directory and the file exists.
pub fn release_poses(dir: &Path) -> Option<PathBuf> {
    let poses = dir.join("hesai_pose.txt");
    (dir.join("raycast").join("hesai").is_dir() && poses.is_file()).then_some(poses)
}

/// All `*.ply` frames in `dir`, sorted by timestamp. Errors when the
/// directory is unreadable, holds no frame, or a stem is not a timestamp.
pub fn list_frames(dir: &Path) -> Result<Vec<FrameEntry>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let mut frames = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Error::io(dir, e))?;
        let path = entry.path();
        let is_ply = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
        if !is_ply || !path.is_file() {
            continue;
        }
        let (name, stamp) = parse_stamp(&path)?;
        frames.push(FrameEntry { path, name, stamp });
    }
    if frames.is_empty() {
        return Err(Error::Input(format!(
            "no *.ply frames in {}",
            dir.display()
        )));
    }
    frames.sort_by(|a, b| {
        a.stamp
            .total_cmp(&b.stamp)
            .then_with(|| a.name.cmp(&b.name))
    });
    Ok(frames)
}

/// Seconds for messages: three decimals, more for small values.
fn secs(d: f64) -> String {
    if d >= 0.1 {
        format!("{d:.3}")
    } else {
        format!("{d:.6}")
    }
}

/// The pose of each frame: the pose whose timestamp is nearest, which must lie
/// within `tolerance` seconds. Never by position in a list. `poses_path` names
/// the pose file in errors.
///
/// `poses` need not be sorted. On a tie the earlier pose wins.
pub fn match_poses(
    frames: &[FrameEntry],
    poses: &[StampedPose],
    tolerance: f64,
    poses_path: &Path,
) -> Result<Vec<Isometry3<f64>>> {
    if tolerance.is_nan() || tolerance < 0.0 {
        return Err(Error::Config(format!(
            "pose time tolerance must be a number >= 0, got {tolerance}"
        )));
    }
    if poses.is_empty() {
        return Err(Error::format(poses_path, "the pose file holds no poses"));
    }
    let mut sorted: Vec<&StampedPose> = poses.iter().collect();
    sorted.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    frames
        .iter()
        .map(|f| {
            let i = sorted.partition_point(|p| p.stamp < f.stamp);
            let mut best: Option<(f64, &StampedPose)> = None;
            for j in [i.checked_sub(1), Some(i)].into_iter().flatten() {
                if let Some(p) = sorted.get(j) {
                    let d = (p.stamp - f.stamp).abs();
                    if best.is_none_or(|(bd, _)| d < bd) {
                        best = Some((d, p));
                    }
                }
            }
            match best {
                Some((d, p)) if d <= tolerance => Ok(p.pose),
                Some((d, _)) => Err(Error::format(
                    poses_path,
                    format!(
                        "no pose within {tolerance} s of frame {} (nearest is {} s away)",
                        f.name,
                        secs(d)
                    ),
                )),
                None => Err(Error::format(poses_path, "the pose file holds no poses")),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(stamp: f64, x: f64) -> StampedPose {
        StampedPose {
            stamp,
            pose: Isometry3::translation(x, 0.0, 0.0),
        }
    }

    fn frame(stamp: f64) -> FrameEntry {
        FrameEntry {
            path: PathBuf::from(format!("{stamp}.ply")),
            name: format!("{stamp}"),
            stamp,
        }
    }

    #[test]
    fn nearest_pose_in_unsorted_list() {
        let poses = [pose(3.0, 3.0), pose(1.0, 1.0), pose(2.0, 2.0)];
        let frames = [frame(2.004), frame(0.999), frame(3.0)];
        let m = match_poses(&frames, &poses, 0.005, Path::new("p.txt")).unwrap();
        let xs: Vec<f64> = m.iter().map(|p| p.translation.x).collect();
        assert_eq!(xs, vec![2.0, 1.0, 3.0]);
    }

    #[test]
    fn too_far_is_an_error() {
        let poses = [pose(1.0, 1.0)];
        let err = match_poses(&[frame(1.731)], &poses, 0.005, Path::new("p.txt"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("p.txt"), "{err}");
        assert!(
            err.contains("no pose within 0.005 s of frame 1.731 (nearest is 0.731 s away)"),
            "{err}"
        );
    }

    #[test]
    fn stamps_from_names() {
        let (n, s) = parse_stamp(Path::new("/x/1689496219.652560.ply")).unwrap();
        assert_eq!(n, "1689496219.652560");
        assert_eq!(s, 1689496219.65256);
        assert!(parse_stamp(Path::new("scan.ply")).is_err());
        assert!(parse_stamp(Path::new("nan.ply")).is_err());
    }
}
