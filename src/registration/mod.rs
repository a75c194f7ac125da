//! Plane registration: the rigid transform that maps one set of planes onto
//! another.
//!
//! The paper's "Plane Registration", one file per step:
//!
//! 1. [`matching`]: candidate pairs of planes of the same kind, by the four
//!    similarity criteria (normal cosine, offset, centroid distance, area
//!    ratio).
//! 2. [`rejector`]: mismatch removal ([`MismatchRejector`]); the paper's
//!    RANSAC over plane triples that always include the ground pair is
//!    [`GroundTripleRansac`].
//! 3. [`closed_form`](mod@closed_form): the closed-form transform of a set of pairs —
//!    rotation by SVD of `Σ n_s n_tᵀ` (determinant checked), translation by
//!    the pseudo-inverse of the stacked target normals.
//! 4. [`gauss_newton`]: Gauss–Newton refinement over all inlier pairs with
//!    the paper's residual `e = (R n_s − n_t ; (R n_s)·t + d_t − d_s)` on
//!    SE(3), right perturbation `T ← T · exp(δ)`.
//! 5. [`degeneracy`]: which directions the pairs do not constrain (the
//!    eigenvalues of the information matrix `JᵀJ`); the solvers move only
//!    in the observable subspace and keep the prior elsewhere.
//!
//! Convention: a registration returns `T` mapping the *source* frame to
//! the *target* frame, so a source plane maps onto its target as
//! `n_t = R n_s`, `d_t = d_s − n_t·t` ([`Plane::transformed`]).

pub mod closed_form;
pub mod degeneracy;
pub mod gauss_newton;
pub mod matching;
pub mod point_to_plane;
pub mod rejector;

pub use closed_form::closed_form;
pub use degeneracy::Degeneracy;
pub use gauss_newton::{refine, GaussNewtonParams, Refinement};
pub use matching::{match_planes, MatchCriteria};
pub use point_to_plane::{
    point_residual, refine_free_directions, PointRefineParams, PointRefinement, SurfaceSample,
};
pub use rejector::{
    AcceptAll, Consensus, GroundTripleRansac, MismatchRejector, RejectorName, RejectorParams,
};

use nalgebra::Isometry3;

use crate::geometry::Plane;

/// A source plane matched to a target plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correspondence {
    /// The plane in the source frame.
    pub source: Plane,
    /// The plane in the target frame.
    pub target: Plane,
    /// Both planes are ground planes (the RANSAC anchor).
    pub ground: bool,
    /// Index of the source plane in its list.
    pub source_index: usize,
    /// Index of the target plane in its list (a frame plane or a landmark).
    pub target_index: usize,
}

impl Correspondence {
    /// Whether the pair agrees with transform `t` within `min_cos` (normal
    /// cosine) and `max_offset` (offset difference, m).
    pub fn agrees(&self, t: &Isometry3<f64>, min_cos: f64, max_offset: f64) -> bool {
        let moved = self.source.transformed(t);
        moved.normal.dot(&self.target.normal) >= min_cos
            && (moved.d - self.target.d).abs() <= max_offset
    }
}

/// The result of registering one set of pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct Registration {
    /// The transform, source frame to target frame.
    pub pose: Isometry3<f64>,
    /// Indices (into the pairs) of the inliers used.
    pub inliers: Vec<usize>,
    /// The Gauss–Newton refinement over the inliers.
    pub refinement: Refinement,
}

/// Register `pairs`: reject mismatches, then refine over the inliers with
/// Gauss–Newton, starting from the rejector's hypothesis; the inliers are
/// reselected once with the refined transform. Directions the inliers do
/// not constrain keep the value of `prior`. `None` when the rejector finds
/// no consistent hypothesis.
pub fn register(
    pairs: &[Correspondence],
    prior: &Isometry3<f64>,
    rejector: &dyn MismatchRejector,
    params: &GaussNewtonParams,
    inlier_cos: f64,
    inlier_offset: f64,
    seed: u64,
) -> Option<Registration> {
    let consensus = rejector.reject(pairs, prior, seed)?;
    let subset: Vec<Correspondence> = consensus.inliers.iter().map(|&i| pairs[i]).collect();
    let mut refinement = refine(&subset, &consensus.pose, params);
    let mut inliers = consensus.inliers;
    // Reselect with the refined transform; refine again if the set changed.
    let again: Vec<usize> = (0..pairs.len())
        .filter(|&i| pairs[i].agrees(&refinement.pose, inlier_cos, inlier_offset))
        .collect();
    if again != inliers && again.len() >= inliers.len() {
        let subset: Vec<Correspondence> = again.iter().map(|&i| pairs[i]).collect();
        refinement = refine(&subset, &refinement.pose, params);
        inliers = again;
    }
    Some(Registration {
        pose: refinement.pose,
        inliers,
        refinement,
    })
}

/// Test helper: the correspondence of a plane `(n, d)` with its image under
/// `t` (shared by the registration tests).
#[cfg(test)]
pub(crate) fn test_pair(
    n: nalgebra::Vector3<f64>,
    d: f64,
    t: &nalgebra::Isometry3<f64>,
) -> Correspondence {
    let source = crate::geometry::Plane::new(n, d).expect("valid test plane");
    Correspondence {
        source,
        target: source.transformed(t),
        ground: false,
        source_index: 0,
        target_index: 0,
    }
}
