//! `specular detect`: classify a frame directory and write predictions.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use specular::config::{Config, Method};
use specular::io;
use specular::pipeline::{run_single_scan, RunOutput, Sequence, StageTimings};

use super::{load_config, MethodArg};

/// Arguments of `detect`.
#[derive(Args, Debug)]
pub struct DetectArgs {
    /// Directory of 3DRef frames (`<timestamp>.ply`).
    #[arg(long)]
    pub frames: PathBuf,
    /// TUM pose file (`T_world_sensor`); frames are matched by timestamp.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Output directory (predictions/, metrics.json, config.toml).
    #[arg(long)]
    pub out: PathBuf,
    /// Method; defaults to the configuration's `method`.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Configuration: built-in name (default, paper) or TOML file.
    #[arg(long, default_value = "default")]
    pub config: String,
    /// Print milliseconds per frame for every stage.
    #[arg(long)]
    pub timings: bool,
}

/// Run `detect`.
pub fn run(args: DetectArgs) -> Result<()> {
    let mut config = load_config(&args.config)?;
    if let Some(m) = args.method {
        config.method = m.into();
    }
    let (sequence, output) = detect(&args.frames, args.poses.as_deref(), &config)?;
    write_outputs(&args.out, &config, &sequence, &output)?;
    println!(
        "{} frames, method {}: predictions in {}",
        sequence.len(),
        config.method.name(),
        args.out.join("predictions").display()
    );
    if let Some(conf) = output.confusion(&sequence) {
        print!("{}", conf.metrics().table());
    }
    if args.timings {
        print!("{}", output.timings.table());
    }
    Ok(())
}

/// Load a sequence and run the configured method on it.
pub(crate) fn detect(
    frames: &Path,
    poses: Option<&Path>,
    config: &Config,
) -> Result<(Sequence, RunOutput)> {
    let mut timings = StageTimings::default();
    let wall = std::time::Instant::now();
    let sequence = Sequence::load(frames, poses, config.input.pose_tolerance, &mut timings)?;
    let mut output = match config.method {
        Method::SingleScan => run_single_scan(&sequence, config)?,
        Method::PlaneOptimized => {
            bail!("method plane-optimized is not available yet; use --method single-scan")
        }
    };
    timings.merge(&output.timings);
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    output.timings = timings;
    Ok((sequence, output))
}

/// Write predictions, metrics (when labelled) and the configuration used.
pub(crate) fn write_outputs(
    out: &Path,
    config: &Config,
    sequence: &Sequence,
    output: &RunOutput,
) -> Result<()> {
    let pred_dir = out.join("predictions");
    for f in &output.frames {
        let ids: Vec<u8> = f.classes.iter().map(|c| c.id()).collect();
        io::write_labels(&pred_dir.join(format!("{}.label", f.name)), &ids)?;
    }
    io::write_atomic(&out.join("config.toml"), |w| {
        std::io::Write::write_all(w, config.to_toml().as_bytes())
    })?;
    if let Some(conf) = output.confusion(sequence) {
        let json = serde_json::to_string_pretty(&conf.metrics()).context("serialising metrics")?;
        io::write_atomic(&out.join("metrics.json"), |w| {
            std::io::Write::write_all(w, json.as_bytes())
        })?;
    }
    Ok(())
}
