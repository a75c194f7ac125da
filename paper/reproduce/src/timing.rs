//! Per-stage timing of single-scan and plane-optimized on real frames, on
//! one thread and on all threads (machine-dependent, so kept apart from the
//! deterministic tables).
//!
//! Each measurement loads the frames (PLY parsing is the "parse" stage)
//! and runs the method inside a rayon pool of the given size; it is
//! repeated and the run with the median wall time is reported.

use std::path::Path;
use std::time::{Duration, Instant};

use serde::Serialize;

use super::data::resolve_real;
use specular::config::{Config, Method};
use specular::pipeline::{run_plane_optimized, run_single_scan, Sequence, StageTimings};
use specular::{Error, Result};

/// One (method, thread count) measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimingRow {
    /// Method name.
    pub method: String,
    /// Threads of the rayon pool.
    pub threads: usize,
    /// Frames processed per run.
    pub frames: usize,
    /// Milliseconds per frame of every stage (CPU time summed over the
    /// workers), in pipeline order.
    pub stages_ms: Vec<(String, f64)>,
    /// Wall milliseconds per frame of the whole run, parsing included.
    pub wall_ms: f64,
    /// Repetitions the median is taken over.
    pub repeats: usize,
}

/// The timing of a dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimingReport {
    /// The dataset measured (its directory's name).
    pub data: String,
    /// Threads available to the process.
    pub threads_available: usize,
    /// One row per (method, threads).
    pub rows: Vec<TimingRow>,
}

/// Measure both methods (our default configuration) on the 3DRef-format
/// directory `dir`, `repeats` times each, on one thread and on all.
pub fn measure(dir: &Path, repeats: usize) -> Result<TimingReport> {
    let (frames, poses) = resolve_real(dir)?;
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads = vec![1];
    if all > 1 {
        threads.push(all);
    }
    let mut rows = Vec::new();
    for &n in &threads {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .map_err(|e| Error::Input(format!("cannot start {n} worker threads: {e}")))?;
        for method in [Method::SingleScan, Method::PlaneOptimized] {
            let mut config = Config::resolve("default")?;
            config.method = method;
            let mut runs: Vec<(Duration, StageTimings)> = pool.install(|| {
                (0..repeats.max(1))
                    .map(|_| once(&frames, &poses, &config))
                    .collect::<Result<_>>()
            })?;
            runs.sort_by_key(|(wall, _)| *wall);
            let (wall, timings) = runs.swap_remove(runs.len() / 2);
            let per = |d: Duration| d.as_secs_f64() * 1e3 / timings.frames.max(1) as f64;
            rows.push(TimingRow {
                method: method.name().to_string(),
                threads: n,
                frames: timings.frames,
                stages_ms: timings
                    .stages
                    .iter()
                    .map(|(s, d)| (s.to_string(), per(*d)))
                    .collect(),
                wall_ms: per(wall),
                repeats: repeats.max(1),
            });
        }
    }
    Ok(TimingReport {
        data: super::data::dir_name(dir),
        threads_available: all,
        rows,
    })
}

/// Load and run once: the wall time and the stage timings.
fn once(frames: &Path, poses: &Path, config: &Config) -> Result<(Duration, StageTimings)> {
    let start = Instant::now();
    let mut timings = StageTimings::default();
    let sequence = Sequence::load(
        frames,
        Some(poses),
        config.input.pose_tolerance,
        &mut timings,
    )?;
    let run = match config.method {
        Method::SingleScan => run_single_scan(&sequence, config)?,
        Method::PlaneOptimized => run_plane_optimized(&sequence, config)?.run,
    };
    let wall = start.elapsed();
    timings.merge(&run.timings);
    timings.frames = sequence.len();
    Ok((wall, timings))
}
