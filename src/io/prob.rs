//! Confidence files: `predictions/<stem>.prob` beside each `.label`, one
//! little-endian `f32` per input point, in input order: the probability,
//! in `[0, 1]`, that the point's class in the `.label` file is right (0 at
//! each point set aside when read, which the label file marks 0,
//! unclassified).

use std::io::Write;
use std::path::Path;

use crate::{Error, Result};

/// Write confidences as little-endian `f32` (atomically).
pub fn write_probs(path: &Path, probs: &[f32]) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        let mut chunk = [0u8; 4096];
        for values in probs.chunks(chunk.len() / 4) {
            for (out, p) in chunk.chunks_exact_mut(4).zip(values) {
                out.copy_from_slice(&p.to_le_bytes());
            }
            w.write_all(&chunk[..values.len() * 4])?;
        }
        Ok(())
    })
}

/// Read a `.prob` file. Errors (naming the file) when its length is not a
/// multiple of four bytes, or a value is NaN or outside `[0, 1]` (naming
/// the point).
pub fn read_probs(path: &Path) -> Result<Vec<f32>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.len() % 4 != 0 {
        return Err(Error::format(
            path,
            format!(
                "length {} bytes is not a multiple of 4 (one little-endian f32 per point)",
                bytes.len()
            ),
        ));
    }
    let probs: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if let Some((i, bad)) = probs
        .iter()
        .enumerate()
        .find(|(_, p)| !(0.0..=1.0).contains(*p))
    {
        return Err(Error::format(
            path,
            format!("point {i} has confidence {bad}, not a probability in [0, 1]"),
        ));
    }
    Ok(probs)
}

/// [`read_probs`], and an error (naming the file) unless it holds exactly
/// `points` values, one per input point.
pub fn read_probs_for(path: &Path, points: usize) -> Result<Vec<f32>> {
    let probs = read_probs(path)?;
    if probs.len() != points {
        return Err(Error::format(
            path,
            format!(
                "{} confidences for {points} points (one per input point)",
                probs.len()
            ),
        ));
    }
    Ok(probs)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(e: Error) -> String {
        assert!(matches!(e, Error::Format { .. }), "{e:?}");
        e.to_string()
    }

    #[test]
    fn round_trip_bit_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.prob");
        // More than one write chunk, edges included.
        let probs: Vec<f32> = (0..3000).map(|i| (i % 101) as f32 / 100.0).collect();
        write_probs(&path, &probs).unwrap();
        assert_eq!(std::fs::metadata(&path).unwrap().len(), 4 * 3000);
        let back = read_probs_for(&path, 3000).unwrap();
        assert_eq!(back, probs);
        assert_eq!(back[100], 1.0);
        assert_eq!(back[0], 0.0);
        // Empty file, empty frame.
        write_probs(&path, &[]).unwrap();
        assert!(read_probs_for(&path, 0).unwrap().is_empty());
    }

    #[test]
    fn bad_files_are_errors_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("frame7.prob");
        std::fs::write(&path, [0u8; 6]).unwrap();
        let m = message(read_probs(&path).unwrap_err());
        assert!(
            m.contains("frame7.prob") && m.contains("not a multiple of 4"),
            "{m}"
        );

        write_probs(&path, &[0.5, 0.25]).unwrap();
        let m = message(read_probs_for(&path, 3).unwrap_err());
        assert!(
            m.contains("frame7.prob") && m.contains("2 confidences for 3 points"),
            "{m}"
        );

        for (bad, shown) in [(f32::NAN, "NaN"), (1.5, "1.5"), (-0.25, "-0.25")] {
            let mut bytes = Vec::new();
            for p in [0.5f32, 1.0, bad] {
                bytes.extend_from_slice(&p.to_le_bytes());
            }
            std::fs::write(&path, bytes).unwrap();
            let m = message(read_probs(&path).unwrap_err());
            assert!(
                m.contains("frame7.prob") && m.contains(&format!("point 2 has confidence {shown}")),
                "{m}"
            );
        }
        let m = read_probs(&dir.path().join("missing.prob"))
            .unwrap_err()
            .to_string();
        assert!(m.contains("missing.prob"), "{m}");
    }
}
