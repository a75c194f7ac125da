//! Gauss–Newton refinement of a plane registration on SE(3).
//!
//! The paper's residual of one pair, for `T = (R, t)` mapping source to
//! target:
//!
//! ```text
//! e(T) = ( R n_s − n_t ;  (R n_s)·t + d_t − d_s )  ∈ ℝ⁴
//! ```
//!
//! (zero exactly when `n_t = R n_s` and `d_t = d_s − n_t·t`). The pose is
//! perturbed on the right, `T ← T · exp(δ)` with `δ = (ρ, φ)` in the
//! ordering of [`crate::geometry::se3`], so `R ← R exp([φ]×)` and
//! `t ← t + R ρ` to first order. The analytic Jacobian `∂e/∂δ` at `δ = 0`:
//!
//! ```text
//! ∂(R n_s)/∂ρ = 0          ∂(R n_s)/∂φ = −R [n_s]×
//! ∂e₄/∂ρ      = n_sᵀ       ∂e₄/∂φ      = (n_s × Rᵀ t)ᵀ
//! ```
//!
//! Each iteration solves `JᵀJ δ = −Jᵀe` in the observable subspace only
//! (see [`Degeneracy`]): unobservable directions keep the initial value.
//!
//! Anchoring: the offset row couples rotation with the target frame's
//! origin (`∂e₄/∂φ` grows with `‖t‖`), so in a world frame whose origin is
//! far from the sensor the normal equations condition badly and their
//! eigenvalues — the degeneracy test — would depend on where the world
//! origin happens to be. [`refine`] therefore evaluates the same residual in
//! the target frame shifted to the initial sensor position (`t₀`): target
//! offsets become `d_t + n_t·t₀` and the translation `t − t₀`, which is
//! small; the result is shifted back.

use nalgebra::{Isometry3, Matrix4x6, Matrix6, Translation3, UnitQuaternion, Vector4, Vector6};
use serde::{Deserialize, Serialize};

use super::{Correspondence, Degeneracy};
use crate::geometry::se3;

/// Gauss–Newton settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GaussNewtonParams {
    /// Most iterations: [`MAX_ITERATIONS`].
    #[serde(skip, default = "max_iterations")]
    pub max_iterations: usize,
    /// Stop when the step's norm falls below this: [`MIN_STEP`].
    #[serde(skip, default = "min_step")]
    pub min_step: f64,
    /// Eigenvalues of `JᵀJ` at or below this mark unobservable directions.
    /// One unit-normal pair contributes `cos²` of the angle between its
    /// normal and a translation direction, so 0.25 asks for a plane within
    /// 60° of it; the position error along a direction is about the offset
    /// noise over `√λ`, so weaker directions are better left to the motion
    /// model (dimensionless, like the eigenvalues).
    pub degeneracy_threshold: f64,
}

/// Gauss–Newton iterations of a plane registration at most.
pub const MAX_ITERATIONS: usize = 10;

/// A plane registration stops when its step's norm (a twist: m and rad)
/// falls below this.
pub const MIN_STEP: f64 = 1e-9;

fn max_iterations() -> usize {
    MAX_ITERATIONS
}

fn min_step() -> f64 {
    MIN_STEP
}

impl Default for GaussNewtonParams {
    /// `[slam.gauss_newton]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("slam.gauss_newton")
    }
}

/// The outcome of a refinement.
#[derive(Debug, Clone, PartialEq)]
pub struct Refinement {
    /// The refined transform.
    pub pose: Isometry3<f64>,
    /// Iterations run.
    pub iterations: usize,
    /// Sum of squared residuals at the start.
    pub initial_cost: f64,
    /// Sum of squared residuals at the end.
    pub cost: f64,
    /// Eigen-analysis of `JᵀJ` at the refined transform.
    pub degeneracy: Degeneracy,
}

/// The residual of one pair under `t`.
#[inline]
pub fn residual(t: &Isometry3<f64>, c: &Correspondence) -> Vector4<f64> {
    let rn = t.rotation * c.source.normal;
    let e = rn - c.target.normal;
    Vector4::new(
        e.x,
        e.y,
        e.z,
        rn.dot(&t.translation.vector) + c.target.d - c.source.d,
    )
}

/// The analytic Jacobian of [`residual`] with respect to the right
/// perturbation `δ = (ρ, φ)` at `δ = 0`.
#[inline]
pub fn jacobian(t: &Isometry3<f64>, c: &Correspondence) -> Matrix4x6<f64> {
    let r = t.rotation.to_rotation_matrix().into_inner();
    let n = c.source.normal;
    let dn_dphi = -r * se3::hat(&n);
    let coupling = n.cross(&(r.transpose() * t.translation.vector));
    let mut j = Matrix4x6::zeros();
    j.fixed_view_mut::<3, 3>(0, 3).copy_from(&dn_dphi);
    j[(3, 0)] = n.x;
    j[(3, 1)] = n.y;
    j[(3, 2)] = n.z;
    j[(3, 3)] = coupling.x;
    j[(3, 4)] = coupling.y;
    j[(3, 5)] = coupling.z;
    j
}

/// `JᵀJ`, `Jᵀe` and `Σ‖e‖²` over `pairs` at `t`.
fn normal_equations(
    t: &Isometry3<f64>,
    pairs: &[Correspondence],
) -> (Matrix6<f64>, Vector6<f64>, f64) {
    let mut h = Matrix6::zeros();
    let mut g = Vector6::zeros();
    let mut cost = 0.0;
    for c in pairs {
        let e = residual(t, c);
        let j = jacobian(t, c);
        h += j.transpose() * j;
        g += j.transpose() * e;
        cost += e.norm_squared();
    }
    (h, g, cost)
}

/// Refine `init` over `pairs` (every pair an inlier), anchored at the
/// initial sensor position (see the module documentation).
pub fn refine(
    pairs: &[Correspondence],
    init: &Isometry3<f64>,
    params: &GaussNewtonParams,
) -> Refinement {
    let anchor = init.translation.vector;
    let shift = Translation3::from(-anchor);
    let anchored: Vec<Correspondence> = pairs
        .iter()
        .map(|c| Correspondence {
            target: c
                .target
                .transformed(&Isometry3::from_parts(shift, UnitQuaternion::identity())),
            ..*c
        })
        .collect();
    let mut r = refine_at(&anchored, &(shift * init), params);
    r.pose = Translation3::from(anchor) * r.pose;
    r
}

/// [`refine`] without anchoring.
fn refine_at(
    pairs: &[Correspondence],
    init: &Isometry3<f64>,
    params: &GaussNewtonParams,
) -> Refinement {
    let mut pose = *init;
    let (mut h, mut g, initial_cost) = normal_equations(&pose, pairs);
    let mut cost = initial_cost;
    let mut iterations = 0;
    while iterations < params.max_iterations && !pairs.is_empty() {
        let step = Degeneracy::of(&h, params.degeneracy_threshold).solve(&g);
        if !step.iter().all(|v| v.is_finite()) {
            break;
        }
        let candidate = se3::retract(&pose, &step);
        let (h2, g2, c2) = normal_equations(&candidate, pairs);
        iterations += 1;
        // Gauss–Newton on this residual is nearly linear; a step that does
        // not decrease the cost means we are at the minimum (round-off).
        if c2 > cost {
            break;
        }
        pose = candidate;
        (h, g, cost) = (h2, g2, c2);
        if step.norm() < params.min_step {
            break;
        }
    }
    let degeneracy = if pairs.is_empty() {
        Degeneracy::none_observable(params.degeneracy_threshold)
    } else {
        Degeneracy::of(&h, params.degeneracy_threshold)
    };
    Refinement {
        pose,
        iterations,
        initial_cost,
        cost,
        degeneracy,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    use crate::registration::test_pair as pair;

    #[test]
    fn converges_from_a_perturbed_start() {
        let truth = Isometry3::new(Vector3::new(0.4, -0.3, 0.1), Vector3::new(0.05, -0.1, 0.4));
        let pairs: Vec<_> = [
            (Vector3::new(0.0, 0.0, 1.0), 1.2),
            (Vector3::new(1.0, 0.1, 0.0), 3.0),
            (Vector3::new(-0.2, 1.0, 0.1), 2.0),
            (Vector3::new(0.7, -0.7, 0.1), 5.0),
        ]
        .iter()
        .map(|(n, d)| pair(*n, *d, &truth))
        .collect();
        let start = se3::retract(&truth, &Vector6::new(0.2, 0.1, -0.1, 0.05, 0.02, -0.08));
        let r = refine(&pairs, &start, &GaussNewtonParams::default());
        assert!(r.cost < 1e-20, "{}", r.cost);
        assert!(se3::local(&truth, &r.pose).norm() < 1e-9);
        assert!(!r.degeneracy.is_degenerate());
    }

    #[test]
    fn the_degeneracy_analysis_does_not_depend_on_the_world_origin() {
        let truth = Isometry3::new(Vector3::new(0.1, 0.2, 0.0), Vector3::new(0.0, 0.0, 0.3));
        let pairs: Vec<_> = [
            (Vector3::z(), 1.5),
            (Vector3::x(), 2.0),
            (Vector3::y(), 3.0),
            (Vector3::new(1.0, 1.0, 0.0), 2.5),
        ]
        .iter()
        .map(|(n, d)| pair(*n, *d, &truth))
        .collect();
        let params = GaussNewtonParams::default();
        let near = refine(&pairs, &truth, &params).degeneracy.eigenvalues;
        // The same problem with the world origin moved 50 m away.
        let far_origin = Isometry3::translation(30.0, -40.0, 0.0);
        let moved: Vec<_> = pairs
            .iter()
            .map(|c| Correspondence {
                target: c.target.transformed(&far_origin),
                ..*c
            })
            .collect();
        let r = refine(&moved, &(far_origin * truth), &params);
        for (a, b) in near.iter().zip(&r.degeneracy.eigenvalues) {
            assert!(
                (a - b).abs() < 1e-9,
                "{near:?} vs {:?}",
                r.degeneracy.eigenvalues
            );
        }
        assert!(se3::local(&(far_origin * truth), &r.pose).norm() < 1e-9);
    }

    #[test]
    fn a_corridor_has_exactly_one_degenerate_translation() {
        // Floor, ceiling and two parallel walls; the corridor runs along x.
        // A rolled sensor: the corridor axis stays x in both frames.
        let truth = Isometry3::new(Vector3::new(0.3, 0.05, 0.02), Vector3::new(0.03, 0.0, 0.0));
        let pairs: Vec<_> = [
            (Vector3::z(), 1.5),
            (-Vector3::z(), 1.5),
            (Vector3::y(), 1.3),
            (-Vector3::y(), 1.3),
        ]
        .iter()
        .map(|(n, d)| pair(*n, *d, &truth))
        .collect();
        // Prior: the motion model says 0.25 m along x.
        let prior = Isometry3::new(Vector3::new(0.25, 0.0, 0.0), Vector3::zeros());
        let r = refine(&pairs, &prior, &GaussNewtonParams::default());
        let deg = &r.degeneracy;
        assert_eq!(deg.count(), 1, "{:?}", deg.eigenvalues);
        let v = deg.directions().next().unwrap();
        assert!(v[0].abs() > 1.0 - 1e-9, "{v}");
        // Observable parts converge; x keeps the prior.
        assert!((r.pose.translation.vector.y - truth.translation.vector.y).abs() < 1e-9);
        assert!((r.pose.translation.vector.z - truth.translation.vector.z).abs() < 1e-9);
        assert!(r.pose.rotation.angle_to(&truth.rotation) < 1e-9);
        assert!((r.pose.translation.vector.x - 0.25).abs() < 1e-12);
        assert!(deg
            .describe(&Isometry3::identity())
            .starts_with("t(1.00 0.00 0.00)"));
    }
}
