//! TUM trajectory files: `timestamp tx ty tz qx qy qz qw`, one pose per line,
//! each `T_world_sensor`.

use std::io::Write;
use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use crate::{Error, Result};

/// A pose with its timestamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Seconds.
    pub stamp: f64,
    /// `T_world_sensor`.
    pub pose: Isometry3<f64>,
}

/// Field names in TUM order, for messages.
const FIELDS: [&str; 8] = ["timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"];

/// Read a TUM file. Blank lines and `#` comments are skipped.
///
/// Every other line must hold exactly eight finite numbers. Quaternions are
/// normalised (a zero quaternion is an error). Errors name the file and the
/// 1-based line.
pub fn read_tum(path: &Path) -> Result<Vec<StampedPose>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_tum(&bytes, path)
}

/// Parse the content of a TUM file (`path` names it in errors); see
/// [`read_tum`].
pub fn parse_tum(bytes: &[u8], path: &Path) -> Result<Vec<StampedPose>> {
    Ok(parse_tum_lines(bytes, path)?
        .into_iter()
        .map(|(_, pose)| pose)
        .collect())
}

/// [`parse_tum`], each pose with its 1-based line number in the file (for
/// errors found later, such as an implausible pose).
pub fn parse_tum_lines(bytes: &[u8], path: &Path) -> Result<Vec<(usize, StampedPose)>> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::format(path, format!("not valid UTF-8 text ({e})")))?;
    let mut poses = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fail = |msg: String| Error::format(path, format!("line {line_no}: {msg}"));
        let mut v = [0f64; 8];
        let mut n = 0;
        for tok in line.split_ascii_whitespace() {
            if n < 8 {
                v[n] = tok.parse().map_err(|_| {
                    fail(format!(
                        "field '{}' is not a number: '{}'",
                        FIELDS[n],
                        crate::error::excerpt(tok)
                    ))
                })?;
                if !v[n].is_finite() {
                    return Err(fail(format!(
                        "field '{}' is not finite: '{}'",
                        FIELDS[n],
                        crate::error::excerpt(tok)
                    )));
                }
            }
            n += 1;
        }
        if n != 8 {
            return Err(fail(format!(
                "expected 8 fields (timestamp tx ty tz qx qy qz qw), found {n}"
            )));
        }
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        let norm = q.norm();
        if !norm.is_finite() || norm <= 1e-12 {
            return Err(fail("quaternion has zero norm".to_string()));
        }
        poses.push((
            line_no,
            StampedPose {
                stamp: v[0],
                pose: Isometry3::from_parts(
                    Translation3::new(v[1], v[2], v[3]),
                    UnitQuaternion::new_unchecked(q / norm),
                ),
            },
        ));
    }
    Ok(poses)
}

/// Write a TUM file (atomically).
///
/// Timestamps get six decimals (microseconds, as the 3DRef files), the other
/// values nine.
pub fn write_tum(path: &Path, poses: &[StampedPose]) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        for p in poses {
            let t = &p.pose.translation.vector;
            let q = p.pose.rotation.quaternion();
            writeln!(
                w,
                "{:.6} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9}",
                p.stamp, t.x, t.y, t.z, q.i, q.j, q.k, q.w
            )?;
        }
        Ok(())
    })
}
