//! `specular slam`: Reflection SLAM on a frame directory or a ROS 2 bag.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use nalgebra::Isometry3;
use serde_json::json;
use specular::backend::FactorGraph;
use specular::eval::trajectory_error;
use specular::io::{self, StampedPose};
use specular::pipeline::slam::classify_with_poses;
use specular::pipeline::{optimize_tracked, run_plane_optimized_into, track_sequence, Discard};
use specular::viz::plots::{self, TrajectorySeries};

use super::input::InputArgs;
use super::load_config;
use super::output::{OutputOptions, RunWriter};
use super::run_dir::RunDir;

/// Arguments of `slam`.
#[derive(Args, Debug)]
pub struct SlamArgs {
    /// The frames: `--frames DIR` (a 3DRef release sequence directory
    /// brings its true poses) or `--bag PATH --topic NAME`.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output directory (poses.txt, planes.json, frames.csv, predictions/,
    /// metrics.json, config.toml, trajectory.png).
    #[arg(long)]
    pub out: PathBuf,
    /// True poses (TUM, `T_world_sensor`): the first aligns the estimate's
    /// world frame, all of them score the trajectory.
    #[arg(long)]
    pub gt_poses: Option<PathBuf>,
    /// Configuration: built-in name (default, paper) or a TOML file of
    /// changes, layered over the default (or `extends = "paper"`).
    #[arg(long, default_value = "default")]
    pub config: String,
    /// Skip the classification pass (trajectory only).
    #[arg(long)]
    pub no_classify: bool,
    /// Print milliseconds per frame for every stage.
    #[arg(long)]
    pub timings: bool,
    /// Replace the outputs of an earlier run in `--out` (a directory holding
    /// anything else is still refused).
    #[arg(long)]
    pub force: bool,
    /// Seconds between a frame and the nearest true pose that still match
    /// (overrides `input.pose_tolerance`).
    #[arg(long)]
    pub pose_tolerance: Option<f64>,
    /// Back-end run after tracking: average (the paper), gn, lm, factrs
    /// (overrides `[backend] name`).
    #[arg(long)]
    pub backend: Option<String>,
    /// Also write the back-end's factor graph (initial values = tracking)
    /// as JSON (docs/graph-format.md), e.g. for paper/gtsam_solve.py.
    #[arg(long)]
    pub export_graph: Option<PathBuf>,
}

/// Run `slam`.
pub fn run(args: SlamArgs) -> Result<()> {
    let mut config = load_config(&args.config)?;
    args.input.apply_sensor(&mut config)?;
    if let Some(name) = &args.backend {
        config.backend.name = name.parse()?;
    }
    if let Some(t) = args.pose_tolerance {
        config.input.pose_tolerance = t;
    }
    // The 3DRef release layout brings its pose file (the ground truth).
    let gt_poses = args.input.pose_file(args.gt_poses.as_deref());
    let mut sequence = args
        .input
        .open(gt_poses.as_ref().map(|p| p.path.as_path()), &config)?;
    let dir = RunDir::claim(&args.out, args.force)?;
    let truth = sequence.poses.clone();
    let origin = truth.as_ref().map(|t| t[0]);
    let wall = std::time::Instant::now();
    let tracked = track_sequence(&sequence, &config, origin)?;
    // The frames kept from tracking are not needed while the back-end
    // solves (its graph grows with the frames): the classification passes
    // keep them again, so the peak is the larger of the two, not their sum.
    sequence = sequence.with_frame_cache(config.input.frame_cache_mb);
    let mut slam = optimize_tracked(tracked, &config)?;
    slam.timings.wall = wall.elapsed();
    let out = dir.path();

    // Poses, map, per-frame report.
    let stamped: Vec<StampedPose> = sequence
        .entries
        .iter()
        .zip(&slam.poses)
        .map(|(f, p)| StampedPose {
            stamp: f.stamp,
            pose: *p,
        })
        .collect();
    io::write_tum(&out.join("poses.txt"), &stamped)?;
    write_trajectory_plot(
        out,
        &slam.poses,
        &slam.tracked_poses,
        truth.as_deref(),
        config.backend.name.as_str(),
    )?;
    let names = sequence.names();
    let records: Vec<_> = slam
        .map
        .landmarks
        .iter()
        .map(|l| l.record(&l.bounded(), &names))
        .collect();
    io::write_planes(&out.join("planes.json"), &records)?;
    let mut csv = String::from(
        "name,planes,frame_matches,frame_inliers,map_matches,inliers,degenerate,degenerate_directions,min_eigenvalue,fallback,fixed_by_points,landmarks,time_ms,interval,gap,jump,turn_deg,implausible_motion,recovered_yaw_deg,points_yaw_deg,loop_candidates,loop_with,loop_correction,loop_resolved\n",
    );
    for (r, t) in slam.reports.iter().zip(&slam.frame_times) {
        writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{:.4},{},{},{},{:.3},{},{},{:.4},{:.2},{},{},{},{},{},{},{}",
            names[r.index],
            r.planes,
            r.frame_matches,
            r.frame_inliers,
            r.map_matches,
            r.inliers,
            r.degenerate_directions(),
            r.degeneracy
                .as_ref()
                .map(|d| d.describe(&r.pose))
                .unwrap_or_default(),
            r.degeneracy
                .as_ref()
                .map_or(f64::NAN, |d| d.min_eigenvalue()),
            r.fallback,
            r.fixed_by_points,
            r.landmarks,
            t.as_secs_f64() * 1e3,
            r.timing
                .interval
                .map(|dt| format!("{dt:.4}"))
                .unwrap_or_default(),
            r.timing.gap,
            r.motion.jump,
            r.motion.turn_deg,
            r.motion.implausible,
            r.recovered_yaw_deg
                .map(|y| format!("{y:.1}"))
                .unwrap_or_default(),
            r.points_yaw_deg
                .map(|y| format!("{y:.1}"))
                .unwrap_or_default(),
            r.loop_candidates,
            r.loop_closure
                .as_ref()
                .map(|l| names[l.with].clone())
                .unwrap_or_default(),
            r.loop_closure
                .as_ref()
                .map(|l| format!("{:.4}", l.check.correction))
                .unwrap_or_default(),
            r.loop_closure.as_ref().is_some_and(|l| l.resolved),
        )?;
    }
    io::write_atomic(&out.join("frames.csv"), |w| {
        std::io::Write::write_all(w, csv.as_bytes())
    })?;
    io::write_atomic(&out.join("config.toml"), |w| {
        std::io::Write::write_all(w, config.to_toml().as_bytes())
    })?;

    if let Some(path) = &args.export_graph {
        slam.graph.write(path)?;
    }
    // The graph grows with the frames and the classification pass does not
    // need it.
    slam.graph = FactorGraph::new();

    // Trajectory error, of the back-end's result and of tracking alone.
    let (trajectory, tracking) = match &truth {
        Some(t) => (
            Some(trajectory_error(&slam.poses, t, config.slam.rpe_segment)?),
            Some(trajectory_error(
                &slam.tracked_poses,
                t,
                config.slam.rpe_segment,
            )?),
        ),
        None => (None, None),
    };
    let degenerate = slam.reports.iter().filter(|r| r.is_degenerate()).count();
    let fallback = slam.reports.iter().filter(|r| r.fallback).count();
    let input = InputReport::new(&slam.reports, &names);
    let loops = LoopSummary::new(&slam.reports, &names, slam.merged_at_end);
    let total: f64 = slam.frame_times.iter().map(|d| d.as_secs_f64()).sum();
    let fps = slam.reports.len() as f64 / total.max(1e-12);

    // Classification with the estimated poses (and, for comparison, with the
    // true ones).
    let mut classification = None;
    let mut reference = None;
    // Counted by the classification pass (`None` with --no-classify).
    let mut dropped_non_finite = None;
    // The calibration of the confidences with the estimated poses.
    let mut reliability = None;
    if !args.no_classify {
        // Predictions are written frame by frame as they are classified.
        let mut writer = RunWriter::new(out, &config, OutputOptions::default())?;
        let estimated =
            classify_with_poses(&mut sequence, slam.poses.clone(), &config, &mut writer)?;
        writer.finish()?;
        dropped_non_finite = Some(estimated.run.dropped_non_finite);
        classification = estimated.run.confusion.map(|c| c.metrics());
        reliability = estimated.run.reliability.map(|r| r.report());
        if classification.is_some() && truth.is_some() {
            let with_truth = run_plane_optimized_into(&sequence, &config, &mut Discard)?;
            reference = with_truth.run.confusion.map(|c| c.metrics());
        }
    }
    let metrics = json!({
        "frames": slam.reports.len(),
        "degenerate_frames": degenerate,
        "fallback_frames": fallback,
        "fallback": input.fallback,
        "input_period": input.period,
        "timestamps": input.stamped,
        "gaps": input.gaps,
        "implausible_motion_frames": input.implausible.len(),
        "implausible_motion": input.implausible,
        "recovered_frames": input.recovered.len(),
        "recovered": input.recovered,
        "loop_closures": loops.entries,
        "loop_closure_count": loops.entries.len(),
        "loop_candidates_verified": loops.verified,
        "merged_landmarks": loops.merged,
        "landmarks": slam.map.landmarks.len(),
        "specular": specular::provenance(),
        "frames_per_cpu_second": fps,
        "trajectory": trajectory,
        "trajectory_tracking_only": tracking,
        "backend": config.backend.name.as_str(),
        "backend_report": slam.backend.as_ref().map(|r| json!({
            "initial_cost": r.initial_cost,
            "final_cost": r.final_cost,
            "iterations": r.iterations,
            "converged": r.converged,
            "seconds": r.total_seconds,
            "poses_with_unconstrained_directions": r.observability.weak.len(),
        })),
        "classification": classification,
        "classification_true_poses": reference,
        "reliability": reliability,
        "dropped_non_finite_points": dropped_non_finite,
    });
    let text = serde_json::to_string_pretty(&metrics).context("serialising metrics")?;
    io::write_atomic(&out.join("metrics.json"), |w| {
        std::io::Write::write_all(w, text.as_bytes())
    })?;

    println!(
        "{} frames: {} landmarks, {} degenerate frames, {} on the motion model alone; {:.1} frames per CPU-second (front end + tracking)",
        slam.reports.len(),
        slam.map.landmarks.len(),
        degenerate,
        fallback,
        fps
    );
    println!(
        "poses.txt, planes.json, frames.csv, metrics.json, trajectory.png in {}",
        args.out.display()
    );
    for line in input.lines() {
        println!("{line}");
    }
    if config.slam.loop_closure.enabled {
        println!("{}", loops.line());
    }
    if let Some(r) = &slam.backend {
        println!(
            "back-end {}: cost {:.6e} -> {:.6e} in {} iterations, {:.1} ms",
            config.backend.name.as_str(),
            r.initial_cost,
            r.final_cost,
            r.iterations,
            r.total_seconds * 1e3
        );
    }
    if let Some(t) = &tracking {
        println!("trajectory, tracking alone: {}", t.summary());
    }
    if let Some(t) = &trajectory {
        println!("trajectory: {}", t.summary());
    }
    if let Some(m) = &classification {
        println!("classification with the estimated poses:");
        print!("{}", m.table());
    }
    if let Some(m) = &reference {
        println!(
            "plane-optimized with the true poses: mIoU {:.2}, accuracy {:.2}",
            m.miou, m.accuracy
        );
    }
    if args.timings {
        let mut t = slam.timings.clone();
        t.frames = slam.reports.len();
        print!("{}", t.table());
    }
    dir.finish()
}

/// The loop closures of a run, for `metrics.json` and the summary.
struct LoopSummary {
    /// One object per closed loop: frame, name, the frame it closes with,
    /// inliers, smallest eigenvalue, correction, whether it re-solved.
    entries: Vec<serde_json::Value>,
    /// Candidates verified over the run (accepted or not).
    verified: usize,
    /// Duplicate landmarks merged (at the closures and before the final
    /// batch).
    merged: usize,
}

impl LoopSummary {
    fn new(
        reports: &[specular::slam::FrameReport],
        names: &[String],
        merged_at_end: usize,
    ) -> Self {
        let entries = reports
            .iter()
            .filter_map(|r| r.loop_closure.as_ref().map(|l| (r, l)))
            .map(|(r, l)| {
                json!({
                    "frame": r.index,
                    "name": names[r.index],
                    "with": l.with,
                    "with_name": names[l.with],
                    "matches": l.check.matches,
                    "inliers": l.check.inliers,
                    "min_eigenvalue": l.check.min_eigenvalue,
                    "correction": l.check.correction,
                    "correction_deg": l.check.correction_deg,
                    "resolved": l.resolved,
                    "merged_landmarks": l.merged,
                })
            })
            .collect();
        let merged = reports
            .iter()
            .filter_map(|r| r.loop_closure.as_ref())
            .map(|l| l.merged)
            .sum::<usize>()
            + merged_at_end;
        Self {
            entries,
            verified: reports.iter().map(|r| r.loop_candidates).sum(),
            merged,
        }
    }

    /// One summary line.
    fn line(&self) -> String {
        let resolved = self
            .entries
            .iter()
            .filter(|e| e["resolved"].as_bool() == Some(true))
            .count();
        let first = self
            .entries
            .first()
            .map(|e| {
                format!(
                    " (first at frame {} with frame {}, correction {:.3} m)",
                    e["name"].as_str().unwrap_or_default(),
                    e["with_name"].as_str().unwrap_or_default(),
                    e["correction"].as_f64().unwrap_or(f64::NAN)
                )
            })
            .unwrap_or_default();
        format!(
            "loop closure: {} loop{} closed of {} candidates verified{first}, {resolved} re-solve{} during tracking, {} duplicate landmark{} merged",
            self.entries.len(),
            if self.entries.len() == 1 { "" } else { "s" },
            self.verified,
            if resolved == 1 { "" } else { "s" },
            self.merged,
            if self.merged == 1 { "" } else { "s" },
        )
    }
}

/// `OUT/trajectory.png`: the back-end's poses and tracking's alone, over the
/// ground truth when given (drawn as they are, without the SE(3) alignment
/// of the ATE: the estimate starts at the true first pose).
fn write_trajectory_plot(
    out: &std::path::Path,
    estimated: &[Isometry3<f64>],
    tracked: &[Isometry3<f64>],
    truth: Option<&[Isometry3<f64>]>,
    backend: &str,
) -> Result<()> {
    let xy = |poses: &[Isometry3<f64>]| -> Vec<[f64; 2]> {
        poses
            .iter()
            .map(|p| [p.translation.vector.x, p.translation.vector.y])
            .collect()
    };
    let mut series = Vec::new();
    if let Some(t) = truth {
        series.push(TrajectorySeries {
            name: "ground truth".into(),
            colour: [170, 170, 170],
            width: 7,
            points: xy(t),
        });
    }
    series.push(TrajectorySeries {
        name: "tracking alone".into(),
        colour: [30, 90, 255],
        width: 2,
        points: xy(tracked),
    });
    series.push(TrajectorySeries {
        name: format!("estimated (back-end {backend})"),
        colour: [220, 30, 30],
        width: 2,
        points: xy(estimated),
    });
    let caption = if truth.is_some() {
        "SLAM trajectory over the ground truth (top-down, not aligned)"
    } else {
        "SLAM trajectory (top-down, first pose at the origin)"
    };
    plots::trajectory_png(&out.join("trajectory.png"), caption, &series)?;
    Ok(())
}

/// What the input's timing and the tracker's failures were, for the
/// summary and `metrics.json`: a gap, a failed registration or an
/// implausible motion is reported, never silent.
struct InputReport {
    /// Whether every frame had a timestamp.
    stamped: bool,
    /// The median interval between frames, s.
    period: Option<f64>,
    /// Frames after a gap: name, index, seconds since the previous frame.
    gaps: Vec<serde_json::Value>,
    /// Frames posed by the motion model alone (registration failed).
    fallback: Vec<String>,
    /// Frames whose frame-to-frame registration was found by the heading
    /// search: name, index, degrees from the prediction.
    recovered: Vec<serde_json::Value>,
    /// Frames whose pose jumped from the extrapolation of the poses
    /// before it: name, index, distance and angle.
    implausible: Vec<serde_json::Value>,
}

impl InputReport {
    fn new(reports: &[specular::slam::FrameReport], names: &[String]) -> Self {
        let mut intervals: Vec<f64> = reports
            .iter()
            .filter_map(|r| r.timing.interval)
            .filter(|dt| *dt > 0.0)
            .collect();
        intervals.sort_by(f64::total_cmp);
        let name =
            |r: &specular::slam::FrameReport| names.get(r.index).cloned().unwrap_or_default();
        Self {
            stamped: reports.iter().all(|r| r.stamp.is_some()),
            period: intervals.get(intervals.len() / 2).copied(),
            gaps: reports
                .iter()
                .filter(|r| r.timing.gap)
                .map(|r| {
                    json!({
                        "frame": name(r),
                        "index": r.index,
                        "seconds": r.timing.interval,
                        "usual_interval": r.timing.period,
                    })
                })
                .collect(),
            fallback: reports.iter().filter(|r| r.fallback).map(name).collect(),
            recovered: reports
                .iter()
                .filter_map(|r| {
                    r.recovered_yaw_deg.map(|yaw| {
                        json!({
                            "frame": name(r),
                            "index": r.index,
                            "yaw_deg": yaw,
                        })
                    })
                })
                .collect(),
            implausible: reports
                .iter()
                .filter(|r| r.motion.implausible)
                .map(|r| {
                    json!({
                        "frame": name(r),
                        "index": r.index,
                        "jump": r.motion.jump,
                        "turn_deg": r.motion.turn_deg,
                    })
                })
                .collect(),
        }
    }

    /// The summary's lines about the input and the tracker's failures.
    fn lines(&self) -> Vec<String> {
        let mut out = Vec::new();
        match self.period {
            _ if !self.stamped => out.push(
                "input: no timestamps reached the tracker: every interval taken as [slam.motion] frame_period, gaps not detected".into(),
            ),
            Some(p) => out.push(format!(
                "input: {:.1} Hz (median interval {:.3} s), {} gap{}",
                1.0 / p,
                p,
                self.gaps.len(),
                if self.gaps.len() == 1 { "" } else { "s" }
            )),
            None => out.push("input: no interval between frames (one frame)".into()),
        }
        let list = |v: &[String]| {
            let shown: Vec<&str> = v.iter().take(5).map(String::as_str).collect();
            let more = v.len().saturating_sub(shown.len());
            if more > 0 {
                format!("{} and {more} more", shown.join(", "))
            } else {
                shown.join(", ")
            }
        };
        for g in &self.gaps {
            out.push(format!(
                "warning: gap of {:.2} s (usual {:.3} s) before frame {}",
                g["seconds"].as_f64().unwrap_or(f64::NAN),
                g["usual_interval"].as_f64().unwrap_or(f64::NAN),
                g["frame"].as_str().unwrap_or("?")
            ));
        }
        if !self.fallback.is_empty() {
            out.push(format!(
                "warning: registration failed on {} frame{}, posed by the motion model alone: {}",
                self.fallback.len(),
                if self.fallback.len() == 1 { "" } else { "s" },
                list(&self.fallback)
            ));
        }
        if !self.recovered.is_empty() {
            let names: Vec<String> = self
                .recovered
                .iter()
                .map(|v| {
                    format!(
                        "{} ({:+.0} deg)",
                        v["frame"].as_str().unwrap_or("?"),
                        v["yaw_deg"].as_f64().unwrap_or(f64::NAN)
                    )
                })
                .collect();
            out.push(format!(
                "note: frame-to-frame registration failed at the predicted heading and was found by the heading search on {} frame{}: {}",
                names.len(),
                if names.len() == 1 { "" } else { "s" },
                list(&names)
            ));
        }
        if !self.implausible.is_empty() {
            let names: Vec<String> = self
                .implausible
                .iter()
                .map(|v| v["frame"].as_str().unwrap_or("?").to_string())
                .collect();
            out.push(format!(
                "warning: implausible motion (a jump past slam::motion::IMPLAUSIBLE_JUMP m or IMPLAUSIBLE_TURN_DEG deg) on {} frame{}: {}",
                names.len(),
                if names.len() == 1 { "" } else { "s" },
                list(&names)
            ));
        }
        out
    }
}
