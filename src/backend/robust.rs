//! Robust kernels applied to a factor's whitened squared norm `s = ‖r‖²`.
//!
//! Cost convention (GTSAM's): a factor contributes `½ ρ(s)`, with `ρ(s) = s`
//! without a kernel, so `½ ρ(e²)` equals GTSAM's `mEstimator::loss(e)`.
//! The solvers use iteratively reweighted least squares, as GTSAM does: the
//! whitened residual and Jacobian are scaled by `√ρ'(s)`, which gives the
//! exact gradient `ρ'(s) Jᵀ r` and a Gauss-Newton Hessian without the
//! second-order (Triggs) term; `ρ''` is provided for tests and for callers
//! that want the Triggs correction.

use serde::{Deserialize, Serialize};

use crate::{Error, Result};

/// A robust kernel, chosen per factor.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RobustKernel {
    /// Plain least squares, `ρ(s) = s`.
    #[default]
    None,
    /// Huber: `ρ(s) = s` for `s ≤ k²`, else `2k√s − k²` (linear beyond `k`).
    Huber {
        /// Threshold on the whitened residual norm.
        k: f64,
    },
    /// Cauchy: `ρ(s) = k² ln(1 + s / k²)`.
    Cauchy {
        /// Scale on the whitened residual norm.
        k: f64,
    },
}

impl RobustKernel {
    /// An error unless the kernel's parameter is finite and positive.
    pub fn validate(&self) -> Result<()> {
        match *self {
            RobustKernel::None => Ok(()),
            RobustKernel::Huber { k } | RobustKernel::Cauchy { k } => {
                if k.is_finite() && k > 0.0 {
                    Ok(())
                } else {
                    Err(Error::Input(format!(
                        "robust kernel parameter k must be finite and positive, got {k}"
                    )))
                }
            }
        }
    }

    /// `ρ(s)` for the whitened squared norm `s ≥ 0`.
    #[inline]
    pub fn rho(&self, s: f64) -> f64 {
        match *self {
            RobustKernel::None => s,
            RobustKernel::Huber { k } => {
                if s <= k * k {
                    s
                } else {
                    2.0 * k * s.sqrt() - k * k
                }
            }
            RobustKernel::Cauchy { k } => k * k * (s / (k * k)).ln_1p(),
        }
    }

    /// `ρ'(s)`, the IRLS weight (1 without a kernel).
    #[inline]
    pub fn weight(&self, s: f64) -> f64 {
        match *self {
            RobustKernel::None => 1.0,
            RobustKernel::Huber { k } => {
                if s <= k * k {
                    1.0
                } else {
                    k / s.sqrt()
                }
            }
            RobustKernel::Cauchy { k } => 1.0 / (1.0 + s / (k * k)),
        }
    }

    /// `ρ''(s)` (for the Triggs correction and tests).
    #[inline]
    pub fn second_derivative(&self, s: f64) -> f64 {
        match *self {
            RobustKernel::None => 0.0,
            RobustKernel::Huber { k } => {
                if s <= k * k {
                    0.0
                } else {
                    -0.5 * k / (s * s.sqrt())
                }
            }
            RobustKernel::Cauchy { k } => {
                let q = 1.0 + s / (k * k);
                -1.0 / (k * k * q * q)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huber_matches_gtsam_loss() {
        // GTSAM Huber loss(e) = k|e| − k²/2 beyond k; ours is ½ρ(e²).
        let h = RobustKernel::Huber { k: 1.345 };
        let e: f64 = 3.0;
        assert!((0.5 * h.rho(e * e) - (1.345 * e - 0.5 * 1.345 * 1.345)).abs() < 1e-14);
        assert_eq!(h.rho(1.0), 1.0);
        assert!(RobustKernel::Cauchy { k: f64::NAN }.validate().is_err());
        assert!(RobustKernel::Huber { k: 0.0 }.validate().is_err());
    }
}
