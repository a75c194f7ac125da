//! Livox bags of `PointCloud2` laid out exactly as livox_ros_driver2 writes
//! them (26-byte packed records): the return read from the `tag` bits, the
//! `line` as ring, the absolute `timestamp` as per-point time. (The
//! drivers' `CustomMsg` is in `livox_custom_msg.rs`.)

mod common;

use common::bags::{at, azimuth, bag_time, cloud, write_db3, Records};
use specular::io::{read_bag_frames_with, BagOptions, Driver};

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
