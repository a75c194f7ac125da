//! The frames a sequence keeps between its passes, up to a budget.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

use crate::cloud::Frame;
use crate::sensor::OrganizedScan;

/// Frames kept after their first read, up to a budget of bytes: the first
/// frames of a sequence (passes read in order), so a short sequence is
/// parsed once and a long one costs no more memory than the budget.
/// The organized scans of the kept frames are kept too (same budget):
/// every pass pairs the returns of the frames it reads.
#[derive(Debug)]
pub(super) struct FrameCache {
    /// Per frame, the frame as read, when kept.
    pub(super) frames: Vec<OnceLock<Frame>>,
    /// Per frame, its organized scan, when kept.
    pub(super) scans: Vec<OnceLock<OrganizedScan>>,
    /// Per frame, whether its points carry times (asked at every pass,
    /// answered once: an untimed frame is a scan of all its points).
    pub(super) timed: Vec<OnceLock<bool>>,
    budget: usize,
    used: AtomicUsize,
}

impl FrameCache {
    /// Room for `frames` frames, keeping at most `budget` bytes.
    pub(super) fn new(frames: usize, budget: usize) -> Self {
        Self {
            frames: (0..frames).map(|_| OnceLock::new()).collect(),
            scans: (0..frames).map(|_| OnceLock::new()).collect(),
            timed: (0..frames).map(|_| OnceLock::new()).collect(),
            budget,
            used: AtomicUsize::new(0),
        }
    }

    /// Keep `value` in `cell` if its `bytes` fit the budget; gives it back
    /// otherwise.
    pub(super) fn keep<'a, T>(
        &self,
        cell: &'a OnceLock<T>,
        value: T,
        bytes: usize,
    ) -> std::result::Result<&'a T, T> {
        let before = self.used.fetch_add(bytes, Ordering::Relaxed);
        if before + bytes > self.budget {
            self.used.fetch_sub(bytes, Ordering::Relaxed);
            return Err(value);
        }
        match cell.set(value) {
            Ok(()) => Ok(cell.get().expect("just set")),
            // Made twice at once: keep the first, count it once.
            Err(value) => {
                self.used.fetch_sub(bytes, Ordering::Relaxed);
                Err(value)
            }
        }
    }
}

/// Megabytes as bytes (negative and NaN as 0).
pub(super) fn megabytes(mb: f64) -> usize {
    if mb > 0.0 {
        (mb * 1e6) as usize
    } else {
        0
    }
}
