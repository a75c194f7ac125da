//! The paper's plane "optimisation": no joint optimisation at all. Poses are
//! left as they are; each landmark becomes the running weighted average of
//! its observations moved to the world with the current poses, weighted as
//! the paper's map merger (`map::merge`): the new observation 1, the stored
//! plane 3 after one observation, then its observation count capped at 10.
//!
//! It is the baseline the joint solvers are measured against.

use std::collections::BTreeMap;
use std::time::Instant;

use super::factors::AnyFactor;
use super::graph::FactorGraph;
use super::observability;
use super::solver::{prepare, SolveReport, SolverParams, Termination};
use super::variables::{PlaneVar, Values};
use crate::geometry::Plane;
use crate::Result;

/// Weights of the running average (the paper's merger).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AverageWeights {
    /// Weight of the stored plane after its first observation (paper: 3).
    pub second: f64,
    /// Cap on the stored plane's weight (paper: 10).
    pub max: f64,
}

impl Default for AverageWeights {
    fn default() -> Self {
        Self {
            second: 3.0,
            max: 10.0,
        }
    }
}

/// Landmarks re-estimated by weighted averaging; poses unchanged.
pub fn average_planes(
    graph: &FactorGraph,
    initial: &Values,
    weights: AverageWeights,
    params: &SolverParams,
) -> Result<(Values, SolveReport)> {
    let t0 = Instant::now();
    prepare(graph, initial)?;
    let initial_cost = graph.cost(initial)?;
    let mut values = initial.clone();
    let mut fused: BTreeMap<u32, (Plane, usize)> = BTreeMap::new();
    for f in &graph.factors {
        let (pose, plane, measured) = match &f.factor {
            AnyFactor::PlaneObservation(o) => {
                let (x, p) = o.ids();
                (x, p, Some(o.measured))
            }
            AnyFactor::PointToPlane(o) => {
                let (x, p) = o.ids();
                (x, p, o.fitted_plane())
            }
            _ => continue,
        };
        let Some(measured) = measured else { continue };
        let world = measured.transformed(values.pose(pose)?);
        match fused.get_mut(&plane) {
            None => {
                fused.insert(plane, (world, 1));
            }
            Some((stored, count)) => {
                let w = if *count == 1 {
                    weights.second
                } else {
                    (*count as f64).min(weights.max)
                };
                let n = world.normal + stored.normal * w;
                let d = world.d + stored.d * w;
                if let Some(p) = Plane::new(n / (1.0 + w), d / (1.0 + w)) {
                    *stored = p;
                }
                *count += 1;
            }
        }
    }
    for (id, (plane, _)) in fused {
        if let Some(v) = values.planes.get_mut(&id) {
            *v = PlaneVar::from(plane);
        }
    }
    let final_cost = graph.cost(&values)?;
    let observability = observability::analyse(graph, &values, params.unobservable_threshold)?;
    let report = SolveReport {
        solver: "average".into(),
        initial_cost,
        final_cost,
        iterations: 0,
        converged: true,
        termination: Termination::NotIterative,
        per_iteration: Vec::new(),
        assembly_seconds: 0.0,
        factorization_seconds: 0.0,
        solve_seconds: 0.0,
        setup_seconds: 0.0,
        total_seconds: t0.elapsed().as_secs_f64(),
        nnz_h: 0,
        nnz_factor: 0,
        observability,
    };
    Ok((values, report))
}
