//! Dual-return candidates: beams whose two returns disagree.
//!
//! The paper's rule (its dual-return analysis): when the first/strongest and
//! the last return of one beam differ by more than a threshold, a reflective
//! surface lies along the beam, and the nearer return is the one that may
//! have come from it.

use crate::cloud::Frame;
use crate::sensor::OrganizedScan;

/// Indices of the nearer return of every beam whose returns are more than
/// `min_gap` metres apart, ascending.
pub fn dual_return_candidates(frame: &Frame, scan: &OrganizedScan, min_gap: f64) -> Vec<u32> {
    let mut out: Vec<u32> = scan
        .dual_cells()
        .filter_map(|(_, a, b)| {
            let (pa, pb) = (frame.points[a].position(), frame.points[b].position());
            ((pa - pb).norm() > min_gap).then(|| {
                if pa.coords.norm_squared() <= pb.coords.norm_squared() {
                    a as u32
                } else {
                    b as u32
                }
            })
        })
        .collect();
    out.sort_unstable();
    out
}
