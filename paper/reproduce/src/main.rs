//! `specular-reproduce`: the paper's experiments, side by side with its
//! published tables (see the [`specular_paper`] library). Writes `results.json`,
//! `tables.md`, `timings.json`, `timings.md` and `around_corner.png` into
//! `--out`, and fills the generated blocks of the README beside it (from
//! the template `paper/README.in.md` when it does not exist yet).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Parser;
use specular_paper::{
    self as reproduce, data::resolve_real, readme, tables, timing, KissIcp, Options, Source, SCENES,
};

#[cfg(feature = "mimalloc")]
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The README template: hand-written text around the generated blocks
/// (used when the README does not exist yet).
const README_TEMPLATE: &str = include_str!("../../README.in.md");

/// Reproduce the paper's experiments beside its published tables.
#[derive(Parser, Debug)]
#[command(name = "specular-reproduce", version, about, long_about = None)]
pub struct ReproduceArgs {
    /// Output directory of the results (tables, JSON, figures); the README
    /// goes beside it. A fresh directory by default: the tracked
    /// `paper/results` is refreshed only when named (`--out paper/results`).
    #[arg(long, default_value = "runs/reproduce/results")]
    pub out: PathBuf,
    /// A further real 3DRef-format directory (`*.ply` frames in `frames/`,
    /// in `raycast/hesai/` as in the 3DRef release's `raw/seqN/`, or
    /// directly; `poses.txt` or `hesai_pose.txt`); repeatable.
    #[arg(long)]
    pub data: Vec<PathBuf>,
    /// Cut the simulated sequences to their first frames and time one run
    /// (for tests; not the reproduction's numbers).
    #[arg(long)]
    pub quick: bool,
    /// Also run KISS-ICP (creates a venv and pip-installs kiss-icp under
    /// OUT/.kiss-icp).
    #[arg(long)]
    pub with_kiss_icp: bool,
    /// Where to write the README (default: the parent of --out).
    #[arg(long)]
    pub readme: Option<PathBuf>,
    /// No progress bars (they are also hidden when stderr is not a terminal).
    #[arg(short, long)]
    pub quiet: bool,
    /// Log to stderr: -v info, -vv debug (RUST_LOG overrides).
    #[arg(short, long, action = clap::ArgAction::Count)]
    pub verbose: u8,
}

/// The ten shared real frames, when `../shared/data` exists beside the
/// repository (it does in CI).
fn shared_frames() -> Option<PathBuf> {
    let dir = repository().join("../shared/data/3dref-seq1-demo");
    dir.is_dir().then_some(dir)
}

/// The repository's root (this crate is `paper/reproduce/` in it).
fn repository() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// The repository's bundled real sample.
fn bundled_sample() -> PathBuf {
    repository().join("datasets/3dref-sample")
}

/// The real directories in table order: the bundled sample, the shared ten
/// frames, then every `--data` (each once), each checked before any work.
fn real_dirs(args: &ReproduceArgs) -> Result<Vec<PathBuf>> {
    let mut dirs = vec![bundled_sample()];
    dirs.extend(shared_frames());
    for d in &args.data {
        let (frames, _) = resolve_real(d)?;
        let listed = specular::io::list_frames(&frames)
            .with_context(|| format!("--data {}", d.display()))?;
        if listed.is_empty() {
            anyhow::bail!("--data {}: no frames (*.ply) found", d.display());
        }
        dirs.push(d.clone());
    }
    let mut seen = Vec::new();
    dirs.retain(|d| {
        let key = d.canonicalize().unwrap_or_else(|_| d.clone());
        let fresh = !seen.contains(&key);
        seen.push(key);
        fresh
    });
    Ok(dirs)
}

/// The command line, as reproducible text (global flags left out).
fn command_line(args: &ReproduceArgs) -> String {
    let mut s = format!("specular-reproduce --out {}", args.out.display());
    for d in &args.data {
        s.push_str(&format!(" --data {}", d.display()));
    }
    if args.quick {
        s.push_str(" --quick");
    }
    if args.with_kiss_icp {
        s.push_str(" --with-kiss-icp");
    }
    s
}

fn main() -> std::process::ExitCode {
    let args = ReproduceArgs::parse();
    specular::logging::init(args.verbose);
    specular::progress::set_enabled(!args.quiet && std::io::stderr().is_terminal());
    match run(args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// Run the reproduction.
fn run(args: ReproduceArgs) -> Result<()> {
    let started = Instant::now();
    let dirs = real_dirs(&args)?;
    let timing_dir = shared_frames().unwrap_or_else(bundled_sample);
    let mut sources: Vec<Source> = dirs.into_iter().map(Source::Real).collect();
    sources.extend(SCENES.iter().map(|s| Source::Simulated(s.to_string())));
    let options = Options {
        sources,
        quick: args.quick,
        kiss_icp: args
            .with_kiss_icp
            .then(|| KissIcp::new(args.out.join(".kiss-icp"))),
    };
    let out = &args.out;
    let readme = args
        .readme
        .clone()
        .unwrap_or_else(|| out.parent().unwrap_or(Path::new(".")).join("README.md"));
    let base = readme_base(&readme, out)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let command = command_line(&args);
    let mut log = |line: &str| {
        eprintln!("[{:6.1} s] {line}", started.elapsed().as_secs_f64());
    };
    let results = reproduce::run(&options, out, &mut log)?;
    let tables_md = tables::markdown(&results, &command);
    reproduce::write_json(&out.join("results.json"), &results)?;
    reproduce::write_text(&out.join("tables.md"), &tables_md)?;

    log(&format!("timing on {}", timing_dir.display()));
    let repeats = if args.quick { 1 } else { 3 };
    let timings = timing::measure(&timing_dir, repeats)?;
    let total = started.elapsed().as_secs_f64();
    // The 1, 5 and 15 minute load averages (Linux): other work on the
    // machine shows in every time measured.
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|l| l.split_whitespace().take(3).collect::<Vec<_>>().join(" "));
    let timings_md = tables::timing_markdown(&timings, total, load.as_deref(), &command);
    reproduce::write_json(
        &out.join("timings.json"),
        &serde_json::json!({ "total_wall_s": total, "load_average": load, "timing": timings }),
    )?;
    reproduce::write_text(&out.join("timings.md"), &timings_md)?;

    let figure = if results.corner_figure.is_some() {
        format!(
            "![Mapping around the corner on mirror-room]({})",
            relative(out, &readme).join(reproduce::CORNER_PNG).display()
        )
    } else {
        "(no figure: the mirror-room scene was not run)".into()
    };
    // Same order as README_BLOCKS.
    let contents = [
        format!("```sh\n{command}\n```"),
        tables::headline(&results),
        tables_md,
        figure,
        timings_md,
    ];
    let pairs: Vec<(&str, &str)> = README_BLOCKS
        .iter()
        .zip(&contents)
        .map(|(n, c)| (*n, c.as_str()))
        .collect();
    let text = readme::fill(&base, &pairs);
    reproduce::write_text(&readme, &text)?;
    println!(
        "reproduce: {} datasets in {total:.0} s; {} (tables.md, results.json, timings.md, timings.json, {}) and {}",
        results.datasets.len(),
        out.display(),
        reproduce::CORNER_PNG,
        readme.display()
    );
    Ok(())
}

/// The generated blocks of the README, in their order.
const README_BLOCKS: [&str; 5] = ["command", "headline", "tables", "figure", "timings"];

/// The text the README is regenerated from, checked before any work: the
/// existing README with its hand-written text, or the template for a new
/// one. A file without the blocks is someone else's README (e.g. the
/// project's, with `--out results`) and is never overwritten.
fn readme_base(readme: &Path, out: &Path) -> Result<String> {
    match std::fs::read_to_string(readme) {
        Ok(text) if readme::has_blocks(&text, &README_BLOCKS) => Ok(text),
        Ok(_) => anyhow::bail!(
            "{} exists and has no generated blocks: not overwriting it (pass --readme FILE for the results in {})",
            readme.display(),
            out.display()
        ),
        Err(_) => Ok(README_TEMPLATE.to_string()),
    }
}

/// `out` as seen from the README's directory (the name alone when the README
/// sits in its parent, the default).
fn relative(out: &Path, readme: &Path) -> PathBuf {
    let readme_dir = readme.parent().unwrap_or(Path::new(""));
    match out.strip_prefix(readme_dir) {
        Ok(rel) if !rel.as_os_str().is_empty() => rel.to_path_buf(),
        _ => out.to_path_buf(),
    }
}
