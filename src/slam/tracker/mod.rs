//! The tracking step: one frame's planes in, its pose and the updated map
//! out.
//!
//! [`Tracker::track_at`] runs the steps in order; the point refinement of
//! the directions the planes leave free is in `points`, the back-end
//! during tracking (sliding window, loop closure, the re-solve at a loop)
//! in `loops`.

mod loops;
mod points;

use nalgebra::{Isometry3, Vector6};
use serde::{Deserialize, Serialize};

use super::association::{associate, MapMatchParams};
use super::clock::{FrameClock, FrameTiming};
use super::log::{LandmarkObservation, TrackedFrame, TrackingLog};
use super::loop_closure::{LoopClosureParams, LoopDetector, LoopMatch};
use super::motion::{MotionModel, MotionParams, MotionUpdate};
use super::point_map::{LocalPointMap, PointParams, ScanSamples};
use super::recovery::{recover_heading, RecoveryParams, RegistrationContext};
use crate::backend::{Backend, BackendParams};
use crate::frontend::FramePlane;
use crate::io::PlaneKind;
use crate::map::{MapMerger, PlaneMap};
use crate::registration::{
    match_planes, register, Degeneracy, GaussNewtonParams, MatchCriteria, MismatchRejector,
    RejectorParams, SurfaceSample,
};

/// Reflection SLAM settings (`[slam]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SlamParams {
    /// The motion model that predicts each pose.
    pub motion: MotionParams,
    /// Register each frame to the previous one before the map (the paper;
    /// every configuration, no key); without it the prediction alone starts
    /// scan-to-map.
    #[serde(skip, default = "yes")]
    pub frame_to_frame: bool,
    /// Reflective planes take part in registration (the paper; every
    /// configuration, no key).
    #[serde(skip, default = "yes")]
    pub use_reflective: bool,
    /// Frame-to-frame matching criteria: [`FRAME_MATCHING`] (no keys).
    #[serde(skip, default = "frame_matching")]
    pub frame_matching: MatchCriteria,
    /// Scan-to-map matching: [`MAP_MATCHING`] (no keys).
    #[serde(skip, default = "map_matching")]
    pub map_matching: MapMatchParams,
    /// Mismatch rejection.
    pub rejector: RejectorParams,
    /// Gauss–Newton refinement and the degeneracy threshold.
    pub gauss_newton: GaussNewtonParams,
    /// Points where planes are not enough: the directions the planes leave
    /// free are refined against a local map of points.
    pub points: PointParams,
    /// The heading search for frames whose frame-to-frame registration
    /// failed.
    pub recovery: RecoveryParams,
    /// Landmarks are pruned once this many frames old ...
    pub prune_after: usize,
    /// ... when they have fewer observations (frames) than this.
    pub prune_min_observations: usize,
    /// Segment length of the relative pose error, m.
    pub rpe_segment: f64,
    /// Frames in the sliding window optimised during tracking by the
    /// back-end, at least 2 (absent: no window; the batch optimisation at
    /// the end runs regardless).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub window: Option<usize>,
    /// The window is optimised after every this many frames:
    /// [`WINDOW_EVERY`].
    #[serde(skip, default = "window_every")]
    pub window_every: usize,
    /// A frame is a keyframe, kept in the batch back-end's graph with its
    /// plane observations, when it moved more than this from the last
    /// keyframe, m; the others are placed relative to their keyframe
    /// afterwards. With `keyframe_turn_deg` also absent every frame is a
    /// keyframe (the graph then grows with every frame).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframe_move: Option<f64>,
    /// ... or turned more than this, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keyframe_turn_deg: Option<f64>,
    /// A frame that comes more than this many times the input's usual
    /// interval after the previous one follows a gap (frames missing),
    /// reported per frame (a ratio of intervals).
    pub gap_ratio: f64,
    /// Loop closure: recognise revisits, verify them, add loop factors
    /// and re-solve ([`super::loop_closure`]).
    pub loop_closure: LoopClosureParams,
}

impl FrameReport {
    /// Number of unobservable directions (0 for the first frame).
    pub fn degenerate_directions(&self) -> usize {
        self.degeneracy.as_ref().map_or(0, Degeneracy::count)
    }

    /// Whether some direction of the pose came from the motion model.
    pub fn is_degenerate(&self) -> bool {
        self.degenerate_directions() > 0
    }

    /// The directions the frame's planes left free (orthonormal tangent
    /// vectors `(ρ, φ)`, sensor frame; empty when none).
    pub fn free_directions(&self) -> Vec<Vector6<f64>> {
        self.degeneracy
            .as_ref()
            .filter(|d| d.is_degenerate())
            .map(|d| d.directions().copied().collect())
            .unwrap_or_default()
    }
}

/// The sliding window, when configured, is optimised every 5 frames.
pub const WINDOW_EVERY: usize = 5;

/// Frame-to-frame matching (the paper's thresholds): normals within
/// acos 0.8 (37 deg), offsets within 0.1 m, centroids within 0.7071 m,
/// hull areas within a factor 1.5.
// 0.7071 as the paper's code writes it, not 1/√2: the results depend on it.
#[allow(clippy::approx_constant)]
pub const FRAME_MATCHING: MatchCriteria = MatchCriteria {
    min_normal_cos: 0.8,
    max_offset: 0.1,
    max_centroid_distance: 0.7071,
    max_area_ratio: 1.5,
};

/// Scan-to-map matching (the paper's thresholds): normals within acos 0.8,
/// offsets within 0.1 m, hulls overlapping by 0.7 of the smaller.
pub const MAP_MATCHING: MapMatchParams = MapMatchParams {
    min_normal_cos: 0.8,
    max_offset: 0.1,
    min_overlap: 0.7,
};

fn yes() -> bool {
    true
}

fn window_every() -> usize {
    WINDOW_EVERY
}

fn frame_matching() -> MatchCriteria {
    FRAME_MATCHING
}

fn map_matching() -> MapMatchParams {
    MAP_MATCHING
}

impl Default for SlamParams {
    /// `[slam]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam")
    }
}

/// What happened in one tracking step (a row of `frames.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameReport {
    /// Index of the frame in the sequence.
    pub index: usize,
    /// Planes of the frame (ground, ordinary, reflective).
    pub planes: usize,
    /// Candidate pairs with the previous frame.
    pub frame_matches: usize,
    /// Of those, the inliers of the frame-to-frame registration.
    pub frame_inliers: usize,
    /// Frame planes associated with landmarks.
    pub map_matches: usize,
    /// Of those, the inliers of the scan-to-map registration.
    pub inliers: usize,
    /// Eigen-analysis of the final scan-to-map information matrix; `None`
    /// for the first frame (it defines the world frame, nothing is
    /// registered).
    pub degeneracy: Option<Degeneracy>,
    /// The pose came from the motion model alone (no registration).
    pub fallback: bool,
    /// Of the directions the planes left free, how many the points fixed
    /// (the others kept the motion model's prediction).
    pub fixed_by_points: usize,
    /// The frame-to-frame registration failed at the predicted heading and
    /// was found this many degrees away from it
    /// ([`RecoveryParams`]).
    pub recovered_yaw_deg: Option<f64>,
    /// The planes left the heading free and the point search
    /// ([`search_heading_by_points`](super::recovery::search_heading_by_points))
    /// turned the pose by this many degrees before the point refinement.
    pub points_yaw_deg: Option<f64>,
    /// Landmarks in the map after the update.
    pub landmarks: usize,
    /// Landmarks pruned in this step.
    pub pruned: usize,
    /// The estimated pose `T_world_sensor`.
    pub pose: Isometry3<f64>,
    /// The frame's timestamp, s (`None` when the tracker was not given
    /// one).
    pub stamp: Option<f64>,
    /// The interval since the previous frame and whether frames are
    /// missing before this one.
    pub timing: FrameTiming,
    /// How far the tracked pose departs from the motion model's
    /// prediction, as accelerations; `implausible` when beyond its bounds.
    pub motion: MotionUpdate,
    /// Loop candidates verified at this frame (accepted or not).
    pub loop_candidates: usize,
    /// The loop closed at this frame, if any.
    pub loop_closure: Option<LoopReport>,
}

/// A loop closed at a frame (a row of `frames.csv`, an entry of
/// `metrics.json`).
#[derive(Debug, Clone, PartialEq)]
pub struct LoopReport {
    /// The earlier frame the loop closes with.
    pub with: usize,
    /// What the verification found.
    pub check: LoopMatch,
    /// The whole graph was re-solved at this frame (the loop moved the
    /// estimate by more than `resolve_correction`).
    pub resolved: bool,
    /// Duplicate landmarks merged after the re-solve.
    pub merged: usize,
}

/// Scan-to-map tracking over a sequence of frames' planes.
///
/// Per frame: predict the pose (motion model); register the frame's planes
/// to the previous frame's (frame-to-frame, the paper's initial pose);
/// associate them with the map's landmarks at that pose and register
/// against the map (RANSAC + Gauss–Newton, unobservable directions kept
/// from the prediction); fuse the observations into the map; prune rare
/// landmarks.
pub struct Tracker {
    params: SlamParams,
    rejector: Box<dyn MismatchRejector>,
    merger: Box<dyn MapMerger>,
    map: PlaneMap,
    motion: MotionModel,
    previous: Option<(Vec<FramePlane>, Isometry3<f64>)>,
    frames: usize,
    origin: Isometry3<f64>,
    log: TrackingLog,
    window: Option<(Box<dyn Backend>, BackendParams)>,
    /// Pose of the last keyframe.
    last_keyframe: Option<Isometry3<f64>>,
    /// The frames' timing.
    clock: FrameClock,
    /// Earlier frames' surface samples around the sensor.
    points: LocalPointMap,
    /// The loop-closure keyframe database.
    loops: LoopDetector,
    /// The current frame's surface samples without reflections (sensor
    /// frame), for the loop-closure database.
    clean_samples: Vec<SurfaceSample>,
}

impl Tracker {
    /// A tracker whose first frame gets pose `origin` (identity defines the
    /// world frame; a first true pose aligns the outputs with the truth).
    pub fn new(
        params: SlamParams,
        rejector: Box<dyn MismatchRejector>,
        merger: Box<dyn MapMerger>,
        origin: Isometry3<f64>,
    ) -> Self {
        Self {
            params,
            rejector,
            merger,
            map: PlaneMap::new(),
            motion: MotionModel::new(params.motion),
            previous: None,
            frames: 0,
            origin,
            log: TrackingLog::default(),
            window: None,
            last_keyframe: None,
            clock: FrameClock::new(params.gap_ratio),
            points: LocalPointMap::new(params.points.map_voxel, params.points.max_points_per_voxel),
            loops: LoopDetector::new(),
            clean_samples: Vec::new(),
        }
    }

    /// Optimise a sliding window of the last [`SlamParams::window`] frames
    /// with `backend` during tracking.
    pub fn with_window(mut self, backend: Box<dyn Backend>, params: BackendParams) -> Self {
        self.window = Some((backend, params));
        self
    }

    /// The map so far.
    pub fn map(&self) -> &PlaneMap {
        &self.map
    }

    /// The final map.
    pub fn into_map(self) -> PlaneMap {
        self.map
    }

    /// The observations and odometry logged so far (for a back-end).
    pub fn log(&self) -> &TrackingLog {
        &self.log
    }

    /// The motion model's velocity after the frames tracked so far: a
    /// body-frame twist per second `(ρ, φ)` (zero before two frames), the
    /// motion the next frame's sweep is deskewed with
    /// ([`crate::slam::deskew`]).
    pub fn velocity(&self) -> nalgebra::Vector6<f64> {
        self.motion.velocity()
    }

    /// The final map and the log.
    pub fn into_parts(self) -> (PlaneMap, TrackingLog) {
        (self.map, self.log)
    }

    /// Track one frame given its planes (sensor frame); `seed` makes the
    /// randomised parts deterministic. Without surface samples the
    /// directions the planes leave free keep the motion model's prediction.
    pub fn track(&mut self, planes: Vec<FramePlane>, seed: u64) -> FrameReport {
        self.track_with_samples(planes, None, seed)
    }

    /// Track one frame given its planes and its surface samples (sensor
    /// frame, [`ScanSamples`]): the directions the planes leave free are
    /// refined against the local point map ([`PointParams`]). The frame's
    /// time is the samples' stamp ([`ScanSamples::stamp`]); see
    /// [`track_at`](Self::track_at).
    pub fn track_with_samples(
        &mut self,
        planes: Vec<FramePlane>,
        samples: Option<&ScanSamples>,
        seed: u64,
    ) -> FrameReport {
        self.track_at(samples.and_then(|s| s.stamp), planes, samples, seed)
    }

    /// Track one frame stamped `stamp` (seconds; `None` when unknown) given
    /// its planes and optionally its surface samples. The motion model
    /// extrapolates over the time since the previous frame (one
    /// `frame_period` when unknown), and a frame after a gap is reported
    /// ([`FrameReport::timing`]).
    pub fn track_at(
        &mut self,
        stamp: Option<f64>,
        planes: Vec<FramePlane>,
        samples: Option<&ScanSamples>,
        seed: u64,
    ) -> FrameReport {
        let p = self.params;
        let index = self.frames;
        self.frames += 1;
        let timing = self.clock.tick(stamp);
        let dt = self.motion.interval(timing.interval);
        let usable: Vec<FramePlane> = planes
            .iter()
            .filter(|fp| p.use_reflective || fp.kind != PlaneKind::Reflective)
            .cloned()
            .collect();
        let inlier_cos = p.rejector.inlier_cos();
        let inlier_offset = p.rejector.inlier_offset;
        let mut report = FrameReport {
            index,
            planes: planes.len(),
            frame_matches: 0,
            frame_inliers: 0,
            map_matches: 0,
            inliers: 0,
            degeneracy: None,
            fallback: false,
            fixed_by_points: 0,
            recovered_yaw_deg: None,
            points_yaw_deg: None,
            landmarks: 0,
            pruned: 0,
            pose: self.origin,
            stamp,
            timing,
            motion: MotionUpdate::default(),
            loop_candidates: 0,
            loop_closure: None,
        };

        // 1. Predict (the first frame defines the world frame).
        let mut matched: Vec<Option<usize>> = vec![None; usable.len()];
        let mut odometry = None;
        let mut odometry_free: Vec<Vector6<f64>> = Vec::new();
        let pose = match (self.motion.predict(dt), &self.previous) {
            (Some(predicted), Some((prev_planes, prev_pose))) => {
                // 2. Frame-to-frame registration: the initial global pose.
                let mut initial = predicted;
                if p.frame_to_frame {
                    let rel_prior = prev_pose.inverse() * predicted;
                    let pairs = match_planes(&usable, prev_planes, &rel_prior, &p.frame_matching);
                    report.frame_matches = pairs.len();
                    let mut f2f = register(
                        &pairs,
                        &rel_prior,
                        self.rejector.as_ref(),
                        &p.gauss_newton,
                        inlier_cos,
                        inlier_offset,
                        seed,
                    );
                    let weak = f2f
                        .as_ref()
                        .is_none_or(|r| r.inliers.len() < p.recovery.min_inliers);
                    if p.recovery.enabled && weak {
                        let ctx = RegistrationContext {
                            rejector: self.rejector.as_ref(),
                            gauss_newton: &p.gauss_newton,
                            criteria: &p.frame_matching,
                            inlier_cos,
                            inlier_offset,
                            seed,
                        };
                        if let Some(r) =
                            recover_heading(&usable, prev_planes, &rel_prior, &p.recovery, &ctx)
                        {
                            report.recovered_yaw_deg = Some(r.yaw_deg);
                            f2f = Some(r.registration);
                        }
                    }
                    if let Some(reg) = f2f {
                        report.frame_inliers = reg.inliers.len();
                        odometry = Some(reg.pose);
                        odometry_free = reg.refinement.degeneracy.directions().copied().collect();
                        initial = prev_pose * reg.pose;
                    }
                }
                // 3. Scan-to-map registration.
                let pairs = associate(&usable, &initial, &self.map, &p.map_matching);
                report.map_matches = pairs.len();
                match register(
                    &pairs,
                    &initial,
                    self.rejector.as_ref(),
                    &p.gauss_newton,
                    inlier_cos,
                    inlier_offset,
                    seed ^ 0x5eed,
                ) {
                    Some(reg) => {
                        report.inliers = reg.inliers.len();
                        for &k in &reg.inliers {
                            matched[pairs[k].source_index].get_or_insert(pairs[k].target_index);
                        }
                        report.degeneracy = Some(reg.refinement.degeneracy);
                        reg.pose
                    }
                    None => {
                        report.fallback = true;
                        report.degeneracy = Some(Degeneracy::none_observable(
                            p.gauss_newton.degeneracy_threshold,
                        ));
                        initial
                    }
                }
            }
            _ => self.origin,
        };

        // 4. Points where planes are not enough.
        let mut points_anchor = None;
        let pose = match samples.filter(|_| p.points.enabled) {
            Some(samples) => {
                let (refined, anchor) =
                    self.refine_with_points(&planes, samples, pose, index, &mut report);
                if let Some(a) = &anchor {
                    odometry_free = points::without_span(&odometry_free, &a.directions);
                }
                points_anchor = anchor;
                if refined != pose {
                    // The frame-to-frame registration left the same
                    // directions free: the back-end's odometry is the
                    // refined motion.
                    if let Some((_, prev_pose)) = &self.previous {
                        odometry = Some(prev_pose.inverse() * refined);
                    }
                }
                refined
            }
            None => pose,
        };

        // 5. Map update: matched planes fuse into their landmark, the others
        //    go through the merger's own matching (or become landmarks).
        let keyframe = self.is_keyframe(&pose);
        for (fp, m) in usable.iter().zip(&matched) {
            let obs = fp.observation(&pose, index);
            let k = match m {
                Some(j) => self.merger.fuse(&mut self.map, *j, &obs),
                None => self.merger.merge(&mut self.map, &obs),
            };
            self.log_observation(index, k, fp);
        }
        if !p.use_reflective {
            for fp in planes.iter().filter(|fp| fp.kind == PlaneKind::Reflective) {
                let k = self
                    .merger
                    .merge(&mut self.map, &fp.observation(&pose, index));
                self.log_observation(index, k, fp);
            }
        }
        if keyframe {
            self.last_keyframe = Some(pose);
        }
        self.log.frames.push(TrackedFrame {
            pose,
            odometry,
            odometry_free: if odometry.is_some() {
                odometry_free
            } else {
                Vec::new()
            },
            keyframe,
            points_anchor,
        });
        report.pruned = self
            .map
            .prune(index, p.prune_after, p.prune_min_observations);
        report.landmarks = self.map.landmarks.len();

        report.motion = self
            .motion
            .update_with_free(pose, dt, &report.free_directions());
        self.previous = Some((usable, pose));
        report.pose = pose;
        if p.loop_closure.enabled {
            if let Some(corrected) = self.close_loop(index, pose, seed, &mut report) {
                report.pose = corrected;
            }
        }
        if p.window.is_some_and(|w| w >= 2)
            && p.window_every >= 1
            && (index + 1).is_multiple_of(p.window_every)
        {
            if let Some(corrected) = self.optimize_window(index) {
                report.pose = corrected;
            }
        }
        report
    }

    /// Whether a frame tracked at `pose` is a keyframe: the first, every
    /// frame when both keyframe thresholds are absent, else one that moved or
    /// turned past them from the last keyframe.
    fn is_keyframe(&self, pose: &Isometry3<f64>) -> bool {
        let p = &self.params;
        let Some(last) = &self.last_keyframe else {
            return true;
        };
        if p.keyframe_move.is_none() && p.keyframe_turn_deg.is_none() {
            return true;
        }
        let rel = last.inverse() * pose;
        p.keyframe_move
            .is_some_and(|m| rel.translation.vector.norm() > m)
            || p.keyframe_turn_deg
                .is_some_and(|t| rel.rotation.angle().to_degrees() > t)
    }

    /// Log that `plane` of frame `frame` was fused into the landmark at
    /// index `k` of the map.
    fn log_observation(&mut self, frame: usize, k: usize, plane: &FramePlane) {
        if let Some(l) = self.map.landmarks.get(k) {
            self.log
                .observations
                .push(LandmarkObservation::new(frame, l.id, plane));
        }
    }
}
