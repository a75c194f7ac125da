//! Integration tests of `specular::io`: round trips, the real 3DRef demo
//! frames, and one test per kind of bad input (each checking the message and
//! that it names the file).

mod common;

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use specular::cloud::{Frame, IntensityScale, Point};
use specular::io::{
    list_frames, match_poses, parse_frame, read_frame, read_frames, read_labels, read_tum,
    write_frame, write_labels, write_tum, PlyEncoding, StampedPose,
};

const DEMO_FRAME: &str = "1689496219.652560.ply";

fn demo_dir() -> Option<PathBuf> {
    common::shared_frames()
}

fn sample_frame(has_labels: bool) -> Frame {
    let points = (0..500u32)
        .map(|i| {
            let f = i as f32;
            Point {
                xyz: [
                    (f * 0.731).sin() * 12.345_679,
                    -(f * 1.3e-3),
                    f32::from_bits(0x3f80_0000 + i * 7919),
                ],
                intensity: (i % 256) as f32,
                ring: (i % 64) as u16,
                ret: 1 + (i % 2) as u8,
                label: if has_labels { (i % 7) as u8 } else { 0 },
                time: 0.0,
            }
        })
        .collect();
    Frame {
        name: "1689496219.652560".into(),
        stamp: 1689496219.65256,
        points,
        has_labels,
        dropped_non_finite: 0,
        intensity_scale: None,
    }
}

/// A synthetic ascii frame with the real files' header and `rows` as body.
fn ascii_ply(props: &[&str], rows: &[&str]) -> Vec<u8> {
    let mut s = format!("ply\nformat ascii 1.0\nelement vertex {}\n", rows.len());
    for p in props {
        s += &format!("property float {p}\n");
    }
    s += "end_header\n";
    for r in rows {
        s += r;
        s += "\n";
    }
    s.into_bytes()
}

const PROPS: [&str; 10] = [
    "x",
    "y",
    "z",
    "nx",
    "ny",
    "nz",
    "intensity",
    "ring",
    "return",
    "label",
];
const ROW: &str = "2.6758089 11.371753 1.3117709 0.98 0.04 0.14 14.0 36.0 1.0 4.0";

fn path() -> &'static Path {
    Path::new("/data/1689496219.652560.ply")
}

/// Parse `bytes` expecting an error; check the message holds `want` and
/// the file name.
fn expect_err(bytes: &[u8], want: &str) {
    let err = parse_frame(bytes, path())
        .expect_err("parse should fail")
        .to_string();
    assert!(err.contains(want), "message {err:?} lacks {want:?}");
    assert!(err.contains("1689496219.652560.ply"), "no file name: {err}");
}

// --- round trips --------------------------------------------------------

#[test]
fn ply_round_trip_binary_and_ascii() {
    let dir = tempfile::tempdir().unwrap();
    for labels in [true, false] {
        let frame = sample_frame(labels);
        for enc in [PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii] {
            let p = dir.path().join("1689496219.652560.ply");
            write_frame(&p, &frame, enc).unwrap();
            let back = read_frame(&p).unwrap();
            assert_eq!(back.name, frame.name);
            assert_eq!(back.stamp, frame.stamp);
            assert_eq!(back.has_labels, labels);
            assert_eq!(back.points, frame.points, "{enc:?} labels={labels}");
            assert_eq!(back.intensity_scale, None);
        }
    }
}

/// A frame that says what its intensities measure says so in its header
/// (the simulator's raw power), and reads back the same; a scale the reader
/// does not know is an error naming it.
#[test]
fn ply_round_trip_keeps_the_intensity_scale() {
    let dir = tempfile::tempdir().unwrap();
    for scale in [IntensityScale::RawPower, IntensityScale::Reflectivity] {
        let frame = Frame {
            intensity_scale: Some(scale),
            ..sample_frame(true)
        };
        for enc in [PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii] {
            let p = dir.path().join("1689496219.652560.ply");
            write_frame(&p, &frame, enc).unwrap();
            let back = read_frame(&p).unwrap();
            assert_eq!(back.intensity_scale, Some(scale), "{enc:?}");
            assert_eq!(back.points, frame.points);
        }
    }
    let mut bytes = ascii_ply(&PROPS, &[ROW]);
    let at = bytes.windows(7).position(|w| w == b"element").unwrap();
    bytes.splice(
        at..at,
        b"comment intensity_scale raw-power\n".iter().copied(),
    );
    let frame = parse_frame(&bytes, path()).unwrap();
    assert_eq!(frame.intensity_scale, Some(IntensityScale::RawPower));
    let bad = String::from_utf8(bytes)
        .unwrap()
        .replace("raw-power", "photons");
    expect_err(bad.as_bytes(), "unknown intensity_scale 'photons'");
}

#[test]
fn tum_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("poses.txt");
    let poses: Vec<StampedPose> = (0..20)
        .map(|i| StampedPose {
            stamp: 1689496219.65256 + i as f64 * 0.1,
            pose: Isometry3::from_parts(
                Translation3::new(i as f64 * 0.5, -1.25, 0.125),
                UnitQuaternion::from_scaled_axis(Vector3::new(0.1, -0.2, 0.3 * i as f64)),
            ),
        })
        .collect();
    write_tum(&p, &poses).unwrap();
    let back = read_tum(&p).unwrap();
    assert_eq!(back.len(), poses.len());
    for (a, b) in poses.iter().zip(&back) {
        assert!((a.stamp - b.stamp).abs() < 1e-6);
        assert!((a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-9);
        assert!(a.pose.rotation.angle_to(&b.pose.rotation) < 1e-8);
    }
}

#[test]
fn tum_comments_blank_lines_and_normalisation() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("poses.txt");
    std::fs::write(&p, "# header\n\n1.0 1 2 3 0 0 0 2\n  \n2.0 0 0 0 0 0 1 1\n").unwrap();
    let poses = read_tum(&p).unwrap();
    assert_eq!(poses.len(), 2);
    assert_eq!(poses[0].pose.rotation, UnitQuaternion::identity());
    assert!((poses[1].pose.rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
}

#[test]
fn labels_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("predictions/1689496219.652560.label");
    let labels: Vec<u8> = (0..1000).map(|i| (i % 7) as u8).collect();
    write_labels(&p, &labels).unwrap();
    assert_eq!(std::fs::metadata(&p).unwrap().len(), 4000);
    let back = read_labels(&p).unwrap();
    assert_eq!(back, labels.iter().map(|&l| l as u32).collect::<Vec<_>>());
}

// --- variants the reader accepts -----------------------------------------

#[test]
fn ply_other_types_elements_and_crlf() {
    // Typed properties, an element before and after the vertices, comments,
    // CRLF line ends, and no label.
    let text = "ply\r\nformat ascii 1.0\r\ncomment x\r\nobj_info y\r\n\
                element camera 1\r\nproperty double f\r\n\
                element vertex 2\r\nproperty int16 ring\r\nproperty double x\r\n\
                property float32 y\r\nproperty float z\r\nproperty uchar return\r\n\
                property uint8 intensity\r\nelement face 1\r\nproperty int n\r\n\
                end_header\r\n3.5\r\n7 1.5 -2 3e-1 2 200\r\n\r\n0 -0 .5 1E2 1 0\r\n9\r\n";
    let f = parse_frame(text.as_bytes(), path()).unwrap();
    assert!(!f.has_labels);
    assert_eq!(f.points.len(), 2);
    assert_eq!(
        f.points[0],
        Point {
            xyz: [1.5, -2.0, 0.3],
            intensity: 200.0,
            ring: 7,
            ret: 2,
            label: 0,
            time: 0.0,
        }
    );
    assert_eq!(f.points[1].xyz, [-0.0, 0.5, 100.0]);
}

#[test]
fn binary_with_doubles_and_extra_element() {
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\n\
                  property double x\nproperty double y\nproperty double z\n\
                  property float nx\nproperty uchar intensity\nproperty ushort ring\n\
                  property char return\nproperty uint label\n\
                  element extra 1\nproperty short s\nend_header\n"
        .to_vec();
    for i in 0..2u32 {
        for c in [1.25f64, -2.5, 3.0 + i as f64] {
            b.extend_from_slice(&c.to_le_bytes());
        }
        b.extend_from_slice(&9.0f32.to_le_bytes());
        b.push(17);
        b.extend_from_slice(&(63u16 - i as u16).to_le_bytes());
        b.push(1 + i as u8);
        b.extend_from_slice(&6u32.to_le_bytes());
    }
    b.extend_from_slice(&5i16.to_le_bytes());
    let f = parse_frame(&b, path()).unwrap();
    assert!(f.has_labels);
    assert_eq!(f.points.len(), 2);
    assert_eq!(
        f.points[1],
        Point {
            xyz: [1.25, -2.5, 4.0],
            intensity: 17.0,
            ring: 62,
            ret: 2,
            label: 6,
            time: 0.0,
        }
    );
    // One byte short: truncated.
    expect_err(&b[..b.len() - 3], "truncated");
}

// --- the real demo data ---------------------------------------------------

// The literals are the text of the file, as written there.
#[allow(clippy::excessive_precision)]
#[test]
fn real_frame() {
    let Some(dir) = demo_dir() else { return };
    let f = read_frame(&dir.join(DEMO_FRAME)).unwrap();
    assert_eq!(f.name, "1689496219.652560");
    assert_eq!(f.stamp, 1689496219.65256);
    assert_eq!(f.points.len(), 33_718);
    assert_eq!(f.points.iter().filter(|p| p.ret == 1).count(), 32_627);
    assert_eq!(f.second_returns(), 1_091);
    assert!(f.has_labels);
    assert!(f.points.iter().all(|p| p.ring < 64));
    // The first line of the file.
    assert_eq!(
        f.points[0],
        Point {
            xyz: [2.6758089, 11.371753, 1.3117709],
            intensity: 14.0,
            ring: 36,
            ret: 1,
            label: 4,
            time: 0.0,
        }
    );
    // Binary round trip of real data.
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join(DEMO_FRAME);
    write_frame(&p, &f, PlyEncoding::BinaryLittleEndian).unwrap();
    assert_eq!(read_frame(&p).unwrap().points, f.points);
}

#[test]
fn real_frames_match_poses_by_timestamp() {
    let Some(dir) = demo_dir() else { return };
    let frames = list_frames(&dir).unwrap();
    assert_eq!(frames.len(), 10);
    assert!(frames.windows(2).all(|w| w[0].stamp < w[1].stamp));
    let pose_path = dir.join("hesai_pose.txt");
    let poses = read_tum(&pose_path).unwrap();
    let matched = match_poses(&frames, &poses, 0.005, &pose_path).unwrap();
    assert_eq!(matched.len(), 10);
    for (f, m) in frames.iter().zip(&matched) {
        let exact: Vec<&StampedPose> = poses.iter().filter(|p| p.stamp == f.stamp).collect();
        assert_eq!(exact.len(), 1, "frame {}", f.name);
        assert_eq!(exact[0].pose, *m, "frame {}", f.name);
    }
    let paths: Vec<PathBuf> = frames.iter().map(|f| f.path.clone()).collect();
    let all = read_frames(&paths).unwrap();
    assert_eq!(all.len(), 10);
    for (f, e) in all.iter().zip(&frames) {
        assert_eq!(f.name, e.name);
    }
}

#[test]
fn truncated_real_frame() {
    let Some(dir) = demo_dir() else { return };
    let bytes = std::fs::read(dir.join(DEMO_FRAME)).unwrap();
    // Cut in the middle of the body (mid-line).
    let cut = &bytes[..bytes.len() / 2 + 7];
    let err = parse_frame(cut, path()).unwrap_err().to_string();
    assert!(
        err.contains("expected 33718 vertices, file ends after"),
        "{err}"
    );
    assert!(
        err.contains("(truncated?)") && err.contains(DEMO_FRAME),
        "{err}"
    );
}

// --- one test per bad input ------------------------------------------------

#[test]
fn truncated_synthetic() {
    let mut b = ascii_ply(&PROPS, &[ROW, ROW, ROW]);
    let text = String::from_utf8(b.clone()).unwrap();
    b.truncate(text.rfind(ROW).unwrap());
    expect_err(&b, "expected 3 vertices, file ends after 2 (truncated?)");
}

#[test]
fn header_without_return() {
    let props: Vec<&str> = PROPS.iter().copied().filter(|p| *p != "return").collect();
    expect_err(
        &ascii_ply(&props, &["1 2 3 0 0 0 5 6 0"]),
        "header has no 'return' property (3DRef frames need x y z intensity ring return)",
    );
}

#[test]
fn header_without_ring() {
    let props: Vec<&str> = PROPS.iter().copied().filter(|p| *p != "ring").collect();
    expect_err(
        &ascii_ply(&props, &["1 2 3 0 0 0 5 1 0"]),
        "header has no 'ring' property",
    );
}

#[test]
fn non_numeric_field() {
    let bad = "2.6758089 11.371753 abc 0.98 0.04 0.14 14.0 36.0 1.0 4.0";
    // 3 header lines + 10 properties + end_header: the second vertex is line 16.
    expect_err(
        &ascii_ply(&PROPS, &[ROW, bad]),
        "line 16: property 'z' is not a number: 'abc'",
    );
}

/// Non-finite coordinates are not errors: the point is dropped and counted
/// (real recordings hold such points), in both encodings.
#[test]
fn nan_coordinates_are_dropped() {
    let bad = "2.6758089 nan 1.0 0.98 0.04 0.14 14.0 36.0 1.0 4.0";
    let frame = parse_frame(&ascii_ply(&PROPS, &[ROW, ROW, ROW, ROW, ROW, bad]), path()).unwrap();
    assert_eq!((frame.points.len(), frame.dropped_non_finite), (5, 1));
    let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 2\n".to_vec();
    for p in ["x", "y", "z", "intensity", "ring", "return"] {
        b.extend_from_slice(format!("property float {p}\n").as_bytes());
    }
    b.extend_from_slice(b"end_header\n");
    for v in [
        f32::NAN,
        0.0,
        0.0,
        1.0,
        1.0,
        1.0,
        1.0,
        2.0,
        3.0,
        1.0,
        1.0,
        1.0,
    ] {
        b.extend_from_slice(&v.to_le_bytes());
    }
    let frame = parse_frame(&b, path()).unwrap();
    assert_eq!(frame.dropped_non_finite, 1);
    assert_eq!(frame.points.len(), 1);
    assert_eq!(frame.points[0].xyz, [1.0, 2.0, 3.0]);
}

#[test]
fn empty_frame() {
    expect_err(&ascii_ply(&PROPS, &[]), "frame has no points");
}

#[test]
fn bad_return_ring_label_and_field_count() {
    let row = |ring: &str, ret: &str, label: &str| format!("1 2 3 0 0 0 5 {ring} {ret} {label}");
    expect_err(
        &ascii_ply(&PROPS, &[&row("3", "4", "0")]),
        "return must be 1, 2 or 3 (a third return: Livox), got 4",
    );
    expect_err(
        &ascii_ply(&PROPS, &[&row("-1", "1", "0")]),
        "ring must be an integer in 0..=65535, got -1",
    );
    expect_err(
        &ascii_ply(&PROPS, &[&row("2.5", "1", "0")]),
        "ring must be an integer",
    );
    expect_err(
        &ascii_ply(&PROPS, &[&row("70000", "1", "0")]),
        "ring must be an integer",
    );
    expect_err(
        &ascii_ply(&PROPS, &[&row("1", "1", "7")]),
        "label must be an integer in 0..=6, got 7",
    );
    expect_err(
        &ascii_ply(&PROPS, &["1 2 3 0 0 0 5 1 1", ROW]),
        "line 15: too few fields (found 9, the header declares 10)",
    );
    expect_err(
        &ascii_ply(&PROPS, &[&format!("{ROW} 9")]),
        "line 15: too many fields",
    );
}

#[test]
fn header_errors() {
    let body = ascii_ply(&PROPS, &[ROW]);
    let text = String::from_utf8(body.clone()).unwrap();
    expect_err(
        text.replace("ascii", "binary_big_endian").as_bytes(),
        "unsupported",
    );
    expect_err(
        text.replace("end_header\n", "").as_bytes(),
        "unknown keyword '2.6758089' (is the end_header line missing?)",
    );
    expect_err(
        &body[..text.find("end_header").unwrap()],
        "header has no end_header line",
    );
    expect_err(b"hello\n", "not a PLY file");
    let mut bad = body.clone();
    bad[12] = 0xff; // inside "format ascii 1.0"
    expect_err(&bad, "not valid UTF-8");
    expect_err(
        text.replace(
            "element vertex 1",
            "element vertex 1\nproperty list uchar int idx",
        )
        .as_bytes(),
        "list properties are not supported",
    );
    let err = parse_frame(&body, Path::new("/d/scan.ply"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("file name must be <timestamp>.ply") && err.contains("scan.ply"),
        "{err}"
    );
}

#[test]
fn frame_without_pose_within_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let poses_path = dir.path().join("hesai_pose.txt");
    std::fs::write(
        &poses_path,
        "1689496218.921560 0 0 0 0 0 0 1\n1689496221.000000 0 0 0 0 0 0 1\n",
    )
    .unwrap();
    std::fs::write(
        dir.path().join("1689496219.652560.ply"),
        ascii_ply(&PROPS, &[ROW]),
    )
    .unwrap();
    let frames = list_frames(dir.path()).unwrap();
    let poses = read_tum(&poses_path).unwrap();
    let err = match_poses(&frames, &poses, 0.005, &poses_path)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no pose within 0.005 s of frame 1689496219.652560 (nearest is 0.731 s away)"),
        "{err}"
    );
    assert!(err.contains("hesai_pose.txt"), "{err}");
}

#[test]
fn frame_dir_errors() {
    let dir = tempfile::tempdir().unwrap();
    let err = list_frames(dir.path()).unwrap_err().to_string();
    assert!(err.contains("no *.ply frames in"), "{err}");
    let err = list_frames(&dir.path().join("missing"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("missing"), "{err}");
    std::fs::write(dir.path().join("scan.ply"), b"").unwrap();
    let err = list_frames(dir.path()).unwrap_err().to_string();
    assert!(
        err.contains("scan.ply") && err.contains("file name must be <timestamp>.ply"),
        "{err}"
    );
}

#[test]
fn tum_bad_lines() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("poses.txt");
    let cases = [
        ("1 2 3 4 5 6 7\n", "line 1: expected 8 fields"),
        (
            "# c\n1 2 3 x 0 0 0 1\n",
            "line 2: field 'tz' is not a number: 'x'",
        ),
        ("1 2 3 4 0 0 0 nan\n", "line 1: field 'qw' is not finite"),
        ("\n1 2 3 4 0 0 0 0\n", "line 2: quaternion has zero norm"),
    ];
    for (text, want) in cases {
        std::fs::write(&p, text).unwrap();
        let err = read_tum(&p).unwrap_err().to_string();
        assert!(err.contains(want) && err.contains("poses.txt"), "{err}");
    }
}

#[test]
fn label_file_with_bad_length() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("1689496219.652560.label");
    std::fs::write(&p, [0u8; 10]).unwrap();
    let err = read_labels(&p).unwrap_err().to_string();
    assert!(
        err.contains("not a multiple of 4") && err.contains("1689496219.652560.label"),
        "{err}"
    );
}

// --- never panic -----------------------------------------------------------

proptest! {
    #[test]
    fn arbitrary_body_never_panics(
        body in proptest::collection::vec(any::<u8>(), 0..2000),
        text in "[0-9eE+\\-. \nnaif]{0,400}",
        binary in any::<bool>(),
        count in 0usize..50,
    ) {
        let mut h = format!(
            "ply\nformat {} 1.0\nelement vertex {count}\n",
            if binary { "binary_little_endian" } else { "ascii" }
        );
        for p in PROPS {
            h += &format!("property float {p}\n");
        }
        h += "end_header\n";
        for tail in [body.as_slice(), text.as_bytes()] {
            let mut b = h.clone().into_bytes();
            b.extend_from_slice(tail);
            let _ = parse_frame(&b, path());
        }
    }

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..500)) {
        let mut b = b"ply\n".to_vec();
        b.extend_from_slice(&bytes);
        prop_assert!(parse_frame(&bytes, path()).is_err() || bytes.starts_with(b"ply"));
        let _ = parse_frame(&b, path());
    }

    #[test]
    fn huge_declared_count_is_an_error(count in 1_000_000usize..usize::MAX, binary in any::<bool>()) {
        let b = format!(
            "ply\nformat {} 1.0\nelement vertex {count}\nproperty float x\nproperty float y\n\
             property float z\nproperty float intensity\nproperty float ring\n\
             property float return\nend_header\n1 2 3 4 5 1\n",
            if binary { "binary_little_endian" } else { "ascii" }
        );
        prop_assert!(parse_frame(b.as_bytes(), path()).is_err());
    }
}
