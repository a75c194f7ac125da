//! Factors of the pose-plane graph: the [`Factor`] trait, one file per
//! factor, and [`AnyFactor`], the closed set the graph stores and serialises.
//!
//! Every factor returns its residual already whitened (multiplied by its
//! square-root information) and one analytic Jacobian block per key, taken
//! with respect to the variables' tangent updates (poses `X · exp(δ)`,
//! `δ = (ρ, φ)`; planes `(Exp_n(B v), d + δd)`). Robust kernels are applied
//! on top by [`GraphFactor`].

mod between;
mod plane_observation;
mod point_to_plane;
mod pose_prior;
mod sensor_plane;

pub use between::Between;
pub use plane_observation::PlaneObservation;
pub use point_to_plane::PointToPlane;
pub use pose_prior::PosePrior;

use nalgebra::{Matrix6, Vector6};

use super::robust::RobustKernel;
use super::variables::{Key, Values};
use crate::Result;

/// Largest residual dimension and key count of any factor: linearisations
/// live in fixed-size buffers (no allocation per factor).
pub const MAX_DIM: usize = 6;

/// A factor's whitened residual and Jacobian blocks at one linearisation
/// point. Only the top-left `dim × key.dim()` part of each block is used.
#[derive(Debug, Clone, Default)]
pub struct Linearization {
    /// Residual dimension.
    pub dim: usize,
    /// Whitened residual (first `dim` entries).
    pub residual: Vector6<f64>,
    /// Whitened Jacobian block per key, in [`Factor::keys`] order.
    pub jacobians: [Matrix6<f64>; 2],
}

/// A measurement constraining one or two variables.
///
/// Implementations compute `S · r(x)` (whitened residual) and, on request,
/// `S · ∂r/∂δ` for each key (GTSAM's `evaluateError` with `H`s).
pub trait Factor {
    /// The variables, in the order of the Jacobian blocks.
    fn keys(&self) -> &[Key];
    /// Residual dimension.
    fn dim(&self) -> usize;
    /// Whitened residual; fills `jacobians[k]` for every key when asked.
    fn evaluate(
        &self,
        values: &Values,
        jacobians: Option<&mut [Matrix6<f64>; 2]>,
    ) -> Result<Vector6<f64>>;

    /// Residual and Jacobians into a reusable buffer.
    fn linearize(&self, values: &Values, out: &mut Linearization) -> Result<()> {
        out.dim = self.dim();
        out.residual = self.evaluate(values, Some(&mut out.jacobians))?;
        Ok(())
    }
}

/// Every factor type the graph can hold (also the unit of the file format).
#[derive(Debug, Clone, PartialEq)]
pub enum AnyFactor {
    /// Prior on a pose.
    PosePrior(PosePrior),
    /// Relative pose between two poses.
    Between(Between),
    /// Plane-to-plane observation of a landmark from a pose.
    PlaneObservation(PlaneObservation),
    /// Point-to-plane (scatter) observation of a landmark from a pose.
    PointToPlane(PointToPlane),
}

impl AnyFactor {
    /// Short type name as used in the file format.
    pub fn type_name(&self) -> &'static str {
        match self {
            AnyFactor::PosePrior(_) => "pose_prior",
            AnyFactor::Between(_) => "between",
            AnyFactor::PlaneObservation(_) => "plane_observation",
            AnyFactor::PointToPlane(_) => "point_to_plane",
        }
    }

    /// Whether this factor measures a plane (used by the observability
    /// analysis, which looks at what planes alone say about a pose).
    pub fn is_plane_factor(&self) -> bool {
        matches!(
            self,
            AnyFactor::PlaneObservation(_) | AnyFactor::PointToPlane(_)
        )
    }
}

impl Factor for AnyFactor {
    fn keys(&self) -> &[Key] {
        match self {
            AnyFactor::PosePrior(f) => f.keys(),
            AnyFactor::Between(f) => f.keys(),
            AnyFactor::PlaneObservation(f) => f.keys(),
            AnyFactor::PointToPlane(f) => f.keys(),
        }
    }

    fn dim(&self) -> usize {
        match self {
            AnyFactor::PosePrior(f) => f.dim(),
            AnyFactor::Between(f) => f.dim(),
            AnyFactor::PlaneObservation(f) => f.dim(),
            AnyFactor::PointToPlane(f) => f.dim(),
        }
    }

    fn evaluate(
        &self,
        values: &Values,
        jacobians: Option<&mut [Matrix6<f64>; 2]>,
    ) -> Result<Vector6<f64>> {
        match self {
            AnyFactor::PosePrior(f) => f.evaluate(values, jacobians),
            AnyFactor::Between(f) => f.evaluate(values, jacobians),
            AnyFactor::PlaneObservation(f) => f.evaluate(values, jacobians),
            AnyFactor::PointToPlane(f) => f.evaluate(values, jacobians),
        }
    }
}

/// A factor with its robust kernel: what the graph stores.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphFactor {
    /// The measurement model.
    pub factor: AnyFactor,
    /// Kernel applied to the whitened squared norm.
    pub robust: RobustKernel,
}

impl GraphFactor {
    /// A factor without a robust kernel.
    pub fn new(factor: AnyFactor) -> Self {
        Self {
            factor,
            robust: RobustKernel::None,
        }
    }

    /// The same factor with a robust kernel.
    pub fn with_robust(mut self, robust: RobustKernel) -> Self {
        self.robust = robust;
        self
    }

    /// The factor's cost `½ ρ(‖S r‖²)`.
    pub fn cost(&self, values: &Values) -> Result<f64> {
        let r = self.factor.evaluate(values, None)?;
        let s = r.rows(0, self.factor.dim()).norm_squared();
        Ok(0.5 * self.robust.rho(s))
    }

    /// Linearise with the IRLS reweighting (residual and Jacobians scaled by
    /// `√ρ'(s)`); returns the cost `½ ρ(s)` at `values`.
    pub fn linearize(&self, values: &Values, out: &mut Linearization) -> Result<f64> {
        self.factor.linearize(values, out)?;
        let s = out.residual.rows(0, out.dim).norm_squared();
        if !s.is_finite() {
            return Err(crate::Error::Input(format!(
                "{} factor on {} has a non-finite residual",
                self.factor.type_name(),
                keys_text(self.factor.keys())
            )));
        }
        if self.robust != RobustKernel::None {
            let w = self.robust.weight(s).sqrt();
            out.residual *= w;
            for j in &mut out.jacobians {
                *j *= w;
            }
        }
        Ok(0.5 * self.robust.rho(s))
    }
}

/// `x0, p3` for messages.
pub(crate) fn keys_text(keys: &[Key]) -> String {
    keys.iter()
        .map(|k| k.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}
