//! Prediction files: `predictions/<stem>.label`, one little-endian `u32` per
//! input point, in input order (the SemanticKITTI convention).

use std::io::Write;
use std::path::Path;

use crate::{Error, Result};

/// Write labels as little-endian `u32` (atomically).
pub fn write_labels(path: &Path, labels: &[u8]) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        let mut chunk = [0u8; 4096];
        for ids in labels.chunks(chunk.len() / 4) {
            for (out, &l) in chunk.chunks_exact_mut(4).zip(ids) {
                out.copy_from_slice(&(l as u32).to_le_bytes());
            }
            w.write_all(&chunk[..ids.len() * 4])?;
        }
        Ok(())
    })
}

/// Read a `.label` file. Errors (naming the file) when its length is not a
/// multiple of four bytes.
pub fn read_labels(path: &Path) -> Result<Vec<u32>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if bytes.len() % 4 != 0 {
        return Err(Error::format(
            path,
            format!(
                "length {} bytes is not a multiple of 4 (one little-endian u32 per point)",
                bytes.len()
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}
