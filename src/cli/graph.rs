//! `specular graph`: export synthetic pose-plane graphs and solve graph
//! files with a back-end (the side-by-side with `paper/gtsam_solve.py`),
//! writing the solution when asked.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use specular::backend::synthetic::{synthetic, SyntheticParams};
use specular::backend::{
    backend, BackendName, BackendParams, FactorGraph, PlaneFactorKind, Values,
};
use specular::io::{self, StampedPose};

use super::run_dir::RunDir;

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
        /// Output directory for the solution, new or empty as for `detect`
        /// and `slam`: `poses.txt` (the optimised poses as TUM, in id
        /// order), `graph.json` (the same graph with the optimised poses and
        /// planes as its values, in the graph format: solving it again
        /// starts at the solution) and `solve.json` (the printed summary or
        /// report).
        #[arg(long)]
        out: Option<PathBuf>,
        /// TUM file whose timestamps, in file order, stamp the poses in id
        /// order (e.g. the `poses.txt` of the `slam` run that exported the
        /// graph); without it a pose's timestamp in `poses.txt` is its id.
        #[arg(long, requires = "out")]
        stamps: Option<PathBuf>,
        /// Replace the outputs of an earlier run in `--out`.
        #[arg(long, requires = "out")]
        force: bool,
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
            out,
            stamps,
            force,
        } => {
            let g = FactorGraph::read(&graph)?;
            // Checked before solving, so a bad stamp file costs no solve.
            let stamps = match &stamps {
                Some(path) => Some(pose_stamps(path, g.values.poses.len())?),
                None => None,
            };
            let name = match which {
                BackendArg::Average => BackendName::Average,
                BackendArg::Gn => BackendName::Gn,
                BackendArg::Lm => BackendName::Lm,
                BackendArg::Factrs => BackendName::Factrs,
            };
            let mut params = BackendParams::default();
            params.solver.initial_lambda = SOLVE_INITIAL_LAMBDA;
            params.solver.max_iterations = max_iterations;
            params.solver.relative_tolerance = tolerance;
            params.solver.absolute_tolerance = tolerance;
            let b = backend(name, &params)?;
            let t0 = Instant::now();
            let (solved, r) = b
                .optimize(&g, &g.values)
                .with_context(|| format!("solving {}", graph.display()))?;
            let seconds = t0.elapsed().as_secs_f64();
            // A solution worse than the start is no solution: nothing is
            // written (Gauss-Newton damps a step that raises the cost, so
            // this guards the other back-ends and anything unforeseen).
            if r.final_cost.is_nan() || r.final_cost > r.initial_cost {
                bail!(
                    "{}: the {} solve diverged (cost {:.6e} at the start, {:.6e} at the end); no solution written (try --backend lm)",
                    graph.display(),
                    b.name(),
                    r.initial_cost,
                    r.final_cost
                );
            }
            // Claimed only now: a graph that cannot be solved leaves an
            // earlier solution in --out as it was.
            let dir = match &out {
                Some(out) => Some(RunDir::claim(out, force)?),
                None => None,
            };
            let printed = if report {
                serde_json::to_string_pretty(&r)?
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
                summary.to_string()
            };
            println!("{printed}");
            if let (Some(out), Some(dir)) = (&out, dir) {
                write_solution(dir.path(), &g, solved, stamps.as_deref(), &printed)?;
                dir.finish()?;
                eprintln!("poses.txt, graph.json, solve.json in {}", out.display());
            }
            Ok(())
        }
    }
}

/// The timestamps of a TUM file in file order, one per pose of a graph of
/// `poses` poses.
/// `graph solve`'s initial Levenberg–Marquardt damping: the tool solves
/// graph files with its own settings (`--max-iterations`, `--tolerance`),
/// and has started at this λ since it was written (the pipeline's is
/// `backend::solver::INITIAL_LAMBDA`).
const SOLVE_INITIAL_LAMBDA: f64 = 1e-8;

fn pose_stamps(path: &Path, poses: usize) -> Result<Vec<f64>> {
    let stamps: Vec<f64> = io::read_tum(path)?.iter().map(|p| p.stamp).collect();
    if stamps.len() != poses {
        bail!(
            "--stamps {}: {} timestamps for a graph of {poses} poses",
            path.display(),
            stamps.len()
        );
    }
    Ok(stamps)
}

/// Write the solution into `out`, each file atomically: `poses.txt` (TUM,
/// poses in id order, stamped by `stamps` or by their ids), `graph.json`
/// (`graph` with `solved` as its values) and `solve.json` (`summary`).
fn write_solution(
    out: &Path,
    graph: &FactorGraph,
    solved: Values,
    stamps: Option<&[f64]>,
    summary: &str,
) -> Result<()> {
    let poses: Vec<StampedPose> = solved
        .poses
        .iter()
        .enumerate()
        .map(|(k, (&id, pose))| StampedPose {
            stamp: stamps.map_or(f64::from(id), |s| s[k]),
            pose: *pose,
        })
        .collect();
    io::write_tum(&out.join("poses.txt"), &poses)?;
    let solution = FactorGraph {
        values: solved,
        ..graph.clone()
    };
    solution.write(&out.join("graph.json"))?;
    io::write_atomic(&out.join("solve.json"), |w| {
        std::io::Write::write_all(w, format!("{summary}\n").as_bytes())
    })?;
    Ok(())
}
