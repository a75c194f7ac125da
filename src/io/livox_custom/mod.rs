//! Livox `CustomMsg` point clouds: what livox_ros2_driver (the Avia's ROS 2
//! driver, `livox_interfaces/msg/CustomMsg`) and livox_ros_driver2
//! (`livox_ros_driver2/msg/CustomMsg`) publish with `xfer_format = 1`, the
//! form most Livox bags are recorded in because, unlike livox_ros2_driver's
//! `PointCloud2`, it carries each point's time. Decoded into the same
//! [`Decoded`] frames as a `PointCloud2` ([`decode_custom_msg`]), written
//! for tests ([`encode_custom_msg`]).
//!
//! # The message
//!
//! ```text
//! std_msgs/Header header      # stamp (int32 sec, uint32 nanosec), string frame_id
//! uint64 timebase             # ns, time of the first point
//! uint32 point_num
//! uint8 lidar_id
//! uint8[3] rsvd
//! CustomPoint[] points        # uint32 offset_time (ns after timebase),
//!                             # float32 x y z, uint8 reflectivity tag line
//! ```
//!
//! # Its CDR bytes
//!
//! Little-endian CDR (ROS 2's `CDR_LE`): offsets count from the payload
//! start, after the 4-byte encapsulation header, and each primitive is
//! aligned to its size. With `L` the frame id's length including its NUL
//! and `T = align8(12 + L)`:
//!
//! | offset | field | CDR |
//! |---|---|---|
//! | 0 | `header.stamp.sec` | int32 |
//! | 4 | `header.stamp.nanosec` | uint32 |
//! | 8 | `header.frame_id` | uint32 `L`, then `L` bytes |
//! | `T` | `timebase` | uint64, aligned to **8** (up to 7 bytes of padding before it) |
//! | `T + 8` | `point_num` | uint32 |
//! | `T + 12` | `lidar_id` | uint8 |
//! | `T + 13` | `rsvd` | 3 × uint8 (a fixed array: no length) |
//! | `T + 16` | `points` length `n` | uint32 |
//! | `T + 20 + 20 i` | `points[i]` | `offset_time` uint32 +0, `x y z` float32 +4/+8/+12, `reflectivity tag line` uint8 +16/+17/+18 |
//!
//! A point is 4 + 12 + 3 = 19 bytes ([`POINT_BYTES`]); the next point's
//! `offset_time` aligns to 4, so one byte of padding follows each point
//! but the last: the points take `20 n - 1` bytes, with a stride of 20
//! ([`POINT_STRIDE`]). (The frame id `livox_frame`, `L` = 12, gives `T` =
//! 24 and the first point at payload byte 44.)
//!
//! # As points
//!
//! * position `x y z`, in message order (the echoes of one pulse are
//!   consecutive: the pairing by emission of
//!   [`OrganizedScan`](crate::sensor::OrganizedScan) takes a return 1 and
//!   the later returns after it);
//! * [`Point::time`] = `timebase + offset_time - header stamp`, seconds
//!   (the echoes of a pulse share `offset_time`, so they share a time);
//! * intensity = `reflectivity` (the Avia model's intensity scale,
//!   `configs/sensors/livox_avia.toml`);
//! * return from `tag` bits 5:4, exactly as the `PointCloud2` layout reads
//!   it ([`livox_tag_return`]);
//! * ring = `line`; no label.
//!
//! Points not finite or at the origin are set aside and counted as every
//! reader does ([`set_aside_non_returns`](crate::cloud::set_aside_non_returns)).

pub mod message;

pub use message::{CustomMsg, CustomPoint, POINT_BYTES, POINT_STRIDE};

use super::pointcloud2::drivers::livox_tag_return;
use super::pointcloud2::{Decoded, Driver};
use crate::cloud::{Frame, Point};

/// livox_ros2_driver's message type (the Avia's ROS 2 driver).
pub const LIVOX_INTERFACES_CUSTOM_MSG: &str = "livox_interfaces/msg/CustomMsg";

/// livox_ros_driver2's message type (HAP, Mid-360); the same fields.
pub const LIVOX_ROS_DRIVER2_CUSTOM_MSG: &str = "livox_ros_driver2/msg/CustomMsg";

/// Both `CustomMsg` types, read alike.
pub const CUSTOM_MSG_TYPES: [&str; 2] = [LIVOX_INTERFACES_CUSTOM_MSG, LIVOX_ROS_DRIVER2_CUSTOM_MSG];

/// Whether `kind` (a bag topic's type) is a Livox `CustomMsg`.
pub fn is_custom_msg(kind: &str) -> bool {
    CUSTOM_MSG_TYPES.contains(&kind)
}

/// The `ros2msg` schema text of the `CustomMsg` type `kind` (one of
/// [`CUSTOM_MSG_TYPES`]) with its dependencies, in the concatenated form
/// rosbag2 writes into an MCAP file.
pub fn custom_msg_schema(kind: &str) -> String {
    let package = kind.split('/').next().unwrap_or("livox_interfaces");
    format!(
        "std_msgs/Header header\nuint64 timebase\nuint32 point_num\nuint8 lidar_id\nuint8[3] rsvd\nCustomPoint[] points\n\
         ================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
         ================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n\
         ================================================================================\nMSG: {package}/CustomPoint\nuint32 offset_time\nfloat32 x\nfloat32 y\nfloat32 z\nuint8 reflectivity\nuint8 tag\nuint8 line\n"
    )
}

/// Decode one CDR `CustomMsg` into a frame named by its header stamp, with
/// the [`Driver::Livox`] layout (see the module documentation); an error
/// says where a damaged message ends.
pub fn decode_custom_msg(data: &[u8]) -> Result<Decoded, String> {
    let msg = CustomMsg::parse(data)?;
    let points: Vec<Point> = msg
        .points
        .iter()
        .map(|p| Point {
            xyz: [p.x, p.y, p.z],
            intensity: p.reflectivity as f32,
            ring: p.line as u16,
            ret: livox_tag_return(p.tag),
            label: 0,
            time: msg.time_of(p),
        })
        .collect();
    let shape = (1, points.len());
    Ok(Decoded::assemble(
        points,
        false,
        shape,
        (msg.sec, msg.nanosec),
        Driver::Livox,
    ))
}

/// The `tag` of a point of return `ret`: the echo number in bits 5:4 (1,
/// 2, or 3 for any later return; 0 for 0), noise bits clear. Read back
/// with [`livox_tag_return`].
pub fn tag_of_return(ret: u8) -> u8 {
    ret.min(3) << 4
}

/// Encode `frame` as a CDR `CustomMsg` as a Livox driver writes it: header
/// stamp from [`Frame::stamp`], `timebase` the earliest point's time (the
/// stamp when the frame has no point), `offset_time` each point's time
/// after it in whole nanoseconds; `reflectivity` the intensity rounded and
/// clamped to 0-255, `tag` from the return ([`tag_of_return`]), `line` the
/// ring (at most 255). What tests write bags with.
pub fn encode_custom_msg(frame: &Frame, frame_id: &str) -> Vec<u8> {
    let sec = frame.stamp.floor();
    let nanosec = ((frame.stamp - sec) * 1e9).round().min(999_999_999.0);
    let (sec, nanosec) = (sec as i32, nanosec as u32);
    let stamp_ns = sec as i64 * 1_000_000_000 + nanosec as i64;
    let ns = |p: &Point| (p.time as f64 * 1e9).round() as i64;
    let first = frame.points.iter().map(ns).min().unwrap_or(0);
    let timebase = stamp_ns.saturating_add(first).max(0);
    let points = frame
        .points
        .iter()
        .map(|p| CustomPoint {
            offset_time: stamp_ns
                .saturating_add(ns(p))
                .saturating_sub(timebase)
                .clamp(0, u32::MAX as i64) as u32,
            x: p.xyz[0],
            y: p.xyz[1],
            z: p.xyz[2],
            reflectivity: p.intensity.round().clamp(0.0, 255.0) as u8,
            tag: tag_of_return(p.ret),
            line: p.ring.min(255) as u8,
        })
        .collect::<Vec<_>>();
    CustomMsg {
        sec,
        nanosec,
        frame_id: frame_id.to_string(),
        timebase: timebase as u64,
        point_num: points.len() as u32,
        lidar_id: 0,
        rsvd: [0; 3],
        points,
    }
    .encode()
}

#[cfg(test)]
mod tests;
