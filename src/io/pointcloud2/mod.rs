//! `sensor_msgs/msg/PointCloud2` messages in CDR, as drivers write them:
//! the message parsed ([`cloud`]), each driver's fields mapped to points
//! ([`drivers`]), and frames decoded ([`decode`]) or encoded ([`encode`]).
//!
//! Fields read: `x y z` (float32/float64), the intensity, ring, return and
//! per-point time as the driver's mapping says ([`drivers::FieldMapping`]),
//! and `label` when present (any numeric type). A frame is named after its
//! header stamp (`{:.6}` seconds), like a 3DRef file stem; a point's time
//! is seconds after that stamp ([`Point::time`]).
//!
//! Points whose `x`, `y`, `z` or `intensity` is NaN or infinite (drivers
//! publish them for beams without a return, with `is_dense = false`), or
//! that lie exactly at the origin, are set aside and counted in
//! [`Frame::dropped_non_finite`], exactly as the PLY reader does (see
//! [`crate::cloud::set_aside_non_returns`]); the other points keep their
//! order and labels.

pub mod cloud;
pub mod drivers;
pub mod encode;
mod pairing;

pub use cloud::{Cloud, Field};
pub use drivers::{Driver, FieldMapping};
pub use encode::{encode_pointcloud2, RawCloud};

use crate::cloud::{set_aside_non_returns, Frame, Point, SetAside};

/// The schema name of a ROS 2 point cloud.
pub const POINTCLOUD2: &str = "sensor_msgs/msg/PointCloud2";

/// The `ros2msg` schema text of `sensor_msgs/msg/PointCloud2` (with its
/// dependencies, in the concatenated form rosbag2 writes).
pub const POINTCLOUD2_SCHEMA: &str = "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n";

/// One decoded cloud: its frame, where the points set aside were, and what
/// pairing it with another topic's cloud needs.
#[derive(Debug, Clone)]
pub struct Decoded {
    /// The frame (points kept, in message order).
    pub frame: Frame,
    /// The points set aside.
    pub aside: SetAside,
    /// `(height, width)` of the cloud.
    pub shape: (usize, usize),
    /// Header stamp `(sec, nanosec)`, exact.
    pub stamp: (i32, u32),
    /// The layout it was read with.
    pub driver: Driver,
}

/// Decode one CDR `PointCloud2` with the mapping of `driver` (detected from
/// the fields when `None`, [`Driver::detect`]); `ret` is the return of
/// every point when the layout has no return of its own (the Ouster
/// driver's topics: 1 on the first, 2 on the second). An error says what
/// is wrong: a damaged message, or the fields the named driver's layout
/// needs and the cloud lacks.
pub fn decode(data: &[u8], driver: Option<Driver>, ret: u8) -> Result<Decoded, String> {
    let cloud = Cloud::parse(data)?;
    let driver = driver.unwrap_or_else(|| Driver::detect(&cloud));
    let mapping = driver.mapping();
    mapping.check(&cloud)?;
    let reader = mapping.reader(&cloud);
    let stamp = cloud.stamp();
    let mut points: Vec<Point> = Vec::with_capacity(cloud.len());
    points.extend(cloud.records().map(|rec| reader.point(rec, stamp, ret)));
    mapping.finish(&cloud, &mut points)?;
    Ok(Decoded::assemble(
        points,
        cloud.has("label"),
        (cloud.height, cloud.width),
        (cloud.sec, cloud.nanosec),
        driver,
    ))
}

impl Decoded {
    /// A message's decoded `points` (in message order) as a frame named
    /// after the header `stamp`, the points that are no return set aside
    /// ([`set_aside_non_returns`]): what every message type's decoder
    /// ends with.
    pub(crate) fn assemble(
        mut points: Vec<Point>,
        has_labels: bool,
        shape: (usize, usize),
        stamp: (i32, u32),
        driver: Driver,
    ) -> Self {
        let aside = set_aside_non_returns(&mut points);
        let seconds = stamp.0 as f64 + stamp.1 as f64 * 1e-9;
        let frame = Frame {
            name: format!("{seconds:.6}"),
            stamp: seconds,
            points,
            has_labels,
            dropped_non_finite: aside.len(),
            intensity_scale: None,
        };
        Decoded {
            frame,
            aside,
            shape,
            stamp,
            driver,
        }
    }
}

/// Decode one CDR `sensor_msgs/msg/PointCloud2` into a frame, its layout
/// detected from its fields (non-finite points dropped and counted, see
/// the module documentation).
pub fn decode_pointcloud2(data: &[u8]) -> Result<Frame, String> {
    decode(data, None, 1).map(|d| d.frame)
}

/// [`decode_pointcloud2`], and where the points it set aside were.
pub fn decode_pointcloud2_full(data: &[u8]) -> Result<(Frame, SetAside), String> {
    decode(data, None, 1).map(|d| (d.frame, d.aside))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointcloud2_round_trips() {
        let frame = Frame {
            name: "1689496219.652560".into(),
            stamp: 1_689_496_219.652_56,
            points: (0..5)
                .map(|i| Point {
                    xyz: [i as f32, -1.5, 0.25],
                    intensity: 10.0 * i as f32,
                    ring: 60 - i as u16,
                    ret: 1 + (i % 2) as u8,
                    label: 5,
                    time: 0.01 * i as f32,
                })
                .collect(),
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        };
        let data = encode_pointcloud2(&frame, "lidar");
        assert_eq!(decode_pointcloud2(&data).unwrap().dropped_non_finite, 0);
        let back = decode_pointcloud2(&data).unwrap();
        assert_eq!(back.name, frame.name);
        assert_eq!(back.points, frame.points);
        assert!(back.has_labels);
        // Truncated and garbage messages are errors, not panics.
        for cut in [0, 3, 10, 40, data.len() - 30] {
            assert!(decode_pointcloud2(&data[..cut]).is_err(), "cut {cut}");
        }
    }

    /// A cloud with `is_dense = false`, as drivers publish it: points with a
    /// NaN or infinite coordinate or intensity are dropped and counted; the
    /// others keep their order and labels.
    #[test]
    fn non_finite_points_are_dropped_and_counted() {
        let good = |i: u8| Point {
            xyz: [1.0 + i as f32, 2.0, -0.5],
            intensity: 5.0 * i as f32,
            ring: i as u16,
            ret: 1,
            label: i % 7,
            time: 0.0,
        };
        let mut points: Vec<Point> = (0..6).map(good).collect();
        points[1].xyz = [f32::NAN; 3];
        points[3].xyz[2] = f32::INFINITY;
        points[4].intensity = f32::NAN;
        let frame = Frame {
            name: "10.500000".into(),
            stamp: 10.5,
            points,
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        };
        let back = decode_pointcloud2(&encode_pointcloud2(&frame, "lidar")).unwrap();
        assert_eq!(back.dropped_non_finite, 3);
        assert_eq!(back.points, vec![good(0), good(2), good(5)]);
        assert_eq!(back.labels(), vec![0, 2, 5]);
    }
}
