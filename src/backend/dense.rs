//! Dense reference solver: the same linearisation as the sparse solvers,
//! normal equations in a dense `nalgebra::DMatrix`, plain Gauss–Newton.
//!
//! It is the reference the tests compare the sparse solvers against, and a
//! simple choice for tiny graphs (a few dozen variables). It shares nothing
//! with the sparse path below the factor linearisation: no pattern, no
//! scaling, no faer.

use std::time::Instant;

use nalgebra::{DMatrix, DVector};

use super::factors::{Factor, Linearization};
use super::graph::FactorGraph;
use super::observability;
use super::ordering::{Ordering, FIXED};
use super::solver::{prepare, IterationStats, SolveReport, SolverParams, Termination};
use super::variables::Values;
use crate::{Error, Result};

/// Assemble the dense `H` and `g` at `values`; returns the cost.
pub fn assemble_dense(
    graph: &FactorGraph,
    ordering: &Ordering,
    values: &Values,
) -> Result<(DMatrix<f64>, DVector<f64>, f64)> {
    let n = ordering.dim;
    let mut h = DMatrix::zeros(n, n);
    let mut g = DVector::zeros(n);
    let mut lin = Linearization::default();
    let mut cost = 0.0;
    for f in &graph.factors {
        cost += f.linearize(values, &mut lin)?;
        let keys = f.factor.keys();
        let m = lin.dim;
        for (a, &ka) in keys.iter().enumerate() {
            let va = ordering.var(ka);
            if va == FIXED {
                continue;
            }
            let oa = ordering.offsets[va as usize];
            let ja = lin.jacobians[a].view((0, 0), (m, ka.dim()));
            let r = lin.residual.rows(0, m);
            let mut gs = g.rows_mut(oa, ka.dim());
            gs += ja.transpose() * r;
            for (b, &kb) in keys.iter().enumerate() {
                let vb = ordering.var(kb);
                if vb == FIXED {
                    continue;
                }
                let ob = ordering.offsets[vb as usize];
                let jb = lin.jacobians[b].view((0, 0), (m, kb.dim()));
                let mut hs = h.view_mut((oa, ob), (ka.dim(), kb.dim()));
                hs += ja.transpose() * jb;
            }
        }
    }
    Ok((h, g, cost))
}

/// Plain Gauss–Newton with dense Cholesky; same stopping rules and report as
/// the sparse solvers (the observability analysis included).
pub fn dense_gauss_newton(
    graph: &FactorGraph,
    initial: &Values,
    params: &SolverParams,
) -> Result<(Values, SolveReport)> {
    let t0 = Instant::now();
    let ordering = prepare(graph, initial)?;
    let mut values = initial.clone();
    let (mut h, mut g, mut cost) = assemble_dense(graph, &ordering, &values)?;
    let initial_cost = cost;
    let mut stats = Vec::new();
    let mut termination = Termination::MaxIterations;
    for iteration in 1..=params.max_iterations {
        let ti = Instant::now();
        let chol = h.clone().cholesky().ok_or_else(|| {
            Error::Input(format!(
                "dense Gauss-Newton: H is not positive definite at iteration {iteration}"
            ))
        })?;
        let step = chol.solve(&(-&g));
        if !step.iter().all(|v| v.is_finite()) {
            return Err(Error::Input("dense Gauss-Newton: non-finite step".into()));
        }
        for (key, &off) in ordering.keys.iter().zip(&ordering.offsets) {
            values.retract_key(*key, step.rows(off, key.dim()).as_slice())?;
        }
        let old = cost;
        (h, g, cost) = assemble_dense(graph, &ordering, &values)?;
        stats.push(IterationStats {
            iteration,
            cost,
            lambda: 0.0,
            accepted: true,
            assembly_seconds: 0.0,
            factorization_seconds: 0.0,
            solve_seconds: 0.0,
            seconds: ti.elapsed().as_secs_f64(),
        });
        let dec = old - cost;
        if cost <= f64::MIN_POSITIVE {
            termination = Termination::ZeroCost;
            break;
        }
        if dec.abs() < params.absolute_tolerance {
            termination = Termination::AbsoluteDecrease;
            break;
        }
        if dec.abs() < params.relative_tolerance * cost {
            termination = Termination::RelativeDecrease;
            break;
        }
        if step.amax() < params.step_tolerance {
            termination = Termination::SmallStep;
            break;
        }
    }
    let observability = observability::analyse(graph, &values, params.unobservable_threshold)?;
    let nnz = h.iter().filter(|v| **v != 0.0).count();
    let report = SolveReport {
        solver: "dense".into(),
        initial_cost,
        final_cost: cost,
        iterations: stats.len(),
        converged: termination != Termination::MaxIterations,
        termination,
        per_iteration: stats,
        assembly_seconds: 0.0,
        factorization_seconds: 0.0,
        solve_seconds: 0.0,
        setup_seconds: 0.0,
        total_seconds: t0.elapsed().as_secs_f64(),
        nnz_h: nnz,
        nnz_factor: ordering.dim * (ordering.dim + 1) / 2,
        observability,
    };
    Ok((values, report))
}
