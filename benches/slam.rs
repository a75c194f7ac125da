//! Frames per second of the Reflection SLAM stages on QT64 frames, one core.
//!
//! Run: `cargo bench --bench slam`. Frames: the shared 3DRef frames
//! (`../shared/data/3dref-seq1-demo`) when present, else the bundled
//! sample, or a directory given as the first argument. Every stage runs on
//! the calling thread (no rayon), each pass over all frames is repeated
//! and the median time per frame is reported:
//!
//! - detection: organize the scan and detect reflective planes;
//! - extraction: filter, normals, ground, region growing, RANSAC, hulls,
//!   and the surface samples of the point term (`[slam.points]`);
//! - registration: frame-to-frame matching, RANSAC and Gauss–Newton;
//! - tracking: the whole `Tracker::track_with_samples` step (frame-to-frame
//!   and scan-to-map registration, the point refinement of free
//!   directions, map update);
//! - whole step: detection + extraction + tracking.

use std::path::PathBuf;
use std::time::Instant;

use nalgebra::Isometry3;
use specular::config::Config;
use specular::frontend::{reflective_planes, FramePlane};
use specular::io;
use specular::pipeline::registry::{detector, extractor, frame_seed, merger, rejector};
use specular::registration::{match_planes, register};
use specular::sensor::{OrganizedScan, SensorModel};
use specular::slam::{ScanSamples, Tracker};

fn frames_dir() -> PathBuf {
    if let Some(arg) = std::env::args().skip(1).find(|a| !a.starts_with('-')) {
        return PathBuf::from(arg);
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let shared = root.join("../shared/data/3dref-seq1-demo");
    if shared.is_dir() {
        shared
    } else {
        root.join("datasets/3dref-sample/frames")
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let dir = frames_dir();
    let entries = io::list_frames(&dir).expect("frame directory");
    let frames: Vec<_> = entries
        .iter()
        .map(|e| io::read_frame(&e.path).expect("frame"))
        .collect();
    let config = Config::resolve("default").expect("config");
    let sensor = SensorModel::resolve(&config.sensor).expect("sensor");
    let det = detector(&config, &sensor);
    let ex = extractor(&config);
    let rej = rejector(&config);
    let p = config.slam;
    let passes: usize = std::env::var("BENCH_PASSES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(7);
    let (mut t_detect, mut t_extract, mut t_register, mut t_track) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut planes_per_frame = 0.0;
    for _ in 0..passes {
        let mut tracker =
            Tracker::new(p, rejector(&config), merger(&config), Isometry3::identity());
        let mut previous: Option<Vec<FramePlane>> = None;
        let (mut d, mut e, mut r, mut t) = (0.0, 0.0, 0.0, 0.0);
        let mut count = 0usize;
        for f in &frames {
            let start = Instant::now();
            let scan = OrganizedScan::build(f, &sensor).expect("scan");
            let detection = det.detect(f, &scan, frame_seed(config.seed, &f.name));
            d += start.elapsed().as_secs_f64();
            let start = Instant::now();
            let mut planes = ex.extract(f, &scan, &detection, frame_seed(1, &f.name));
            planes.extend(reflective_planes(f, &detection, &config.extractor));
            let samples = p
                .points
                .enabled
                .then(|| ScanSamples::sample(f, &scan, p.points.sample_voxel, p.points.min_range));
            e += start.elapsed().as_secs_f64();
            count += planes.len();
            if let Some(prev) = &previous {
                let start = Instant::now();
                let pairs = match_planes(&planes, prev, &Isometry3::identity(), &p.frame_matching);
                let reg = register(
                    &pairs,
                    &Isometry3::identity(),
                    rej.as_ref(),
                    &p.gauss_newton,
                    p.rejector.inlier_cos(),
                    p.rejector.inlier_offset,
                    3,
                );
                r += start.elapsed().as_secs_f64();
                std::hint::black_box(reg);
            }
            previous = Some(planes.clone());
            let start = Instant::now();
            std::hint::black_box(tracker.track_with_samples(planes, samples.as_ref(), 5));
            t += start.elapsed().as_secs_f64();
        }
        let n = frames.len() as f64;
        t_detect.push(d / n);
        t_extract.push(e / n);
        t_register.push(r / (n - 1.0).max(1.0));
        t_track.push(t / n);
        planes_per_frame = count as f64 / n;
    }
    let (d, e, r, t) = (
        median(t_detect),
        median(t_extract),
        median(t_register),
        median(t_track),
    );
    println!(
        "{} frames from {} ({:.1} planes per frame), median of {passes} passes, one thread",
        frames.len(),
        dir.display(),
        planes_per_frame
    );
    println!("stage                ms/frame   frames/s");
    for (name, s) in [
        ("detection", d),
        ("extraction", e),
        ("registration (f2f)", r),
        ("tracking step", t),
        ("whole step", d + e + t),
        ("whole without detect", e + t),
    ] {
        println!("{:<20} {:>8.3} {:>10.1}", name, s * 1e3, 1.0 / s);
    }
}
