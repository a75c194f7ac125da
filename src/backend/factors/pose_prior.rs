//! Prior on one pose: `r = log(P⁻¹ · X)` in `(ρ, φ)` order.
//!
//! Jacobian under `X · exp(δ)`: `log(P⁻¹ X exp(δ)) ≈ r + J_r⁻¹(r) δ`, so
//! `∂r/∂δ = J_r⁻¹(r)` (exact, [`se3::se3_right_jacobian_inv`]). The same
//! residual as GTSAM's `PriorFactor<Pose3>` up to the `(ω, v)` ordering.

use nalgebra::{Isometry3, Matrix6, Vector6};

use super::Factor;
use crate::backend::variables::{Key, Values};
use crate::geometry::se3;
use crate::Result;

/// Prior `P` on pose `key` with 6×6 square-root information `S` (`SᵀS = Σ⁻¹`,
/// rows and columns in `(ρ, φ)` order).
#[derive(Debug, Clone, PartialEq)]
pub struct PosePrior {
    keys: [Key; 1],
    /// The prior pose `P`.
    pub prior: Isometry3<f64>,
    /// Square-root information `S`.
    pub sqrt_info: Matrix6<f64>,
}

impl PosePrior {
    /// A prior on pose `id`.
    pub fn new(id: u32, prior: Isometry3<f64>, sqrt_info: Matrix6<f64>) -> Self {
        Self {
            keys: [Key::Pose(id)],
            prior,
            sqrt_info,
        }
    }

    /// The pose id.
    pub fn pose(&self) -> u32 {
        match self.keys[0] {
            Key::Pose(i) => i,
            Key::Plane(_) => unreachable!("constructed with a pose key"),
        }
    }
}

impl Factor for PosePrior {
    fn keys(&self) -> &[Key] {
        &self.keys
    }

    fn dim(&self) -> usize {
        6
    }

    fn evaluate(
        &self,
        values: &Values,
        jacobians: Option<&mut [Matrix6<f64>; 2]>,
    ) -> Result<Vector6<f64>> {
        let x = values.pose(self.pose())?;
        let r = se3::log(&(self.prior.inverse() * x));
        if let Some(j) = jacobians {
            j[0] = self.sqrt_info * se3::se3_right_jacobian_inv(&r);
        }
        Ok(self.sqrt_info * r)
    }
}
