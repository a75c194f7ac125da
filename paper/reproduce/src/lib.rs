//! Reproduction of the paper's experiments ("Detection and Utilization of
//! Reflections in LiDAR Scans Through Plane Optimization and Plane SLAM"),
//! side by side with its published tables: the `specular-reproduce`
//! command (`cargo run --release -p specular-paper -- --out DIR`).
//!
//! This crate sits beside the `specular` library, not in it: the library a
//! user links holds the method; the paper's tables, published values,
//! figures, the KISS-ICP driver and the README filling live here and use
//! the library through its public API only.
//!
//! For every dataset (real 3DRef directories and the simulator's benchmark
//! scenes, simulated in memory with their true poses) it runs
//!
//! 1. the classification comparison of the paper's Tables "Classification
//!    Precision/Recall" and "Filtered point cloud precision and reflection
//!    removal rate": single-scan (Zhao's method, paper configuration),
//!    plane-optimized with the paper's configuration and with ours;
//! 2. the Reflection SLAM comparison (IoU and removal tables) for every
//!    back-end of [`slam_backends`], with the trajectory error of each;
//! 3. optionally the external odometry peer KISS-ICP ([`kiss_icp`]);
//! 4. the "mapping around the corner" figure on `mirror-room`
//!    ([`corner`]);
//!
//! and, on the real frames, the per-stage timing ([`timing`]). Everything
//! but the timing is deterministic (seeded, independent of the thread
//! count); the results go to `results.json` and, rendered in the paper's
//! layouts with the published values beside ours ([`tables`]), to
//! `tables.md` and the README.

pub mod corner;
pub mod data;
pub mod kiss_icp;
pub mod published;
pub mod readme;
pub mod tables;
pub mod timing;

use std::path::Path;

use serde::Serialize;

use specular::backend::{backend, BackendName, BackendParams};
use specular::config::{Config, Method};
use specular::eval::{trajectory_error, Metrics, TrajectoryError};
use specular::io::write_atomic;
use specular::pipeline::slam::classify_with_poses;
use specular::pipeline::{
    optimize_tracked, run_plane_optimized, run_single_scan, run_slam, track_sequence, Discard,
};
use specular::{Error, Result};

pub use data::{DataKind, Dataset, Source};
pub use kiss_icp::KissIcp;

/// The simulator's benchmark scenes, in table order.
pub const SCENES: [&str; 5] = ["office", "lobby", "corridor", "mirror-room", "glass-loop"];
/// Frames simulated per scene with `--quick` (the first ones).
pub const QUICK_FRAMES: usize = 12;
/// The scene of the "mapping around the corner" figure.
pub const CORNER_SCENE: &str = "mirror-room";
/// File name of the figure in the output directory.
pub const CORNER_PNG: &str = "around_corner.png";

/// The back-ends the Reflection SLAM comparison loops over: every one
/// this build of the library has (`factrs` only with its cargo feature).
pub fn slam_backends() -> Vec<String> {
    let params = BackendParams::default();
    [
        BackendName::Average,
        BackendName::Gn,
        BackendName::Lm,
        BackendName::Factrs,
    ]
    .into_iter()
    .filter(|&name| backend(name, &params).is_ok())
    .map(|name| name.as_str().to_string())
    .collect()
}

/// `config` with its SLAM back-end set to `name` (one of
/// [`slam_backends`]); an unknown name is an error.
pub fn with_backend(config: &Config, name: &str) -> Result<Config> {
    let mut config = config.clone();
    config.backend.name = name.parse()?;
    Ok(config)
}

/// What to reproduce.
#[derive(Debug, Clone)]
pub struct Options {
    /// Where the data come from, in table order.
    pub sources: Vec<Source>,
    /// Shorten the simulated sequences to [`QUICK_FRAMES`] frames.
    pub quick: bool,
    /// Run KISS-ICP (`None`: its rows say how to enable it).
    pub kiss_icp: Option<KissIcp>,
}

/// One method's classification of one dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ClassificationRow {
    /// Dataset name.
    pub dataset: String,
    /// Method and configuration, e.g. "plane-optimized (paper)".
    pub method: String,
    /// The paper's metrics (`None` without labels).
    pub metrics: Option<Metrics>,
}

/// Reflection SLAM with one back-end on one dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SlamRow {
    /// Dataset name.
    pub dataset: String,
    /// Back-end name (see [`slam_backends`]).
    pub backend: String,
    /// Trajectory error against the true poses.
    pub trajectory: TrajectoryError,
    /// Classification with the estimated poses (`None` without labels).
    pub metrics: Option<Metrics>,
    /// Frames whose registration left a direction unconstrained.
    pub degenerate_frames: usize,
    /// Frames tracked on the motion model alone.
    pub fallback_frames: usize,
    /// Landmarks in the final map.
    pub landmarks: usize,
}

/// The external odometry peer on one dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OdometryRow {
    /// Dataset name.
    pub dataset: String,
    /// Peer and version, e.g. "KISS-ICP 1.3.0".
    pub method: String,
    /// Its trajectory error, or why it was not run.
    pub outcome: OdometryOutcome,
}

/// Result of running the odometry peer.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OdometryOutcome {
    /// It ran; its poses scored with [`trajectory_error`].
    Ran(TrajectoryError),
    /// It did not run, and why.
    NotRun(String),
}

/// Everything deterministic the reproduction produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Results {
    /// Whether the simulated sequences were shortened (`--quick`).
    pub quick: bool,
    /// The datasets, in table order.
    pub datasets: Vec<data::DatasetInfo>,
    /// Classification rows, dataset by dataset, three methods each.
    pub classification: Vec<ClassificationRow>,
    /// Reflection SLAM rows, dataset by dataset, one per back-end.
    pub slam: Vec<SlamRow>,
    /// The odometry peer, per simulated dataset.
    pub odometry: Vec<OdometryRow>,
    /// What the around-the-corner figure shows (`None`: not drawn).
    pub corner_figure: Option<corner::CornerSummary>,
}

/// The three classification methods: (row name, configuration, method).
fn classification_methods() -> Vec<(&'static str, &'static str, Method)> {
    vec![
        ("single-scan (paper)", "paper", Method::SingleScan),
        ("plane-optimized (paper)", "paper", Method::PlaneOptimized),
        (
            "plane-optimized (default)",
            "default",
            Method::PlaneOptimized,
        ),
    ]
}

/// Run every experiment of `options`, writing the figure into `out`;
/// `log` receives one line per step. Returns the deterministic results.
pub fn run(options: &Options, out: &Path, log: &mut dyn FnMut(&str)) -> Result<Results> {
    let mut results = Results {
        quick: options.quick,
        datasets: Vec::new(),
        classification: Vec::new(),
        slam: Vec::new(),
        odometry: Vec::new(),
        corner_figure: None,
    };
    let kiss = match &options.kiss_icp {
        Some(k) => {
            log("KISS-ICP: preparing its venv (pip install kiss-icp)");
            let ready = k.prepare().map_err(|e| e.to_string());
            if let Err(e) = &ready {
                log(&format!(
                    "KISS-ICP: install failed, its rows are skipped: {e}"
                ));
            }
            Some((k, ready))
        }
        None => None,
    };
    for source in &options.sources {
        let started = std::time::Instant::now();
        let mut dataset = data::load(source, options.quick)?;
        log(&format!(
            "{}: {} frames loaded",
            dataset.name,
            dataset.sequence.len()
        ));
        results.datasets.push(dataset.info()?);
        run_dataset(&mut dataset, kiss.as_ref(), out, &mut results, log)?;
        log(&format!(
            "{}: done in {:.1} s",
            dataset.name,
            started.elapsed().as_secs_f64()
        ));
    }
    Ok(results)
}

/// The experiments on one dataset, appended to `results`: KISS-ICP
/// started in the background, classification, Reflection SLAM, then
/// KISS-ICP's result.
fn run_dataset(
    dataset: &mut Dataset,
    kiss: Option<&(&KissIcp, std::result::Result<(), String>)>,
    out: &Path,
    results: &mut Results,
    log: &mut dyn FnMut(&str),
) -> Result<()> {
    // KISS-ICP runs in the background (one thread) while ours run.
    let kiss_run = match kiss {
        Some((kiss, Ok(()))) if dataset.kind == DataKind::Simulated => {
            log(&format!("{}: KISS-ICP started", dataset.name));
            Some(kiss.start(&dataset.name, &dataset.sequence))
        }
        _ => None,
    };
    classify_dataset(dataset, out, results, log)?;
    let truth = slam_dataset(dataset, results, log)?;
    if dataset.kind == DataKind::Simulated {
        let outcome = match kiss {
            None => OdometryOutcome::NotRun("not run: pass --with-kiss-icp".into()),
            Some((_, Err(e))) => OdometryOutcome::NotRun(format!("not run: install failed ({e})")),
            Some((_, Ok(()))) => match kiss_run.map(|run| run.and_then(|r| r.finish())) {
                Some(Ok(poses)) => {
                    let segment = dataset.config("default")?.slam.rpe_segment;
                    OdometryOutcome::Ran(trajectory_error(&poses, &truth, segment)?)
                }
                Some(Err(e)) => OdometryOutcome::NotRun(format!("failed: {e}")),
                None => OdometryOutcome::NotRun("not run".into()),
            },
        };
        log(&format!(
            "{}: KISS-ICP: {}",
            dataset.name,
            match &outcome {
                OdometryOutcome::Ran(t) => format!("ATE {:.3} m", t.ate_rmse),
                OdometryOutcome::NotRun(why) => why.clone(),
            }
        ));
        results.odometry.push(OdometryRow {
            dataset: dataset.name.clone(),
            method: format!("KISS-ICP {}", kiss_icp::VERSION),
            outcome,
        });
    }
    Ok(())
}

/// The three classification methods on one dataset, and the
/// around-the-corner figure when it is the figure's scene.
fn classify_dataset(
    dataset: &Dataset,
    out: &Path,
    results: &mut Results,
    log: &mut dyn FnMut(&str),
) -> Result<()> {
    let seq = &dataset.sequence;
    let mut default_po = None;
    for (name, config_name, method) in classification_methods() {
        let mut config = dataset.config(config_name)?;
        config.method = method;
        let (run, po) = match method {
            Method::SingleScan => (run_single_scan(seq, &config)?, None),
            Method::PlaneOptimized => {
                let po = run_plane_optimized(seq, &config)?;
                (po.run.clone(), Some(po))
            }
        };
        let metrics = run.confusion.map(|c| c.metrics());
        log(&format!(
            "{}: {name}: {}",
            dataset.name,
            metrics.as_ref().map_or("no labels".into(), short)
        ));
        results.classification.push(ClassificationRow {
            dataset: dataset.name.clone(),
            method: name.into(),
            metrics,
        });
        if config_name == "default" {
            default_po = po;
        }
    }
    if dataset.scene.as_deref() == Some(CORNER_SCENE) {
        if let Some(po) = &default_po {
            let config = dataset.config("default")?;
            results.corner_figure = Some(corner::draw(&out.join(CORNER_PNG), seq, po, &config)?);
            log(&format!("{}: figure {CORNER_PNG} drawn", dataset.name));
        }
    }
    Ok(())
}

/// Reflection SLAM with every back-end on one dataset, scored against its
/// true poses, which are returned.
fn slam_dataset(
    dataset: &mut Dataset,
    results: &mut Results,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<nalgebra::Isometry3<f64>>> {
    let truth = dataset
        .sequence
        .poses
        .clone()
        .ok_or_else(|| Error::Input(format!("{}: SLAM needs true poses", dataset.name)))?;
    let base = dataset.config("default")?;
    // Without a sliding window tracking does not depend on the back-end:
    // track once, optimise once per back-end.
    let shared = if base.slam.window.is_none_or(|w| w < 2) {
        Some(track_sequence(&dataset.sequence, &base, Some(truth[0]))?)
    } else {
        None
    };
    for backend in slam_backends() {
        let config = with_backend(&base, &backend)?;
        let slam = match &shared {
            Some(tracked) => optimize_tracked(tracked.clone(), &config)?,
            None => run_slam(&dataset.sequence, &config, Some(truth[0]))?,
        };
        let trajectory = trajectory_error(&slam.poses, &truth, config.slam.rpe_segment)?;
        // The sequence's true poses are restored afterwards.
        let classified = classify_with_poses(
            &mut dataset.sequence,
            slam.poses.clone(),
            &config,
            &mut Discard,
        )?;
        let metrics = classified.run.confusion.map(|c| c.metrics());
        log(&format!(
            "{}: Reflection SLAM [{backend}]: ATE {:.3} m; {}",
            dataset.name,
            trajectory.ate_rmse,
            metrics.as_ref().map_or("no labels".into(), short)
        ));
        results.slam.push(SlamRow {
            dataset: dataset.name.clone(),
            backend,
            trajectory,
            metrics,
            degenerate_frames: slam.reports.iter().filter(|r| r.is_degenerate()).count(),
            fallback_frames: slam.reports.iter().filter(|r| r.fallback).count(),
            landmarks: slam.map.landmarks.len(),
        });
    }
    Ok(truth)
}

/// A one-line summary of metrics for the log.
fn short(m: &Metrics) -> String {
    format!(
        "accuracy {:.2}, mIoU {:.2}, removal {:.2}",
        m.accuracy, m.miou, m.reflection_removal
    )
}

/// Write `text` to `path` atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))
}

/// Write `value` as pretty JSON to `path` atomically.
pub fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Input(format!("{}: cannot serialise: {e}", path.display())))?;
    write_text(path, &(text + "\n"))
}
