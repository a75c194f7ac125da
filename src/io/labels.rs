//! Prediction files: `predictions/<stem>.label`, one little-endian `u32` per
//! input point, in input order (the SemanticKITTI convention).

use std::path::Path;

use crate::Result;

/// Write labels as little-endian `u32` (atomically).
pub fn write_labels(path: &Path, labels: &[u8]) -> Result<()> {
    todo!("{} {}", path.display(), labels.len())
}

/// Read a `.label` file.
pub fn read_labels(path: &Path) -> Result<Vec<u32>> {
    todo!("{}", path.display())
}
