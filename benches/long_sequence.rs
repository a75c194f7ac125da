//! Frames per second of `detect` (plane-optimized, true poses) and `slam`
//! (tracking, back-end and classification with the estimate) on a long
//! sequence read pass by pass from its files, on one thread and on all.
//!
//! Run: `cargo bench --bench long_sequence [-- DIR]`. DIR holds `frames/`
//! and `poses.txt` (e.g. `specular simulate --scene office --frames 5000
//! --out DIR`); without it, `LONG_FRAMES` frames (default 1000) of the
//! office scene are simulated into a temporary directory first. Each
//! configuration runs `BENCH_PASSES` times (default 1); the median is
//! reported.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use specular::config::Config;
use specular::io::{self, PlyEncoding};
use specular::pipeline::slam::classify_with_poses;
use specular::pipeline::{run_plane_optimized_into, run_slam, Discard, Sequence};
use specular::sim::{Scene, Simulator};

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Simulate `n` office frames into `dir` (frames/, poses.txt), a frame at
/// a time (each depends only on the scene, its index and the seed).
fn simulate(dir: &Path, n: usize) {
    let scene = Scene::resolve("office").expect("office scene");
    let sim = Simulator::new(&scene);
    let frames_dir = dir.join("frames");
    std::fs::create_dir_all(&frames_dir).expect("frames directory");
    (0..n).into_par_iter().for_each(|k| {
        let f = sim.frame(k, scene.seed);
        io::write_frame(
            &frames_dir.join(format!("{}.ply", f.frame.name)),
            &f.frame,
            PlyEncoding::BinaryLittleEndian,
        )
        .expect("write frame");
    });
    let poses: Vec<_> = (0..n).map(|k| sim.pose(k)).collect();
    io::write_tum(&dir.join("poses.txt"), &poses).expect("write poses");
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Frames per second of `run` on a pool of `threads` threads.
fn fps(threads: usize, passes: usize, frames: usize, run: &(dyn Fn() + Sync)) -> f64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("thread pool");
    let times: Vec<f64> = (0..passes)
        .map(|_| {
            let start = Instant::now();
            pool.install(run);
            start.elapsed().as_secs_f64()
        })
        .collect();
    frames as f64 / median(times)
}

fn main() {
    let arg = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from);
    let tmp;
    let dir = match arg {
        Some(dir) => dir,
        None => {
            tmp = tempfile::tempdir().expect("temporary directory");
            let n = env_usize("LONG_FRAMES", 1000);
            eprintln!("simulating {n} office frames into {}", tmp.path().display());
            simulate(tmp.path(), n);
            tmp.path().to_path_buf()
        }
    };
    let passes = env_usize("BENCH_PASSES", 1).max(1);
    let frames = dir.join("frames");
    let poses = dir.join("poses.txt");
    let config = Config::resolve("default").expect("config");
    let sequence = Sequence::open(&frames, Some(&poses), config.input.pose_tolerance)
        .expect("sequence")
        .with_frame_cache(config.input.frame_cache_mb);
    let n = sequence.len();
    let all = rayon::current_num_threads();
    println!(
        "long sequence: {n} frames of {} ({passes} pass(es), median)",
        dir.display()
    );
    println!(
        "{:<46} {:>10} {:>10}",
        "",
        "1 thread",
        format!("{all} threads")
    );
    let detect = || {
        run_plane_optimized_into(&sequence, &config, &mut Discard).expect("detect");
    };
    println!(
        "{:<46} {:>10.1} {:>10.1}",
        "detect (plane-optimized), frames/s",
        fps(1, passes, n, &detect),
        fps(all, passes, n, &detect)
    );
    let slam = || {
        let mut sequence = sequence.clone();
        let origin = sequence.poses.as_ref().map(|p| p[0]);
        let out = run_slam(&sequence, &config, origin).expect("slam");
        classify_with_poses(&mut sequence, out.poses, &config, &mut Discard).expect("classify");
    };
    println!(
        "{:<46} {:>10.1} {:>10.1}",
        "slam (track + back-end + classify), frames/s",
        fps(1, passes, n, &slam),
        fps(all, passes, n, &slam)
    );
}
