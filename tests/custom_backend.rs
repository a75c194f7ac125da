//! A new back-end, added from outside the crate: a type implementing
//! `specular::backend::Backend`, handed to the SLAM pipeline with
//! `pipeline::optimize_tracked_with` (the names of `[backend] name` are the
//! built-in back-ends; a back-end of one's own needs no registry line).

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use specular::backend::{gauss_newton, Backend, FactorGraph, SolveReport, SolverParams, Values};
use specular::config::Config;
use specular::pipeline::{optimize_tracked, optimize_tracked_with, track_sequence, Sequence};
use specular::sim::{self, Scene};

/// Gauss–Newton as the crate has it, counting its solves.
struct CountingGaussNewton {
    params: SolverParams,
    solves: Arc<AtomicUsize>,
}

impl Backend for CountingGaussNewton {
    fn name(&self) -> &'static str {
        "counting-gn"
    }
    fn optimize(
        &self,
        graph: &FactorGraph,
        initial: &Values,
    ) -> specular::Result<(Values, SolveReport)> {
        self.solves.fetch_add(1, Ordering::Relaxed);
        gauss_newton(graph, initial, &self.params)
    }
}

/// A back-end that moves nothing: the tracking estimate unchanged.
struct Frozen {
    params: SolverParams,
}

impl Backend for Frozen {
    fn name(&self) -> &'static str {
        "frozen"
    }
    fn optimize(
        &self,
        graph: &FactorGraph,
        initial: &Values,
    ) -> specular::Result<(Values, SolveReport)> {
        // The report of a real solve (costs, observability), the values
        // as they came.
        let (_, report) = gauss_newton(graph, initial, &self.params)?;
        Ok((initial.clone(), report))
    }
}

/// 30 frames of the simulated office with their true poses.
fn office() -> Sequence {
    let scene = Scene::resolve("office").unwrap();
    let run = sim::simulate(&scene, Some(30), None).unwrap();
    let poses = run.poses.iter().map(|p| p.pose).collect();
    Sequence::from_frames(run.frames, Some(poses), "office").unwrap()
}

#[test]
fn a_custom_backend_is_used_by_the_slam_pipeline() {
    let sequence = office();
    let mut config = Config::default();
    config.backend.name = "gn".parse().unwrap();
    let origin = sequence.poses.as_ref().map(|p| p[0]);
    let tracked = track_sequence(&sequence, &config, origin).unwrap();

    // The crate's Gauss–Newton, chosen by name.
    let by_name = optimize_tracked(tracked.clone(), &config).unwrap();

    // The same method as an outside back-end: the same poses, and it was
    // the one that ran.
    let solves = Arc::new(AtomicUsize::new(0));
    let make = || -> specular::Result<Box<dyn Backend>> {
        Ok(Box::new(CountingGaussNewton {
            params: config.backend.solver,
            solves: solves.clone(),
        }))
    };
    let ours = optimize_tracked_with(tracked.clone(), &config, &make).unwrap();
    assert!(
        solves.load(Ordering::Relaxed) >= 1,
        "the custom back-end ran"
    );
    assert_eq!(ours.poses, by_name.poses);
    assert!(ours.backend.is_some());

    // A back-end that moves nothing leaves tracking's poses; Gauss–Newton
    // moves them: the pipeline's result is the back-end's.
    let frozen = || -> specular::Result<Box<dyn Backend>> {
        Ok(Box::new(Frozen {
            params: config.backend.solver,
        }))
    };
    let still = optimize_tracked_with(tracked, &config, &frozen).unwrap();
    assert_eq!(still.poses, still.tracked_poses);
    assert_ne!(by_name.poses, by_name.tracked_poses);
}
