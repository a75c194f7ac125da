//! The back-end seam: what every pose-plane graph optimiser implements.
//! Its own module so that implementations living in their own modules (the
//! factrs adapter) and the selector by name ([`backend`](super::backend))
//! depend on it, not on each other.

use super::graph::FactorGraph;
use super::solver::SolveReport;
use super::variables::Values;
use crate::Result;

/// A pose-plane graph optimiser. A new back-end is a type implementing this
/// plus one arm in [`backend`](super::backend) (or none, when it is used
/// directly: `tests/custom_backend.rs`).
pub trait Backend {
    /// The back-end's name (as in [`BackendName`](super::BackendName)).
    fn name(&self) -> &'static str;
    /// Optimise `graph` from `initial`; the result holds every variable.
    fn optimize(&self, graph: &FactorGraph, initial: &Values) -> Result<(Values, SolveReport)>;
}
