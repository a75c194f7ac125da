//! The external back-end [factrs](https://github.com/rpl-cmu/factrs) 0.3
//! (behind the `factrs` cargo feature): our [`FactorGraph`] and initial
//! [`Values`] become a factrs problem, factrs' Levenberg–Marquardt or
//! Gauss–Newton solves it, and the result comes back as our [`Values`],
//! scored by our own [`FactorGraph::cost`] so every back-end is compared on
//! the same number.
//!
//! factrs brings its own nalgebra 0.34 and faer 0.23, so every value crosses
//! the boundary as plain `f64` arrays. Mapping (see `docs/backend.md`):
//!
//! * poses → factrs `SE3` (right update `X · exp(ξ)`, `ξ = (ω, v)`); factrs'
//!   prior and between residuals are `log(X⁻¹ P)` and `log(X_j⁻¹ X_i Z)`,
//!   i.e. ours negated and block-swapped, so our square-root information `S`
//!   becomes `S Pᵀ` (columns swapped) and the cost is the same function;
//! * planes → [`FactrsPlane`], a factrs variable whose update is our `Unit3`
//!   retraction; plane factors are [`residuals`] with autodiff Jacobians;
//! * robust kernels → factrs `Huber` / `Cauchy`, whose `loss(s)` is our
//!   `½ ρ(s)` (same convention);
//! * fixed variables ([`FactorGraph::effective_fixed`]) are not factrs
//!   variables: their values are constants baked into the residuals.
//!
//! The rooms: `solve` is the [`Factrs`] back-end and the iteration loop
//! that drives factrs' optimiser with our stopping rules; `convert` carries
//! the graph and the values across the boundary (and exposes the converted
//! costs and linearisations for the tests); `plane` and [`residuals`] are
//! the plane variable and the plane factors on the factrs side.

mod convert;
mod plane;
pub mod residuals;
mod solve;

pub use convert::{
    convert, converted_costs, converted_linearizations, from_plane, from_se3, to_plane, to_se3,
    FactrsLinearization, FactrsProblem,
};
pub use plane::FactrsPlane;
pub use solve::{Factrs, FactrsMethod};
