//! NaN-safe input end to end (issue 18, finding 3; issue 39, case 1):
//! points with a NaN or infinite coordinate, as real drivers publish them
//! (`is_dense = false`), or exactly at the origin, are set aside when read,
//! from PLY frames and from a ROS 2 bag alike: never classified, never in
//! the maps, written with label 0 at their input position (one label per
//! input point, so every later label stays with its point), and counted in
//! `metrics.json`.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output};

use specular::cloud::{Frame, Point};
use specular::io::{self, PlyEncoding};

/// The bundled sample frames.
fn sample_frames() -> Vec<Frame> {
    let entries = io::list_frames(&common::sample_dir().join("frames")).unwrap();
    let paths: Vec<_> = entries.into_iter().map(|e| e.path).collect();
    io::read_frames(&paths).unwrap()
}

/// `frame` with non-finite points spliced in (every 997th position, NaN or
/// infinite in turn, some with the label of a reflection); returns it and
/// the number added.
fn with_holes(frame: &Frame) -> (Frame, usize) {
    let mut points = Vec::with_capacity(frame.points.len() + frame.points.len() / 997 + 1);
    let mut added = 0;
    for (i, p) in frame.points.iter().enumerate() {
        if i % 997 == 0 {
            let xyz = match added % 4 {
                0 => [f32::NAN; 3],
                1 => [p.xyz[0], f32::NAN, p.xyz[2]],
                2 => [0.0; 3],
                _ => [f32::INFINITY, p.xyz[1], p.xyz[2]],
            };
            points.push(Point {
                xyz,
                label: if added % 2 == 0 { 5 } else { 1 },
                ..*p
            });
            added += 1;
        }
        points.push(*p);
    }
    (
        Frame {
            points,
            ..frame.clone()
        },
        added,
    )
}

fn detect(input: &[&str], out: &Path) -> Output {
    let poses = common::sample_dir().join("poses.txt");
    let mut args = vec!["detect"];
    args.extend_from_slice(input);
    args.extend_from_slice(&[
        "--poses",
        poses.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(&args)
        .output()
        .expect("run specular")
}

/// Every coordinate of a map PLY written by specular (binary: `float x y
/// z`, five `uchar`s, `float confidence`) is finite, and every confidence a
/// probability; returns the vertex count.
fn assert_finite_map(path: &Path) -> usize {
    const RECORD: usize = 21;
    let ply = std::fs::read(path).unwrap();
    let end = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let body = &ply[end..];
    assert_eq!(body.len() % RECORD, 0, "{}", path.display());
    let float = |rec: &[u8], at: usize| f32::from_le_bytes(rec[at..at + 4].try_into().unwrap());
    for rec in body.chunks_exact(RECORD) {
        for k in 0..3 {
            let c = float(rec, 4 * k);
            assert!(c.is_finite(), "{}: coordinate {c}", path.display());
        }
        let p = float(rec, 17);
        assert!(
            (0.0..=1.0).contains(&p),
            "{}: confidence {p}",
            path.display()
        );
    }
    body.len() / RECORD
}

fn dropped_in_metrics(dir: &Path) -> u64 {
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap();
    metrics["dropped_non_finite_points"].as_u64().unwrap()
}

/// Write `frames` as a ROS 2 bag (CDR PointCloud2 on `/points`).
fn write_bag(path: &Path, frames: &[Frame]) {
    use specular::io::ros2_bag::{encode_pointcloud2, POINTCLOUD2, POINTCLOUD2_SCHEMA};
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let schema = w
        .add_schema(POINTCLOUD2, "ros2msg", POINTCLOUD2_SCHEMA.as_bytes())
        .unwrap();
    let channel = w
        .add_channel(schema, "/points", "cdr", &BTreeMap::new())
        .unwrap();
    for (k, f) in frames.iter().enumerate() {
        let t = (f.stamp * 1e9) as u64;
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: t,
            publish_time: t,
        };
        w.write_to_known_channel(&header, &encode_pointcloud2(f, "lidar"))
            .unwrap();
    }
    w.finish().unwrap();
}

/// The clean frames' predictions `want` (`.label` or, with `extension`
/// "prob", `.prob` files: 4 bytes a point either way) with a 0 at every
/// position of `holed` where a point cannot be a return: what a run on the
/// holed frames must write (one value per input point).
fn with_zeros(
    want: &BTreeMap<String, Vec<u8>>,
    holed: &[Frame],
    extension: &str,
) -> BTreeMap<String, Vec<u8>> {
    holed
        .iter()
        .map(|h| {
            let name = format!("{}.{extension}", h.name);
            let mut clean = want[&name].chunks_exact(4);
            let mut out = Vec::with_capacity(4 * h.points.len());
            for p in &h.points {
                if p.is_return() {
                    out.extend_from_slice(clean.next().expect("as many kept points as clean ones"));
                } else {
                    out.extend_from_slice(&0u32.to_le_bytes());
                }
            }
            assert!(clean.next().is_none());
            (name, out)
        })
        .collect()
}

/// PLY frames and a bag with NaN, infinite and origin points give exactly
/// the predictions of the clean frames with a 0 at each such point (one
/// label per input point: on the old code the files were shorter and every
/// later label shifted), maps without a non-finite coordinate, the count in
/// metrics.json and a warning per frame naming it.
#[test]
fn non_finite_points_are_dropped_from_ply_frames_and_bags() {
    let tmp = tempfile::tempdir().unwrap();
    let clean = sample_frames();
    let frames_dir = tmp.path().join("frames");
    std::fs::create_dir(&frames_dir).unwrap();
    let mut holed = Vec::new();
    let mut total = 0;
    for (k, f) in clean.iter().enumerate() {
        let (h, added) = with_holes(f);
        assert!(added > 0);
        total += added;
        // Both encodings: the first frame ascii (`NaN`, `inf`), the rest binary.
        let encoding = if k == 0 {
            PlyEncoding::Ascii
        } else {
            PlyEncoding::BinaryLittleEndian
        };
        io::write_frame(&frames_dir.join(format!("{}.ply", f.name)), &h, encoding).unwrap();
        holed.push(h);
    }

    let reference = tmp.path().join("clean");
    let sample = common::sample_dir().join("frames");
    let o = detect(
        &["--frames", sample.to_str().unwrap(), "--no-mcap"],
        &reference,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(dropped_in_metrics(&reference), 0);
    let want = common::predictions(&reference);
    assert_eq!(want.len(), clean.len());
    for f in &clean {
        assert_eq!(want[&format!("{}.label", f.name)].len(), 4 * f.points.len());
    }

    let want = with_zeros(&want, &holed, "label");
    // The confidences too: 0.0 (four zero bytes) at each hole.
    let want_probs = with_zeros(&common::confidences(&reference), &holed, "prob");
    assert_eq!(want_probs.len(), clean.len());
    let from_ply = tmp.path().join("ply");
    let o = detect(&["--frames", frames_dir.to_str().unwrap()], &from_ply);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert_eq!(
        common::predictions(&from_ply),
        want,
        "NaN points change nothing but their own label, 0"
    );
    assert_eq!(
        common::confidences(&from_ply),
        want_probs,
        "NaN points change nothing but their own confidence, 0"
    );
    assert_eq!(dropped_in_metrics(&from_ply), total as u64);
    for (f, h) in clean.iter().zip(&holed) {
        let n = h.points.len() - f.points.len();
        let line = format!("{}.ply: dropped {n} points", f.name);
        assert!(stderr.contains(&line), "no warning {line:?} in {stderr}");
    }
    assert!(assert_finite_map(&from_ply.join("map.ply")) > 10_000);
    assert!(assert_finite_map(&from_ply.join("around_corner.ply")) > 10_000);
    assert!(from_ply.join("run.mcap").exists());

    let bag = tmp.path().join("holes.mcap");
    write_bag(&bag, &holed);
    let from_bag = tmp.path().join("bag");
    let o = detect(
        &[
            "--bag",
            bag.to_str().unwrap(),
            "--topic",
            "/points",
            "--lean",
        ],
        &from_bag,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        common::predictions(&from_bag),
        want,
        "the bag gives the same"
    );
    assert_eq!(common::confidences(&from_bag), want_probs);
    assert_eq!(dropped_in_metrics(&from_bag), total as u64);
    assert!(assert_finite_map(&from_bag.join("around_corner.ply")) > 10_000);
}
