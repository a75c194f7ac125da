//! Wall time of the whole `specular detect` command on one core: ascii PLY
//! parsing, the plane-optimized pipeline and every output file.
//!
//! `cargo bench --bench detect [-- DIR [RUNS]]` (or `SPECULAR_DATA=DIR`;
//! default the ten shared 3DRef frames when present, else the bundled
//! sample; 15 runs). Each run is the release
//! binary as a user runs it, `detect --frames DIR --poses DIR/hesai_pose.txt
//! --lean --timings`, with one worker thread (`RAYON_NUM_THREADS=1`) and,
//! where `taskset` exists, pinned to one CPU. The runs of the configurations
//! are interleaved so that a noisy machine slows them alike; the median and
//! the best run are reported per stage, from the command's own `--timings`
//! table.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Stage name to its milliseconds per frame, one entry per run.
type Samples = BTreeMap<String, Vec<f64>>;

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/3dref-seq1-demo");
    let bundled = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/3dref-sample");
    let dir = args
        .first()
        .cloned()
        .or_else(|| std::env::var("SPECULAR_DATA").ok())
        .map(PathBuf::from)
        .unwrap_or(if shared.is_dir() { shared } else { bundled });
    let runs: usize = args.get(1).and_then(|r| r.parse().ok()).unwrap_or(15);
    // The 3DRef release layout (frames and `hesai_pose.txt` together) or
    // the bundled sample's (`frames/`, `poses.txt`).
    let (dir, poses) = if dir.join("hesai_pose.txt").is_file() {
        (dir.clone(), dir.join("hesai_pose.txt"))
    } else {
        (dir.join("frames"), dir.join("poses.txt"))
    };
    if !poses.is_file() || !dir.is_dir() {
        eprintln!(
            "detect bench: no frames and poses at {} ({} expected)",
            dir.display(),
            poses.display()
        );
        std::process::exit(1);
    }
    let out = std::env::temp_dir().join(format!("specular-detect-bench-{}", std::process::id()));
    let pinned = Command::new("taskset").arg("-V").output().is_ok();
    let configs = ["default", "paper"];
    let mut samples: Vec<Samples> = vec![Samples::new(); configs.len()];
    for _ in 0..runs {
        for (config, s) in configs.iter().zip(&mut samples) {
            match run(&dir, &poses, &out, config, pinned) {
                Ok(table) => {
                    for (stage, ms) in table {
                        s.entry(stage).or_default().push(ms);
                    }
                }
                Err(e) => {
                    eprintln!("detect bench: {e}");
                    std::process::exit(1);
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(&out);
    println!(
        "specular detect on {} ({runs} runs per configuration, 1 thread{}), ms per frame:",
        dir.display(),
        if pinned { ", pinned to one CPU" } else { "" }
    );
    for (config, s) in configs.iter().zip(&samples) {
        println!("config {config}:");
        println!("  {:<16} {:>8} {:>8}", "stage", "median", "best");
        for (stage, v) in s {
            let mut v = v.clone();
            v.sort_by(f64::total_cmp);
            println!("  {stage:<16} {:>8.3} {:>8.3}", v[v.len() / 2], v[0]);
        }
    }
}

/// One run of the command; its `--timings` table (stage, ms per frame),
/// with the wall time per frame as stage "wall per frame".
fn run(
    dir: &Path,
    poses: &Path,
    out: &Path,
    config: &str,
    pinned: bool,
) -> Result<Vec<(String, f64)>, String> {
    let exe = env!("CARGO_BIN_EXE_specular");
    let mut cmd = if pinned {
        let mut c = Command::new("taskset");
        c.args(["-c", "0", exe]);
        c
    } else {
        Command::new(exe)
    };
    let output = cmd
        .env("RAYON_NUM_THREADS", "1")
        .arg("detect")
        .arg("--frames")
        .arg(dir)
        .arg("--poses")
        .arg(poses)
        .arg("--out")
        .arg(out)
        .args(["--config", config, "--lean", "--timings", "--force"])
        .output()
        .map_err(|e| format!("running {exe}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "detect failed: {}",
            String::from_utf8_lossy(&output.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&output.stdout);
    let table: Vec<(String, f64)> = text
        .lines()
        .skip_while(|l| !l.starts_with("stage"))
        .skip(1)
        .filter_map(|l| {
            // "name words   1.234  (...)": the name is everything before the
            // first number.
            let mut words = l.split_whitespace();
            let mut name = Vec::new();
            for w in words.by_ref() {
                if let Ok(ms) = w.parse::<f64>() {
                    return Some((name.join(" "), ms));
                }
                name.push(w);
            }
            None
        })
        .collect();
    if table.is_empty() {
        return Err("no --timings table in the output".into());
    }
    Ok(table)
}
