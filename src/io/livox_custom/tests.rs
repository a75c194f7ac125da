use super::*;

/// A `CustomMsg` written byte by byte from the layout in the module
/// documentation: stamp 100.5 s, frame id `livox_frame` (L = 12, so
/// timebase at payload byte 24 and the points at 44, 20 bytes apart, the
/// last without padding). Pulse 0 has two echoes (tag 0x10, then 0x21:
/// return 2 with a noise flag) 1 µs after the stamp; pulse 1 (4,167 ns
/// later) has no echo: the driver writes the origin.
fn hand_written() -> Vec<u8> {
    let mut m = vec![0u8, 1, 0, 0];
    m.extend_from_slice(&100u32.to_le_bytes()); // 0: sec
    m.extend_from_slice(&500_000_000u32.to_le_bytes()); // 4: nanosec
    m.extend_from_slice(&12u32.to_le_bytes()); // 8: frame_id length
    m.extend_from_slice(b"livox_frame\0"); // 12..24
    m.extend_from_slice(&100_500_001_000u64.to_le_bytes()); // 24: timebase
    m.extend_from_slice(&3u32.to_le_bytes()); // 32: point_num
    m.extend_from_slice(&[7, 0, 0, 0]); // 36: lidar_id, 37: rsvd
    m.extend_from_slice(&3u32.to_le_bytes()); // 40: points length
    let point = |m: &mut Vec<u8>, t: u32, xyz: [f32; 3], refl_tag_line: [u8; 3]| {
        m.extend_from_slice(&t.to_le_bytes());
        for v in xyz {
            m.extend_from_slice(&v.to_le_bytes());
        }
        m.extend_from_slice(&refl_tag_line);
    };
    point(&mut m, 0, [1.0, 2.0, 3.0], [200, 0x10, 3]); // 44..63
    m.push(0); // 63: padding
    point(&mut m, 0, [4.0, 8.0, 12.0], [10, 0x21, 3]); // 64..83
    m.push(0); // 83: padding
    point(&mut m, 4167, [0.0; 3], [0, 0x10, 4]); // 84..103, no padding
    assert_eq!(m.len(), 4 + 44 + 3 * POINT_STRIDE - 1);
    m
}

#[test]
fn a_hand_written_message_decodes_to_its_points() {
    let data = hand_written();
    let d = decode_custom_msg(&data).unwrap();
    assert_eq!(d.driver, Driver::Livox);
    assert_eq!(d.stamp, (100, 500_000_000));
    assert_eq!(d.shape, (1, 3));
    let f = &d.frame;
    assert_eq!(f.name, "100.500000");
    assert_eq!(f.dropped_non_finite, 1);
    assert_eq!(d.aside.positions, vec![2]);
    assert_eq!(f.points.len(), 2);
    assert_eq!(f.points[0].xyz, [1.0, 2.0, 3.0]);
    assert_eq!(f.points[1].xyz, [4.0, 8.0, 12.0]);
    let rets: Vec<u8> = f.points.iter().map(|p| p.ret).collect();
    assert_eq!(rets, [1, 2]);
    assert_eq!(f.points[0].intensity, 200.0);
    assert_eq!(f.points[1].intensity, 10.0);
    assert!(f.points.iter().all(|p| p.ring == 3));
    // timebase - stamp = 1,000 ns; the echoes share the pulse's time.
    assert!(f.points.iter().all(|p| p.time == 1e-6_f32));
    assert!(!f.has_labels);
}

#[test]
fn the_encoder_writes_the_documented_bytes() {
    let data = hand_written();
    let msg = CustomMsg::parse(&data).unwrap();
    assert_eq!(msg.frame_id, "livox_frame");
    assert_eq!(msg.timebase, 100_500_001_000);
    assert_eq!((msg.point_num, msg.lidar_id), (3, 7));
    assert_eq!(msg.points[2].offset_time, 4167);
    assert_eq!(msg.encode(), data);
}

/// Every cut of the message short of its last byte is an error naming
/// what is missing, never a panic; bytes after the last point are padding.
#[test]
fn truncated_messages_are_errors() {
    let data = hand_written();
    for cut in 0..data.len() {
        let err = decode_custom_msg(&data[..cut]).unwrap_err();
        assert!(
            err.contains("truncated") || err.contains("CDR"),
            "cut {cut}: {err}"
        );
    }
    let err = decode_custom_msg(&data[..60]).unwrap_err();
    assert!(err.contains("3 points need 59 bytes"), "{err}");
    let err = decode_custom_msg(&data[..20]).unwrap_err();
    assert!(err.contains("frame_id") || err.contains("string"), "{err}");
    let mut padded = data.clone();
    padded.extend_from_slice(&[0; 3]);
    assert_eq!(decode_custom_msg(&padded).unwrap().frame.points.len(), 2);
    // A length claiming more points than the bytes hold.
    let mut huge = data.clone();
    huge[44..48].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(decode_custom_msg(&huge).unwrap_err().contains("truncated"));
    let mut big_endian = data;
    big_endian[1] = 0;
    assert!(decode_custom_msg(&big_endian).is_err());
}

/// A frame encoded and decoded: positions, returns, rings, reflectivities
/// and times (to the nanosecond, the message's unit) come back, times
/// before the stamp too.
#[test]
fn frames_round_trip_through_the_encoder() {
    let point = |i: usize, ret: u8, time: f32| Point {
        xyz: [1.0 + i as f32, -2.0, 0.5],
        intensity: 10.0 * i as f32,
        ring: i as u16 % 6,
        ret,
        label: 0,
        time,
    };
    let frame = Frame {
        name: "1700000000.250000".into(),
        stamp: 1_700_000_000.25,
        points: vec![
            point(0, 1, -2e-6),
            point(1, 2, -2e-6),
            point(2, 1, 0.0),
            point(3, 1, 0.05),
            point(4, 2, 0.05),
        ],
        ..Frame::default()
    };
    let d = decode_custom_msg(&encode_custom_msg(&frame, "livox_frame")).unwrap();
    assert_eq!(d.frame.name, frame.name);
    assert_eq!(d.stamp, (1_700_000_000, 250_000_000));
    for (a, b) in d.frame.points.iter().zip(&frame.points) {
        assert_eq!(
            (a.xyz, a.ret, a.ring, a.intensity),
            (b.xyz, b.ret, b.ring, b.intensity)
        );
        assert!((a.time - b.time).abs() <= 1e-9 + f32::EPSILON * b.time.abs());
    }
    let msg = CustomMsg::parse(&encode_custom_msg(&frame, "f")).unwrap();
    assert_eq!(msg.timebase as i64, msg.stamp_ns() - 2_000);
    assert_eq!(msg.points[0].offset_time, msg.points[1].offset_time);
    assert_eq!(
        msg.points.iter().map(|p| p.tag).collect::<Vec<_>>(),
        [0x10, 0x20, 0x10, 0x10, 0x20]
    );
}

#[test]
fn the_schema_names_the_package_of_the_type() {
    let s = custom_msg_schema(LIVOX_ROS_DRIVER2_CUSTOM_MSG);
    assert!(s.contains("MSG: livox_ros_driver2/CustomPoint"), "{s}");
    assert!(s.starts_with("std_msgs/Header header\nuint64 timebase\n"));
    assert!(is_custom_msg(LIVOX_INTERFACES_CUSTOM_MSG));
    assert!(!is_custom_msg("sensor_msgs/msg/PointCloud2"));
}

/// Times no message can hold are clamped, not overflowed (no panic).
#[test]
fn the_encoder_clamps_times_out_of_range() {
    let mut frame = Frame {
        name: "1.000000".into(),
        stamp: 1.0,
        points: vec![Point {
            xyz: [1.0, 0.0, 0.0],
            ret: 1,
            ..Point::default()
        }],
        ..Frame::default()
    };
    frame.points.push(Point {
        time: 1e30,
        ..frame.points[0]
    });
    let msg = CustomMsg::parse(&encode_custom_msg(&frame, "f")).unwrap();
    assert_eq!(msg.points[1].offset_time, u32::MAX);
    frame.points[1].time = -1e30;
    let msg = CustomMsg::parse(&encode_custom_msg(&frame, "f")).unwrap();
    assert_eq!(msg.timebase, 0);
}
