//! KITTI-format poses: one `3 × 4` matrix `[R | t]` per line, row-major (12
//! numbers), `T_world_sensor` of the i-th frame in time order. The format
//! has no timestamps, so frames are matched by their order alone.

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};

use crate::{Error, Result};

/// Read a KITTI pose file. Errors (naming the file and line) on a line
/// without 12 finite numbers or whose `R` is not a rotation.
pub fn read_kitti(path: &Path) -> Result<Vec<Isometry3<f64>>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_kitti(&bytes, path)
}

/// Parse the content of a KITTI pose file (`path` names it in errors).
pub fn parse_kitti(bytes: &[u8], path: &Path) -> Result<Vec<Isometry3<f64>>> {
    Ok(parse_kitti_lines(bytes, path)?
        .into_iter()
        .map(|(_, pose)| pose)
        .collect())
}

/// [`parse_kitti`], each pose with its 1-based line number in the file.
pub fn parse_kitti_lines(bytes: &[u8], path: &Path) -> Result<Vec<(usize, Isometry3<f64>)>> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| Error::format(path, format!("not valid UTF-8 text ({e})")))?;
    let mut poses = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fail = |msg: String| Error::format(path, format!("line {}: {msg}", i + 1));
        let v: Vec<f64> = line
            .split_ascii_whitespace()
            .map(|t| {
                t.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        fail(format!(
                            "'{}' is not a finite number",
                            crate::error::excerpt(t)
                        ))
                    })
            })
            .collect::<Result<_>>()?;
        if v.len() != 12 {
            return Err(fail(format!(
                "expected 12 numbers (a 3 x 4 matrix [R | t], row-major), found {}",
                v.len()
            )));
        }
        let r = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let off = (r.transpose() * r - Matrix3::identity()).norm();
        if off > 1e-3 || r.determinant() < 0.0 {
            return Err(fail(format!(
                "the 3 x 3 part is not a rotation (|R^T R - I| = {off:.2e}, det = {:.3})",
                r.determinant()
            )));
        }
        // The nearest rotation to R (removes the file's rounding).
        let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
        poses.push((
            i + 1,
            Isometry3::from_parts(Translation3::new(v[3], v[7], v[11]), rotation),
        ));
    }
    Ok(poses)
}

/// Whether a pose file is in KITTI format (its first data line holds 12
/// numbers; TUM lines hold 8).
pub fn is_kitti(bytes: &[u8]) -> bool {
    std::str::from_utf8(bytes).is_ok_and(|text| {
        text.lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))
            .is_some_and(|l| l.split_ascii_whitespace().count() == 12)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    #[test]
    fn kitti_lines_become_poses_and_bad_ones_are_named() {
        let text = "1 0 0 1.5 0 0 -1 2 0 1 0 -3\n\n0 -1 0 0 1 0 0 0 0 0 1 0\n";
        let p = parse_kitti(text.as_bytes(), Path::new("k.txt")).unwrap();
        assert_eq!(p.len(), 2);
        assert_eq!(p[0].translation.vector, Vector3::new(1.5, 2.0, -3.0));
        let x = p[1] * nalgebra::Point3::new(1.0, 0.0, 0.0);
        assert!((x.coords - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        assert!(is_kitti(text.as_bytes()));
        assert!(!is_kitti(b"1.0 0 0 0 0 0 0 1\n"));
        let short = parse_kitti(b"1 0 0 0 0 1 0 0\n", Path::new("k.txt")).unwrap_err();
        assert!(short.to_string().contains("k.txt") && short.to_string().contains("line 1"));
        let skew = parse_kitti(b"1 0 0 0 0 2 0 0 0 0 1 0\n", Path::new("k.txt")).unwrap_err();
        assert!(skew.to_string().contains("not a rotation"), "{skew}");
    }
}
