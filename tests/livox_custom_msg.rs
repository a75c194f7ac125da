//! Livox `CustomMsg` bags (issue 40, part 2): what livox_ros2_driver and
//! livox_ros_driver2 publish with `xfer_format = 1`. Simulated Avia frames
//! (timed: the sweep on) are written as `CustomMsg`s into an MCAP bag and a
//! `.db3` bag (bare, and in a rosbag2 directory) and read back with their positions, returns, rings,
//! reflectivities, per-point times and pulse pairing; a damaged message is
//! an error naming the bag; encode and decode are inverses on random
//! messages; `detect` and `slam --bag` read such a bag.

mod common;

use std::path::Path;

use common::bags::{write_db3_as, write_mcap_as, Message};
use proptest::prelude::*;
use specular::cloud::Frame;
use specular::io::livox_custom::{
    custom_msg_schema, decode_custom_msg, encode_custom_msg, CustomMsg, CustomPoint,
    LIVOX_INTERFACES_CUSTOM_MSG, LIVOX_ROS_DRIVER2_CUSTOM_MSG,
};
use specular::io::pointcloud2::drivers::livox_tag_return;
use specular::io::{read_bag_frames, read_bag_frames_with, BagOptions, Driver};
use specular::sensor::{OrganizedScan, SensorModel};
use specular::sim::{SceneChanges, SceneSource, Simulator};

const TOPIC: &str = "/livox/lidar";

/// Two frames of the Avia in the corridor, fired over the period (each
/// point timed, up to three returns), and the sensor model.
fn avia_frames() -> (SensorModel, Vec<Frame>) {
    let changes = SceneChanges {
        sensor: Some("livox-avia".into()),
        sweep: true,
        ..Default::default()
    };
    let (scene, _) = SceneSource::Named("corridor".into())
        .resolve_with(&changes)
        .unwrap();
    let sim = Simulator::new(&scene);
    let frames = (0..2).map(|k| sim.frame(k, 3).frame).collect();
    (scene.sensor.model, frames)
}

/// The frames as `CustomMsg`s on [`TOPIC`], at their stamps.
fn messages(frames: &[Frame]) -> Vec<Message> {
    frames
        .iter()
        .map(|f| {
            let t = (f.stamp * 1e9).round() as u64;
            (TOPIC, t, encode_custom_msg(f, "livox_frame"))
        })
        .collect()
}

/// `back` is `sent` as a Livox driver carries it: every point where it
/// was, return from the tag bits (a third echo is a later return, 2),
/// line as ring, reflectivity as intensity, time to the nanosecond; and
/// each later return paired with the same emission's return 1.
fn check_frames(model: &SensorModel, sent: &[Frame], back: &[Frame]) {
    assert_eq!(back.len(), sent.len());
    for (b, s) in back.iter().zip(sent) {
        assert_eq!(b.name, s.name);
        assert_eq!(b.dropped_non_finite, 0);
        assert_eq!(b.points.len(), s.points.len());
        assert!(s.points.iter().any(|p| p.ret == 2));
        assert!(s.points.iter().any(|p| p.time > 0.05));
        for (p, q) in b.points.iter().zip(&s.points) {
            assert_eq!(p.xyz, q.xyz);
            assert_eq!(p.ret, q.ret.min(2), "{q:?}");
            assert_eq!(p.ring, q.ring);
            assert_eq!(p.intensity, q.intensity.round().clamp(0.0, 255.0));
            let tolerance = 1e-9 + f32::EPSILON * q.time.abs();
            assert!((p.time - q.time).abs() <= tolerance, "{p:?} {q:?}");
        }
        let (sb, ss) = (
            OrganizedScan::build(b, model).unwrap(),
            OrganizedScan::build(s, model).unwrap(),
        );
        let mut paired = 0;
        for i in 0..s.points.len() {
            assert_eq!(sb.partner(i), ss.partner(i), "point {i}");
            paired += usize::from(s.points[i].ret > 1 && ss.partner(i).is_some());
        }
        assert!(paired > 50, "{paired}");
    }
}

/// A rosbag2 directory as `ros2 bag record -s sqlite3` leaves it: its
/// `metadata.yaml` names the topic's type, the `.db3` file holds the
/// messages.
fn rosbag2_dir(dir: &Path, kind: &str, frames: &[Frame]) {
    std::fs::create_dir_all(dir).unwrap();
    write_db3_as(&dir.join("avia_0.db3"), kind, &messages(frames));
    let meta = format!(
        "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  relative_file_paths:\n  - avia_0.db3\n  topics_with_message_count:\n  - message_count: {}\n    topic_metadata:\n      name: {TOPIC}\n      type: {kind}\n      serialization_format: cdr\n",
        frames.len()
    );
    std::fs::write(dir.join("metadata.yaml"), meta).unwrap();
}

#[test]
fn custom_msg_bags_read_back_the_simulated_avia_frames() {
    let (model, frames) = avia_frames();
    let tmp = tempfile::tempdir().unwrap();
    let mcap = tmp.path().join("avia.mcap");
    let kind = LIVOX_INTERFACES_CUSTOM_MSG;
    write_mcap_as(&mcap, kind, &custom_msg_schema(kind), &messages(&frames));
    let db3 = tmp.path().join("avia.db3");
    write_db3_as(&db3, LIVOX_ROS_DRIVER2_CUSTOM_MSG, &messages(&frames));
    let dir = tmp.path().join("avia_bag");
    rosbag2_dir(&dir, LIVOX_INTERFACES_CUSTOM_MSG, &frames);
    for bag in [&mcap, &db3, &dir] {
        check_frames(&model, &frames, &read_bag_frames(bag, TOPIC).unwrap());
        let options = BagOptions {
            driver: Some(Driver::Livox),
            second_topic: None,
        };
        let back = read_bag_frames_with(bag, TOPIC, &options).unwrap();
        check_frames(&model, &frames, &back);
    }
}

/// The tag bits read as the `PointCloud2` layout reads them.
#[test]
fn the_return_is_the_tag_bits_of_the_pointcloud2_layout() {
    for tag in 0..=255u8 {
        let msg = CustomMsg {
            sec: 1,
            points: vec![CustomPoint {
                x: 2.0,
                tag,
                ..Default::default()
            }],
            ..Default::default()
        };
        let d = decode_custom_msg(&msg.encode()).unwrap();
        assert_eq!(d.frame.points[0].ret, livox_tag_return(tag), "{tag:#b}");
    }
}

/// A bag whose second message is cut short: an error naming the bag, the
/// topic, the message and where it ends, not a panic. Another named
/// driver, and a topic of another type, are errors too.
#[test]
fn damaged_and_mismatched_custom_msg_bags_are_errors() {
    let (_, frames) = avia_frames();
    let tmp = tempfile::tempdir().unwrap();
    let mut msgs = messages(&frames);
    let cut = msgs[1].2.len() - 30;
    msgs[1].2.truncate(cut);
    let kind = LIVOX_ROS_DRIVER2_CUSTOM_MSG;
    let mcap = tmp.path().join("cut.mcap");
    write_mcap_as(&mcap, kind, &custom_msg_schema(kind), &msgs);
    let db3 = tmp.path().join("cut.db3");
    write_db3_as(&db3, kind, &msgs);
    for bag in [&mcap, &db3] {
        let err = read_bag_frames(bag, TOPIC).unwrap_err().to_string();
        assert!(
            err.starts_with(&format!("{}: {TOPIC} message at", bag.display())),
            "{err}"
        );
        assert!(err.contains("truncated"), "{err}");
    }
    let whole = tmp.path().join("whole.db3");
    write_db3_as(&whole, kind, &messages(&frames));
    let options = BagOptions {
        driver: Some(Driver::Ouster),
        second_topic: None,
    };
    let err = read_bag_frames_with(&whole, TOPIC, &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("read with the livox layout, not ouster"),
        "{err}"
    );
    let chatter = tmp.path().join("chatter.db3");
    write_db3_as(
        &chatter,
        "std_msgs/msg/String",
        &[(TOPIC, 0, vec![0, 1, 0, 0])],
    );
    let err = read_bag_frames(&chatter, TOPIC).unwrap_err().to_string();
    for kind in [
        "sensor_msgs/msg/PointCloud2",
        LIVOX_INTERFACES_CUSTOM_MSG,
        LIVOX_ROS_DRIVER2_CUSTOM_MSG,
    ] {
        assert!(err.contains(kind), "{err}");
    }
}

fn custom_point() -> impl Strategy<Value = CustomPoint> {
    let xyz = (-500.0f32..500.0, -500.0f32..500.0, -500.0f32..500.0);
    (any::<u32>(), xyz, any::<[u8; 3]>()).prop_map(|(t, (x, y, z), [r, tag, line])| CustomPoint {
        offset_time: t,
        x,
        y,
        z,
        reflectivity: r,
        tag,
        line,
    })
}

fn custom_msg() -> impl Strategy<Value = CustomMsg> {
    (
        (any::<i32>(), 0u32..1_000_000_000, "[a-z_]{0,20}"),
        (any::<u64>(), any::<u32>(), any::<u8>(), any::<[u8; 3]>()),
        prop::collection::vec(custom_point(), 0..40),
    )
        .prop_map(
            |((sec, nanosec, frame_id), (timebase, point_num, lidar_id, rsvd), points)| CustomMsg {
                sec,
                nanosec,
                frame_id,
                timebase,
                point_num,
                lidar_id,
                rsvd,
                points,
            },
        )
}

proptest! {
    /// Parse after encode is the identity, whatever the frame id's length
    /// (every padding before `timebase`); every cut short is an error; the
    /// decoded points are the message's, timed `timebase + offset_time -
    /// stamp`.
    #[test]
    fn encode_then_decode_is_the_identity(msg in custom_msg()) {
        let data = msg.encode();
        prop_assert_eq!(&CustomMsg::parse(&data).unwrap(), &msg);
        let n = msg.points.len();
        let padding = (8 - (12 + msg.frame_id.len() + 1) % 8) % 8;
        let header = 4 + 12 + msg.frame_id.len() + 1 + padding + 20;
        prop_assert_eq!(data.len(), header + (20 * n).saturating_sub(1));
        prop_assert!(CustomMsg::parse(&data[..data.len() - 1]).is_err());
        let d = decode_custom_msg(&data).unwrap();
        let kept: Vec<&CustomPoint> = msg.points.iter().filter(|p| (p.x, p.y, p.z) != (0.0, 0.0, 0.0)).collect();
        prop_assert_eq!(d.frame.points.len(), kept.len());
        for (p, q) in d.frame.points.iter().zip(kept) {
            prop_assert_eq!(p.xyz, [q.x, q.y, q.z]);
            prop_assert_eq!(p.ring, q.line as u16);
            prop_assert_eq!(p.intensity, q.reflectivity as f32);
            prop_assert_eq!(p.ret, livox_tag_return(q.tag));
            prop_assert_eq!(p.time, msg.time_of(q));
        }
    }
}

/// `detect` and `slam` read a `CustomMsg` bag as the Avia's (`--sensor
/// livox-avia`), one label per point.
#[test]
fn detect_and_slam_read_a_custom_msg_bag() {
    let (_, frames) = avia_frames();
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("avia.mcap");
    let kind = LIVOX_INTERFACES_CUSTOM_MSG;
    write_mcap_as(&bag, kind, &custom_msg_schema(kind), &messages(&frames));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let input = [
        "--bag",
        &s(&bag),
        "--topic",
        TOPIC,
        "--sensor",
        "livox-avia",
    ];
    let out = tmp.path().join("detect");
    let mut args = vec!["detect"];
    args.extend_from_slice(&input);
    args.extend_from_slice(&["--method", "single-scan", "--lean", "--out"]);
    let out_s = s(&out);
    args.push(&out_s);
    let o = common::specular(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let predictions = common::predictions(&out);
    assert_eq!(predictions.len(), 2);
    for (labels, f) in predictions.values().zip(&frames) {
        assert_eq!(labels.len(), 4 * f.points.len());
    }
    let out = tmp.path().join("slam");
    let out_s = s(&out);
    let mut args = vec!["slam"];
    args.extend_from_slice(&input);
    args.extend_from_slice(&["--driver", "livox", "--out", &out_s]);
    let o = common::specular(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let poses = std::fs::read_to_string(out.join("poses.txt")).unwrap();
    assert_eq!(poses.lines().count(), 2);
}
