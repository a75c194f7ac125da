//! Issue 39: the readers against damaged files. Small valid files are made
//! here (a PLY frame in ascii and in binary, a TUM and a KITTI pose file, a
//! ROS 2 bag as MCAP and as rosbag2 sqlite3, a factor graph in JSON), then
//! cut short and flipped at random (proptest, 256 cases per reader, 1,792
//! in all, 2-20 s in `cargo test --release` as the machine is loaded): each damaged file is
//! an error or parses to something sound, never a panic.
//!
//! An allocation beyond what the file can hold would show as the test
//! process aborting (out of memory), a hang as the test not ending.

use std::path::{Path, PathBuf};

mod common;

use common::bags::{write_db3, write_mcap, Message};
use proptest::prelude::*;
use specular::backend::synthetic::{synthetic, SyntheticParams};
use specular::cloud::{Frame, Point};
use specular::io::ros2_bag::encode_pointcloud2;
use specular::io::{self, PlyEncoding, StampedPose};

/// Cases per reader.
const CASES: u32 = 256;

/// A frame of 24 labelled points, two returns, one NaN.
fn small_frame() -> Frame {
    Frame {
        name: "1689496219.652560".into(),
        stamp: 1689496219.65256,
        points: (0..24u16)
            .map(|i| Point {
                xyz: if i == 5 {
                    [f32::NAN, 1.0, 1.0]
                } else {
                    [
                        1.0 + i as f32 * 0.25,
                        -2.0 + i as f32 * 0.5,
                        0.125 * i as f32,
                    ]
                },
                intensity: 10.0 + i as f32,
                ring: i % 64,
                ret: 1 + (i % 2) as u8,
                label: [1u8, 2, 5, 6][i as usize % 4],
                time: 0.0,
            })
            .collect(),
        has_labels: true,
        dropped_non_finite: 0,
        intensity_scale: None,
    }
}

/// The bytes of `small_frame` as a PLY file.
fn ply_bytes(dir: &Path, encoding: PlyEncoding) -> Vec<u8> {
    let path = dir.join("1689496219.652560.ply");
    io::write_frame(&path, &small_frame(), encoding).unwrap();
    std::fs::read(path).unwrap()
}

/// A short TUM file.
fn tum_bytes(dir: &Path) -> Vec<u8> {
    let poses: Vec<StampedPose> = (0..5)
        .map(|k| StampedPose {
            stamp: 1689496219.0 + 0.1 * k as f64,
            pose: nalgebra::Isometry3::new(
                nalgebra::Vector3::new(0.1 * k as f64, -0.2, 1.5),
                nalgebra::Vector3::new(0.0, 0.0, 0.05 * k as f64),
            ),
        })
        .collect();
    let path = dir.join("poses.txt");
    io::write_tum(&path, &poses).unwrap();
    std::fs::read(path).unwrap()
}

/// A short KITTI file.
fn kitti_bytes() -> Vec<u8> {
    (0..4)
        .map(|k| format!("1 0 0 {}.5 0 1 0 -0.25 0 0 1 {}\n", k, k * 2))
        .collect::<String>()
        .into_bytes()
}

/// `frames` as CDR messages on `/points`, 0.1 s apart.
fn messages() -> Vec<Message> {
    let mut f = small_frame();
    (0..2)
        .map(|k| {
            f.stamp += 0.1 * k as f64;
            f.name = format!("{:.6}", f.stamp);
            (
                "/points",
                (f.stamp * 1e9) as u64,
                encode_pointcloud2(&f, "lidar"),
            )
        })
        .collect()
}

/// An MCAP bag of two frames (made in `dir`).
fn mcap_bytes(dir: &Path) -> Vec<u8> {
    let path = dir.join("made.mcap");
    write_mcap(&path, &messages());
    std::fs::read(path).unwrap()
}

/// A rosbag2 sqlite3 file of two frames (made in `dir`).
fn db3_bytes(dir: &Path) -> Vec<u8> {
    let path = dir.join("bag.db3");
    write_db3(&path, &messages());
    std::fs::read(path).unwrap()
}

/// A synthetic factor graph of 6 poses as JSON.
fn graph_bytes(dir: &Path) -> Vec<u8> {
    let g = synthetic(&SyntheticParams {
        poses: 6,
        ..SyntheticParams::default()
    })
    .unwrap();
    let path = dir.join("graph.json");
    g.graph.write(&path).unwrap();
    std::fs::read(path).unwrap()
}

/// A damage: cut the file at `cut` (a share of its length; 1.0 keeps it
/// whole), then set the bytes at `flips` (shares of the length) to values.
fn damage(bytes: &[u8], cut: f64, flips: &[(f64, u8)]) -> Vec<u8> {
    let len = ((bytes.len() as f64) * cut).round() as usize;
    let mut out = bytes[..len.min(bytes.len())].to_vec();
    if !out.is_empty() {
        for &(at, v) in flips {
            let i = ((out.len() as f64) * at) as usize;
            let i = i.min(out.len() - 1);
            out[i] = v;
        }
    }
    out
}

/// Cut shares (whole half the time) and up to 6 flips.
fn damages() -> impl Strategy<Value = (f64, Vec<(f64, u8)>)> {
    (
        prop_oneof![Just(1.0), 0.0..1.0f64],
        prop::collection::vec((0.0..1.0f64, any::<u8>()), 0..6),
    )
}

/// The damaged file written to disk, for readers that take a path.
fn on_disk(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// A parsed frame is sound: its points are returns, the count adds up.
fn sound_frame(frame: &Frame, input_points: Option<usize>) {
    assert!(frame.points.iter().all(|p| p.is_return()));
    if let Some(n) = input_points {
        assert!(frame.points.len() + frame.dropped_non_finite <= n.max(1 << 20));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(CASES))]

    /// Ascii PLY: an error naming the file, or a sound frame.
    #[test]
    fn damaged_ascii_ply((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&ply_bytes(tmp.path(), PlyEncoding::Ascii), cut, &flips);
        let path = Path::new("/x/1689496219.652560.ply");
        match io::parse_frame_full(&bytes, path) {
            Ok((frame, aside)) => {
                sound_frame(&frame, None);
                prop_assert_eq!(aside.len(), frame.dropped_non_finite);
            }
            Err(e) => prop_assert!(e.to_string().contains("1689496219.652560.ply")),
        }
    }

    /// Binary PLY: the same.
    #[test]
    fn damaged_binary_ply((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&ply_bytes(tmp.path(), PlyEncoding::BinaryLittleEndian), cut, &flips);
        let path = Path::new("/x/1689496219.652560.ply");
        match io::parse_frame_full(&bytes, path) {
            Ok((frame, aside)) => {
                // A binary body holds at most len / 4 points.
                sound_frame(&frame, Some(bytes.len() / 4));
                prop_assert_eq!(aside.len(), frame.dropped_non_finite);
            }
            Err(e) => prop_assert!(e.to_string().contains("1689496219.652560.ply")),
        }
    }

    /// TUM poses: an error naming the file, or finite unit-quaternion poses.
    #[test]
    fn damaged_tum((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&tum_bytes(tmp.path()), cut, &flips);
        match io::parse_tum(&bytes, Path::new("poses.txt")) {
            Ok(poses) => {
                for p in poses {
                    prop_assert!(p.stamp.is_finite());
                    prop_assert!(p.pose.translation.vector.iter().all(|v| v.is_finite()));
                    prop_assert!((p.pose.rotation.norm() - 1.0).abs() < 1e-9);
                }
            }
            Err(e) => prop_assert!(e.to_string().contains("poses.txt")),
        }
    }

    /// KITTI poses: the same.
    #[test]
    fn damaged_kitti((cut, flips) in damages()) {
        let bytes = damage(&kitti_bytes(), cut, &flips);
        match io::parse_kitti(&bytes, Path::new("poses.kitti")) {
            Ok(poses) => {
                for p in poses {
                    prop_assert!(p.translation.vector.iter().all(|v| v.is_finite()));
                }
            }
            Err(e) => prop_assert!(e.to_string().contains("poses.kitti")),
        }
    }

    /// An MCAP bag: an error naming the file, or sound frames.
    #[test]
    fn damaged_mcap((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&mcap_bytes(tmp.path()), cut, &flips);
        let path = on_disk(tmp.path(), "bag.mcap", &bytes);
        match io::read_bag_frames(&path, "/points") {
            Ok(frames) => frames.iter().for_each(|f| sound_frame(f, Some(bytes.len() / 4))),
            Err(e) => prop_assert!(e.to_string().contains("bag.mcap"), "{}", e),
        }
    }

    /// A rosbag2 sqlite3 file: the same.
    #[test]
    fn damaged_db3((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&db3_bytes(tmp.path()), cut, &flips);
        let path = on_disk(tmp.path(), "damaged.db3", &bytes);
        match io::read_bag_frames(&path, "/points") {
            Ok(frames) => frames.iter().for_each(|f| sound_frame(f, Some(bytes.len() / 4))),
            Err(e) => prop_assert!(e.to_string().contains("damaged.db3"), "{}", e),
        }
    }

    /// A factor graph in JSON: an error naming the file, or a graph.
    #[test]
    fn damaged_graph_json((cut, flips) in damages()) {
        let tmp = tempfile::tempdir().unwrap();
        let bytes = damage(&graph_bytes(tmp.path()), cut, &flips);
        let path = on_disk(tmp.path(), "damaged.json", &bytes);
        match specular::backend::FactorGraph::read(&path) {
            Ok(g) => prop_assert!(g.values.poses.len() <= 6),
            Err(e) => prop_assert!(e.to_string().contains("damaged.json"), "{}", e),
        }
    }
}

/// The valid files themselves parse (so the damage, not the making, is
/// what the cases above exercise).
#[test]
fn the_undamaged_files_parse() {
    let tmp = tempfile::tempdir().unwrap();
    let p = Path::new("/x/1689496219.652560.ply");
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
        let (frame, aside) = io::parse_frame_full(&ply_bytes(tmp.path(), encoding), p).unwrap();
        assert_eq!((frame.points.len(), aside.positions.clone()), (23, vec![5]));
    }
    assert_eq!(io::parse_tum(&tum_bytes(tmp.path()), p).unwrap().len(), 5);
    assert_eq!(io::parse_kitti(&kitti_bytes(), p).unwrap().len(), 4);
    let mcap = on_disk(tmp.path(), "bag.mcap", &mcap_bytes(tmp.path()));
    assert_eq!(io::read_bag_frames(&mcap, "/points").unwrap().len(), 2);
    let db3 = on_disk(tmp.path(), "copy.db3", &db3_bytes(tmp.path()));
    assert_eq!(io::read_bag_frames(&db3, "/points").unwrap().len(), 2);
    let graph = on_disk(tmp.path(), "g.json", &graph_bytes(tmp.path()));
    assert_eq!(
        specular::backend::FactorGraph::read(&graph)
            .unwrap()
            .values
            .poses
            .len(),
        6
    );
}
