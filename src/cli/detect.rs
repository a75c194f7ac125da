//! `specular detect`: classify a frame directory and write predictions.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Args;
use specular::config::{Config, Method};
use specular::pipeline::{
    run_plane_optimized_into, run_single_scan_into, PlaneOptimizedOutput, RunOutput, Sequence,
};

use super::input::InputArgs;
use super::output::{predicted_counts, write_summaries, OutputOptions, RunWriter};
use super::run_dir::RunDir;
use super::visual::{write_visual, VisualOptions};
use super::{load_config, MethodArg};

/// Arguments of `detect`.
#[derive(Args, Debug)]
pub struct DetectArgs {
    /// The frames: `--frames DIR` or `--bag PATH --topic NAME`.
    #[command(flatten)]
    pub input: InputArgs,
    /// Pose file (`T_world_sensor`): TUM, matched by timestamp (and
    /// interpolated between neighbours within `input.pose_interpolation_gap`),
    /// or KITTI (12 numbers a line), one per frame in order.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Seconds between a frame and the nearest pose that still match
    /// (overrides `input.pose_tolerance`).
    #[arg(long)]
    pub pose_tolerance: Option<f64>,
    /// Output directory (predictions/, metrics.json, config.toml).
    #[arg(long)]
    pub out: PathBuf,
    /// Method; defaults to the configuration's `method`.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Configuration: built-in name (default, paper) or a TOML file of
    /// changes, layered over the default (or `extends = "paper"`).
    #[arg(long, default_value = "default")]
    pub config: String,
    /// Print milliseconds per frame for every stage.
    #[arg(long)]
    pub timings: bool,
    /// Do not write the Foxglove recording `run.mcap`.
    #[arg(long)]
    pub no_mcap: bool,
    /// Write only the results (predictions, metrics, planes.json,
    /// around_corner.ply): no map.ply, recording, plots or report.
    #[arg(long)]
    pub lean: bool,
    /// Also write, beside each `predictions/FRAME.label`, `FRAME.rule`: the
    /// id of the rule that decided each point (see `specular::classify::Rule`;
    /// same format as the labels), to see why a point got its class.
    #[arg(long)]
    pub rules: bool,
    /// Replace the outputs of an earlier run in `--out` (a directory holding
    /// anything else is still refused).
    #[arg(long)]
    pub force: bool,
}

/// Run `detect`.
pub fn run(args: DetectArgs) -> Result<()> {
    let mut config = load_config(&args.config)?;
    args.input.apply_sensor(&mut config)?;
    if let Some(m) = args.method {
        config.method = m.into();
    }
    if let Some(t) = args.pose_tolerance {
        config.input.pose_tolerance = t;
    }
    let wall = std::time::Instant::now();
    let poses = args.input.pose_file(args.poses.as_deref());
    if config.method == Method::PlaneOptimized && poses.is_none() && !args.input.has_own_poses() {
        bail!("the plane-optimized method needs poses: add --poses FILE (or use --method single-scan)");
    }
    if let Some(p) = poses.as_ref().filter(|p| p.from_release) {
        println!("poses: {} (3DRef release layout)", p.path.display());
    }
    let input = args.input.path();
    let sequence = args
        .input
        .open(poses.as_ref().map(|p| p.path.as_path()), &config)?;
    let visual = (!args.lean).then(|| VisualOptions {
        mcap: !args.no_mcap,
        title: format!("specular detect: {}", input.display()),
    });
    let dir = RunDir::claim(&args.out, args.force)?;
    let result = detect_into(dir.path(), &sequence, &config, visual.as_ref(), args.rules)?;
    dir.finish()?;
    let mut timings = result.run.timings.clone();
    timings.wall = wall.elapsed();
    println!(
        "{} frames, method {}: predictions in {}",
        sequence.len(),
        config.method.name(),
        args.out.join("predictions").display()
    );
    if result.run.dropped_non_finite > 0 {
        println!(
            "{} input points dropped: a coordinate or the intensity was NaN or infinite",
            result.run.dropped_non_finite
        );
    }
    if let Some(map) = &result.map {
        println!(
            "plane map: {} landmarks, {} used ({}); planes.json, around_corner.ply",
            map.map.landmarks.len(),
            map.used.len(),
            config.map.selection()
        );
        for line in map.ghost_lines() {
            println!("{line}");
        }
    }
    if let Some(conf) = &result.run.confusion {
        print!("{}", conf.metrics().table());
        if let Some(r) = result.run.reliability.map(|r| r.report()) {
            println!(
                "confidence: expected calibration error {:.3} over {} points; {} points at >= 0.9, {:.1}% of them correct",
                r.ece,
                r.points,
                r.confident_points,
                100.0 * r.confident_accuracy
            );
        }
    } else {
        let counts: Vec<String> = predicted_counts(&result.run)
            .into_iter()
            .map(|(class, n)| format!("{class} {n}"))
            .collect();
        println!(
            "points predicted (no labels to score): {}",
            counts.join(", ")
        );
    }
    if args.timings {
        print!("{}", timings.table());
    }
    if !args.lean {
        println!("report: {}", args.out.join("report.md").display());
    }
    Ok(())
}

/// A finished `detect` run.
pub(crate) struct Detected {
    /// Scores and timings (no per-frame classes: they were written).
    pub run: RunOutput,
    /// The plane map, for the plane-optimized method.
    pub map: Option<PlaneOptimizedOutput>,
}

/// Run the configured method over `sequence` and write every output into
/// `out` as the frames are classified (the report and plots too, with
/// `visual`). A run that fails leaves no output behind.
pub(crate) fn detect_into(
    out: &Path,
    sequence: &Sequence,
    config: &Config,
    visual: Option<&VisualOptions>,
    rules: bool,
) -> Result<Detected> {
    let map_method = config.method == Method::PlaneOptimized;
    let options = OutputOptions {
        around_corner: map_method,
        visual: visual.is_some() && sequence.poses.is_some(),
        mcap: visual.is_some_and(|v| v.mcap),
        rules,
    };
    let mut writer = RunWriter::new(out, config, options)?;
    let (mut run, map) = match config.method {
        Method::SingleScan => (run_single_scan_into(sequence, config, &mut writer)?, None),
        Method::PlaneOptimized => {
            let out = run_plane_optimized_into(sequence, config, &mut writer)?;
            (out.run.clone(), Some(out))
        }
    };
    let start = std::time::Instant::now();
    let written = writer.finish()?;
    let names = sequence.names();
    write_summaries(out, config, &names, &run, map.as_ref(), &written)?;
    if let Some(visual) = visual {
        write_visual(
            out,
            config,
            sequence.len(),
            &run,
            map.as_ref(),
            &written,
            visual,
        )?;
    }
    run.timings.add("write outputs", start.elapsed());
    Ok(Detected { run, map })
}
