//! `specular bench families`: the held-out benchmark (both pipelines over
//! seeds of every scene family), its table on stdout and `bench.md`,
//! `bench.json`, `bench.png` and `reliability.png` (the calibration of the
//! per-point confidences over all seeds) in the output directory.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use specular::bench::{self, BenchSpec, SeedResult, Summary};
use specular::io;
use specular::sim::family::{self, Split};

use super::load_config;

/// Arguments of `bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(subcommand)]
    command: BenchCommand,
}

#[derive(Subcommand, Debug)]
enum BenchCommand {
    /// The plane-optimized pipeline (true poses) and Reflection SLAM over
    /// seeds of every scene family: median, 10th percentile and worst per
    /// family and over all.
    Families(FamiliesArgs),
}

/// Which seeds.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum SplitArg {
    /// Seeds 0-999: tune here.
    Development,
    /// Seeds from 1000000: report, never tune.
    HeldOut,
}

/// Arguments of `bench families`.
#[derive(Args, Debug)]
struct FamiliesArgs {
    /// Configuration: built-in name (default, paper) or TOML file.
    #[arg(long, default_value = "default")]
    config: String,
    /// The split whose seeds run.
    #[arg(long, value_enum, default_value_t = SplitArg::HeldOut)]
    split: SplitArg,
    /// Seeds per family (the split's first).
    #[arg(long, default_value_t = bench::DEFAULT_SEEDS)]
    seeds: usize,
    /// Frames per sequence.
    #[arg(long, default_value_t = bench::DEFAULT_FRAMES)]
    frames: usize,
    /// Only these families (repeat the flag; default: every family).
    #[arg(long = "family")]
    families: Vec<String>,
    /// Skip Reflection SLAM (no ATE).
    #[arg(long)]
    no_slam: bool,
    /// A quick check of every family: one seed of 20 frames.
    #[arg(long)]
    quick: bool,
    /// Output directory for bench.md, bench.json, bench.png and
    /// reliability.png.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Replace an earlier benchmark's files in `--out`.
    #[arg(long)]
    force: bool,
}

/// Run `bench`.
pub fn run(args: BenchArgs) -> Result<()> {
    match args.command {
        BenchCommand::Families(a) => families(a),
    }
}

fn families(args: FamiliesArgs) -> Result<()> {
    let config = load_config(&args.config)?;
    let families = if args.families.is_empty() {
        family::names().into_iter().map(String::from).collect()
    } else {
        for f in &args.families {
            family::family(f)?;
        }
        args.families.clone()
    };
    let (seeds, frames) = if args.quick {
        (1, 20)
    } else {
        (args.seeds, args.frames)
    };
    if seeds == 0 || frames == 0 {
        bail!("--seeds and --frames must be at least 1");
    }
    let split = match args.split {
        SplitArg::Development => Split::Development,
        SplitArg::HeldOut => Split::HeldOut,
    };
    let spec = BenchSpec {
        families,
        split,
        seeds,
        frames,
        slam: !args.no_slam,
    };
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("runs/bench-{}", split.name())));
    if out.join("bench.json").exists() && !args.force {
        bail!(
            "{} already holds a benchmark (bench.json); use --force to replace it or another --out",
            out.display()
        );
    }
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;

    let mut results: Vec<SeedResult> = Vec::new();
    for (name, seed) in spec.runs() {
        let r = bench::run_seed(&name, seed, spec.frames, spec.slam, &config)
            .with_context(|| format!("benchmark run {name}/{seed}"))?;
        eprintln!(
            "{name}/{seed}: mIoU {:.2}, removal {:.2} (of {} reflections), obstacle IoU {:.2}, normal recall {:.2}, glass IoU {:.2}{} ({:.0} s)",
            r.miou,
            r.reflection_removal,
            r.reflections,
            r.obstacle_iou,
            r.normal_recall,
            r.glass_iou,
            r.ate.map(|a| format!(", ATE {a:.3} m")).unwrap_or_default(),
            r.seconds
        );
        results.push(r);
    }
    let summary = Summary::of(&results);
    let reliability = bench::reliability(&results).report();
    let title = format!(
        "{} split, {} seeds x {} frames per family, config {}",
        split.name(),
        spec.seeds,
        spec.frames,
        args.config
    );
    let table = format!(
        "# specular bench families\n\n{title}; each cell: median / 10th percentile / worst seed (for the ATE, the 90th percentile and the largest).\n\n{}\n## Confidence calibration\n\nThe plane-optimized pipeline's points over every seed, binned by the confidence of their class (points with a scored label and a class other than unclassified), against the share of them correct.\n\n{}",
        summary.markdown(),
        reliability.markdown()
    );
    println!("{table}");
    let json = serde_json::json!({
        "specular": specular::provenance(),
        "config": args.config,
        "spec": spec,
        "summary": summary,
        "reliability": reliability,
        "seeds": results,
    });
    io::write_atomic(&out.join("bench.json"), |w| {
        serde_json::to_writer_pretty(&mut *w, &json).map_err(std::io::Error::other)
    })?;
    io::write_atomic(&out.join("bench.md"), |w| w.write_all(table.as_bytes()))?;
    specular::viz::bench::bench_png(&out.join("bench.png"), &title, &results)?;
    specular::viz::bench::reliability_png(&out.join("reliability.png"), &title, &reliability)?;
    eprintln!(
        "wrote {}/bench.md, bench.json, bench.png, reliability.png",
        out.display()
    );
    Ok(())
}
