//! `specular detect`: classify a frame directory and write predictions.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use clap::Args;
use specular::classify::Class;
use specular::config::{Config, Method};
use specular::eval::Confusion;
use specular::io;
use specular::pipeline::plane_optimized::around_corner_map;
use specular::pipeline::{
    run_plane_optimized, run_single_scan, PlaneOptimizedOutput, RunOutput, Sequence, StageTimings,
};
use specular::reflect::BoundedPlane;

use super::visual::{write_visual, VisualOptions};
use super::{load_config, MethodArg};

/// Arguments of `detect`.
#[derive(Args, Debug)]
pub struct DetectArgs {
    /// Directory of 3DRef frames (`<timestamp>.ply`).
    #[arg(long, required_unless_present = "bag")]
    pub frames: Option<PathBuf>,
    /// ROS 2 bag (`.mcap`) of `sensor_msgs/msg/PointCloud2` frames, instead
    /// of `--frames`.
    #[arg(long, conflicts_with = "frames", requires = "topic")]
    pub bag: Option<PathBuf>,
    /// The bag's point-cloud topic.
    #[arg(long)]
    pub topic: Option<String>,
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
    /// Do not write the Foxglove recording `run.mcap`.
    #[arg(long)]
    pub no_mcap: bool,
    /// Write only the results (predictions, metrics, planes.json,
    /// around_corner.ply): no map.ply, recording, plots or report.
    #[arg(long)]
    pub lean: bool,
}

/// Run `detect`.
pub fn run(args: DetectArgs) -> Result<()> {
    let mut config = load_config(&args.config)?;
    if let Some(m) = args.method {
        config.method = m.into();
    }
    let (input, (sequence, mut output, map)) = match (&args.frames, &args.bag) {
        (Some(frames), _) => (frames, detect(frames, args.poses.as_deref(), &config)?),
        (None, Some(bag)) => {
            let topic = args.topic.as_deref().unwrap_or_default();
            (bag, detect_bag(bag, topic, args.poses.as_deref(), &config)?)
        }
        (None, None) => bail!("give --frames DIR or --bag FILE --topic NAME"),
    };
    let start = std::time::Instant::now();
    let confusion = write_outputs(&args.out, &config, &sequence, &output, map.as_ref())?;
    if !args.lean {
        let visual = VisualOptions {
            mcap: !args.no_mcap,
            title: format!("specular detect: {}", input.display()),
        };
        write_visual(
            &args.out,
            &config,
            &sequence,
            &output,
            map.as_ref(),
            &visual,
        )?;
    }
    output.timings.add("write outputs", start.elapsed());
    output.timings.wall += start.elapsed();
    println!(
        "{} frames, method {}: predictions in {}",
        sequence.len(),
        config.method.name(),
        args.out.join("predictions").display()
    );
    if let Some(map) = &map {
        println!(
            "plane map: {} landmarks, {} used ({}); planes.json, around_corner.ply",
            map.map.landmarks.len(),
            map.used.len(),
            config.map.selection()
        );
    }
    if let Some(conf) = confusion {
        print!("{}", conf.metrics().table());
    }
    if args.timings {
        print!("{}", output.timings.table());
    }
    if !args.lean {
        println!("report: {}", args.out.join("report.md").display());
    }
    Ok(())
}

/// Load a sequence and run the configured method on it; the plane-optimized
/// method also returns its map.
pub(crate) fn detect(
    frames: &Path,
    poses: Option<&Path>,
    config: &Config,
) -> Result<(Sequence, RunOutput, Option<PlaneOptimizedOutput>)> {
    let mut timings = StageTimings::default();
    let wall = std::time::Instant::now();
    if config.method == Method::PlaneOptimized && poses.is_none() {
        bail!("the plane-optimized method needs poses: add --poses FILE (or use --method single-scan)");
    }
    let sequence = Sequence::load(frames, poses, config.input.pose_tolerance, &mut timings)?;
    let (mut output, map) = run_method(&sequence, config)?;
    timings.merge(&output.timings);
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    output.timings = timings;
    Ok((sequence, output, map))
}

/// Like [`detect`], from the point clouds on `topic` of a ROS 2 bag.
pub(crate) fn detect_bag(
    bag: &Path,
    topic: &str,
    poses: Option<&Path>,
    config: &Config,
) -> Result<(Sequence, RunOutput, Option<PlaneOptimizedOutput>)> {
    let wall = std::time::Instant::now();
    if config.method == Method::PlaneOptimized && poses.is_none() {
        bail!("the plane-optimized method needs poses: add --poses FILE (or use --method single-scan)");
    }
    let frames = io::read_bag_frames(bag, topic)?;
    let mut sequence = Sequence::from_frames(frames, None, &bag.display().to_string())?;
    if let Some(path) = poses {
        let stamped = io::read_tum(path)?;
        sequence.poses = Some(io::match_poses(
            &sequence.entries,
            &stamped,
            config.input.pose_tolerance,
            path,
        )?);
    }
    let (mut output, map) = run_method(&sequence, config)?;
    output.timings.wall = wall.elapsed();
    Ok((sequence, output, map))
}

/// Run the configured method on a loaded sequence.
pub(crate) fn run_method(
    sequence: &Sequence,
    config: &Config,
) -> Result<(RunOutput, Option<PlaneOptimizedOutput>)> {
    Ok(match config.method {
        Method::SingleScan => (run_single_scan(sequence, config)?, None),
        Method::PlaneOptimized => {
            let out = run_plane_optimized(sequence, config)?;
            (out.run.clone(), Some(out))
        }
    })
}

/// Write predictions, metrics (when labelled), the configuration used and,
/// with a plane map, `planes.json` and `around_corner.ply`. Returns the
/// confusion counts when the frames are labelled.
pub(crate) fn write_outputs(
    out: &Path,
    config: &Config,
    sequence: &Sequence,
    output: &RunOutput,
    map: Option<&PlaneOptimizedOutput>,
) -> Result<Option<Confusion>> {
    let pred_dir = out.join("predictions");
    for f in &output.frames {
        let ids: Vec<u8> = f.classes.iter().map(|c| c.id()).collect();
        io::write_labels(&pred_dir.join(format!("{}.label", f.name)), &ids)?;
    }
    io::write_atomic(&out.join("config.toml"), |w| {
        std::io::Write::write_all(w, config.to_toml().as_bytes())
    })?;
    if let Some(map) = map {
        let names: Vec<String> = sequence.frames.iter().map(|f| f.name.clone()).collect();
        let records: Vec<_> = map
            .used
            .iter()
            .zip(&map.planes)
            .map(|(&i, bp)| map.map.landmarks[i].record(bp, &names))
            .collect();
        io::write_planes(&out.join("planes.json"), &records)?;
        let planes: &[BoundedPlane] = &map.planes;
        let classes: Vec<Vec<Class>> = output.frames.iter().map(|f| f.classes.clone()).collect();
        let points = around_corner_map(
            sequence,
            &classes,
            planes,
            config.plane_map.hull_margin,
            config.output.map_voxel,
        );
        io::write_map_ply(&out.join("around_corner.ply"), &points)?;
    }
    let confusion = output.confusion(sequence);
    if let Some(conf) = &confusion {
        // The scores, and which rule decided how many points of each label.
        let mut value = serde_json::to_value(conf.metrics()).context("serialising metrics")?;
        if let Some(obj) = value.as_object_mut() {
            obj.insert(
                "rules".into(),
                serde_json::to_value(output.rule_tally(sequence)).context("serialising rules")?,
            );
        }
        let json = serde_json::to_string_pretty(&value).context("serialising metrics")?;
        io::write_atomic(&out.join("metrics.json"), |w| {
            std::io::Write::write_all(w, json.as_bytes())
        })?;
    }
    Ok(confusion)
}
