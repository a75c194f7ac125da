//! The loop closure's settings (`[slam.loop_closure]`): the keys, and the
//! constants that replaced the keys nobody tuned (issue 38).

use nalgebra::{Matrix6, Vector6};
use serde::{Deserialize, Serialize};

use super::verify::LoopMatch;
use crate::backend::RobustKernel;
use crate::registration::MatchCriteria;

/// Loop-closure settings (`[slam.loop_closure]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoopClosureParams {
    /// Look for loops at all.
    pub enabled: bool,
    /// A frame enters the keyframe database (and looks for a loop) once
    /// the sensor moved this far from the last entry, m ...
    ///
    /// [`KEYFRAME_MOVE`] in every configuration (no key).
    #[serde(skip, default = "keyframe_move")]
    pub keyframe_move: f64,
    /// ... or turned this much, degrees.
    ///
    /// [`KEYFRAME_TURN_DEG`] in every configuration (no key).
    #[serde(skip, default = "keyframe_turn_deg")]
    pub keyframe_turn_deg: f64,
    /// Candidates lie at least this many frames back.
    pub min_frames_apart: usize,
    /// Candidates lie within this distance of the current estimate, m ...
    pub search_radius: f64,
    /// ... plus this share of the path travelled since them (drift).
    ///
    /// [`RADIUS_PER_METRE`] in every configuration (no key).
    #[serde(skip, default = "radius_per_metre")]
    pub radius_per_metre: f64,
    /// Descriptor distance (`1 −` cosine similarity) of a candidate at
    /// most.
    ///
    /// [`MAX_DESCRIPTOR_DISTANCE`] in every configuration (no key).
    #[serde(skip, default = "max_descriptor_distance")]
    pub max_descriptor_distance: f64,
    /// Candidates verified per query, best descriptor first.
    ///
    /// [`MAX_CANDIDATES`] in every configuration (no key).
    #[serde(skip, default = "max_candidates")]
    pub max_candidates: usize,
    /// Plane matching of the verification (looser than frame-to-frame: the
    /// viewpoints differ and the estimate has drifted).
    ///
    /// [`MATCHING`] in every configuration (no key).
    #[serde(skip, default = "matching")]
    pub matching: MatchCriteria,
    /// The candidate's points for the directions the planes leave free are
    /// those of this many database keyframes either side of it too (one
    /// frame's samples are too sparse to fix a corridor's axis; the
    /// tracker's point map holds many).
    ///
    /// [`SUBMAP_KEYFRAMES`] in every configuration (no key).
    #[serde(skip, default = "submap_keyframes")]
    pub submap_keyframes: usize,
    /// Information (facing samples matched, `Σ (n·v)²`) a free direction
    /// needs to be fixed by the points in a verification.
    ///
    /// [`MIN_POINT_INFORMATION`] in every configuration (no key).
    #[serde(skip, default = "min_point_information")]
    pub min_point_information: f64,
    /// A sample takes part in the verification's point refinement only
    /// when its surface faces along a free direction at least this much
    /// ([`PointRefineParams::min_alignment`](crate::registration::PointRefineParams::min_alignment)).
    /// The blended normals of edge samples bias the measurement by
    /// centimetres (glass-lined loop, the last frame against the first,
    /// samples unfiltered: 2.4 cm at 0.3, 0.7 cm at 0.7), but at 0.7 the
    /// reflection-filtered samples there no longer fix the axis at all.
    ///
    /// [`MIN_POINT_ALIGNMENT`] in every configuration (no key).
    #[serde(skip, default = "min_point_alignment")]
    pub min_point_alignment: f64,
    /// The candidate's points include the tracker's own map points of
    /// every frame between its neighbouring keyframes (where the map still
    /// holds them), not only the keyframes' samples.
    ///
    /// [`SUBMAP_FRAMES`] in every configuration (no key).
    #[serde(skip, default = "submap_frames")]
    pub submap_frames: bool,
    /// Points fix free directions only for a candidate within this distance
    /// of the current estimate, m: from nearly the same viewpoint both
    /// frames sample the same surfaces (farther apart, a door frame's
    /// samples meet the wall beside it and bias the axis by decimetres).
    ///
    /// [`MAX_POINT_DISTANCE`] in every configuration (no key).
    #[serde(skip, default = "max_point_distance")]
    pub max_point_distance: f64,
    /// Plane pairs that must agree with the verified pose.
    ///
    /// [`MIN_INLIERS`] in every configuration (no key).
    #[serde(skip, default = "min_inliers")]
    pub min_inliers: usize,
    /// Smallest eigenvalue of the verifying registration's `JᵀJ` (every
    /// direction observed).
    ///
    /// [`MIN_EIGENVALUE`] in every configuration (no key).
    #[serde(skip, default = "min_eigenvalue")]
    pub min_eigenvalue: f64,
    /// A verified loop moves the estimate by at most this, m ...
    pub max_correction: f64,
    /// ... plus this share of the path travelled since the candidate
    /// (the drift tracking may have gathered; a registration that moves
    /// the estimate further has matched a wrong plane).
    ///
    /// [`MAX_CORRECTION_PER_METRE`] in every configuration (no key).
    #[serde(skip, default = "max_correction_per_metre")]
    pub max_correction_per_metre: f64,
    /// ... and this, degrees.
    ///
    /// [`MAX_CORRECTION_DEG`] in every configuration (no key).
    #[serde(skip, default = "max_correction_deg")]
    pub max_correction_deg: f64,
    /// Loop-factor translation noise, m.
    ///
    /// [`TRANSLATION_SIGMA`] in every configuration (no key).
    #[serde(skip, default = "translation_sigma")]
    pub translation_sigma: f64,
    /// Loop-factor rotation noise, radians.
    ///
    /// [`ROTATION_SIGMA`] in every configuration (no key).
    #[serde(skip, default = "rotation_sigma")]
    pub rotation_sigma: f64,
    /// Robust kernel on loop factors (a wrong loop that passed the gates
    /// is down-weighted, not obeyed).
    ///
    /// [`ROBUST`] in every configuration (no key).
    #[serde(skip, default = "robust")]
    pub robust: RobustKernel,
    /// The whole graph is re-solved during tracking when a loop moves the
    /// estimate by more than this, m (smaller corrections wait for the
    /// batch at the end).
    ///
    /// [`RESOLVE_CORRECTION`] in every configuration (no key).
    #[serde(skip, default = "resolve_correction")]
    pub resolve_correction: f64,
    /// Whether a loop that only the points measured in some direction (its
    /// planes left it free) may re-solve the graph during tracking. Such a
    /// loop can be centimetres off along a corridor's axis and still pass
    /// the gates; re-solved at once, it moves the map the tracker then
    /// follows. Without the re-solve it waits for the batch at the end,
    /// where the robust kernel weighs it against everything else.
    ///
    /// [`RESOLVE_ON_POINT_LOOPS`] in every configuration (no key).
    #[serde(skip, default = "resolve_on_point_loops")]
    pub resolve_on_point_loops: bool,
    /// Duplicate landmarks merge when their normals agree within this,
    /// degrees ...
    ///
    /// [`MERGE_MAX_ANGLE_DEG`] in every configuration (no key).
    #[serde(skip, default = "merge_max_angle_deg")]
    pub merge_max_angle_deg: f64,
    /// ... each one's boundary centre lies within this of the other's
    /// plane, m ...
    ///
    /// [`MERGE_MAX_OFFSET`] in every configuration (no key).
    #[serde(skip, default = "merge_max_offset")]
    pub merge_max_offset: f64,
    /// ... and their extents overlap by this share of the smaller one.
    ///
    /// [`MERGE_MIN_OVERLAP`] in every configuration (no key).
    #[serde(skip, default = "merge_min_overlap")]
    pub merge_min_overlap: f64,
}

/// A frame enters the loop keyframe database (and looks for a loop) once the
/// sensor moved this far from the last entry, m.
pub const KEYFRAME_MOVE: f64 = 1.0;

fn keyframe_move() -> f64 {
    KEYFRAME_MOVE
}

/// ... or turned this much, degrees.
pub const KEYFRAME_TURN_DEG: f64 = 20.0;

fn keyframe_turn_deg() -> f64 {
    KEYFRAME_TURN_DEG
}

/// Loop candidates lie within `search_radius` plus this share of the path
/// travelled since them (drift), m per m.
pub const RADIUS_PER_METRE: f64 = 0.02;

fn radius_per_metre() -> f64 {
    RADIUS_PER_METRE
}

/// Descriptor distance (`1 −` cosine similarity) of a loop candidate at most.
pub const MAX_DESCRIPTOR_DISTANCE: f64 = 0.5;

fn max_descriptor_distance() -> f64 {
    MAX_DESCRIPTOR_DISTANCE
}

/// Loop candidates verified per query, best descriptor first.
pub const MAX_CANDIDATES: usize = 3;

fn max_candidates() -> usize {
    MAX_CANDIDATES
}

/// Plane matching of a loop verification, looser than frame-to-frame (the
/// viewpoints differ and the estimate has drifted): normals within acos 0.9,
/// offsets within 0.3 m, centroids within 5 m, hull areas within a factor 10.
pub const MATCHING: MatchCriteria = MatchCriteria {
    min_normal_cos: 0.9,
    max_offset: 0.3,
    max_centroid_distance: 5.0,
    max_area_ratio: 10.0,
};

fn matching() -> MatchCriteria {
    MATCHING
}

/// A loop candidate's points: its keyframe's and this many either side.
pub const SUBMAP_KEYFRAMES: usize = 3;

fn submap_keyframes() -> usize {
    SUBMAP_KEYFRAMES
}

/// Information (facing samples matched, `Σ (n·v)²`) a free direction needs to
/// be fixed by the points in a loop verification.
pub const MIN_POINT_INFORMATION: f64 = 20.0;

fn min_point_information() -> f64 {
    MIN_POINT_INFORMATION
}

/// A sample takes part in a loop verification's point refinement only when
/// its surface faces along a free direction at least this much (`|n · v|`;
/// glass-lined loop, samples unfiltered: 2.4 cm bias at 0.3, 0.7 cm at 0.7,
/// but at 0.7 the reflection-filtered samples no longer fix the axis).
pub const MIN_POINT_ALIGNMENT: f64 = 0.3;

fn min_point_alignment() -> f64 {
    MIN_POINT_ALIGNMENT
}

/// Whether a loop candidate's points include the tracker's own map points of
/// every frame between its neighbouring keyframes (no: the keyframes'
/// samples only).
pub const SUBMAP_FRAMES: bool = false;

fn submap_frames() -> bool {
    SUBMAP_FRAMES
}

/// Points fix free directions only for a loop candidate within this
/// distance of the current estimate, m.
pub const MAX_POINT_DISTANCE: f64 = 1.0;

fn max_point_distance() -> f64 {
    MAX_POINT_DISTANCE
}

/// Plane pairs that must agree with a verified loop.
pub const MIN_INLIERS: usize = 6;

fn min_inliers() -> usize {
    MIN_INLIERS
}

/// Smallest eigenvalue of a verifying registration's `JᵀJ` (every direction
/// observed; dimensionless).
pub const MIN_EIGENVALUE: f64 = 0.5;

fn min_eigenvalue() -> f64 {
    MIN_EIGENVALUE
}

/// A verified loop moves the estimate by at most `max_correction` plus this
/// share of the path travelled since the candidate, m per m.
pub const MAX_CORRECTION_PER_METRE: f64 = 0.002;

fn max_correction_per_metre() -> f64 {
    MAX_CORRECTION_PER_METRE
}

/// ... and by at most this, degrees.
pub const MAX_CORRECTION_DEG: f64 = 5.0;

fn max_correction_deg() -> f64 {
    MAX_CORRECTION_DEG
}

/// Loop-factor translation noise, m.
pub const TRANSLATION_SIGMA: f64 = 0.02;

fn translation_sigma() -> f64 {
    TRANSLATION_SIGMA
}

/// Loop-factor rotation noise, rad.
pub const ROTATION_SIGMA: f64 = 0.005;

fn rotation_sigma() -> f64 {
    ROTATION_SIGMA
}

/// Robust kernel on loop factors (a wrong loop that passed the gates is
/// down-weighted, not obeyed): Cauchy, k = 1.
pub const ROBUST: RobustKernel = RobustKernel::Cauchy { k: 1.0 };

fn robust() -> RobustKernel {
    ROBUST
}

/// The whole graph is re-solved during tracking when a loop moves the
/// estimate by more than this, m.
pub const RESOLVE_CORRECTION: f64 = 0.03;

fn resolve_correction() -> f64 {
    RESOLVE_CORRECTION
}

/// Whether a loop that only the points measured in some direction may
/// re-solve the graph during tracking (no: it can be centimetres off along a
/// corridor's axis; it waits for the batch at the end).
pub const RESOLVE_ON_POINT_LOOPS: bool = false;

fn resolve_on_point_loops() -> bool {
    RESOLVE_ON_POINT_LOOPS
}

/// Duplicate landmarks merge when their normals agree within this, degrees ...
pub const MERGE_MAX_ANGLE_DEG: f64 = 3.0;

fn merge_max_angle_deg() -> f64 {
    MERGE_MAX_ANGLE_DEG
}

/// ... each one's boundary centre lies within this of the other's plane, m ...
pub const MERGE_MAX_OFFSET: f64 = 0.05;

fn merge_max_offset() -> f64 {
    MERGE_MAX_OFFSET
}

/// ... and their extents overlap by this share of the smaller one.
pub const MERGE_MIN_OVERLAP: f64 = 0.3;

fn merge_min_overlap() -> f64 {
    MERGE_MIN_OVERLAP
}

impl Default for LoopClosureParams {
    /// `[slam.loop_closure]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.loop_closure")
    }
}

impl LoopClosureParams {
    /// An error message naming the first invalid key.
    pub fn validate(&self) -> Result<(), String> {
        let non_negative = [
            ("keyframe_move", self.keyframe_move),
            ("keyframe_turn_deg", self.keyframe_turn_deg),
            ("search_radius", self.search_radius),
            ("radius_per_metre", self.radius_per_metre),
            ("max_descriptor_distance", self.max_descriptor_distance),
            ("min_eigenvalue", self.min_eigenvalue),
            ("min_point_information", self.min_point_information),
            ("min_point_alignment", self.min_point_alignment),
            ("max_point_distance", self.max_point_distance),
            ("max_correction", self.max_correction),
            ("max_correction_per_metre", self.max_correction_per_metre),
            ("max_correction_deg", self.max_correction_deg),
            ("resolve_correction", self.resolve_correction),
            ("merge_max_angle_deg", self.merge_max_angle_deg),
            ("merge_max_offset", self.merge_max_offset),
            ("merge_min_overlap", self.merge_min_overlap),
        ];
        for (name, v) in non_negative {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(format!("slam.loop_closure.{name} must be >= 0, got {v}"));
            }
        }
        for (name, v) in [
            ("translation_sigma", self.translation_sigma),
            ("rotation_sigma", self.rotation_sigma),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!(
                    "slam.loop_closure.{name} must be positive, got {v}"
                ));
            }
        }
        if self.min_inliers < 3 {
            return Err("slam.loop_closure.min_inliers must be at least 3".into());
        }
        self.robust
            .validate()
            .map_err(|e| format!("slam.loop_closure.robust: {e}"))
    }

    /// Whether the verified loop `check` re-solves the whole graph during
    /// tracking: it moved the estimate by more than `resolve_correction`,
    /// and its planes observed every direction (or
    /// `resolve_on_point_loops`).
    pub fn resolves(&self, check: &LoopMatch) -> bool {
        check.correction > self.resolve_correction
            && (self.resolve_on_point_loops || check.fixed_by_points == 0)
    }

    /// Square-root information of a loop factor.
    pub fn sqrt_info(&self) -> Matrix6<f64> {
        let t = 1.0 / self.translation_sigma;
        let r = 1.0 / self.rotation_sigma;
        Matrix6::from_diagonal(&Vector6::new(t, t, t, r, r, r))
    }
}
