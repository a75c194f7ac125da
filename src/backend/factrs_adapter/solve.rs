//! The factrs back-end: our graph converted, factrs' Levenberg–Marquardt
//! or Gauss–Newton driven one step at a time with our stopping rules, the
//! result converted back and scored by our own cost.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::time::Instant;

use factrs::containers::Values as FValues;
use factrs::optimizers::{
    BaseOptParams, GaussNewton as FGaussNewton, LevenMarquardt, LevenParams, OptError, Optimizer,
};

use super::convert::{convert, convert_back};
use crate::backend::graph::FactorGraph;
use crate::backend::observability;
use crate::backend::seam::Backend;
use crate::backend::solver::{prepare, IterationStats, SolveReport, SolverParams, Termination};
use crate::backend::variables::Values;
use crate::{Error, Result};

/// Which factrs optimiser runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FactrsMethod {
    /// factrs' Levenberg–Marquardt (diagonal damping `λ·diag(JᵀJ)`).
    #[default]
    LevenbergMarquardt,
    /// factrs' Gauss–Newton (every step taken).
    GaussNewton,
}

/// The factrs back-end.
#[derive(Debug, Clone, Default)]
pub struct Factrs {
    /// Iteration limit, tolerances, `max_lambda` and `lambda_decrease`
    /// (factrs' λ factor is `1 / lambda_decrease`, used both ways; its
    /// initial λ is fixed at 1e-10, so `initial_lambda` and `step_tolerance`
    /// do not map).
    pub params: SolverParams,
    /// The optimiser.
    pub method: FactrsMethod,
}

impl Backend for Factrs {
    fn name(&self) -> &'static str {
        "factrs"
    }

    fn optimize(&self, graph: &FactorGraph, initial: &Values) -> Result<(Values, SolveReport)> {
        let t_start = Instant::now();
        prepare(graph, initial)?;
        let initial_cost = graph.cost(initial)?;
        let fixed = graph.effective_fixed();
        let problem = convert(graph, initial, &fixed)?;
        let setup_seconds = t_start.elapsed().as_secs_f64();
        let p = &self.params;
        let base = BaseOptParams {
            max_iterations: p.max_iterations,
            error_tol_relative: p.relative_tolerance,
            error_tol_absolute: p.absolute_tolerance,
            error_tol: 0.0,
        };
        let (fvalues, run) = if problem.values.is_empty() {
            (problem.values, Run::empty())
        } else {
            match self.method {
                FactrsMethod::LevenbergMarquardt => {
                    let params = LevenParams {
                        lambda_max: p.max_lambda,
                        // factrs divides λ by this after a success and
                        // multiplies by it after a failure.
                        lambda_factor: 1.0 / p.lambda_decrease,
                        base,
                        ..LevenParams::default()
                    };
                    let mut opt = LevenMarquardt::new(params, problem.graph);
                    iterate(&mut opt, problem.values, p)?
                }
                FactrsMethod::GaussNewton => {
                    let mut opt = FGaussNewton::new(base, problem.graph);
                    iterate(&mut opt, problem.values, p)?
                }
            }
        };
        let values = convert_back(initial, &fvalues, &problem.free)?;
        let final_cost = graph.cost(&values)?;
        let observability = observability::analyse(graph, &values, p.unobservable_threshold)?;
        let report = SolveReport {
            solver: "factrs".into(),
            initial_cost,
            final_cost,
            iterations: run.per_iteration.len(),
            converged: run.converged,
            termination: run.termination,
            per_iteration: run.per_iteration,
            assembly_seconds: 0.0,
            factorization_seconds: 0.0,
            solve_seconds: 0.0,
            setup_seconds,
            total_seconds: t_start.elapsed().as_secs_f64(),
            nnz_h: 0,
            nnz_factor: 0,
            observability,
        };
        Ok((values, report))
    }
}

/// What the iteration loop did.
struct Run {
    per_iteration: Vec<IterationStats>,
    converged: bool,
    termination: Termination,
}

impl Run {
    /// Nothing to optimise (every variable fixed or untouched).
    fn empty() -> Self {
        Self {
            per_iteration: Vec::new(),
            converged: true,
            termination: Termination::NotIterative,
        }
    }
}

/// Drive factrs' optimiser one step at a time (its own `optimize` drops
/// the values when it cannot step), with our stopping rules on factrs'
/// cost (the same function as ours minus constant fully-fixed factors).
/// A panic inside factrs (e.g. a failed Cholesky) becomes a typed error.
fn iterate<O: Optimizer>(
    opt: &mut O,
    mut values: FValues,
    p: &SolverParams,
) -> Result<(FValues, Run)> {
    let panicked = |what: &str| {
        Error::Input(format!(
            "factrs failed while {what} (singular or non-finite system?)"
        ))
    };
    let mut cost = catch_unwind(AssertUnwindSafe(|| {
        opt.init(&values);
        opt.error(&values)
    }))
    .map_err(|_| panicked("setting up"))?;
    let mut run = Run {
        per_iteration: Vec::new(),
        converged: false,
        termination: Termination::MaxIterations,
    };
    if cost <= f64::MIN_POSITIVE {
        run.converged = true;
        run.termination = Termination::ZeroCost;
        return Ok((values, run));
    }
    for i in 1..=p.max_iterations {
        let t = Instant::now();
        let stepped = catch_unwind(AssertUnwindSafe(|| opt.step(values.clone(), i)))
            .map_err(|_| panicked(&format!("taking step {i}")))?;
        let next = match stepped {
            Ok((next, _)) => next,
            Err(OptError::FailedToStep) => {
                run.termination = Termination::DampingLimit;
                break;
            }
            Err(OptError::InvalidSystem) => return Err(panicked(&format!("solving step {i}"))),
            Err(OptError::MaxIterations(_)) => break,
        };
        let new_cost = catch_unwind(AssertUnwindSafe(|| opt.error(&next)))
            .map_err(|_| panicked("evaluating the cost"))?;
        if !new_cost.is_finite() {
            return Err(Error::Input(format!(
                "factrs step {i} gave a non-finite cost"
            )));
        }
        values = next;
        run.per_iteration.push(IterationStats {
            iteration: i,
            cost: new_cost,
            lambda: 0.0,
            accepted: true,
            assembly_seconds: 0.0,
            factorization_seconds: 0.0,
            solve_seconds: 0.0,
            seconds: t.elapsed().as_secs_f64(),
        });
        let decrease = cost - new_cost;
        cost = new_cost;
        let stop = if new_cost <= f64::MIN_POSITIVE {
            Some(Termination::ZeroCost)
        } else if decrease.abs() < p.absolute_tolerance {
            Some(Termination::AbsoluteDecrease)
        } else if decrease.abs() < p.relative_tolerance * new_cost {
            Some(Termination::RelativeDecrease)
        } else {
            None
        };
        if let Some(t) = stop {
            run.converged = true;
            run.termination = t;
            break;
        }
    }
    Ok((values, run))
}
