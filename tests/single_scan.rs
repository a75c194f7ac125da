//! The single-scan pipeline on real 3DRef frames.

mod common;

use specular::classify::Class;
use specular::config::{Config, Method};
use specular::io::{self, PlyEncoding};
use specular::pipeline::{registry, run_single_scan, Sequence, StageTimings};
use specular::sensor::{OrganizedScan, SensorModel};

fn single_scan_config() -> Config {
    let mut c = Config::resolve("default").unwrap();
    c.method = Method::SingleScan;
    c
}

fn load(dir: &std::path::Path, poses: Option<&std::path::Path>) -> Sequence {
    Sequence::load(dir, poses, 0.01, &mut StageTimings::default()).unwrap()
}

#[test]
fn detects_the_office_window_in_every_sample_frame() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), Some(&dir.join("poses.txt")));
    let config = single_scan_config();
    let sensor = SensorModel::resolve(&config.sensor).unwrap();
    let detector = registry::detector(&config, &sensor);
    for frame in seq.in_memory().unwrap() {
        let scan = OrganizedScan::build(frame, &sensor).unwrap();
        let det = detector.detect(frame, &scan, 7);
        let window = &det.planes.first().expect("a reflective plane").bounded;
        // The 3DRef sequence-1 window: n ~ (-0.998, 0.027, 0.049), d ~ 5.0 m.
        let n = window.plane.normal;
        assert!(
            n.dot(&nalgebra::Vector3::new(-0.998, 0.027, 0.049)) > 0.99,
            "normal {n}"
        );
        assert!((window.plane.d - 5.0).abs() < 0.1, "d {}", window.plane.d);
        // Most of its inliers are labelled glass.
        let glass = det.planes[0]
            .inliers
            .iter()
            .filter(|&&i| frame.points[i as usize].label == 2)
            .count();
        assert!(
            glass * 10 > det.planes[0].inliers.len() * 8,
            "{glass} of {}",
            det.planes[0].inliers.len()
        );
        assert!(window.boundary.area() > 4.0);
    }
}

#[test]
fn sample_classification_is_deterministic_and_sensible() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), Some(&dir.join("poses.txt")));
    let config = single_scan_config();
    let a = run_single_scan(&seq, &config).unwrap();
    let b = run_single_scan(&seq, &config).unwrap();
    for (x, y) in a.frames.iter().zip(&b.frames) {
        assert_eq!(x.classes, y.classes, "frame {}", x.name);
    }
    let m = a.confusion.unwrap().metrics();
    assert!(m.accuracy > 90.0, "{}", m.table());
    assert!(m.reflection_removal > 80.0, "{}", m.table());
    assert!(m.class(Class::Normal).iou > 95.0, "{}", m.table());
}

/// The acceptance floor of the foundation issue: at least the original
/// single-frame code on the ten shared frames (sensor-frame input).
#[test]
fn single_scan_at_least_matches_the_original_on_the_ten_shared_frames() {
    let Some(dir) = common::shared_frames() else {
        return;
    };
    let seq = load(&dir, Some(&dir.join("hesai_pose.txt")));
    assert_eq!(seq.len(), 10);
    let out = run_single_scan(&seq, &single_scan_config()).unwrap();
    let m = out.confusion.unwrap().metrics();
    let t = m.table();
    assert!(m.accuracy >= 91.0, "{t}");
    assert!(m.reflection_removal >= 81.0, "{t}");
    assert!(m.class(Class::Normal).iou >= 96.4, "{t}");
    assert!(m.class(Class::Glass).iou >= 50.4, "{t}");
    assert!(m.class(Class::Obstacle).iou >= 36.8, "{t}");
}

#[test]
fn binary_sample_gives_the_same_predictions_as_the_ascii_originals() {
    let Some(dir) = common::shared_frames() else {
        return;
    };
    let sample = common::sample_dir();
    let config = single_scan_config();
    let bin = run_single_scan(&load(&sample.join("frames"), None), &config).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    for f in &bin.frames {
        std::fs::copy(
            dir.join(format!("{}.ply", f.name)),
            tmp.path().join(format!("{}.ply", f.name)),
        )
        .unwrap();
    }
    let ascii = run_single_scan(&load(tmp.path(), None), &config).unwrap();
    for (a, b) in ascii.frames.iter().zip(&bin.frames) {
        assert_eq!(a.name, b.name);
        assert_eq!(a.classes, b.classes);
    }
}

#[test]
fn a_frame_without_a_reflective_plane_is_all_normal() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), None);
    // Keep only a handful of second returns: too few candidates for a plane.
    let mut frame = seq.frame(0).unwrap().into_owned();
    let mut kept = 0;
    frame.points.retain(|p| {
        if p.ret == 2 {
            kept += 1;
            kept <= 20
        } else {
            true
        }
    });
    let tmp = tempfile::tempdir().unwrap();
    io::write_frame(
        &tmp.path().join(format!("{}.ply", frame.name)),
        &frame,
        PlyEncoding::BinaryLittleEndian,
    )
    .unwrap();
    let seq = load(tmp.path(), None);
    let out = run_single_scan(&seq, &single_scan_config()).unwrap();
    assert_eq!(out.frames[0].planes, 0);
    assert!(out.frames[0].classes.iter().all(|&c| c == Class::Normal));
}

#[test]
fn a_frame_without_second_returns_is_a_clear_error() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), None);
    let mut frame = seq.frame(0).unwrap().into_owned();
    frame.points.retain(|p| p.ret == 1);
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join(format!("{}.ply", frame.name));
    io::write_frame(&path, &frame, PlyEncoding::BinaryLittleEndian).unwrap();
    let seq = load(tmp.path(), None);
    let err = run_single_scan(&seq, &single_scan_config())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no second return") && err.contains(&frame.name),
        "{err}"
    );
}
