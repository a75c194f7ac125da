//! Hesai bags laid out exactly as the drivers write them: HesaiLidar_ROS_2.0
//! (both echoes in one cloud, no return index: paired by order) and tier4's
//! nebula (`return_type`), in MCAP and sqlite3 `.db3`; and a bag read as
//! the wrong driver names the fields it lacks.

mod common;

use common::bags::{at, azimuth, bag_time, cloud, write_db3, write_mcap, Records};
use specular::io::{read_bag_frames, read_bag_frames_with, BagOptions, Driver};

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
