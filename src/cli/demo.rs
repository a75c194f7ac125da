//! `specular demo`: the main job on built-in data, no files needed.
//!
//! 1. Simulate the built-in `demo` scene (a room with a window and a mirror)
//!    in memory and run the plane-optimized pipeline with its true poses.
//! 2. Run the same pipeline on the bundled real 3DRef sample.
//!
//! Both are scored against their labels; outputs (predictions, maps, plots,
//! `run.mcap`, `report.md`) go to `OUT/sim` and
//! `OUT/real`, with an index in `OUT/report.md`.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use specular::config::Method;
use specular::pipeline::Sequence;
use specular::sim::{self, Scene};

use super::detect::{detect_into, Detected};
use super::input::{InputArgs, LabelsArg};
use super::run_dir::RunDir;
use super::visual::{write_index, VisualOptions};
use super::{bundled_sample, load_config};

/// Arguments of `demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "runs/demo")]
    pub out: PathBuf,
    /// Configuration: built-in name (default, paper) or a TOML file of
    /// changes, layered over the default (or `extends = "paper"`).
    #[arg(long, default_value = "default")]
    pub config: String,
    /// Built-in scene name or scene TOML to simulate.
    #[arg(long, default_value = "demo")]
    pub scene: String,
    /// Do not write the Foxglove recordings `run.mcap`.
    #[arg(long)]
    pub no_mcap: bool,
    /// Write into `--out` even when it holds files the demo would replace
    /// that an earlier demo did not write (e.g. a `report.md` of your own).
    #[arg(long)]
    pub force: bool,
}

/// Refuse an `--out` holding something the demo would overwrite that is
/// not an earlier demo's (its index `report.md` starts with the demo's
/// title; `sim/` and `real/` are checked as run directories when claimed).
fn check_demo_out(out: &std::path::Path, force: bool) -> Result<()> {
    if force {
        return Ok(());
    }
    let index = out.join("report.md");
    if index.exists() {
        let head = std::fs::read(&index).unwrap_or_default();
        if !head.starts_with(b"# specular demo\n") {
            anyhow::bail!(
                "--out {}: {} is not an earlier demo's index and would be overwritten; give another directory or --force",
                out.display(),
                index.display()
            );
        }
    }
    for part in ["sim", "real"] {
        let p = out.join(part);
        if p.exists() && !p.is_dir() {
            anyhow::bail!(
                "--out {}: {} is a file, where the demo writes a directory; give another directory",
                out.display(),
                p.display()
            );
        }
    }
    Ok(())
}

/// Run the demo.
pub fn run(args: DemoArgs) -> Result<()> {
    let mut config = load_config(&args.config)?;
    config.method = Method::PlaneOptimized;
    check_demo_out(&args.out, args.force)?;

    // 1. Simulated sequence.
    let start = Instant::now();
    let scene = Scene::resolve(&args.scene)?;
    let simulation = sim::simulate(&scene, None, None)?;
    let sim_time = start.elapsed();
    let poses = simulation.poses.iter().map(|p| p.pose).collect();
    let sequence = Sequence::from_frames(
        simulation.frames,
        Some(poses),
        &format!("simulated:{}", args.scene),
    )?;
    config.sensor = scene.sensor.model.name.clone();
    let sim_out = args.out.join("sim");
    let sim_title = format!("specular demo: simulated scene '{}'", args.scene);
    // The demo writes into its own directory: an earlier demo's outputs
    // are replaced.
    let sim_dir = RunDir::claim(&sim_out, true)?;
    let Detected { run, map } = detect_into(
        sim_dir.path(),
        &sequence,
        &config,
        Some(&visual(&args, sim_title.clone())),
        false,
    )
    .context("plane-optimized on the simulated scene")?;
    sim_dir.finish()?;
    let confusion = run.confusion;
    println!(
        "specular demo 1/2: simulated scene '{}' ({} frames, simulated in {:.1} s), plane-optimized with true poses",
        args.scene,
        sequence.len(),
        sim_time.as_secs_f64()
    );
    if let Some(conf) = confusion {
        print!("{}", conf.metrics().table());
    }
    if let Some(map) = &map {
        println!("  reflective landmarks used: {}", map.used.len());
    }
    print_outputs(&sim_out, args.no_mcap);

    // 2. Real sample.
    let mut config = load_config(&args.config)?;
    config.method = Method::PlaneOptimized;
    let sample = bundled_sample();
    let real_out = args.out.join("real");
    let real_title = "specular demo: bundled 3DRef sample".to_string();
    let frames = InputArgs {
        frames: Some(sample.join("frames")),
        bag: None,
        topic: None,
        driver: None,
        second_topic: None,
        scene: None,
        family: None,
        scene_frames: None,
        seed: None,
        labels: LabelsArg::Raycast3dref,
        sensor: None,
        no_deskew: false,
    };
    let sequence = frames.open(Some(&sample.join("poses.txt")), &config)?;
    let real_dir = RunDir::claim(&real_out, true)?;
    let Detected { run, .. } = detect_into(
        real_dir.path(),
        &sequence,
        &config,
        Some(&visual(&args, real_title.clone())),
        false,
    )
    .with_context(|| format!("running the demo on {}", sample.display()))?;
    real_dir.finish()?;
    let confusion = run.confusion;
    println!(
        "\nspecular demo 2/2: {} real 3DRef frames ({}), plane-optimized",
        sequence.len(),
        sample.display()
    );
    if let Some(conf) = confusion {
        print!("{}", conf.metrics().table());
    }
    print_outputs(&real_out, args.no_mcap);
    let parts = [(sim_title, "sim"), (real_title, "real")];
    write_index(&args.out, "specular demo", &parts, !args.no_mcap)?;
    println!("\nindex: {}", args.out.join("report.md").display());
    Ok(())
}

fn visual(args: &DemoArgs, title: String) -> VisualOptions {
    VisualOptions {
        mcap: !args.no_mcap,
        title,
    }
}

/// Where the outputs of one part are.
fn print_outputs(dir: &std::path::Path, no_mcap: bool) {
    println!("  outputs: {}", dir.display());
    println!("    report     {}", dir.join("report.md").display());
    if !no_mcap {
        println!(
            "    Foxglove   {} (Open local file; 3D panel; colour /cloud by `class`)",
            dir.join("run.mcap").display()
        );
    }
    println!(
        "    maps       {} (as measured), {} (reflections mirrored back)",
        dir.join("map.ply").display(),
        dir.join("around_corner.ply").display()
    );
    println!(
        "    plots      {}, trajectory.png, metrics.png",
        dir.join("topdown.png").display()
    );
}
