//! Loop closure: recognise a revisit, verify it, and hand the back-end a
//! loop factor (issue 15, item 3).
//!
//! 1. **Keyframe database.** Whenever the sensor has moved `keyframe_move`
//!    metres or turned `keyframe_turn_deg` since the last entry, the
//!    frame's planes (sensor frame) and their
//!    [`PlaneDescriptor`] are stored.
//! 2. **Candidates** ([`LoopDetector::candidates`]): entries at least
//!    `min_frames_apart` frames back, whose pose lies within a plausible
//!    distance of the current estimate (`search_radius` plus
//!    `radius_per_metre` of the path travelled since: the drift it may
//!    have gathered), ranked by descriptor distance (at most
//!    `max_descriptor_distance`), the best `max_candidates`.
//! 3. **Verification** ([`verify`]): plane registration against the
//!    candidate with inlier, observability and plausibility gates.
//! 4. **Loop factor**: a relative-pose factor between the two frames under
//!    a robust kernel ([`LoopConstraint`], added to the pose-plane graph by
//!    [`crate::slam::graph`]; it is the existing
//!    [`Between`](crate::backend::Between) factor, whose Jacobian is
//!    property-tested in `tests/backend_props.rs`). When the loop moves the
//!    estimate by more than `resolve_correction` and its planes observed
//!    every direction ([`LoopClosureParams::resolves`]), the tracker
//!    re-solves the whole graph at once and carries on from the result; a
//!    loop the points measured in some direction waits for the batch.
//! 5. **Duplicate landmarks** ([`merge`]): after the re-solve the same
//!    plane, mapped twice before the loop was closed, is one landmark
//!    again.

pub mod descriptor;
pub mod merge;
mod params;
pub mod verify;

use nalgebra::{Isometry3, Matrix6};

use crate::backend::RobustKernel;
use crate::frontend::FramePlane;
use crate::registration::SurfaceSample;
use descriptor::PlaneDescriptor;

pub use merge::{merge_duplicates, MergeDuplicates};
pub use params::*;
pub use verify::{LoopMatch, LoopRejection, Pair, Samples, Verifier};

/// A verified loop, as the back-end's relative-pose measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopConstraint {
    /// The earlier frame (the candidate keyframe).
    pub from: usize,
    /// The current frame.
    pub to: usize,
    /// `T_from_to`, measured by the verification.
    pub relative: Isometry3<f64>,
    /// Square-root information of the measurement.
    pub sqrt_info: Matrix6<f64>,
    /// Robust kernel of its factor.
    pub robust: RobustKernel,
    /// What the verification found.
    pub check: LoopMatch,
}

/// One keyframe of the database.
#[derive(Debug, Clone)]
struct Entry {
    frame: usize,
    planes: Vec<FramePlane>,
    samples: Vec<SurfaceSample>,
    descriptor: PlaneDescriptor,
}

/// The keyframe database and the path length per frame, for the candidate
/// search.
#[derive(Debug, Clone, Default)]
pub struct LoopDetector {
    entries: Vec<Entry>,
    /// Path length up to each frame, m.
    path: Vec<f64>,
    /// Pose of the last entry.
    last: Option<Isometry3<f64>>,
}

/// A candidate keyframe for a loop with the current frame.
#[derive(Debug, Clone)]
pub struct Candidate<'a> {
    /// Its frame index.
    pub frame: usize,
    /// Its planes (sensor frame).
    pub planes: &'a [FramePlane],
    /// Descriptor distance to the current frame.
    pub distance: f64,
}

impl LoopDetector {
    /// An empty database.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of keyframes stored.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether no keyframe is stored.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Record that frame `frame` was tracked at `pose` (call once per
    /// frame, in order) and whether it is a loop keyframe by `params`.
    pub fn advance(
        &mut self,
        frame: usize,
        pose: &Isometry3<f64>,
        previous: Option<&Isometry3<f64>>,
        params: &LoopClosureParams,
    ) -> bool {
        let step = previous.map_or(0.0, |p| {
            (pose.translation.vector - p.translation.vector).norm()
        });
        let before = self.path.last().copied().unwrap_or(0.0);
        self.path.resize(frame, before);
        self.path.push(before + step);
        match &self.last {
            None => true,
            Some(last) => {
                let rel = last.inverse() * pose;
                rel.translation.vector.norm() >= params.keyframe_move
                    || rel.rotation.angle().to_degrees() >= params.keyframe_turn_deg
            }
        }
    }

    /// Store frame `frame`'s planes and surface samples (sensor frame)
    /// tracked at `pose`.
    pub fn insert(
        &mut self,
        frame: usize,
        planes: &[FramePlane],
        samples: &[SurfaceSample],
        pose: &Isometry3<f64>,
    ) {
        let planes: Vec<FramePlane> = planes
            .iter()
            .map(|p| FramePlane {
                inliers: Vec::new(),
                ..p.clone()
            })
            .collect();
        let descriptor = PlaneDescriptor::of(&planes);
        self.entries.push(Entry {
            frame,
            planes,
            samples: samples.to_vec(),
            descriptor,
        });
        self.last = Some(*pose);
    }

    /// The path travelled from frame `from` to frame `to` (as far as
    /// recorded), m.
    pub fn path_between(&self, from: usize, to: usize) -> f64 {
        let at = |k: usize| {
            self.path
                .get(k)
                .or(self.path.last())
                .copied()
                .unwrap_or(0.0)
        };
        (at(to) - at(from)).max(0.0)
    }

    /// Move the last entry's pose (after a re-solve).
    pub fn correct_last(&mut self, pose: &Isometry3<f64>) {
        if self.last.is_some() {
            self.last = Some(*pose);
        }
    }

    /// The surface samples of the keyframe of frame `frame` and of
    /// `neighbours` keyframes either side of it in the database, in
    /// `frame`'s sensor frame (`poses[k]`: frame `k`'s current estimate),
    /// and the frames those keyframes span (from the first one's frame to
    /// the frame before the keyframe after the last one).
    pub fn submap(
        &self,
        frame: usize,
        neighbours: usize,
        poses: impl Fn(usize) -> Option<Isometry3<f64>>,
    ) -> (Vec<SurfaceSample>, std::ops::RangeInclusive<usize>) {
        let Ok(at) = self.entries.binary_search_by_key(&frame, |e| e.frame) else {
            return (Vec::new(), frame..=frame);
        };
        let Some(origin) = poses(frame) else {
            return (Vec::new(), frame..=frame);
        };
        let lo = at.saturating_sub(neighbours);
        let hi = (at + neighbours + 1).min(self.entries.len());
        let last = self
            .entries
            .get(hi)
            .map_or(frame, |e| e.frame.saturating_sub(1))
            .max(self.entries[hi - 1].frame);
        let span = self.entries[lo].frame..=last;
        let mut out = Vec::new();
        for e in &self.entries[lo..hi] {
            let Some(pose) = poses(e.frame) else {
                continue;
            };
            let t = origin.inverse() * pose;
            out.extend(e.samples.iter().map(|s| SurfaceSample {
                point: t * s.point,
                normal: t.rotation * s.normal,
            }));
        }
        (out, span)
    }

    /// The candidates for a loop with frame `frame` (planes `planes`,
    /// estimated at `pose`; `poses[k]` is frame `k`'s current estimate),
    /// best descriptor first ([module docs](self)).
    pub fn candidates(
        &self,
        frame: usize,
        planes: &[FramePlane],
        pose: &Isometry3<f64>,
        poses: impl Fn(usize) -> Option<Isometry3<f64>>,
        params: &LoopClosureParams,
    ) -> Vec<Candidate<'_>> {
        let here = self.path.get(frame).copied().unwrap_or(0.0);
        let descriptor = PlaneDescriptor::of(planes);
        let mut out: Vec<Candidate<'_>> = self
            .entries
            .iter()
            .filter(|e| e.frame + params.min_frames_apart <= frame)
            .filter(|e| {
                let Some(p) = poses(e.frame) else {
                    return false;
                };
                let travelled = here - self.path.get(e.frame).copied().unwrap_or(here);
                let radius = params.search_radius + params.radius_per_metre * travelled.max(0.0);
                (p.translation.vector - pose.translation.vector).norm() <= radius
            })
            .map(|e| Candidate {
                frame: e.frame,
                planes: &e.planes,
                distance: descriptor.distance(&e.descriptor),
            })
            .filter(|c| c.distance <= params.max_descriptor_distance)
            .collect();
        out.sort_by(|a, b| {
            a.distance
                .total_cmp(&b.distance)
                .then(a.frame.cmp(&b.frame))
        });
        out.truncate(params.max_candidates);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loop_match(correction: f64, fixed_by_points: usize) -> LoopMatch {
        LoopMatch {
            relative: Isometry3::identity(),
            matches: 9,
            inliers: 9,
            min_eigenvalue: if fixed_by_points > 0 { 1e-6 } else { 1.0 },
            fixed_by_points,
            correction,
            correction_deg: 0.0,
        }
    }

    #[test]
    fn a_loop_measured_partly_by_points_waits_for_the_batch() {
        let lc = LoopClosureParams::default();
        assert!(!lc.resolve_on_point_loops);
        // 5 cm, every direction seen by planes: re-solve now.
        assert!(lc.resolves(&loop_match(0.05, 0)));
        // 5 cm, the corridor's axis from the points alone: wait.
        assert!(!lc.resolves(&loop_match(0.05, 1)));
        // Small corrections always wait.
        assert!(!lc.resolves(&loop_match(0.01, 0)));
        let eager = LoopClosureParams {
            resolve_on_point_loops: true,
            ..lc
        };
        assert!(eager.resolves(&loop_match(0.05, 1)));
    }
}
