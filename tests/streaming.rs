//! Whole sequences pass by pass: frames read from their files a window at
//! a time give the same result as frames held in memory, and a bad frame
//! in the middle of a long sequence stops the run cleanly.

mod common;

use std::path::Path;
use std::process::Command;

use specular::config::{Config, Method};
use specular::io::{self, PlyEncoding, StampedPose};
use specular::pipeline::{
    run_plane_optimized, run_single_scan, stream_window, PlaneOptimizedOutput, Sequence,
    StageTimings,
};
use specular::sim::{self, Scene};

/// Simulate `frames` frames of `scene` into `dir` (frames/, poses.txt).
fn simulate_to(dir: &Path, scene: &str, frames: usize) {
    let scene = Scene::resolve(scene).unwrap();
    let run = sim::simulate(&scene, Some(frames), None).unwrap();
    let frames_dir = dir.join("frames");
    std::fs::create_dir_all(&frames_dir).unwrap();
    for f in &run.frames {
        io::write_frame(
            &frames_dir.join(format!("{}.ply", f.name)),
            f,
            PlyEncoding::BinaryLittleEndian,
        )
        .unwrap();
    }
    let poses: Vec<StampedPose> = run.poses.clone();
    io::write_tum(&dir.join("poses.txt"), &poses).unwrap();
}

/// The same frames read pass by pass from their files (none kept between
/// passes) and held in memory.
fn both_ways(frames: &Path, poses: &Path) -> (Sequence, Sequence) {
    let streamed = Sequence::open(frames, Some(poses), 0.01)
        .unwrap()
        .with_frame_cache(0.0);
    assert!(streamed.in_memory().is_none());
    let loaded = Sequence::load(frames, Some(poses), 0.01, &mut StageTimings::default()).unwrap();
    assert!(loaded.in_memory().is_some());
    (streamed, loaded)
}

/// Every class, rule, landmark and score of two runs.
fn assert_same(a: &PlaneOptimizedOutput, b: &PlaneOptimizedOutput) {
    assert_eq!(a.run.frames.len(), b.run.frames.len());
    for (fa, fb) in a.run.frames.iter().zip(&b.run.frames) {
        assert_eq!(fa.name, fb.name);
        assert_eq!(fa.classes, fb.classes, "frame {}", fa.name);
        assert_eq!(fa.rules, fb.rules, "frame {}", fa.name);
        assert_eq!((fa.planes, fa.candidates), (fb.planes, fb.candidates));
    }
    assert_eq!(a.run.confusion, b.run.confusion);
    assert_eq!(a.run.rules, b.run.rules);
    assert_eq!(a.used, b.used);
    assert_eq!(format!("{:?}", a.map), format!("{:?}", b.map));
    assert_eq!(format!("{:?}", a.planes), format!("{:?}", b.planes));
}

#[test]
fn streaming_equals_in_memory_on_the_real_sample() {
    let sample = common::sample_dir();
    let (streamed, loaded) = both_ways(&sample.join("frames"), &sample.join("poses.txt"));
    let config = Config::resolve("default").unwrap();
    let a = run_plane_optimized(&streamed, &config).unwrap();
    let b = run_plane_optimized(&loaded, &config).unwrap();
    assert!(a.run.confusion.is_some(), "the sample is labelled");
    assert_same(&a, &b);
    let mut single = config.clone();
    single.method = Method::SingleScan;
    let a = run_single_scan(&streamed, &single).unwrap();
    let b = run_single_scan(&loaded, &single).unwrap();
    assert_eq!(a.confusion, b.confusion);
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        assert_eq!(fa.classes, fb.classes);
    }
}

#[test]
fn streaming_equals_in_memory_on_the_shared_real_frames() {
    let Some(dir) = common::shared_frames() else {
        return;
    };
    let (streamed, loaded) = both_ways(&dir, &dir.join("hesai_pose.txt"));
    let config = Config::resolve("default").unwrap();
    assert_same(
        &run_plane_optimized(&streamed, &config).unwrap(),
        &run_plane_optimized(&loaded, &config).unwrap(),
    );
}

/// Several windows, keyframe passes that skip frames, a map of several
/// landmarks: the window boundaries change nothing.
#[test]
fn streaming_over_many_windows_equals_in_memory() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = 3 * stream_window() + 5;
    simulate_to(tmp.path(), "demo", frames);
    let (streamed, loaded) = both_ways(&tmp.path().join("frames"), &tmp.path().join("poses.txt"));
    assert_eq!(streamed.len(), frames);
    let config = Config::resolve("default").unwrap();
    let a = run_plane_optimized(&streamed, &config).unwrap();
    assert!(!a.used.is_empty(), "the demo scene has reflective planes");
    let b = run_plane_optimized(&loaded, &config).unwrap();
    assert_same(&a, &b);
    // With a cache that holds a few of the frames: the first are kept, the
    // rest read again, and nothing changes.
    let one =
        streamed.frame(0).unwrap().points.len() * std::mem::size_of::<specular::cloud::Point>();
    let partly = streamed.clone().with_frame_cache(5.5 * one as f64 / 1e6);
    assert_same(&run_plane_optimized(&partly, &config).unwrap(), &b);
}

/// A frame cut short in the middle of a sequence (after several windows
/// were classified and written) stops `detect` with an error naming it,
/// and leaves no output, for both methods.
#[test]
fn a_truncated_frame_in_a_long_sequence_is_named_and_leaves_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = 3 * stream_window() + 5;
    simulate_to(tmp.path(), "demo", frames);
    let frames_dir = tmp.path().join("frames");
    let mut files: Vec<_> = std::fs::read_dir(&frames_dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    let bad = &files[2 * stream_window() + 3];
    let bytes = std::fs::read(bad).unwrap();
    std::fs::write(bad, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let name = bad.file_name().unwrap().to_str().unwrap();
    let detect = |out: &std::path::Path, extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_specular"))
            .args(["detect", "--frames"])
            .arg(&frames_dir)
            .arg("--poses")
            .arg(tmp.path().join("poses.txt"))
            .arg("--out")
            .arg(out)
            .args(extra)
            .output()
            .unwrap()
    };
    for method in ["plane-optimized", "single-scan"] {
        let out = tmp.path().join(format!("out-{method}"));
        let o = detect(&out, &["--method", method]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{method}: {err}");
        assert!(
            err.contains(name) && err.contains("truncated"),
            "{method}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists(), "{method}: {} was left behind", out.display());
    }
    // Into an existing directory: it stays, empty.
    let out = tmp.path().join("existing");
    std::fs::create_dir(&out).unwrap();
    let o = detect(&out, &["--method", "single-scan", "--no-mcap"]);
    assert!(!o.status.success());
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
}

/// `--frames` accepts the 3DRef release layout (`raw/seqN/raycast/hesai/`
/// with `raw/seqN/hesai_pose.txt`) in place, poses included.
#[test]
fn detect_reads_the_3dref_release_layout_in_place() {
    let sample = common::sample_dir();
    let tmp = tempfile::tempdir().unwrap();
    let seq = tmp.path().join("raw/seq1");
    let hesai = seq.join("raycast/hesai");
    std::fs::create_dir_all(&hesai).unwrap();
    for e in std::fs::read_dir(sample.join("frames")).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, hesai.join(p.file_name().unwrap())).unwrap();
    }
    std::fs::copy(sample.join("poses.txt"), seq.join("hesai_pose.txt")).unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(["detect", "--lean", "--frames"])
        .arg(&seq)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(common::predictions(&out).len(), 3);
    assert!(out.join("planes.json").is_file());
}
