//! The optional per-point `time` property of PLY frames (issue 40, part
//! 3): written only for frames whose points carry a time, read back
//! exactly, and refused with a message naming the file when it has an
//! integer type or a NaN or infinite value.

use std::path::Path;

use specular::cloud::{Frame, Point};
use specular::io::{parse_frame, read_frame, write_frame, PlyEncoding};

fn frame(timed: bool) -> Frame {
    let points = (0..50u32)
        .map(|i| Point {
            xyz: [1.0 + i as f32 * 0.1, -2.0, 0.5],
            intensity: (i % 200) as f32,
            ring: (i % 64) as u16,
            ret: 1 + (i % 2) as u8,
            label: (i % 7) as u8,
            time: if timed { i as f32 * 0.002 - 0.01 } else { 0.0 },
        })
        .collect();
    Frame {
        name: "1700000000.100000".into(),
        stamp: 1_700_000_000.1,
        points,
        has_labels: true,
        dropped_non_finite: 0,
        intensity_scale: None,
    }
}

#[test]
fn time_round_trips_in_both_encodings_and_untimed_frames_have_no_time() {
    let dir = tempfile::tempdir().unwrap();
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian] {
        for timed in [false, true] {
            let f = frame(timed);
            let path = dir.path().join(format!("{}.ply", f.name));
            write_frame(&path, &f, encoding).unwrap();
            let bytes = std::fs::read(&path).unwrap();
            let header_end = bytes.windows(10).position(|w| w == b"end_header").unwrap();
            let header = String::from_utf8_lossy(&bytes[..header_end]);
            assert_eq!(header.contains("property float time"), timed, "{header}");
            let back = read_frame(&path).unwrap();
            assert_eq!(back.points, f.points, "{encoding:?} timed={timed}");
        }
    }
}

fn file(format: &str, time_type: &str, body: &[u8]) -> Vec<u8> {
    let mut bytes = format!(
        "ply\nformat {format} 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
         property float z\nproperty float intensity\nproperty ushort ring\n\
         property uchar return\nproperty {time_type} time\nend_header\n"
    )
    .into_bytes();
    bytes.extend_from_slice(body);
    bytes
}

#[test]
fn double_times_are_read_and_bad_times_name_the_file() {
    let path = Path::new("/data/1700000000.100000.ply");
    let ok = file(
        "ascii",
        "double",
        b"1 2 3 10 4 1 0.05\n2 2 3 10 5 1 -0.01\n",
    );
    let f = parse_frame(&ok, path).unwrap();
    assert_eq!(f.points[0].time, 0.05);
    assert_eq!(f.points[1].time, -0.01);

    let wrong_type = file("ascii", "uchar", b"1 2 3 10 4 1 0\n2 2 3 10 5 1 1\n");
    let e = parse_frame(&wrong_type, path).unwrap_err().to_string();
    assert!(
        e.contains("1700000000.100000.ply") && e.contains("'time' must be float or double"),
        "{e}"
    );
    let nan = file("ascii", "float", b"1 2 3 10 4 1 0.01\n2 2 3 10 5 1 nan\n");
    let e = parse_frame(&nan, path).unwrap_err().to_string();
    assert!(
        e.contains("1700000000.100000.ply") && e.contains("time must be a finite number"),
        "{e}"
    );
    let mut body = Vec::new();
    for t in [0.0f32, f32::INFINITY] {
        for v in [1.0f32, 2.0, 3.0, 10.0] {
            body.extend_from_slice(&v.to_le_bytes());
        }
        body.extend_from_slice(&4u16.to_le_bytes());
        body.push(1);
        body.extend_from_slice(&t.to_le_bytes());
    }
    let e = parse_frame(&file("binary_little_endian", "float", &body), path)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("1700000000.100000.ply") && e.contains("vertex 1"),
        "{e}"
    );
}
