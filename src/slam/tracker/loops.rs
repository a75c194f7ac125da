//! The back-end during tracking: the sliding window, loop closure with its
//! verification, and the whole-graph re-solve a loop may call for.

use nalgebra::Isometry3;

use super::Tracker;
use crate::frontend::FramePlane;
use crate::registration::PointRefineParams;
use crate::slam::graph::{optimized_poses, tracking_graph, update_map, window_graph};
use crate::slam::loop_closure::{merge_duplicates, LoopConstraint, Pair, Samples, Verifier};
use crate::slam::point_map::LocalPointMap;
use crate::slam::tracker::{FrameReport, LoopReport};

impl Tracker {
    /// Optimise the frames `index + 1 - window ..= index` (the oldest one
    /// fixed) with the landmarks they observe; the log's poses, the map's
    /// planes, the previous pose and the motion model take the result.
    /// Returns the corrected pose of frame `index`; `None` (nothing changed)
    /// when there is no window back-end or it fails — tracking goes on.
    pub(super) fn optimize_window(&mut self, index: usize) -> Option<Isometry3<f64>> {
        let (solver, params) = self.window.as_ref()?;
        let start = (index + 1).saturating_sub(self.params.window.unwrap_or(0));
        let graph = window_graph(&self.log, start..index + 1, &self.map, params).ok()?;
        let values = match solver.optimize(&graph, &graph.values) {
            Ok((values, report)) => {
                tracing::debug!(
                    frame = index,
                    iterations = report.iterations,
                    seconds = report.total_seconds,
                    setup = report.setup_seconds,
                    "window"
                );
                values
            }
            Err(e) => {
                tracing::debug!(frame = index, "window optimisation failed: {e}");
                return None;
            }
        };
        for (&k, pose) in &values.poses {
            if let Some(f) = self.log.frames.get_mut(k as usize) {
                f.pose = *pose;
            }
        }
        update_map(&mut self.map, &values);
        let pose = self.log.frames.get(index)?.pose;
        self.motion.correct(pose);
        if let Some((_, previous)) = &mut self.previous {
            *previous = pose;
        }
        Some(pose)
    }

    /// Look for a loop at frame `index` (tracked at `pose`, its planes the
    /// previous frame's now): when it is a loop keyframe, verify the
    /// candidates, log the first verified loop, and when it re-solves
    /// ([`LoopClosureParams::resolves`](crate::slam::loop_closure::LoopClosureParams::resolves): it moved the estimate by more than
    /// `resolve_correction` and its planes observed every direction), re-solve
    /// the whole graph ([`resolve_all`](Self::resolve_all)). Returns the corrected
    /// pose of frame `index` when it moved.
    pub(super) fn close_loop(
        &mut self,
        index: usize,
        pose: Isometry3<f64>,
        seed: u64,
        report: &mut FrameReport,
    ) -> Option<Isometry3<f64>> {
        let lc = self.params.loop_closure;
        let before = index
            .checked_sub(1)
            .and_then(|k| self.log.frames.get(k))
            .map(|f| f.pose);
        if !self.loops.advance(index, &pose, before.as_ref(), &lc) {
            return None;
        }
        let planes: Vec<FramePlane> = self
            .previous
            .as_ref()
            .map(|(planes, _)| planes.clone())
            .unwrap_or_default();
        let frames = &self.log.frames;
        let candidates = self.loops.candidates(
            index,
            &planes,
            &pose,
            |k| frames.get(k).map(|f| f.pose),
            &lc,
        );
        let pp = self.params.points;
        let verifier = Verifier {
            rejector: self.rejector.as_ref(),
            gauss_newton: &self.params.gauss_newton,
            inlier_cos: self.params.rejector.inlier_cos(),
            inlier_offset: self.params.rejector.inlier_offset,
            points: pp.enabled.then_some(PointRefineParams {
                max_correspondence: pp.max_correspondence,
                kernel_scale: pp.kernel_scale,
                max_iterations: pp.max_iterations,
                min_information: pp.min_information,
                min_alignment: pp.min_alignment,
            }),
        };
        let mut found = None;
        for c in &candidates {
            report.loop_candidates += 1;
            let prior = frames[c.frame].pose.inverse() * pose;
            let submap = self.candidate_points(c.frame);
            let samples = Samples {
                current: &self.clean_samples,
                candidate: &submap,
            };
            let pair = Pair {
                current: &planes,
                candidate: c.planes,
                travelled: self.loops.path_between(c.frame, index),
                samples: Some(samples),
            };
            match verifier.verify(&pair, &prior, &lc, seed ^ (c.frame as u64)) {
                Ok(m) => {
                    found = Some((c.frame, m));
                    break;
                }
                Err(why) => {
                    tracing::debug!(frame = index, candidate = c.frame, ?why, "loop rejected")
                }
            }
        }
        self.loops
            .insert(index, &planes, &self.clean_samples, &pose);
        let (from, check) = found?;
        tracing::debug!(frame = index, with = from, ?check, "loop closed");
        for k in [from, index] {
            if let Some(f) = self.log.frames.get_mut(k) {
                f.keyframe = true;
            }
        }
        self.log.loops.push(LoopConstraint {
            from,
            to: index,
            relative: check.relative,
            sqrt_info: lc.sqrt_info(),
            robust: lc.robust,
            check: check.clone(),
        });
        let resolve = lc.resolves(&check);
        let mut out = LoopReport {
            with: from,
            check,
            resolved: false,
            merged: 0,
        };
        let corrected = if resolve {
            self.resolve_all(index).map(|(pose, merged)| {
                out.resolved = true;
                out.merged = merged;
                pose
            })
        } else {
            None
        };
        report.loop_closure = Some(out);
        corrected
    }

    /// The points around loop candidate `frame`, in its sensor frame (for
    /// the directions its planes leave free): the samples of its keyframe
    /// and of `submap_keyframes` database keyframes either side, and the
    /// tracker's own map points added by the frames between those
    /// keyframes, where the map still holds them (it forgets beyond
    /// `map_radius`): every frame's samples there, not one keyframe's per
    /// metre. Each point is placed by its frame's current estimate.
    pub(super) fn candidate_points(&self, frame: usize) -> LocalPointMap {
        let pp = self.params.points;
        let lc = self.params.loop_closure;
        let frames = &self.log.frames;
        let pose = |k: usize| frames.get(k).map(|f| f.pose);
        let mut map = LocalPointMap::new(pp.map_voxel, pp.max_points_per_voxel);
        let Some(origin) = pose(frame) else {
            return map;
        };
        let to_candidate = origin.inverse();
        let (samples, span) = self.loops.submap(frame, lc.submap_keyframes, pose);
        if lc.submap_frames {
            for (p, k) in self.points.points_of(span) {
                map.insert_point(to_candidate * p, k);
            }
        }
        map.insert(&samples, &Isometry3::identity(), frame);
        map
    }

    /// Optimise the whole graph so far (with its loop factors) with the
    /// back-end; every logged pose, the landmarks (planes and boundaries,
    /// each with the correction of the last frame that saw it), the local
    /// point map (each point with its frame's correction), the motion model
    /// and the previous pose take the result; then duplicate landmarks are
    /// merged. Returns frame `index`'s new pose and the number of merges;
    /// `None` (nothing changed) without a back-end or when it fails.
    pub(super) fn resolve_all(&mut self, index: usize) -> Option<(Isometry3<f64>, usize)> {
        let (solver, params) = self.window.as_ref()?;
        let graph = tracking_graph(&self.log, &self.map, params).ok()?;
        let values = match solver.optimize(&graph, &graph.values) {
            Ok((values, _)) => values,
            Err(e) => {
                tracing::debug!(frame = index, "loop re-solve failed: {e}");
                return None;
            }
        };
        let old: Vec<Isometry3<f64>> = self.log.frames.iter().map(|f| f.pose).collect();
        let new = optimized_poses(&values, &old);
        let corrections: Vec<Isometry3<f64>> =
            old.iter().zip(&new).map(|(o, n)| n * o.inverse()).collect();
        for (f, p) in self.log.frames.iter_mut().zip(&new) {
            f.pose = *p;
        }
        for l in &mut self.map.landmarks {
            if let Some(c) = corrections.get(l.last_frame) {
                l.plane = l.plane.transformed(c);
                for v in &mut l.boundary {
                    *v = c * *v;
                }
            }
        }
        update_map(&mut self.map, &values);
        self.points.correct(|k| corrections.get(k).copied());
        let merged = merge_duplicates(&mut self.map, &mut self.log, &self.params.loop_closure);
        let pose = *new.get(index)?;
        self.motion.correct(pose);
        if let Some((_, previous)) = &mut self.previous {
            *previous = pose;
        }
        if let Some(last) = &mut self.last_keyframe {
            *last = corrections.get(index).map_or(*last, |c| c * *last);
        }
        self.loops.correct_last(&pose);
        Some((pose, merged.merged.len()))
    }
}
