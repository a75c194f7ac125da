//! PLY parsing throughput on the 3DRef demo frames.
//!
//! `cargo bench --bench parse [-- DIR]` (or `SPECULAR_DATA=DIR`): times
//! `parse_frame` on in-memory bytes (best and median of 20 runs per frame,
//! one thread) and the parallel `read_frames` (file reads included).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use specular::io::{list_frames, parse_frame, read_frames};

const REPS: usize = 20;

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

fn main() {
    let dir = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .or_else(|| std::env::var("SPECULAR_DATA").ok())
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/3dref-seq1-demo")
        });
    let frames = match list_frames(&dir) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("parse bench: {e}");
            std::process::exit(1);
        }
    };
    let files: Vec<(String, Vec<u8>)> = frames
        .iter()
        .map(|f| (f.name.clone(), std::fs::read(&f.path).expect("read frame")))
        .collect();

    println!("single thread, parse_frame on in-memory bytes, {REPS} runs per frame:");
    let (mut sum_best, mut sum_median, mut total_bytes) = (0.0, 0.0, 0usize);
    for ((name, bytes), entry) in files.iter().zip(&frames) {
        let mut times = Vec::with_capacity(REPS);
        let mut npts = 0;
        for _ in 0..REPS {
            let t = Instant::now();
            let f = parse_frame(bytes, &entry.path).expect("parse frame");
            times.push(t.elapsed());
            npts = std::hint::black_box(f).points.len();
        }
        times.sort();
        let (best, median) = (ms(times[0]), ms(times[REPS / 2]));
        let mb = bytes.len() as f64 / 1e6;
        println!(
            "  {name}: {npts} points, {mb:.2} MB: best {best:.2} ms ({:.0} MB/s), median {median:.2} ms ({:.0} MB/s)",
            mb / best * 1e3,
            mb / median * 1e3
        );
        sum_best += best;
        sum_median += median;
        total_bytes += bytes.len();
    }
    let n = files.len() as f64;
    let mb = total_bytes as f64 / 1e6;
    println!(
        "  mean: best {:.2} ms/frame ({:.0} MB/s), median {:.2} ms/frame ({:.0} MB/s)",
        sum_best / n,
        mb / sum_best * 1e3,
        sum_median / n,
        mb / sum_median * 1e3
    );

    let paths: Vec<PathBuf> = frames.iter().map(|f| f.path.clone()).collect();
    let mut times = Vec::with_capacity(REPS);
    for _ in 0..REPS {
        let t = Instant::now();
        let all = read_frames(&paths).expect("read frames");
        times.push(t.elapsed());
        std::hint::black_box(all);
    }
    times.sort();
    let (best, median) = (ms(times[0]), ms(times[REPS / 2]));
    println!(
        "parallel read_frames ({} threads, files read from disk/page cache), {} frames:",
        rayon::current_num_threads(),
        files.len()
    );
    println!(
        "  best {best:.1} ms ({:.2} ms/frame, {:.0} MB/s), median {median:.1} ms ({:.2} ms/frame, {:.0} MB/s)",
        best / n,
        mb / best * 1e3,
        median / n,
        mb / median * 1e3
    );
}
