//! Motion distortion end to end (issue 40, part 3): the simulator's sweep
//! over the sensor period, and the SLAM's deskewing of it.

mod common;

use common::cli::{s, specular, stderr};
use nalgebra::Isometry3;
use specular::config::Config;
use specular::eval::trajectory_error;
use specular::pipeline::{run_slam, Sequence};
use specular::sim::{self, SceneChanges, SceneSource, Simulator};

/// The built-in demo walked at 1 m/s turning at 45 deg/s, `sweep` on or
/// off, as a sequence with its true poses.
fn walked(sweep: bool, frames: usize) -> (Sequence, Vec<Isometry3<f64>>) {
    let changes = SceneChanges {
        sweep,
        speed: Some(1.0),
        turn_rate_deg: Some(45.0),
        ..Default::default()
    };
    let (scene, _) = SceneSource::Named("demo".into())
        .resolve_with(&changes)
        .unwrap();
    let run = sim::simulate(&scene, Some(frames), None).unwrap();
    let poses: Vec<_> = run.poses.iter().map(|p| p.pose).collect();
    let seq = Sequence::from_frames(run.frames, Some(poses.clone()), "walked").unwrap();
    (seq, poses)
}

/// With the sweep on, points carry their firing times over the period
/// (from the sensor model's rate) and are measured from the pose of that
/// time; the poses (the sweep's start) are the instantaneous ones.
#[test]
fn the_sweep_spreads_firing_times_over_the_period() {
    let (swept, poses) = walked(true, 3);
    let (still, still_poses) = walked(false, 3);
    assert_eq!(poses, still_poses);
    let frame = swept.frame(1).unwrap();
    let times: Vec<f32> = frame.points.iter().map(|p| p.time).collect();
    let max = times.iter().cloned().fold(0.0f32, f32::max);
    assert!(times.iter().all(|&t| (0.0..0.1).contains(&t)), "{max}");
    assert!(max > 0.099, "{max}");
    assert!(still.frame(1).unwrap().points.iter().all(|p| p.time == 0.0));
    // A rosette sensor's pulses are timed too.
    let changes = SceneChanges {
        sensor: Some("livox-avia".into()),
        sweep: true,
        ..Default::default()
    };
    let (scene, _) = SceneSource::Named("demo".into())
        .resolve_with(&changes)
        .unwrap();
    let f = Simulator::new(&scene).frame(0, 1).frame;
    let max = f.points.iter().map(|p| p.time).fold(0.0f32, f32::max);
    assert!(max > 0.09 && max < 0.1, "{max}");
}

/// Reflection SLAM on a distorted sequence: with deskewing (the default)
/// the ATE stays under a centimetre (2.5 mm when written); without it,
/// the ATE and the largest error are more than twice those deskewed
/// (9.1 mm and 10.9 cm against 2.6 cm).
#[test]
fn deskewing_brings_the_slam_back_to_the_truth() {
    let config = Config::resolve("default").unwrap();
    let (seq, truth) = walked(true, 25);
    let error = |seq: &Sequence| {
        let out = run_slam(seq, &config, Some(truth[0])).unwrap();
        let worst = out
            .poses
            .iter()
            .zip(&truth)
            .map(|(e, t)| (e.translation.vector - t.translation.vector).norm())
            .fold(0.0, f64::max);
        let e = trajectory_error(&out.poses, &truth, 1.0).unwrap();
        (worst, e.ate_rmse)
    };
    let (deskewed, ate) = error(&seq);
    let (skewed, ate_skewed) = error(&seq.clone().without_deskew());
    eprintln!(
        "demo walked at 1 m/s turning at 45 deg/s, 25 frames: largest error {deskewed:.4} m \
         (ATE {ate:.4}) deskewed, {skewed:.4} m (ATE {ate_skewed:.4}) not"
    );
    assert!(ate < 0.01, "{ate}");
    assert!(ate_skewed > 2.0 * ate, "{ate_skewed} vs {ate}");
    assert!(skewed > 2.0 * deskewed, "{skewed} vs {deskewed}");
}

/// `simulate --sweep --speed --turn-rate` writes the per-point time and
/// records the changes in `scene.toml`; the same walk without `--sweep`
/// writes no time and the same poses; `slam --no-deskew` runs on it.
#[test]
fn simulate_flags_write_times_and_the_changed_scene() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "simulate",
            "--scene",
            "demo",
            "--frames",
            "3",
            "--out",
            s(&out),
        ];
        args.extend_from_slice(extra);
        let o = specular(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let walk = ["--speed", "1", "--turn-rate", "45"];
    let swept = run("swept", &[&walk[..], &["--sweep"]].concat());
    let still = run("still", &walk);
    let header = |dir: &std::path::Path| {
        let bytes = std::fs::read(dir.join("frames/1700000000.100000.ply")).unwrap();
        let end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
        String::from_utf8_lossy(&bytes[..end]).into_owned()
    };
    assert!(header(&swept).contains("property float time"));
    assert!(!header(&still).contains("time"));
    let scene = std::fs::read_to_string(swept.join("scene.toml")).unwrap();
    assert!(
        scene.contains("sweep = true") && scene.contains("turn_rate_deg = 45.0"),
        "{scene}"
    );
    assert_eq!(
        std::fs::read(swept.join("poses.txt")).unwrap(),
        std::fs::read(still.join("poses.txt")).unwrap()
    );
    let out = dir.path().join("slam");
    let o = specular(&[
        "slam",
        "--frames",
        s(&swept.join("frames")),
        "--gt-poses",
        s(&swept.join("poses.txt")),
        "--no-deskew",
        "--no-classify",
        "--out",
        s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}
