//! The outputs for people: the Foxglove recording, the PLY maps, the plots
//! and the report.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

fn detect_sample(out: &Path, extra: &[&str]) -> Output {
    let sample = common::sample_dir();
    let frames = sample.join("frames");
    let poses = sample.join("poses.txt");
    let mut args = vec![
        "detect",
        "--frames",
        frames.to_str().unwrap(),
        "--poses",
        poses.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(&args)
        .output()
        .expect("run specular")
}

/// Vertex count and the property names of a PLY file; checks the body size
/// for binary little-endian files of float/uchar properties.
fn ply_header(path: &Path) -> (usize, Vec<String>) {
    let ply = std::fs::read(path).unwrap();
    assert!(ply.starts_with(b"ply\n"), "{}", path.display());
    let end = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8_lossy(&ply[..end]).into_owned();
    let count: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    let props: Vec<(String, String)> = header
        .lines()
        .filter_map(|l| l.strip_prefix("property "))
        .map(|l| {
            let (t, n) = l.split_once(' ').unwrap();
            (t.to_string(), n.to_string())
        })
        .collect();
    let stride: usize = props
        .iter()
        .map(|(t, _)| if t == "float" { 4 } else { 1 })
        .sum();
    assert_eq!(ply.len() - end, count * stride, "{}", path.display());
    (count, props.into_iter().map(|(_, n)| n).collect())
}

#[test]
fn detect_writes_mcap_maps_plots_and_report() {
    let out = tempfile::tempdir().unwrap();
    let o = detect_sample(out.path(), &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let dir = out.path();

    // MCAP: schemas, topics and one message per frame on every topic.
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let mut counts: BTreeMap<String, (String, String, usize)> = BTreeMap::new();
    let mut stamps = Vec::new();
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let schema = msg.channel.schema.as_ref().unwrap();
        let e = counts.entry(msg.channel.topic.clone()).or_insert((
            schema.name.clone(),
            msg.channel.message_encoding.clone(),
            0,
        ));
        e.2 += 1;
        if msg.channel.topic == "/cloud" {
            stamps.push(msg.log_time);
            // The point fields are named in each message (protobuf
            // strings): the confidence is among them.
            for name in [&b"rule"[..], b"confidence"] {
                assert!(
                    msg.data.windows(name.len()).any(|w| w == name),
                    "/cloud lacks the field {}",
                    String::from_utf8_lossy(name)
                );
            }
        }
    }
    let expect = [
        ("/cloud", "foxglove.PointCloud"),
        ("/mirrored", "foxglove.PointCloud"),
        ("/planes", "foxglove.SceneUpdate"),
        ("/tf", "foxglove.FrameTransform"),
        ("/trajectory", "foxglove.PosesInFrame"),
    ];
    assert_eq!(counts.len(), expect.len(), "{counts:?}");
    for (topic, schema) in expect {
        let (s, enc, n) = &counts[topic];
        assert_eq!(s, schema, "{topic}");
        assert_eq!(enc, "protobuf", "{topic}");
        assert_eq!(*n, 3, "{topic}: one message per frame");
    }
    // Log time = frame timestamp (the first sample frame is 1689496219.652560).
    assert_eq!(stamps.len(), 3);
    assert!((stamps[0] as f64 * 1e-9 - 1_689_496_219.652_56).abs() < 1e-3);
    assert!(stamps.windows(2).all(|w| w[0] < w[1]));

    // PLY maps.
    let (n_map, props) = ply_header(&dir.join("map.ply"));
    assert!(n_map > 10_000, "{n_map}");
    for p in [
        "x",
        "y",
        "z",
        "red",
        "green",
        "blue",
        "class",
        "mirrored",
        "confidence",
    ] {
        assert!(props.iter().any(|q| q == p), "map.ply lacks {p}");
    }
    let (n_corner, _) = ply_header(&dir.join("around_corner.ply"));
    assert!(n_corner > 10_000, "{n_corner}");

    // Plots are PNG files.
    for png in ["topdown.png", "trajectory.png", "metrics.png"] {
        let b = std::fs::read(dir.join(png)).unwrap();
        assert!(b.starts_with(b"\x89PNG\r\n\x1a\n"), "{png}");
        assert!(b.len() > 5_000, "{png}: {} bytes", b.len());
    }
    // No temporary files are left behind.
    for e in std::fs::read_dir(dir).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        assert!(!name.contains(".tmp"), "{name}");
    }

    // Report: metrics table, plots, files, command line, configuration.
    let report = std::fs::read_to_string(dir.join("report.md")).unwrap();
    for needle in [
        "| class | precision % |",
        "![Top-down map](topdown.png)",
        "![Per-class scores](metrics.png)",
        "[run.mcap](run.mcap)",
        "[map.ply](map.ply)",
        "detect --frames",
        "```toml",
    ] {
        assert!(report.contains(needle), "report lacks {needle}:\n{report}");
    }
}

#[test]
fn no_mcap_skips_the_recording() {
    let out = tempfile::tempdir().unwrap();
    let o = detect_sample(out.path(), &["--no-mcap", "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.path().join("run.mcap").exists());
    assert!(out.path().join("report.md").exists());
    assert!(out.path().join("map.ply").exists());
}

#[test]
fn single_scan_without_poses_still_reports() {
    let sample = common::sample_dir();
    let out = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args([
            "detect",
            "--frames",
            sample.join("frames").to_str().unwrap(),
            "--method",
            "single-scan",
            "--out",
            out.path().to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        !out.path().join("run.mcap").exists(),
        "no poses: no recording"
    );
    assert!(out.path().join("metrics.png").exists());
    assert!(out.path().join("report.md").exists());
}

/// Write the bundled sample as a ROS 2 bag (CDR PointCloud2 on `/points`,
/// plus an unrelated topic) with the mcap crate.
fn write_sample_bag(path: &Path) {
    use specular::io::ros2_bag::{encode_pointcloud2, POINTCLOUD2, POINTCLOUD2_SCHEMA};
    let entries = specular::io::list_frames(&common::sample_dir().join("frames")).unwrap();
    let paths: Vec<_> = entries.into_iter().map(|e| e.path).collect();
    let frames = specular::io::read_frames(&paths).unwrap();
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let schema = w
        .add_schema(POINTCLOUD2, "ros2msg", POINTCLOUD2_SCHEMA.as_bytes())
        .unwrap();
    let points = w
        .add_channel(schema, "/points", "cdr", &BTreeMap::new())
        .unwrap();
    let other = w
        .add_channel(0, "/chatter", "json", &BTreeMap::new())
        .unwrap();
    // Reverse order: the reader sorts by stamp.
    for (k, f) in frames.iter().enumerate().rev() {
        let t = (f.stamp * 1e9) as u64;
        let header = |channel_id| mcap::records::MessageHeader {
            channel_id,
            sequence: k as u32,
            log_time: t,
            publish_time: t,
        };
        w.write_to_known_channel(&header(points), &encode_pointcloud2(f, "lidar"))
            .unwrap();
        w.write_to_known_channel(&header(other), b"{}").unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn a_ros2_bag_gives_the_same_predictions_as_the_ply_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("sample.mcap");
    write_sample_bag(&bag);
    let from_ply = tmp.path().join("ply");
    let o = detect_sample(&from_ply, &["--no-mcap"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let from_bag = tmp.path().join("bag");
    let poses = common::sample_dir().join("poses.txt");
    let run = |topic: &str| {
        Command::new(env!("CARGO_BIN_EXE_specular"))
            .args([
                "detect",
                "--bag",
                bag.to_str().unwrap(),
                "--topic",
                topic,
                "--poses",
                poses.to_str().unwrap(),
                "--out",
                from_bag.to_str().unwrap(),
                "--no-mcap",
            ])
            .output()
            .unwrap()
    };
    let o = run("/points");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (
        common::predictions(&from_ply),
        common::predictions(&from_bag),
    );
    assert_eq!(a.len(), 3);
    assert_eq!(a, b, "identical predictions from the bag");
    assert_eq!(
        std::fs::read(from_ply.join("metrics.json")).unwrap(),
        std::fs::read(from_bag.join("metrics.json")).unwrap()
    );
    // A wrong topic names the topics present.
    let o = run("/nope");
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("/points") && err.contains("/chatter"), "{err}");
    // A topic of another type is a clear error.
    let o = run("/chatter");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains(POINTCLOUD2_NAME));
}

const POINTCLOUD2_NAME: &str = "sensor_msgs/msg/PointCloud2";
