//! Geometric verification of a loop candidate.
//!
//! A descriptor only proposes; this decides (every system read for the
//! reference brief verifies). The current frame's planes are registered
//! against the candidate keyframe's planes with the tracker's own
//! registration (matching, the mismatch rejector, Gauss–Newton), from the
//! relative pose the current estimate implies. The candidate is accepted
//! only when
//!
//! 1. enough plane pairs agree (`min_inliers`);
//! 2. the registration is well conditioned in all six directions: every
//!    eigen-direction of its information matrix `JᵀJ` (the
//!    [`Degeneracy`](crate::registration::Degeneracy) report tracking
//!    uses) reaches `min_eigenvalue`, or — as in tracking — the directions
//!    the planes leave free are fixed by point-to-plane registration of
//!    the current frame's surface samples against the candidate's
//!    ([`refine_free_directions`]). A corridor of floor, ceiling and two
//!    parallel walls leaves its axis free (eigenvalue 0): planes alone
//!    cannot say *where* along a corridor of repeated panes the revisit
//!    is, so such a candidate is rejected unless points (door frames, an
//!    end wall) observe the axis (Voxel-SLAM's gate, reference section
//!    2.3);
//! 3. the correction it implies is plausible drift (`max_correction` plus
//!    `max_correction_per_metre` of the path travelled since the candidate,
//!    `max_correction_deg`): a registration that lands one pane period
//!    away, or that one biased plane pulls by centimetres where tracking
//!    drifted millimetres, is not a measurement of the loop.

use nalgebra::Isometry3;

use super::LoopClosureParams;
use crate::frontend::FramePlane;
use crate::registration::{
    match_planes, refine_free_directions, register, GaussNewtonParams, MismatchRejector,
    PointRefineParams, SurfaceSample,
};
use crate::slam::point_map::LocalPointMap;

/// A verified loop: the current frame registered against the candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopMatch {
    /// `T_candidate_current`: the current sensor frame in the candidate's.
    pub relative: Isometry3<f64>,
    /// Candidate pairs of planes.
    pub matches: usize,
    /// Pairs that agree with the registration.
    pub inliers: usize,
    /// Smallest eigenvalue of the plane registration's information matrix.
    pub min_eigenvalue: f64,
    /// Directions the planes left free that the points fixed.
    pub fixed_by_points: usize,
    /// How far the registration moved the current estimate's relative
    /// pose, m.
    pub correction: f64,
    /// ... and turned it, degrees.
    pub correction_deg: f64,
}

/// Why a candidate was rejected.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopRejection {
    /// The mismatch rejector found no consistent set of pairs.
    NoConsensus {
        /// Candidate pairs of planes.
        matches: usize,
    },
    /// Too few pairs agree.
    TooFewInliers {
        /// Pairs that agreed.
        inliers: usize,
    },
    /// Some direction of the pose is (nearly) unconstrained by the planes
    /// and the points did not fix it.
    Degenerate {
        /// Smallest eigenvalue of `JᵀJ`.
        min_eigenvalue: f64,
        /// Directions below `min_eigenvalue`.
        free: usize,
        /// Of those, fixed by the points.
        fixed_by_points: usize,
    },
    /// The registration moved the estimate further than drift explains.
    ImplausibleCorrection {
        /// Translation, m.
        correction: f64,
        /// Rotation, degrees.
        correction_deg: f64,
    },
}

/// The tracker's registration machinery, borrowed for a verification.
pub struct Verifier<'a> {
    /// Mismatch rejection.
    pub rejector: &'a dyn MismatchRejector,
    /// Gauss–Newton refinement (its degeneracy threshold is not used: the
    /// verification's own `min_eigenvalue` is).
    pub gauss_newton: &'a GaussNewtonParams,
    /// Inlier normal cosine of a pair.
    pub inlier_cos: f64,
    /// Inlier offset of a pair, m.
    pub inlier_offset: f64,
    /// Point refinement of the directions the planes leave free (`None`:
    /// planes alone).
    pub points: Option<PointRefineParams>,
}

/// The current frame's surface samples and the candidate's points, for
/// the directions the planes leave free.
#[derive(Debug, Clone, Copy)]
pub struct Samples<'a> {
    /// The current frame's samples (its sensor frame).
    pub current: &'a [SurfaceSample],
    /// The points around the candidate, in the candidate's sensor frame:
    /// its keyframe's and its neighbours' samples, and the tracker's own
    /// points of the frames around it where it still holds them (one
    /// keyframe's samples are too sparse to measure a corridor's axis).
    pub candidate: &'a LocalPointMap,
}

/// The current frame and the candidate: planes (sensor frames), the path
/// travelled between them, and optionally their surface samples.
#[derive(Debug, Clone, Copy)]
pub struct Pair<'a> {
    /// The current frame's planes.
    pub current: &'a [FramePlane],
    /// The candidate keyframe's planes.
    pub candidate: &'a [FramePlane],
    /// Path travelled from the candidate to the current frame, m.
    pub travelled: f64,
    /// Surface samples for the directions the planes leave free.
    pub samples: Option<Samples<'a>>,
}

impl Verifier<'_> {
    /// Register the current frame's planes (sensor frame) against the
    /// candidate keyframe's (`pair`) from `prior`
    /// (`T_candidate_current` by the current estimate) and apply the gates
    /// of `params` ([module docs](self)).
    pub fn verify(
        &self,
        pair: &Pair<'_>,
        prior: &Isometry3<f64>,
        params: &LoopClosureParams,
        seed: u64,
    ) -> Result<LoopMatch, LoopRejection> {
        let (current, candidate, samples) = (pair.current, pair.candidate, pair.samples);
        let pairs = match_planes(current, candidate, prior, &params.matching);
        let matches = pairs.len();
        let reg = register(
            &pairs,
            prior,
            self.rejector,
            self.gauss_newton,
            self.inlier_cos,
            self.inlier_offset,
            seed,
        )
        .ok_or(LoopRejection::NoConsensus { matches })?;
        let inliers = reg.inliers.len();
        if inliers < params.min_inliers {
            return Err(LoopRejection::TooFewInliers { inliers });
        }
        let degeneracy = &reg.refinement.degeneracy;
        let min_eigenvalue = degeneracy.min_eigenvalue();
        let free: Vec<nalgebra::Vector6<f64>> = degeneracy
            .eigenvalues
            .iter()
            .zip(&degeneracy.eigenvectors)
            .filter(|(l, _)| !(**l >= params.min_eigenvalue))
            .map(|(_, v)| *v)
            .collect();
        let mut pose = reg.pose;
        let mut fixed_by_points = 0;
        let near = prior.translation.vector.norm() <= params.max_point_distance;
        if !free.is_empty() {
            if let (Some(s), Some(mut point_params)) = (samples.filter(|_| near), self.points) {
                point_params.min_information = params.min_point_information;
                point_params.min_alignment = params.min_point_alignment;
                let map = s.candidate;
                let refined = refine_free_directions(
                    s.current,
                    |q, d| map.nearest(q, d),
                    &pose,
                    &free,
                    &point_params,
                );
                tracing::debug!(
                    candidate_points = s.candidate.len(),
                    current = s.current.len(),
                    correspondences = refined.correspondences,
                    fixed = refined.fixed,
                    "loop verification: points"
                );
                fixed_by_points = refined.fixed;
                pose = refined.pose;
            }
            if fixed_by_points < free.len() {
                return Err(LoopRejection::Degenerate {
                    min_eigenvalue,
                    free: free.len(),
                    fixed_by_points,
                });
            }
        }
        let delta = prior.inverse() * pose;
        let correction = delta.translation.vector.norm();
        let correction_deg = delta.rotation.angle().to_degrees();
        let allowed = params.max_correction + params.max_correction_per_metre * pair.travelled;
        if correction > allowed || correction_deg > params.max_correction_deg {
            return Err(LoopRejection::ImplausibleCorrection {
                correction,
                correction_deg,
            });
        }
        Ok(LoopMatch {
            relative: pose,
            matches,
            inliers,
            min_eigenvalue,
            fixed_by_points,
            correction,
            correction_deg,
        })
    }
}
