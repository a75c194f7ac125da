//! The back-end: a sparse pose-plane factor graph solved by Gauss–Newton or
//! Levenberg–Marquardt on faer's sparse Cholesky, the paper's weighted
//! average as a baseline, and a dense reference solver.
//!
//! | module | job |
//! |---|---|
//! | [`variables`] | keys, plane landmarks on S² × ℝ, [`Values`] and retractions |
//! | [`unit3`] | GTSAM's `Unit3` basis, retraction and local coordinates |
//! | [`factors`] | [`PosePrior`], [`Between`], [`PlaneObservation`], [`PointToPlane`] |
//! | [`robust`] | Huber and Cauchy kernels (GTSAM cost convention) |
//! | [`graph`] | [`FactorGraph`]: variables, factors, gauge, total cost |
//! | [`format`](mod@format) | the JSON graph file (`docs/graph-format.md`) |
//! | [`ordering`] / [`linear`] | sparse normal equations, Jacobi scaling, cached symbolic Cholesky |
//! | [`solver`] | Gauss–Newton, Levenberg–Marquardt, [`SolveReport`] |
//! | [`observability`] | per-pose directions the planes leave unconstrained |
//! | [`dense`] | dense reference Gauss–Newton (tests, tiny graphs) |
//! | [`average`] | the paper's weighted plane average |
//! | `factrs_adapter` | the external factrs back-end (cargo feature `factrs`) |
//! | [`backends`] | the [`Backend`] trait, [`BackendName`], [`BackendParams`], [`backend`] |
//! | [`synthetic`] | deterministic synthetic graphs |
//!
//! Conventions: poses are `T_world_sensor`, updated on the right with
//! `δ = (ρ, φ)`; planes are `n·x + d = 0` in the world; costs are
//! `½ Σ ρ(‖S r‖²)` as in GTSAM. See `docs/backend.md`.

pub mod average;
pub mod backends;
pub mod dense;
pub mod factors;
#[cfg(feature = "factrs")]
pub mod factrs_adapter;
pub mod format;
pub mod graph;
pub mod linear;
pub mod observability;
pub mod ordering;
pub mod robust;
pub mod seam;
pub mod solver;
pub mod synthetic;
pub mod unit3;
pub mod variables;

pub use backends::{
    backend, Average, Backend, BackendName, BackendParams, GaussNewton, LevenbergMarquardt,
    PlaneFactorKind,
};
pub use factors::{
    AnyFactor, Between, Factor, GraphFactor, PlaneObservation, PointToPlane, PosePrior,
};
pub use graph::FactorGraph;
pub use observability::ObservabilityReport;
pub use robust::RobustKernel;
pub use solver::{gauss_newton, levenberg_marquardt, SolveReport, SolverParams, Termination};
pub use variables::{Key, PlaneVar, Values};
