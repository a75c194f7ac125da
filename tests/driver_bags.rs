//! Bags laid out exactly as the LiDAR drivers write them (made here, byte
//! by byte: field names, types, offsets, padding, organized or not, return
//! topics): Ouster (ouster-ros), Livox (livox_ros_driver2), Hesai
//! (HesaiLidar_ROS_2.0) and nebula, in MCAP and sqlite3 `.db3`; read back
//! with returns paired, rings, per-point time and intensity; a bag read as
//! the wrong driver names the fields it lacks. And the 3DRef release's
//! Ouster and Livox folders.

mod common;

use std::path::{Path, PathBuf};

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

// ----------------------------------------------------------------- Livox

/// livox_ros_driver2's PointCloud2 (26-byte packed records): x y z
/// intensity f32 at 0/4/8/12, tag u8 16, line u8 17, timestamp f64 18
/// (absolute ns).
const LIVOX_FIELDS: [(&str, u32, u8); 7] = [
    ("x", 0, 7),
    ("y", 4, 7),
    ("z", 8, 7),
    ("intensity", 12, 7),
    ("tag", 16, 2),
    ("line", 17, 2),
    ("timestamp", 18, 8),
];

/// Pulses 4,167 ns apart over the 6 lines, dual return: each pulse's echo
/// 1 (tag return bits 01, with a noise flag in bits 1:0 on odd pulses)
/// then, on even pulses, its echo 2 (bits 10) 3 m farther; pulse 5 has a
/// near target merged into echo 0 (bits 00).
fn livox_cloud(stamp: (i32, u32)) -> Vec<u8> {
    let base = bag_time(stamp) as f64;
    let mut r = Records::new(26);
    for pulse in 0..12u32 {
        let line = (pulse % 6) as u8;
        let (az, el) = (pulse as f32 * 2.0 - 12.0, line as f32 * 3.0 - 7.5);
        let t = base + pulse as f64 * 4167.0;
        let first_tag = if pulse == 5 {
            0b00_00_00
        } else {
            0b01_00_00 | (pulse % 2) as u8
        };
        let range = if pulse == 5 { 1.0 } else { 6.0 };
        r.next()
            .xyz(at(range, az, el))
            .f32(12, 40.0 + pulse as f32)
            .u8(16, first_tag)
            .u8(17, line)
            .f64(18, t);
        if pulse % 2 == 0 {
            r.next()
                .xyz(at(range + 3.0, az, el))
                .f32(12, 5.0)
                .u8(16, 0b10_00_00)
                .u8(17, line)
                .f64(18, t);
        }
    }
    cloud(stamp, (1, r.data.len() as u32 / 26), &LIVOX_FIELDS, &r)
}

#[test]
fn a_livox_bag_reads_the_return_from_the_tag_bits() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("livox.db3");
    let stamp = (1_700_000_100, 500_000_000);
    write_db3(
        &bag,
        &[("/livox/lidar", bag_time(stamp), livox_cloud(stamp))],
    );
    for driver in [None, Some(Driver::Livox)] {
        let options = BagOptions {
            driver,
            second_topic: None,
        };
        let frames = read_bag_frames_with(&bag, "/livox/lidar", &options).unwrap();
        assert_eq!(frames.len(), 1);
        let f = &frames[0];
        assert_eq!(f.points.len(), 18);
        assert_eq!(f.second_returns(), 6);
        let mut pulse = 0;
        for (i, p) in f.points.iter().enumerate() {
            if p.ret == 2 {
                // The echo right before is the same pulse's first.
                let q = &f.points[i - 1];
                assert_eq!((q.ret, q.ring, q.time), (1, p.ring, p.time));
                assert!((azimuth(p.xyz) - azimuth(q.xyz)).abs() < 1e-3);
                continue;
            }
            assert_eq!(p.ring, (pulse % 6) as u16, "line is the ring");
            assert_eq!(p.intensity, 40.0 + pulse as f32);
            let want = pulse as f64 * 4167e-9;
            assert!((p.time as f64 - want).abs() < 1e-6, "{} vs {want}", p.time);
            pulse += 1;
        }
        assert_eq!(pulse, 12, "echo 0 (a near target) is a first return");
    }
}

// ----------------------------------------------------------------- Hesai

/// HesaiLidar_ROS_2.0 `/lidar_points` (fields added one after another, no
/// padding: 26 bytes): x y z intensity f32, ring u16 16, timestamp f64 18
/// (the packet's time, absolute seconds).
const HESAI_FIELDS: [(&str, u32, u8); 6] = [
    ("x", 0, 7),
    ("y", 4, 7),
    ("z", 8, 7),
    ("intensity", 12, 7),
    ("ring", 16, 4),
    ("timestamp", 18, 8),
];
const HESAI_RINGS: u16 = 4;

/// What the driver writes for a QT64-like sensor in dual (first + last)
/// mode: per packet two firings, each as two blocks (every channel's
/// first echo, then every channel's last echo) at one azimuth. At firing
/// 1 channel 2 the two echoes are the same (written twice); at firing 2
/// channel 0 the first echo is missing (zeros).
fn hesai_cloud(stamp: (i32, u32)) -> (Vec<u8>, usize) {
    let mut r = Records::new(26);
    let mut n = 0;
    for firing in 0..4u32 {
        let az = firing as f32 * 0.6;
        let packet_time = stamp.0 as f64 + stamp.1 as f64 * 1e-9 + (firing / 2) as f64 * 1e-4;
        for block in 0..2 {
            for ring in 0..HESAI_RINGS {
                let el = -50.0 + 30.0 * ring as f32;
                let mut range = 3.0 + ring as f32 + 4.0 * block as f32;
                if (firing, ring) == (1, 2) {
                    range = 3.0 + ring as f32;
                }
                let p = if (firing, ring, block) == (2, 0, 0) {
                    [0.0; 3]
                } else {
                    at(range, az, el)
                };
                r.next()
                    .xyz(p)
                    .f32(12, 10.0 * (block + 1) as f32)
                    .u16(16, ring)
                    .f64(18, packet_time);
                n += 1;
            }
        }
    }
    (cloud(stamp, (1, n as u32), &HESAI_FIELDS, &r), n)
}

#[test]
fn a_hesai_bag_pairs_the_two_echoes_of_a_firing_by_order() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("hesai.mcap");
    let stamp = (1_689_496_219, 652_560_000);
    let (data, n) = hesai_cloud(stamp);
    write_mcap(&bag, &[("/lidar_points", bag_time(stamp), data)]);
    for driver in [None, Some(Driver::Hesai)] {
        let options = BagOptions {
            driver,
            second_topic: None,
        };
        let frames = read_bag_frames_with(&bag, "/lidar_points", &options).unwrap();
        let f = &frames[0];
        assert_eq!(f.name, "1689496219.652560");
        // The zero point and the echo written twice are set aside.
        assert_eq!(f.dropped_non_finite, 2);
        assert_eq!(f.points.len(), n - 2);
        let firings = 4 * HESAI_RINGS as usize;
        assert_eq!(f.second_returns(), firings - 2);
        for p in &f.points {
            // Block 0's echo is the nearer: return 1; block 1's return 2
            // (the lone echo of firing 2 channel 0 too is return 1).
            let near = 3.0 + p.ring as f64;
            let want = if (p.range() - near).abs() < 1e-4 {
                1
            } else {
                2
            };
            let lone = p.ring == 0 && (azimuth(p.xyz) - 1.2).abs() < 1e-3;
            assert_eq!(p.ret, if lone { 1 } else { want }, "{p:?}");
            let block0 = want == 1 && !lone;
            assert_eq!(p.intensity, if block0 { 10.0 } else { 20.0 }, "{p:?}");
            let firing = (azimuth(p.xyz) / 0.6).round() as u32;
            let want_t = (firing / 2) as f64 * 1e-4;
            assert!(
                (p.time as f64 - want_t).abs() < 1e-6,
                "{} vs {want_t}",
                p.time
            );
        }
    }
}

// ---------------------------------------------------------------- nebula

/// nebula's PointXYZIRCAEDT (32 bytes): x y z f32, intensity u8 12,
/// return_type u8 13, channel u16 14, azimuth elevation distance f32
/// 16/20/24, time_stamp u32 28 (ns from the scan start).
const NEBULA_FIELDS: [(&str, u32, u8); 10] = [
    ("x", 0, 7),
    ("y", 4, 7),
    ("z", 8, 7),
    ("intensity", 12, 2),
    ("return_type", 13, 2),
    ("channel", 14, 4),
    ("azimuth", 16, 7),
    ("elevation", 20, 7),
    ("distance", 24, 7),
    ("time_stamp", 28, 6),
];

/// Dual (last + first) return: per channel and azimuth a FIRST (2) and a
/// LAST (1) point, or one IDENTICAL (6) where they coincide (channel 1);
/// `single` writes a Last-only cloud (every point LAST).
fn nebula_cloud(stamp: (i32, u32), single: bool) -> Vec<u8> {
    let mut r = Records::new(32);
    for col in 0..3u32 {
        for channel in 0..3u16 {
            let az = col as f32 * 0.6;
            let returns: &[(u8, f32)] = match (single, channel) {
                (true, _) => &[(1, 7.0)],
                (false, 1) => &[(6, 5.0)],
                (false, _) => &[(2, 4.0), (1, 8.0)],
            };
            for &(kind, range) in returns {
                r.next()
                    .xyz(at(range, az, channel as f32 * 10.0))
                    .u8(12, 30 + kind)
                    .u8(13, kind)
                    .u16(14, channel)
                    .f32(24, range)
                    .u32(28, col * 55_555);
            }
        }
    }
    cloud(stamp, (1, r.data.len() as u32 / 32), &NEBULA_FIELDS, &r)
}

#[test]
fn a_nebula_bag_reads_the_return_type() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("nebula.db3");
    let (a, b) = ((1_673_401_195, 788_312_575), (1_673_401_195, 888_312_575));
    write_db3(
        &bag,
        &[
            ("/pandar_points", bag_time(a), nebula_cloud(a, false)),
            ("/pandar_points", bag_time(b), nebula_cloud(b, true)),
        ],
    );
    let frames = read_bag_frames(&bag, "/pandar_points").unwrap();
    assert_eq!(frames.len(), 2);
    let dual = &frames[0];
    assert_eq!(dual.points.len(), 15);
    assert_eq!(dual.second_returns(), 6);
    for p in &dual.points {
        assert_eq!(p.ret == 2, (p.range() - 8.0).abs() < 1e-4, "{p:?}");
        assert_eq!(
            p.intensity,
            if p.ret == 2 {
                31.0
            } else if p.ring == 1 {
                36.0
            } else {
                32.0
            }
        );
        let col = (azimuth(p.xyz) / 0.6).round() as u32;
        assert!((p.time as f64 - col as f64 * 55_555e-9).abs() < 1e-9);
        assert!(p.ring <= 2);
    }
    // Last-only: every point is a first (and only) return.
    assert_eq!(frames[1].points.len(), 9);
    assert_eq!(frames[1].second_returns(), 0);
}

// -------------------------------------------------------------- mismatch

/// A bag read as another driver's layout: the error names the file, the
/// topic, the fields the layout lacks and the fields the cloud has.
#[test]
fn a_bag_read_as_the_wrong_driver_names_the_fields_it_lacks() {
    let tmp = tempfile::tempdir().unwrap();
    let bag = tmp.path().join("hesai.mcap");
    let stamp = (1_689_496_219, 0);
    write_mcap(
        &bag,
        &[("/lidar_points", bag_time(stamp), hesai_cloud(stamp).0)],
    );
    let options = BagOptions {
        driver: Some(Driver::Livox),
        second_topic: None,
    };
    let err = read_bag_frames_with(&bag, "/lidar_points", &options)
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with(&format!("{}: /lidar_points", bag.display())),
        "{err}"
    );
    assert!(err.contains("lacks the field(s) tag line"), "{err}");
    assert!(
        err.contains("fields are x y z intensity ring timestamp"),
        "{err}"
    );
    // The same through the command line, for every other driver.
    for (driver, lacks) in [
        ("ouster", "t"),
        ("nebula", "return_type channel"),
        ("livox", "tag line"),
    ] {
        let out = tmp.path().join(driver);
        let o = common::specular(&[
            "detect",
            "--bag",
            bag.to_str().unwrap(),
            "--topic",
            "/lidar_points",
            "--driver",
            driver,
            "--method",
            "single-scan",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!o.status.success());
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(
            stderr.contains(&format!("lacks the field(s) {lacks};"))
                && stderr.contains("hesai.mcap"),
            "{driver}: {stderr}"
        );
    }
    // A second-return topic named for a layout that has none.
    let options = BagOptions {
        driver: None,
        second_topic: Some("/x".into()),
    };
    let err = read_bag_frames_with(&bag, "/lidar_points", &options)
        .unwrap_err()
        .to_string();
    assert!(err.contains("only for the ouster layout"), "{err}");
}

// ------------------------------------------------------- 3DRef release

/// `x y z nx ny nz intensity ring return label`, ascii float: the one
/// writer of 3DRef's labelling script, for every sensor.
fn write_release_ply(path: &Path, rows: &[[f32; 4]]) {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float intensity\nproperty float ring\nproperty float return\nproperty float label\nend_header\n",
        rows.len()
    );
    for (i, [x, ring, ret, label]) in rows.iter().enumerate() {
        s += &format!(
            "{x} {} 0.5 0 0 0 {} {ring} {ret} {label}\n",
            i as f32 * 0.1,
            10 * i
        );
    }
    std::fs::write(path, s).unwrap();
}

/// A release sequence with Ouster frames (128 rings) and Livox frames (6
/// lines, up to three returns), each with its pose file.
fn release(dir: &Path) -> PathBuf {
    let seq = dir.join("raw/seq1");
    for (sensor, rows) in [
        (
            "ouster",
            vec![
                [3.0, 127.0, 1.0, 1.0],
                [4.0, 127.0, 2.0, 5.0],
                [5.0, 0.0, 1.0, 2.0],
            ],
        ),
        (
            "livox",
            vec![
                [3.0, 5.0, 1.0, 1.0],
                [4.0, 5.0, 2.0, 5.0],
                [6.0, 5.0, 3.0, 5.0],
            ],
        ),
    ] {
        let frames = seq.join("raycast").join(sensor);
        std::fs::create_dir_all(&frames).unwrap();
        for stamp in ["1689496219.600000", "1689496219.700000"] {
            write_release_ply(&frames.join(format!("{stamp}.ply")), &rows);
        }
        std::fs::write(
            seq.join(format!("{sensor}_pose.txt")),
            "1689496219.600000 0 0 0 0 0 0 1\n1689496219.700000 0.1 0 0 0 0 0 1\n",
        )
        .unwrap();
    }
    seq
}

#[test]
fn the_release_ouster_and_livox_folders_are_read_with_their_poses() {
    use specular::io::{frame_dir, release_poses, Dataset, PlyDir};
    let tmp = tempfile::tempdir().unwrap();
    let seq = release(tmp.path());
    for sensor in ["ouster", "livox"] {
        let folder = seq.join("raycast").join(sensor);
        assert_eq!(frame_dir(&folder), folder);
        assert_eq!(
            release_poses(&folder),
            Some(seq.join(format!("{sensor}_pose.txt")))
        );
        let data = PlyDir::open(&folder).unwrap();
        assert_eq!(data.entries().len(), 2);
        let f = data.frame(0).unwrap();
        let rets: Vec<u8> = f.points.iter().map(|p| p.ret).collect();
        let rings: Vec<u16> = f.points.iter().map(|p| p.ring).collect();
        let labels: Vec<u8> = f.points.iter().map(|p| p.label).collect();
        if sensor == "ouster" {
            assert_eq!(
                (rets, rings, labels),
                (vec![1, 2, 1], vec![127, 127, 0], vec![1, 5, 2])
            );
        } else {
            // The Livox's third echo stays return 3: its sensor model pairs
            // up to three returns by emission.
            assert_eq!(
                (rets, rings, labels),
                (vec![1, 2, 3], vec![5, 5, 5], vec![1, 5, 5])
            );
        }
        assert_eq!(f.points[2].intensity, 20.0);
    }
    // The sequence directory without a Hesai folder: the Ouster one.
    assert_eq!(frame_dir(&seq), seq.join("raycast/ouster"));
    assert_eq!(release_poses(&seq), Some(seq.join("ouster_pose.txt")));
    // detect on the Livox folder finds its pose file.
    let out = tmp.path().join("out");
    let o = common::specular(&[
        "detect",
        "--frames",
        seq.join("raycast/livox").to_str().unwrap(),
        "--method",
        "single-scan",
        "--out",
        out.to_str().unwrap(),
        "--lean",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("livox_pose.txt"), "{stdout}");
    assert_eq!(common::predictions(&out).len(), 2);
}
