//! `specular simulate`: write a simulated 3DRef-style sequence (frames,
//! true poses, true reflective planes) from a scene.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use specular::io::{self, PlyEncoding};
use specular::sim::{
    self, family, LabelCounts, PlaneTally, SceneChanges, SceneSource, Simulator, TruePlanes,
};

use super::input::LabelsArg;

/// The sensor frames are read as when they do not name one (the
/// configurations' `sensor`, the 3DRef QT64).
const DEFAULT_SENSOR: &str = "pandar_qt64";

/// Arguments of `simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Scene: a TOML file or a built-in name (demo, office, corridor,
    /// mirror-room, lobby, glass-loop, two-panes).
    #[arg(long, required_unless_present_any = ["family", "list_families"], conflicts_with = "family")]
    pub scene: Option<String>,
    /// A scene family instead: the scene drawn for `--seed` (0-999 the
    /// development split, from 1000000 held out); its scene file is
    /// written as OUT/scene.toml.
    #[arg(long)]
    pub family: Option<String>,
    /// Print the scene families, one a line, and exit.
    #[arg(long)]
    pub list_families: bool,
    /// Output directory: OUT/frames/<timestamp>.ply, OUT/poses.txt,
    /// OUT/planes.json. Optional with --stats (then nothing is written).
    #[arg(long, required_unless_present_any = ["stats", "list_families"])]
    pub out: Option<PathBuf>,
    /// Number of frames (default: the scene's, i.e. its trajectory once).
    #[arg(long)]
    pub frames: Option<usize>,
    /// Seed of the range noise (default: the scene's); with `--family`,
    /// the family's seed (default 0), which draws the scene and its noise.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Which truth the labels carry: 3DRef's ray-cast rule (as the real
    /// data is labelled) or the echo's physical path.
    #[arg(long, value_enum, default_value_t = LabelsArg::Raycast3dref)]
    pub labels: LabelsArg,
    /// Write ascii PLY (as the real 3DRef files) instead of binary.
    #[arg(long)]
    pub ascii: bool,
    /// Print the label shares of the sequence as a Markdown table (the
    /// table of datasets/README.md).
    #[arg(long)]
    pub stats: bool,
    /// Simulate with this sensor instead of the scene's: a built-in model
    /// (ouster-os0-128, ouster-os0-128:2048, livox-avia, pandar_qt64,
    /// velodyne_hdl32e) or a sensor TOML. The frames name it in their
    /// header (`comment sensor NAME`) and OUT/scene.toml is the scene as
    /// simulated, so `detect` and `slam` read them as its.
    #[arg(long)]
    pub sensor: Option<String>,
    /// Motion distortion: fire each frame's beams over the sensor's period
    /// (`1 / rate_hz` of its model) while it moves, each point in the
    /// sensor frame of its own firing time with its time written (PLY
    /// property `time`, seconds after the frame's stamp). A frame's stamp
    /// and its pose in OUT/poses.txt are its sweep's start. Off, every
    /// beam of a frame is fired at its stamp.
    #[arg(long)]
    pub sweep: bool,
    /// Walk the scene's path at this speed, m/s, instead of its own.
    #[arg(long)]
    pub speed: Option<f64>,
    /// Turn the sensor about its vertical axis at this rate, deg/s, on
    /// top of the path's heading (e.g. `--sweep --speed 1 --turn-rate 45`:
    /// walks at 1 m/s, turns at 45 deg/s).
    #[arg(long)]
    pub turn_rate: Option<f64>,
}

/// Run `simulate`.
pub fn run(args: SimulateArgs) -> Result<()> {
    if args.list_families {
        for f in family::FAMILIES {
            println!("{}", f.name());
        }
        return Ok(());
    }
    let source = match (&args.scene, &args.family) {
        (Some(name), _) => SceneSource::Named(name.clone()),
        (None, Some(name)) => SceneSource::Family {
            family: name.clone(),
            seed: args.seed.unwrap_or(0),
        },
        (None, None) => anyhow::bail!("give --scene NAME or --family NAME"),
    };
    let changes = SceneChanges {
        sensor: args.sensor.clone(),
        sweep: args.sweep,
        speed: args.speed,
        turn_rate_deg: args.turn_rate,
    };
    let (scene, scene_file) = source.resolve_with(&changes)?;
    // A family's seed draws its scene and its noise.
    let seed = match &source {
        SceneSource::Named(_) => args.seed.unwrap_or(scene.seed),
        SceneSource::Family { .. } => scene.seed,
    };
    // Frames of the 3DRef sensor say nothing, as 3DRef's own (and as
    // before: their bytes do not change); any other sensor is named.
    let sensor_name = scene.sensor.model.name.clone();
    let sensor_comment = (sensor_name != DEFAULT_SENSOR).then_some(sensor_name.as_str());
    let n = args.frames.unwrap_or(scene.frames);
    sim::check_frames(n)?;
    let sim = Simulator::new(&scene).with_label_rule(args.labels.into());
    let names: Vec<String> = (0..n).map(|k| sim.stamp(k).0).collect();
    let frames_dir = args.out.as_ref().map(|o| o.join("frames"));
    if let Some(dir) = &frames_dir {
        super::run_dir::refuse_other_frames(dir, &names)?;
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    // Marked incomplete until written; Ctrl-C / SIGTERM cleans up (exit 130).
    let guard = match (&args.out, &frames_dir) {
        (Some(out), Some(dir)) => Some(super::run_dir::OutputGuard::new(
            out,
            std::slice::from_ref(dir),
        )?),
        _ => None,
    };
    let encoding = if args.ascii {
        PlyEncoding::Ascii
    } else {
        PlyEncoding::BinaryLittleEndian
    };

    let planes = TruePlanes::of(&scene);
    let bar = progress_bar(n as u64);
    let started = Instant::now();
    // Each frame depends only on (scene, k, seed): any order, same bytes.
    let (counts, tally) = (0..n)
        .into_par_iter()
        .map(|k| -> specular::Result<(LabelCounts, PlaneTally)> {
            let f = sim.frame(k, seed);
            if super::run_dir::interrupted() {
                return Err(specular::Error::Input("interrupted".into()));
            }
            if let Some(dir) = &frames_dir {
                let path = dir.join(format!("{}.ply", names[k]));
                io::write_frame_of(&path, &f.frame, encoding, sensor_comment)?;
            }
            let mut tally = PlaneTally::default();
            tally.add(k, &planes.observed_in(&f));
            bar.inc(1);
            Ok((LabelCounts::of(&f.frame), tally))
        })
        .try_reduce(
            || (LabelCounts::default(), PlaneTally::default()),
            |a, b| Ok((a.0.merge(b.0), a.1.merge(b.1))),
        )?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    let records = planes.records(&scene, &tally, |k| names[k].clone());

    if let Some(out) = &args.out {
        let poses: Vec<_> = (0..n).map(|k| sim.pose(k)).collect();
        io::write_tum(&out.join("poses.txt"), &poses)?;
        io::write_planes(&out.join("planes.json"), &records)?;
        if let Some(text) = &scene_file {
            let path = out.join("scene.toml");
            std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        }
    }
    if let Some(guard) = guard {
        guard.finish()?;
    }
    println!(
        "simulated '{}' with {sensor_name}: {n} frames ({:.0} points/frame, {:.1} frames/s), {} reflective planes{}",
        scene.name,
        counts.points as f64 / n as f64,
        n as f64 / elapsed.max(1e-9),
        records.len(),
        match &args.out {
            Some(out) => format!(" -> {}", out.display()),
            None => String::new(),
        }
    );
    if args.stats {
        println!("{}", LabelCounts::table_header());
        println!("{}", counts.table_row(&scene.name));
    }
    Ok(())
}

/// A progress bar on stderr, hidden when stderr is not a terminal or with
/// `--quiet`.
fn progress_bar(len: u64) -> ProgressBar {
    let bar = ProgressBar::new(len);
    if specular::progress::enabled() {
        if let Ok(style) =
            ProgressStyle::with_template("{bar:40} {pos}/{len} frames, {per_sec}, eta {eta}")
        {
            bar.set_style(style);
        }
    } else {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar
}
