//! Tests of the recording: separate recordings, the trail, cleanup and
//! the `/cloud` fields.

use super::*;
use crate::cloud::{Frame, Point};
use crate::geometry::Plane;
use nalgebra::{Translation3, UnitQuaternion, Vector3 as V3};
use std::collections::BTreeMap;

fn sequence(frames: usize, points: usize) -> Sequence {
    let frames: Vec<Frame> = (0..frames)
        .map(|k| Frame {
            name: format!("{k}"),
            stamp: 100.0 + k as f64 * 0.1,
            points: (0..points)
                .map(|i| Point {
                    xyz: [3.0, i as f32 * 0.01, 0.0],
                    intensity: 7.0,
                    ..Default::default()
                })
                .collect(),
            has_labels: false,
            dropped_non_finite: 0,
            intensity_scale: None,
        })
        .collect();
    let poses = (0..frames.len())
        .map(|k| {
            Isometry3::from_parts(
                Translation3::new(k as f64, 0.0, 0.0),
                UnitQuaternion::from_scaled_axis(V3::new(0.0, 0.0, 0.1 * k as f64)),
            )
        })
        .collect();
    Sequence::from_frames(frames, Some(poses), "test").unwrap()
}

fn topic_counts(path: &Path) -> BTreeMap<String, usize> {
    let bytes = std::fs::read(path).unwrap();
    let mut counts = BTreeMap::new();
    for m in ::mcap::MessageStream::new(&bytes).unwrap() {
        *counts.entry(m.unwrap().channel.topic.clone()).or_default() += 1;
    }
    counts
}

/// Two recordings written at the same time do not mix messages: each
/// has a private context.
#[test]
fn concurrent_recordings_stay_separate() {
    let dir = tempfile::tempdir().unwrap();
    let plane = Plane::new(V3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
    let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let bp = BoundedPlane::from_points(plane, square.iter().map(|&(y, z)| Point3::new(5.0, y, z)));
    let runs = [(2usize, 10usize), (5, 3)];
    std::thread::scope(|s| {
        for (i, &(n, p)) in runs.iter().enumerate() {
            let path = dir.path().join(format!("{i}.mcap"));
            let bp = bp.clone();
            s.spawn(move || {
                let seq = sequence(n, p);
                let classes = vec![vec![Class::Normal; p]; n];
                let planes = [bp];
                let summary = write_run_mcap(
                    &path,
                    &McapRun {
                        sequence: &seq,
                        classes: &classes,
                        rules: &[],
                        confidence: &[],
                        planes: &planes,
                        hull_margin: 0.0,
                    },
                )
                .unwrap();
                assert_eq!(summary.frames, n);
                assert_eq!(summary.cloud_points, n * p);
            });
        }
    });
    for (i, &(n, _)) in runs.iter().enumerate() {
        let counts = topic_counts(&dir.path().join(format!("{i}.mcap")));
        assert_eq!(counts.len(), 5, "{counts:?}");
        assert!(counts.values().all(|&c| c == n), "{counts:?}");
    }
    // Rewriting replaces the file.
    let seq = sequence(1, 1);
    let path = dir.path().join("0.mcap");
    let classes = vec![vec![Class::Glass]];
    write_run_mcap(
        &path,
        &McapRun {
            sequence: &seq,
            classes: &classes,
            rules: &[],
            confidence: &[],
            planes: &[],
            hull_margin: 0.0,
        },
    )
    .unwrap();
    assert!(topic_counts(&path).values().all(|&c| c == 1));
}

/// The trajectory shown stays bounded on long runs, keeps its first
/// and latest pose, and is the whole path on short ones.
#[test]
fn the_trail_is_bounded_and_ends_at_the_latest_pose() {
    let pose = |k: usize| to_pose(&Isometry3::translation(k as f64, 0.0, 0.0));
    let mut short = Trail::default();
    for k in 0..100 {
        short.push(pose(k));
    }
    assert_eq!(short.poses(), (0..100).map(pose).collect::<Vec<_>>());
    let mut long = Trail::default();
    for k in 0..20_000 {
        long.push(pose(k));
        assert!(long.poses().len() <= Trail::MAX + 1);
    }
    let shown = long.poses();
    assert!(shown.len() >= Trail::MAX / 2, "{}", shown.len());
    assert_eq!(shown.first(), Some(&pose(0)));
    assert_eq!(shown.last(), Some(&pose(19_999)));
}

/// A recorder dropped before it finished leaves no file.
#[test]
fn an_unfinished_recording_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.mcap");
    let seq = sequence(1, 3);
    let mut recorder = McapRecorder::create(&path, &[], 0.0).unwrap();
    let frame = seq.frame(0).unwrap();
    recorder
        .add(
            &frame,
            &Isometry3::identity(),
            &[Class::Normal; 3],
            &[],
            &[],
        )
        .unwrap();
    assert!(recorder
        .add(
            &frame,
            &Isometry3::identity(),
            &[Class::Normal; 2],
            &[],
            &[]
        )
        .is_err());
    drop(recorder);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// `/cloud` names its fields at the offsets its records are written
/// with: each point's class, intensity, rule and confidence read back
/// from where the schema says they are.
#[test]
fn cloud_fields_match_the_records() {
    let seq = sequence(1, 3);
    let frame = seq.frame(0).unwrap();
    let pose = Isometry3::translation(1.0, 0.0, 0.0);
    let classes = [Class::Normal, Class::Glass, Class::Reflection];
    let rules = [Rule::Undecided; 3];
    let confidence = [0.25f32, 1.0, 0.5];
    let data = cloud_data(&frame, &pose, &classes, &rules, &confidence);
    let cloud = point_cloud(Timestamp::new(0, 0), data, CLOUD_STRIDE, true);
    assert_eq!(cloud.data.len(), 3 * CLOUD_STRIDE as usize);
    let at = |name: &str| {
        let f = cloud.fields.iter().find(|f| f.name == name).unwrap();
        (f.offset as usize, f.r#type)
    };
    let float = NumericType::Float32 as i32;
    let (off, ty) = at("confidence");
    assert_eq!(ty, float);
    assert_eq!(
        off + 4,
        CLOUD_STRIDE as usize,
        "the last field ends the record"
    );
    for (k, rec) in cloud.data.chunks_exact(CLOUD_STRIDE as usize).enumerate() {
        let f32_at = |o: usize| f32::from_le_bytes(rec[o..o + 4].try_into().unwrap());
        assert_eq!(f32_at(off), confidence[k]);
        assert_eq!(rec[at("class").0], classes[k].id());
        assert_eq!(f32_at(at("intensity").0), 7.0);
        assert_eq!(rec[at("rule").0], Rule::Undecided.id());
        assert_eq!(f32_at(at("x").0), 4.0, "posed: 3 m ahead, 1 m along x");
    }
    // Without confidences the field reads NaN.
    let data = cloud_data(&frame, &pose, &classes, &rules, &[]);
    let p = f32::from_le_bytes(data[off..off + 4].try_into().unwrap());
    assert!(p.is_nan());
}

#[test]
fn mismatched_classes_are_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let seq = sequence(2, 2);
    let err = write_run_mcap(
        &dir.path().join("x.mcap"),
        &McapRun {
            sequence: &seq,
            classes: &[],
            rules: &[],
            confidence: &[],
            planes: &[],
            hull_margin: 0.0,
        },
    );
    assert!(err.is_err());
    assert!(!dir.path().join("x.mcap").exists());
}
