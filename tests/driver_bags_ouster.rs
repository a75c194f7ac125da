//! Ouster bags laid out exactly as ouster-ros writes them (made here, byte
//! by byte: fields, padding, organized clouds, the second return on its
//! own topic), in MCAP and sqlite3 `.db3`: read back with the two topics
//! paired by header stamp and place, rings flipped and per-point time; and
//! `detect` writing one label per point of both topics. (Split from the
//! driver bag tests, one file per driver.)

mod common;

use common::bags::{at, azimuth, bag_time, cloud, write_db3, write_mcap, Message, Records};
use specular::cloud::{Frame, Point};
use specular::io::{read_bag_frames, read_bag_frames_with, BagOptions, Driver};

// ---------------------------------------------------------------- Ouster

/// ouster-ros `point_type: original` (os_point.h, 16-byte aligned struct):
/// x y z at 0/4/8 (+4 padding), intensity f32 16, t u32 20, reflectivity
/// u16 24, ring u16 26, ambient u16 28, range u32 32; 48 bytes.
const OUSTER_FIELDS: [(&str, u32, u8); 9] = [
    ("x", 0, 7),
    ("y", 4, 7),
    ("z", 8, 7),
    ("intensity", 16, 7),
    ("t", 20, 6),
    ("reflectivity", 24, 4),
    ("ring", 26, 4),
    ("ambient", 28, 4),
    ("range", 32, 6),
];
const OUSTER_ROWS: u32 = 4;
const OUSTER_COLS: u32 = 6;

/// Column `c`'s time from the scan start, ns.
fn ouster_t(c: u32) -> u32 {
    c * 16_000_000
}

/// One return's organized cloud (rows = beams from the top, columns):
/// return 1 at 4 m + row, return 2 at 9 m + row in the even columns only
/// (elsewhere zeros, as the driver writes a beam without a second echo);
/// the return-1 beam at row 1, column 3 is NaN (no echo at all).
fn ouster_cloud(stamp: (i32, u32), second: bool) -> Vec<u8> {
    let mut r = Records::new(48);
    for row in 0..OUSTER_ROWS {
        for c in 0..OUSTER_COLS {
            let (az, el) = (c as f32 * 60.0 - 150.0, 20.0 - 10.0 * row as f32);
            let p = match (second, row, c) {
                (false, 1, 3) => [f32::NAN; 3],
                (false, _, _) => at(4.0 + row as f32, az, el),
                (true, _, c) if c % 2 == 0 => at(9.0 + row as f32, az, el),
                (true, _, _) => [0.0; 3],
            };
            let intensity = if second { 7.0 } else { 100.0 + c as f32 };
            r.next()
                .xyz(p)
                .f32(16, intensity)
                .u32(20, ouster_t(c))
                .u16(24, 55)
                .u16(26, row as u16)
                .u16(28, 3)
                .u32(32, 4000);
        }
    }
    cloud(stamp, (OUSTER_ROWS, OUSTER_COLS), &OUSTER_FIELDS, &r)
}

/// Two scans on `/ouster/points` and `/ouster/points2` (the second
/// return's messages first, as they may arrive), plus a stray second-return
/// message whose first was not recorded.
fn ouster_messages(second_topic: &'static str) -> Vec<Message> {
    let stamps = [(1_700_000_000, 100_000_000), (1_700_000_000, 200_000_000)];
    let mut m: Vec<Message> = Vec::new();
    m.push((second_topic, 1, ouster_cloud((1_699_999_999, 0), true)));
    for s in stamps {
        m.push((second_topic, bag_time(s) + 2, ouster_cloud(s, true)));
        m.push(("/ouster/points", bag_time(s) + 5, ouster_cloud(s, false)));
    }
    m
}

fn check_ouster(frames: &[Frame]) {
    assert_eq!(
        frames.len(),
        2,
        "the stray second-return message is no frame"
    );
    let (rows, cols) = (OUSTER_ROWS as usize, OUSTER_COLS as usize);
    for f in frames {
        // 24 first returns but one NaN; 12 second returns (even columns).
        assert_eq!(f.dropped_non_finite, 1 + 12);
        let (first, second): (Vec<&Point>, Vec<&Point>) = f.points.iter().partition(|p| p.ret == 1);
        assert_eq!(first.len(), rows * cols - 1);
        assert_eq!(second.len(), rows * cols / 2);
        assert!(
            f.points[..first.len()].iter().all(|p| p.ret == 1),
            "first topic first"
        );
        for s in &second {
            // Its beam's first return: same ring, same azimuth, nearer.
            let partner = first
                .iter()
                .find(|p| p.ring == s.ring && (azimuth(p.xyz) - azimuth(s.xyz)).abs() < 1e-3)
                .expect("each second return has its first");
            assert!((s.range() - partner.range() - 5.0).abs() < 1e-4);
            assert_eq!(s.time, partner.time, "both returns share the column time");
            assert_eq!(s.intensity, 7.0);
        }
        for p in &first {
            // Rows count from the top; rings from the bottom.
            let row = (p.range() - 4.0).round() as usize;
            assert_eq!(p.ring as usize, rows - 1 - row, "{p:?}");
            let c = ((azimuth(p.xyz) + 150.0) / 60.0).round() as u32;
            assert_eq!(p.intensity, 100.0 + c as f32);
            assert!((p.time as f64 - ouster_t(c) as f64 * 1e-9).abs() < 1e-7);
        }
    }
    assert_eq!(frames[0].name, "1700000000.100000");
}

#[test]
fn an_ouster_bag_pairs_the_second_return_topic_by_stamp_and_place() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("ouster.mcap");
    write_mcap(&bag, &ouster_messages("/ouster/points2"));
    // Detected from the fields, and named.
    check_ouster(&read_bag_frames(&bag, "/ouster/points").unwrap());
    let named = BagOptions {
        driver: Some(Driver::Ouster),
        second_topic: None,
    };
    check_ouster(&read_bag_frames_with(&bag, "/ouster/points", &named).unwrap());
    // Another second-return topic, named.
    let other = tmp.path().join("other.db3");
    write_db3(&other, &ouster_messages("/os/second"));
    let err = read_bag_frames(&other, "/ouster/points")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("/ouster/points2") && err.contains("--second-topic"),
        "{err}"
    );
    let options = BagOptions {
        driver: None,
        second_topic: Some("/os/second".into()),
    };
    check_ouster(&read_bag_frames_with(&other, "/ouster/points", &options).unwrap());
}

/// `detect` on the Ouster bag writes one label per input point of both
/// topics (first topic's, then second's), 0 where a point was set aside.
#[test]
fn detect_on_an_ouster_bag_writes_a_label_per_point_of_both_topics() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("ouster.mcap");
    write_mcap(&bag, &ouster_messages("/ouster/points2"));
    let out = tmp.path().join("out");
    let o = common::specular(&[
        "detect",
        "--bag",
        bag.to_str().unwrap(),
        "--topic",
        "/ouster/points",
        "--driver",
        "ouster",
        "--method",
        "single-scan",
        "--out",
        out.to_str().unwrap(),
        "--lean",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let predictions = common::predictions(&out);
    assert_eq!(predictions.len(), 2);
    let n = (OUSTER_ROWS * OUSTER_COLS) as usize;
    for labels in predictions.values() {
        let labels: Vec<u32> = labels
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
            .collect();
        assert_eq!(labels.len(), 2 * n);
        assert_eq!(labels[OUSTER_COLS as usize + 3], 0, "the NaN beam");
        for c in 0..OUSTER_COLS as usize {
            assert_eq!(labels[n + c] == 0, c % 2 == 1, "second return, column {c}");
        }
    }
}
