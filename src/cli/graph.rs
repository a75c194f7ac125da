//! `specular graph`: export synthetic pose-plane graphs and solve graph
//! files with a back-end (the side-by-side with `paper/gtsam_solve.py`).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use specular::backend::synthetic::{synthetic, SyntheticParams};
use specular::backend::{backend, BackendName, BackendParams, FactorGraph, PlaneFactorKind};

/// Arguments of `graph`.
#[derive(Args, Debug)]
pub struct GraphArgs {
    #[command(subcommand)]
    command: GraphCommand,
}

#[derive(Subcommand, Debug)]
enum GraphCommand {
    /// Write a deterministic synthetic graph (random walk in a box of planes).
    Synth {
        /// Number of poses.
        #[arg(long)]
        poses: usize,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Plane factor type.
        #[arg(long, value_enum, default_value_t = FactorArg::Plane)]
        factor: FactorArg,
        /// Plane observations per pose.
        #[arg(long, default_value_t = 10)]
        observations: usize,
        /// Odometry noise: translation sigma (m); drives the initial drift.
        #[arg(long, default_value_t = 0.05)]
        odometry_sigma_t: f64,
        /// Odometry noise: rotation sigma (rad).
        #[arg(long, default_value_t = 0.01)]
        odometry_sigma_r: f64,
    },
    /// Solve a graph file and print {initial_error, final_error, iterations,
    /// seconds, ...} as JSON.
    Solve {
        /// Graph JSON file.
        #[arg(long)]
        graph: PathBuf,
        /// Back-end.
        #[arg(long, value_enum, default_value_t = BackendArg::Gn)]
        backend: BackendArg,
        /// Maximum iterations.
        #[arg(long, default_value_t = 100)]
        max_iterations: usize,
        /// Relative and absolute cost-decrease tolerance.
        #[arg(long, default_value_t = 1e-5)]
        tolerance: f64,
        /// Print the full report (per-iteration costs and timings,
        /// observability) instead of the summary.
        #[arg(long)]
        report: bool,
    },
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum FactorArg {
    /// Plane-to-plane (GTSAM OrientedPlane3Factor).
    Plane,
    /// Point-to-plane on scatter summaries.
    Point,
}

#[derive(ValueEnum, Clone, Copy, Debug)]
enum BackendArg {
    /// The paper's weighted plane average (poses unchanged).
    Average,
    /// Sparse Gauss-Newton.
    Gn,
    /// Sparse Levenberg-Marquardt.
    Lm,
    /// factrs 0.3 (needs a build with --features factrs; otherwise a clear error).
    Factrs,
}

/// Run `graph`.
pub fn run(args: GraphArgs) -> Result<()> {
    match args.command {
        GraphCommand::Synth {
            poses,
            out,
            seed,
            factor,
            observations,
            odometry_sigma_t,
            odometry_sigma_r,
        } => {
            let s = synthetic(&SyntheticParams {
                poses,
                seed,
                observations_per_pose: observations,
                odometry_translation_sigma: odometry_sigma_t,
                odometry_rotation_sigma: odometry_sigma_r,
                factor: match factor {
                    FactorArg::Plane => PlaneFactorKind::PlaneToPlane,
                    FactorArg::Point => PlaneFactorKind::PointToPlane,
                },
                ..SyntheticParams::default()
            })?;
            s.graph.write(&out)?;
            eprintln!(
                "wrote {} ({} poses, {} planes, {} factors)",
                out.display(),
                s.graph.values.poses.len(),
                s.graph.values.planes.len(),
                s.graph.factors.len()
            );
            Ok(())
        }
        GraphCommand::Solve {
            graph,
            backend: which,
            max_iterations,
            tolerance,
            report,
        } => {
            let g = FactorGraph::read(&graph)?;
            let name = match which {
                BackendArg::Average => BackendName::Average,
                BackendArg::Gn => BackendName::Gn,
                BackendArg::Lm => BackendName::Lm,
                BackendArg::Factrs => BackendName::Factrs,
            };
            let mut params = BackendParams::default();
            params.solver.max_iterations = max_iterations;
            params.solver.relative_tolerance = tolerance;
            params.solver.absolute_tolerance = tolerance;
            let b = backend(name, &params)?;
            let t0 = Instant::now();
            let (_, r) = b
                .optimize(&g, &g.values)
                .with_context(|| format!("solving {}", graph.display()))?;
            let seconds = t0.elapsed().as_secs_f64();
            if report {
                println!("{}", serde_json::to_string_pretty(&r)?);
            } else {
                let summary = serde_json::json!({
                    "backend": b.name(),
                    "initial_error": r.initial_cost,
                    "final_error": r.final_cost,
                    "iterations": r.iterations,
                    "seconds": seconds,
                    "converged": r.converged,
                    "termination": r.termination,
                    "weak_poses": r.observability.weak.len(),
                });
                println!("{summary}");
            }
            Ok(())
        }
    }
}
