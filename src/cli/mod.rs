//! Command-line parsing and the subcommands. A thin layer: it checks the
//! arguments, loads inputs through the library and writes outputs.

mod bench;
mod convert;
mod demo;
mod detect;
mod eval;
mod graph;
mod input;
mod output;
mod run_dir;

pub(crate) use run_dir::interrupted;
mod simulate;
mod slam;
mod visual;

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use specular::config::{Config, Method};

/// Reflection-aware plane SLAM on dual-return LiDAR.
#[derive(Parser, Debug)]
#[command(name = "specular", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// No progress bars (they are also hidden when stderr is not a terminal).
    #[arg(short, long, global = true)]
    quiet: bool,
    /// Log to stderr: -v info, -vv debug (RUST_LOG overrides).
    #[arg(short, long, global = true, action = clap::ArgAction::Count)]
    verbose: u8,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Classify every point of a 3DRef frame directory (N / G / R / O).
    Detect(detect::DetectArgs),
    /// Reflection SLAM: poses and a plane map from the frames alone, then
    /// classification with the estimated poses.
    Slam(slam::SlamArgs),
    /// Score a predictions directory against the frames' labels.
    Eval(eval::EvalArgs),
    /// Rewrite frames as compact binary (or ascii) PLY, with their poses.
    Convert(convert::ConvertArgs),
    /// Run the showcase on the built-in sample and print the metrics.
    Demo(demo::DemoArgs),
    /// Simulate a dual-return LiDAR sequence with glass and mirrors.
    Simulate(simulate::SimulateArgs),
    /// Pose-plane factor graphs: export synthetic ones, solve graph files.
    Graph(graph::GraphArgs),
    /// Benchmarks: the held-out scene families.
    Bench(bench::BenchArgs),
    /// Print the effective configuration as TOML (every key with its value;
    /// for a file, first a comment naming the built-in it layers over and
    /// the keys it sets).
    Config {
        /// Built-in name (default, paper) or path to a TOML file layered over
        /// the default (or `extends = "paper"`).
        #[arg(long, default_value = "default")]
        config: String,
    },
}

/// The method selectable on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum MethodArg {
    /// Each frame against the planes detected in it (Zhao 2020).
    SingleScan,
    /// Global reflective-plane map from external poses (the paper).
    PlaneOptimized,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::SingleScan => Method::SingleScan,
            MethodArg::PlaneOptimized => Method::PlaneOptimized,
        }
    }
}

/// Load a configuration by built-in name or path.
pub(crate) fn load_config(name_or_path: &str) -> Result<Config> {
    Ok(Config::resolve(name_or_path)?)
}

/// Parse the command line and run the subcommand.
pub fn run() -> Result<()> {
    let cli = Cli::parse();
    specular::logging::init(cli.verbose);
    specular::progress::set_enabled(!cli.quiet && std::io::stderr().is_terminal());
    match cli.command {
        Command::Detect(args) => detect::run(args),
        Command::Slam(args) => slam::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Convert(args) => convert::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Graph(args) => graph::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Config { config } => {
            if Config::builtin_names().contains(&config.as_str()) {
                print!("{}", Config::resolve(&config)?.to_toml());
            } else {
                // A file: say what it layers over and what it changes.
                let (merged, layering) = Config::load_layered(std::path::Path::new(&config))?;
                // The sensor it names must exist (a run would fail on it).
                specular::sensor::SensorModel::resolve(&merged.sensor)
                    .with_context(|| format!("{config}: sensor"))?;
                print!("{}\n{}", layering.comment(), merged.to_toml());
            }
            Ok(())
        }
    }
}

/// The repository's bundled real sample (for `demo` and the docs).
pub(crate) fn bundled_sample() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/3dref-sample")
}
