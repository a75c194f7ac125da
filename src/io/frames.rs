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

/// The sensor folders of the 3DRef release, in the order a sequence
/// directory's is chosen: `raw/seqN/raycast/<sensor>/` holds a sensor's
/// frames and `raw/seqN/<sensor>_pose.txt` its poses. The labelling script
/// writes every sensor's frames with one writer (ascii float `x y z nx ny
/// nz intensity ring return label`), so all three are read alike.
pub const RELEASE_SENSORS: [&str; 3] = ["hesai", "ouster", "livox"];

/// The release sensor folder `dir` is or holds: `(frames, sequence
/// directory, sensor)`. `dir` is a sequence directory (`raw/seqN`, whose
/// first sensor folder in [`RELEASE_SENSORS`] order is taken) or a sensor
/// folder itself (`raw/seqN/raycast/ouster`).
fn release_folder(dir: &Path) -> Option<(PathBuf, PathBuf, &'static str)> {
    for sensor in RELEASE_SENSORS {
        let frames = dir.join("raycast").join(sensor);
        if frames.is_dir() {
            return Some((frames, dir.to_path_buf(), sensor));
        }
    }
    let name = dir.file_name()?.to_str()?;
    let sensor = RELEASE_SENSORS.into_iter().find(|s| *s == name)?;
    let raycast = dir
        .parent()
        .filter(|p| p.file_name().is_some_and(|n| n == "raycast"))?;
    Some((dir.to_path_buf(), raycast.parent()?.to_path_buf(), sensor))
}

/// The directory holding a sequence's frames: `dir` itself, or, for the
/// 3DRef release layout (`raw/seqN/` with the frames in
/// `raw/seqN/raycast/{hesai,ouster,livox}/`), the first sensor folder
/// there ([`RELEASE_SENSORS`]), read in place. Give the sensor folder
/// itself (`raw/seqN/raycast/ouster`) to read another sensor.
pub fn frame_dir(dir: &Path) -> PathBuf {
    release_folder(dir).map_or_else(|| dir.to_path_buf(), |(frames, _, _)| frames)
}

/// The pose file of the 3DRef release layout (`raw/seqN/<sensor>_pose.txt`
/// for the sensor folder [`frame_dir`] reads) when `dir` is a sequence
/// directory or one of its sensor folders and the file exists.
pub fn release_poses(dir: &Path) -> Option<PathBuf> {
    let (_, seq, sensor) = release_folder(dir)?;
    let poses = seq.join(format!("{sensor}_pose.txt"));
    poses.is_file().then_some(poses)
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
        if !is_ply {
            continue;
        }
        if !path.is_file() {
            // Named as a frame but not one: say so rather than run on
            // without it.
            let what = match std::fs::symlink_metadata(&path) {
                Ok(m) if m.file_type().is_symlink() => "a symbolic link to nothing readable",
                Ok(m) if m.is_dir() => "a directory",
                _ => "not a regular file (a FIFO, socket or device)",
            };
            return Err(Error::format(
                &path,
                format!("named as a frame but is {what}: remove or rename it"),
            ));
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
            .then_with(|| a.path.cmp(&b.path))
    });
    // Outputs are named after the stem: two frames with one stem
    // (`X.ply` and `X.PLY`) would write over each other's labels.
    if let Some(w) = frames.windows(2).find(|w| w[0].name == w[1].name) {
        return Err(Error::format(
            &w[0].path,
            format!(
                "{} has the same stem, so their outputs would have the same name: keep one",
                w[1].path.display()
            ),
        ));
    }
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

/// How frames find their poses by timestamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseMatching {
    /// A pose within this many seconds of a frame is taken as it is.
    pub tolerance: f64,
    /// Otherwise the frame's pose is interpolated between the poses just
    /// before and after it (linear in translation, SLERP in rotation) when
    /// they are at most this many seconds apart (0: never).
    pub max_gap: f64,
    /// Metres: a longer pose translation is an error naming its line
    /// ([`MAX_POSE_TRANSLATION`] in a run).
    pub max_translation: f64,
    /// Metres per second: consecutive frames whose poses are farther apart
    /// for the time between them are an error ([`MAX_SPEED`] in a run).
    pub max_speed: f64,
}

/// Pose sanity, metres: a pose (`T_world_sensor`) whose translation is
/// longer is an error naming the pose file and line. No LiDAR carried by a
/// vehicle or a person is 100 km from its map origin; such a pose is
/// corrupt or in the wrong unit, and would silently classify every point as
/// Normal.
pub const MAX_POSE_TRANSLATION: f64 = 1e5;

/// Pose sanity, metres per second: consecutive frames whose poses are
/// farther apart than this times the time between their timestamps are an
/// error naming the pose file and line (100 m/s, 360 km/h, is beyond any
/// vehicle or person carrying a LiDAR).
pub const MAX_SPEED: f64 = 100.0;

impl From<f64> for PoseMatching {
    /// The nearest pose within `tolerance` seconds, no interpolation, the
    /// default pose sanity bounds.
    fn from(tolerance: f64) -> Self {
        Self {
            tolerance,
            max_gap: 0.0,
            max_translation: MAX_POSE_TRANSLATION,
            max_speed: MAX_SPEED,
        }
    }
}

/// Match every frame to the pose with the nearest timestamp in `poses`
/// (any order), which must lie within `tolerance` seconds. Errors (naming
/// `poses_path` and the frame) when a frame has no pose close enough.
pub fn match_poses(
    frames: &[FrameEntry],
    poses: &[StampedPose],
    tolerance: f64,
    poses_path: &Path,
) -> Result<Vec<Isometry3<f64>>> {
    match_poses_with(frames, poses, tolerance.into(), poses_path)
}

/// [`match_poses`], and a frame with no pose within the tolerance gets one
/// interpolated between its neighbours when they are close enough in time
/// ([`PoseMatching::max_gap`]). Errors name the file, the frame and how far
/// its poses are.
pub fn match_poses_with(
    frames: &[FrameEntry],
    poses: &[StampedPose],
    matching: PoseMatching,
    poses_path: &Path,
) -> Result<Vec<Isometry3<f64>>> {
    let PoseMatching {
        tolerance, max_gap, ..
    } = matching;
    for (name, v) in [("tolerance", tolerance), ("interpolation gap", max_gap)] {
        if v.is_nan() || v < 0.0 {
            return Err(Error::Config(format!(
                "pose time {name} must be a number >= 0, got {v}"
            )));
        }
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
            let (before, after) = (i.checked_sub(1).map(|j| sorted[j]), sorted.get(i).copied());
            let nearest = [before, after]
                .into_iter()
                .flatten()
                .min_by(|a, b| {
                    (a.stamp - f.stamp)
                        .abs()
                        .total_cmp(&(b.stamp - f.stamp).abs())
                })
                .ok_or_else(|| Error::format(poses_path, "the pose file holds no poses"))?;
            let d = (nearest.stamp - f.stamp).abs();
            if d <= tolerance {
                return Ok(nearest.pose);
            }
            let far = format!(
                "no pose within {tolerance} s of frame {} (nearest is {} s away){}",
                f.name,
                secs(d),
                unit_hint(f.stamp, nearest.stamp)
            );
            match (before, after) {
                (Some(a), Some(b)) if max_gap > 0.0 => {
                    let gap = b.stamp - a.stamp;
                    if gap <= max_gap {
                        let s = (f.stamp - a.stamp) / gap;
                        Ok(interpolate(&a.pose, &b.pose, s))
                    } else {
                        Err(Error::format(
                            poses_path,
                            format!(
                                "{far}, and its neighbours are {} s apart, more than the {max_gap} s a pose is interpolated across",
                                secs(gap)
                            ),
                        ))
                    }
                }
                (None, _) | (_, None) if max_gap > 0.0 => Err(Error::format(
                    poses_path,
                    format!("{far}, and it lies outside the poses' time span: nothing to interpolate between"),
                )),
                _ => Err(Error::format(poses_path, far)),
            }
        })
        .collect()
}

/// A hint when a frame's and a pose's timestamps differ by a factor of
/// about 1e3, 1e6 or 1e9: one of them is in milli-, micro- or nanoseconds
/// where seconds are expected (ROS bags stamp in nanoseconds).
fn unit_hint(frame: f64, pose: f64) -> String {
    if !(frame > 0.0 && pose > 0.0) {
        return String::new();
    }
    let decades = (frame / pose).log10();
    let (bigger, factor) = if decades > 0.0 {
        ("frame", decades)
    } else {
        ("pose", -decades)
    };
    let unit = [(3.0, "milli"), (6.0, "micro"), (9.0, "nano")]
        .into_iter()
        .find(|(d, _)| (factor - d).abs() < 0.5)
        .map(|(_, u)| u);
    match unit {
        Some(u) => format!(
            "; the {bigger} timestamps look like {u}seconds, both must be seconds \
             (e.g. a frame named 1689496219.652560.ply)"
        ),
        None => String::new(),
    }
}

/// The poses of `frames` from the pose file at `path`: TUM (timestamped,
/// matched by [`match_poses_with`]) or KITTI (12 numbers a line, no
/// timestamps: one pose per frame in time order, so the counts must agree).
pub fn read_poses_for(
    frames: &[FrameEntry],
    path: &Path,
    matching: PoseMatching,
) -> Result<Vec<Isometry3<f64>>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if super::kitti::is_kitti(&bytes) {
        let poses = super::kitti::parse_kitti_lines(&bytes, path)?;
        if poses.len() != frames.len() {
            return Err(Error::format(
                path,
                format!(
                    "KITTI poses carry no timestamps, so there must be one per frame: {} poses for {} frames",
                    poses.len(),
                    frames.len()
                ),
            ));
        }
        for (line, pose) in &poses {
            check_translation(path, *line, pose, matching.max_translation)?;
        }
        let lines: Vec<usize> = poses.iter().map(|(l, _)| *l).collect();
        let poses: Vec<Isometry3<f64>> = poses.into_iter().map(|(_, p)| p).collect();
        check_speed(frames, &poses, &lines, path, matching.max_speed)?;
        return Ok(poses);
    }
    let lined = super::tum::parse_tum_lines(&bytes, path)?;
    for (line, p) in &lined {
        check_translation(path, *line, &p.pose, matching.max_translation)?;
    }
    // Two poses for one instant must agree (a file concatenated from two
    // runs, or two sensors' poses mixed, would otherwise be matched at
    // random).
    let mut by_time: Vec<&(usize, StampedPose)> = lined.iter().collect();
    by_time.sort_by(|a, b| a.1.stamp.total_cmp(&b.1.stamp).then(a.0.cmp(&b.0)));
    for w in by_time.windows(2) {
        let ((la, a), (lb, b)) = (w[0], w[1]);
        if a.stamp == b.stamp && a.pose != b.pose {
            return Err(Error::format(
                path,
                format!(
                    "lines {la} and {lb} give different poses for the same timestamp {}",
                    a.stamp
                ),
            ));
        }
    }
    let stamped: Vec<StampedPose> = lined.iter().map(|(_, p)| *p).collect();
    let poses = match_poses_with(frames, &stamped, matching, path)?;
    // The line of the pose nearest each frame in time, for messages.
    let lines: Vec<usize> = frames
        .iter()
        .map(|f| {
            let i = by_time.partition_point(|p| p.1.stamp < f.stamp);
            [i.checked_sub(1), Some(i)]
                .into_iter()
                .flatten()
                .filter_map(|j| by_time.get(j))
                .min_by(|a, b| {
                    (a.1.stamp - f.stamp)
                        .abs()
                        .total_cmp(&(b.1.stamp - f.stamp).abs())
                })
                .map_or(0, |p| p.0)
        })
        .collect();
    check_speed(frames, &poses, &lines, path, matching.max_speed)?;
    Ok(poses)
}

/// An error naming `path` and `line` when `pose` lies farther than
/// `max_translation` metres from the origin.
fn check_translation(
    path: &Path,
    line: usize,
    pose: &Isometry3<f64>,
    max_translation: f64,
) -> Result<()> {
    let t = pose.translation.vector.norm();
    if t > max_translation {
        return Err(Error::format(
            path,
            format!(
                "line {line}: the pose is {t:.3e} m from the origin, beyond the pose sanity bound max_pose_translation ({max_translation} m): not a sensor pose (a corrupt number or a wrong unit?)"
            ),
        ));
    }
    Ok(())
}

/// An error naming `path` and the line of the later pose when two
/// consecutive frames' poses are farther apart than `max_speed` metres per
/// second of the time between the frames (`lines`: per frame, the line of
/// its pose).
fn check_speed(
    frames: &[FrameEntry],
    poses: &[Isometry3<f64>],
    lines: &[usize],
    path: &Path,
    max_speed: f64,
) -> Result<()> {
    for k in 1..frames.len().min(poses.len()) {
        let dt = frames[k].stamp - frames[k - 1].stamp;
        let d = (poses[k].translation.vector - poses[k - 1].translation.vector).norm();
        if dt > 0.0 && d > max_speed * dt {
            return Err(Error::format(
                path,
                format!(
                    "line {}: the poses of frames {} and {} are {d:.3} m apart in {} s ({:.1} m/s), faster than the pose sanity bound max_speed ({max_speed} m/s): not a sensor's motion",
                    lines.get(k).copied().unwrap_or(0),
                    frames[k - 1].name,
                    frames[k].name,
                    secs(dt),
                    d / dt
                ),
            ));
        }
    }
    Ok(())
}

/// The pose a share `s` (0..1) of the way from `a` to `b`: linear in
/// translation, spherical-linear in rotation.
pub fn interpolate(a: &Isometry3<f64>, b: &Isometry3<f64>, s: f64) -> Isometry3<f64> {
    let t = a.translation.vector.lerp(&b.translation.vector, s);
    let r = a.rotation.slerp(&b.rotation, s);
    Isometry3::from_parts(t.into(), r)
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

    /// Between two poses 0.1 s apart a frame gets the interpolated pose
    /// (linear translation, SLERP rotation); across a wider gap, or
    /// outside the poses' span, the error says why.
    #[test]
    fn poses_are_interpolated_within_the_gap() {
        use nalgebra::{UnitQuaternion, Vector3};
        let turn = |deg: f64| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), deg.to_radians());
        let poses = [
            StampedPose {
                stamp: 1.0,
                pose: Isometry3::from_parts(Vector3::new(0.0, 0.0, 0.0).into(), turn(0.0)),
            },
            StampedPose {
                stamp: 1.1,
                pose: Isometry3::from_parts(Vector3::new(1.0, 2.0, 0.0).into(), turn(40.0)),
            },
            StampedPose {
                stamp: 3.0,
                pose: Isometry3::translation(5.0, 0.0, 0.0),
            },
        ];
        let matching = PoseMatching {
            tolerance: 0.005,
            max_gap: 0.2,
            ..PoseMatching::from(0.0)
        };
        let path = Path::new("p.txt");
        let m = match_poses_with(&[frame(1.025)], &poses, matching, path).unwrap();
        assert!((m[0].translation.vector - Vector3::new(0.25, 0.5, 0.0)).norm() < 1e-9);
        assert!((m[0].rotation.angle().to_degrees() - 10.0).abs() < 1e-9);
        // Within the tolerance the nearest pose is taken as it is.
        let m = match_poses_with(&[frame(1.099)], &poses, matching, path).unwrap();
        assert_eq!(m[0], poses[1].pose);
        let wide = match_poses_with(&[frame(2.0)], &poses, matching, path)
            .unwrap_err()
            .to_string();
        assert!(
            wide.contains("1.900 s apart") && wide.contains("0.2 s"),
            "{wide}"
        );
        let outside = match_poses_with(&[frame(3.5)], &poses, matching, path)
            .unwrap_err()
            .to_string();
        assert!(
            outside.contains("outside the poses' time span"),
            "{outside}"
        );
        // Without interpolation the frame between is an error.
        assert!(match_poses(&[frame(1.025)], &poses, 0.005, path).is_err());
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
