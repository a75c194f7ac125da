//! Relative pose (odometry / registration): `r = log(Z⁻¹ · X_i⁻¹ X_j)`.
//!
//! With `E = Z⁻¹ X_i⁻¹ X_j`, `M = X_i⁻¹ X_j` and right perturbations:
//! `∂r/∂δ_j = J_r⁻¹(r)`; since `exp(−δ_i) M = M exp(−Ad(M⁻¹) δ_i)`,
//! `∂r/∂δ_i = −J_r⁻¹(r) Ad(M⁻¹)`. Same residual as GTSAM's
//! `BetweenFactor<Pose3>` up to the `(ω, v)` ordering.

use nalgebra::{Isometry3, Matrix6, Vector6};

use super::Factor;
use crate::backend::variables::{Key, Values};
use crate::geometry::se3;
use crate::Result;

/// Measured `Z = X_i⁻¹ X_j` between poses `i` and `j`, with 6×6
/// square-root information in `(ρ, φ)` order.
#[derive(Debug, Clone, PartialEq)]
pub struct Between {
    keys: [Key; 2],
    ids: [u32; 2],
    /// The measured relative pose `Z`.
    pub measured: Isometry3<f64>,
    /// Square-root information `S`.
    pub sqrt_info: Matrix6<f64>,
}

impl Between {
    /// A relative-pose factor from pose `i` to pose `j`.
    pub fn new(i: u32, j: u32, measured: Isometry3<f64>, sqrt_info: Matrix6<f64>) -> Self {
        Self {
            keys: [Key::Pose(i), Key::Pose(j)],
            ids: [i, j],
            measured,
            sqrt_info,
        }
    }

    /// The pose ids `(i, j)`.
    pub fn poses(&self) -> (u32, u32) {
        (self.ids[0], self.ids[1])
    }
}

impl Factor for Between {
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
        let xi = values.pose(self.ids[0])?;
        let xj = values.pose(self.ids[1])?;
        let m = xi.inverse() * xj;
        let r = se3::log(&(self.measured.inverse() * m));
        if let Some(j) = jacobians {
            let jr_inv = self.sqrt_info * se3::se3_right_jacobian_inv(&r);
            j[0] = -(jr_inv * se3::adjoint(&m.inverse()));
            j[1] = jr_inv;
        }
        Ok(self.sqrt_info * r)
    }
}
