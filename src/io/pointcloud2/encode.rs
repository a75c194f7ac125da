//! Writing CDR `sensor_msgs/msg/PointCloud2` messages: a frame in
//! specular's own layout ([`encode_pointcloud2`]), or any layout given as
//! fields and raw records ([`RawCloud`], how the tests write bags laid out
//! as each driver writes them).

use crate::cloud::Frame;
use crate::io::cdr::CdrWriter;

/// A `PointCloud2` given as its parts: what [`RawCloud::encode`] writes.
#[derive(Debug, Clone, PartialEq)]
pub struct RawCloud<'a> {
    /// Header stamp, whole seconds.
    pub sec: i32,
    /// Header stamp, nanoseconds.
    pub nanosec: u32,
    /// Header frame id.
    pub frame_id: &'a str,
    /// Rows (1 = unorganized).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// `(name, offset, datatype)` per field (datatypes as
    /// `sensor_msgs/PointField`: 2 UINT8, 4 UINT16, 6 UINT32, 7 FLOAT32,
    /// 8 FLOAT64, ...).
    pub fields: &'a [(&'a str, u32, u8)],
    /// Bytes per point record.
    pub point_step: u32,
    /// `height × width` records of `point_step` bytes, row by row.
    pub data: &'a [u8],
    /// Whether every point is valid (no NaN).
    pub is_dense: bool,
}

impl RawCloud<'_> {
    /// The CDR message (little-endian encapsulation).
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::default();
        w.u32(self.sec as u32);
        w.u32(self.nanosec);
        w.string(self.frame_id);
        w.u32(self.height);
        w.u32(self.width);
        w.u32(self.fields.len() as u32);
        for &(name, offset, datatype) in self.fields {
            w.string(name);
            w.u32(offset);
            w.u8(datatype);
            w.u32(1);
        }
        w.u8(0);
        w.u32(self.point_step);
        w.u32(self.point_step * self.width);
        w.u32(self.data.len() as u32);
        w.bytes(self.data);
        w.u8(self.is_dense as u8);
        w.finish()
    }
}

/// Encode a frame as a CDR `sensor_msgs/msg/PointCloud2` (fields `x y z
/// intensity` float32, `ring` uint16, `return` uint8, `label` uint8 when
/// the frame has labels, and `time` float32, seconds after the stamp, when
/// a point has a time); `stamp` is split into seconds and nanoseconds.
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
    let timed = frame.points.iter().any(|p| p.time != 0.0);
    if timed {
        fields.push(("time", 20, 7));
    }
    let step = if timed { 24 } else { 20 };
    let mut data = Vec::with_capacity(step * frame.points.len());
    for p in &frame.points {
        for v in p.xyz {
            data.extend_from_slice(&v.to_le_bytes());
        }
        data.extend_from_slice(&p.intensity.to_le_bytes());
        data.extend_from_slice(&p.ring.to_le_bytes());
        data.push(p.ret);
        data.push(p.label);
        if timed {
            data.extend_from_slice(&p.time.to_le_bytes());
        }
    }
    let sec = frame.stamp.floor();
    let nanosec = ((frame.stamp - sec) * 1e9).round().min(999_999_999.0);
    RawCloud {
        sec: sec as i32,
        nanosec: nanosec as u32,
        frame_id,
        height: 1,
        width: frame.points.len() as u32,
        fields: &fields,
        point_step: step as u32,
        data: &data,
        is_dense: true,
    }
    .encode()
}
