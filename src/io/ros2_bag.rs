//! ROS 2 bags (`.mcap` from `ros2 bag record -s mcap`): dual-return frames
//! as `sensor_msgs/msg/PointCloud2` messages in CDR.
//!
//! Fields read: `x y z` (float32/float64), `intensity`, `ring`, `return`
//! (or `ret`, 1 first / 2 last) and `label` when present (any numeric type).
//! A frame is named after its header stamp (`{:.6}` seconds), like a 3DRef
//! file stem.
//!
//! Points whose `x`, `y`, `z` or `intensity` is NaN or infinite (drivers
//! publish them for beams without a return, with `is_dense = false`) are
//! dropped and counted in [`Frame::dropped_non_finite`], exactly as the PLY
//! reader does (see [`crate::cloud::drop_non_finite`]); the other points
//! keep their order and labels.

use std::collections::BTreeMap;
use std::path::Path;

use crate::cloud::{drop_non_finite, Frame, Point};
use crate::{Error, Result};

/// The schema name of a ROS 2 point cloud.
pub const POINTCLOUD2: &str = "sensor_msgs/msg/PointCloud2";

/// The `ros2msg` schema text of `sensor_msgs/msg/PointCloud2` (with its
/// dependencies, in the concatenated form rosbag2 writes).
pub const POINTCLOUD2_SCHEMA: &str = "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n";

/// Every `PointCloud2` message on `topic` of the bag at `path`, as frames in
/// timestamp order.
pub fn read_bag_frames(path: &Path, topic: &str) -> Result<Vec<Frame>> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let stream = mcap::MessageStream::new(&bytes)
        .map_err(|e| Error::format(path, format!("not an MCAP file: {e}")))?;
    let mut frames = Vec::new();
    let mut topics = BTreeMap::new();
    for msg in stream {
        let msg = msg.map_err(|e| Error::format(path, format!("MCAP: {e}")))?;
        let schema = msg.channel.schema.as_ref().map(|s| s.name.as_str());
        *topics.entry(msg.channel.topic.clone()).or_insert(0usize) += 1;
        if msg.channel.topic != topic {
            continue;
        }
        if schema != Some(POINTCLOUD2) || msg.channel.message_encoding != "cdr" {
            return Err(Error::format(
                path,
                format!(
                    "topic {topic} is {} in {}, not {POINTCLOUD2} in cdr",
                    schema.unwrap_or("schemaless"),
                    msg.channel.message_encoding
                ),
            ));
        }
        let frame = decode_pointcloud2(&msg.data).map_err(|m| {
            Error::format(path, format!("{topic} message at {} ns: {m}", msg.log_time))
        })?;
        frames.push(frame);
    }
    if frames.is_empty() {
        let list: Vec<String> = topics.keys().cloned().collect();
        return Err(Error::format(
            path,
            format!("no messages on {topic}; topics: {}", list.join(", ")),
        ));
    }
    frames.sort_by(|a, b| a.stamp.total_cmp(&b.stamp));
    Ok(frames)
}

/// A little-endian CDR reader (alignment relative to the payload start).
struct Cdr<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Cdr<'a> {
    fn new(data: &'a [u8]) -> std::result::Result<Self, String> {
        match data.get(..4) {
            Some([0, 1, _, _]) => Ok(Self {
                buf: &data[4..],
                pos: 0,
            }),
            Some([0, 0, _, _]) => Err("big-endian CDR is not supported".into()),
            _ => Err("not a CDR message (bad encapsulation header)".into()),
        }
    }

    fn take(&mut self, n: usize, align: usize) -> std::result::Result<&'a [u8], String> {
        self.pos = self.pos.div_ceil(align) * align;
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        let end = end.ok_or_else(|| "message is truncated".to_string())?;
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1, 1)?[0])
    }

    fn u32(&mut self) -> std::result::Result<u32, String> {
        let b = self.take(4, 4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn string(&mut self) -> std::result::Result<String, String> {
        let n = self.u32()? as usize;
        let b = self.take(n, 1)?;
        let b = b.strip_suffix(&[0]).unwrap_or(b);
        Ok(String::from_utf8_lossy(b).into_owned())
    }
}

/// One field of a point record.
#[derive(Debug, Clone, Copy)]
struct Field {
    offset: usize,
    datatype: u8,
}

impl Field {
    fn size(&self) -> usize {
        match self.datatype {
            1 | 2 => 1,
            3 | 4 => 2,
            5..=7 => 4,
            _ => 8,
        }
    }

    fn read(&self, rec: &[u8]) -> f64 {
        let b = &rec[self.offset..self.offset + self.size()];
        match self.datatype {
            1 => b[0] as i8 as f64,
            2 => b[0] as f64,
            3 => i16::from_le_bytes([b[0], b[1]]) as f64,
            4 => u16::from_le_bytes([b[0], b[1]]) as f64,
            5 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            6 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            7 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            _ => f64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]),
        }
    }
}

/// Decode one CDR `sensor_msgs/msg/PointCloud2` into a frame (non-finite
/// points dropped and counted, see the module documentation).
pub fn decode_pointcloud2(data: &[u8]) -> std::result::Result<Frame, String> {
    let mut c = Cdr::new(data)?;
    let sec = c.u32()? as i32;
    let nanosec = c.u32()?;
    let _frame_id = c.string()?;
    let height = c.u32()? as usize;
    let width = c.u32()? as usize;
    let n_fields = c.u32()? as usize;
    let mut fields = BTreeMap::new();
    for _ in 0..n_fields.min(1024) {
        let name = c.string()?;
        let offset = c.u32()? as usize;
        let datatype = c.u8()?;
        let _count = c.u32()?;
        if !(1..=8).contains(&datatype) {
            return Err(format!("field {name}: unknown datatype {datatype}"));
        }
        fields.insert(name, Field { offset, datatype });
    }
    if c.u8()? != 0 {
        return Err("big-endian point data is not supported".into());
    }
    let point_step = c.u32()? as usize;
    let _row_step = c.u32()?;
    let n = c.u32()? as usize;
    let body = c.take(n, 1)?;
    let count = height
        .checked_mul(width)
        .filter(|&k| k.checked_mul(point_step).is_some_and(|b| b <= body.len()))
        .ok_or_else(|| {
            format!("{height}x{width} points of {point_step} bytes exceed the data ({n} bytes)")
        })?;
    let get = |name: &str| fields.get(name).copied();
    let need = |name: &str| get(name).ok_or_else(|| format!("no field '{name}'"));
    let (x, y, z) = (need("x")?, need("y")?, need("z")?);
    let intensity = get("intensity");
    let ring = get("ring");
    let ret = get("return").or_else(|| get("ret"));
    let label = get("label");
    for f in fields.values() {
        if f.offset + f.size() > point_step {
            return Err(format!("a field ends beyond point_step {point_step}"));
        }
    }
    let mut points: Vec<Point> = body
        .chunks_exact(point_step.max(1))
        .take(count)
        .map(|rec| Point {
            xyz: [x.read(rec) as f32, y.read(rec) as f32, z.read(rec) as f32],
            intensity: intensity.map_or(0.0, |f| f.read(rec) as f32),
            ring: ring.map_or(0, |f| f.read(rec) as u16),
            ret: ret.map_or(1, |f| f.read(rec) as u8),
            label: label.map_or(0, |f| f.read(rec) as u8),
        })
        .collect();
    let dropped_non_finite = drop_non_finite(&mut points);
    let stamp = sec as f64 + nanosec as f64 * 1e-9;
    Ok(Frame {
        name: format!("{stamp:.6}"),
        stamp,
        points,
        has_labels: label.is_some(),
        dropped_non_finite,
    })
}

/// Encode a frame as a CDR `sensor_msgs/msg/PointCloud2` (fields `x y z
/// intensity` float32, `ring` uint16, `return` uint8, and `label` uint8 when
/// the frame has labels); `stamp` is split into seconds and nanoseconds.
pub fn encode_pointcloud2(frame: &Frame, frame_id: &str) -> Vec<u8> {
    let mut fields: Vec<(&str, u32, u8)> = vec![
        ("x", 0, 7),
        ("y", 4, 7),
        ("z", 8, 7),
        ("intensity", 12, 7),
        ("ring", 16, 4),
        ("return", 18, 2),
    ];
    if frame.has_labels {
        fields.push(("label", 19, 2));
    }
    let step = 20u32;
    let mut w = CdrWriter::default();
    let sec = frame.stamp.floor();
    let nanosec = ((frame.stamp - sec) * 1e9).round().min(999_999_999.0);
    w.u32(sec as i32 as u32);
    w.u32(nanosec as u32);
    w.string(frame_id);
    w.u32(1);
    w.u32(frame.points.len() as u32);
    w.u32(fields.len() as u32);
    for (name, offset, datatype) in fields {
        w.string(name);
        w.u32(offset);
        w.u8(datatype);
        w.u32(1);
    }
    w.u8(0);
    w.u32(step);
    w.u32(step * frame.points.len() as u32);
    w.u32(step * frame.points.len() as u32);
    for p in &frame.points {
        for v in p.xyz {
            w.buf.extend_from_slice(&v.to_le_bytes());
        }
        w.buf.extend_from_slice(&p.intensity.to_le_bytes());
        w.buf.extend_from_slice(&p.ring.to_le_bytes());
        w.buf.push(p.ret);
        w.buf.push(p.label);
    }
    w.u8(1);
    let mut out = vec![0, 1, 0, 0];
    out.extend_from_slice(&w.buf);
    out
}

#[derive(Default)]
struct CdrWriter {
    buf: Vec<u8>,
}

impl CdrWriter {
    fn align(&mut self, a: usize) {
        while !self.buf.len().is_multiple_of(a) {
            self.buf.push(0);
        }
    }
    fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }
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
                })
                .collect(),
            has_labels: true,
            dropped_non_finite: 0,
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
        };
        let back = decode_pointcloud2(&encode_pointcloud2(&frame, "lidar")).unwrap();
        assert_eq!(back.dropped_non_finite, 3);
        assert_eq!(back.points, vec![good(0), good(2), good(5)]);
        assert_eq!(back.labels(), vec![0, 2, 5]);
    }
}
