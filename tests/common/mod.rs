//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The bundled real sample (always present).
pub fn sample_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/3dref-sample")
}

/// The ten shared real frames, when `../shared/data` exists (it does in CI).
pub fn shared_frames() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/3dref-seq1-demo");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("note: {} not found; test skipped", dir.display());
        None
    }
}
