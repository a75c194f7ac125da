//! One Livox `CustomMsg` as its CDR fields: parsed from a message
//! ([`CustomMsg::parse`]) and written back ([`CustomMsg::encode`]), the
//! two exact inverses (the byte layout is on [`super`]).

use crate::io::cdr::{CdrReader, CdrWriter};

/// The bytes one `CustomPoint` takes in CDR before the next one's
/// alignment: `offset_time` (4), `x y z` (12), `reflectivity tag line` (3).
pub const POINT_BYTES: usize = 19;

/// The stride of the points in a message: [`POINT_BYTES`] and one byte of
/// padding, as the next point's `offset_time` aligns to 4 (the last point
/// has no padding after it).
pub const POINT_STRIDE: usize = 20;

/// One `CustomPoint` as the driver writes it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CustomPoint {
    /// Nanoseconds after the message's [`CustomMsg::timebase`]; the
    /// echoes of one pulse share it.
    pub offset_time: u32,
    /// Position in the sensor frame, metres.
    pub x: f32,
    /// Position in the sensor frame, metres.
    pub y: f32,
    /// Position in the sensor frame, metres.
    pub z: f32,
    /// Reflectivity, 0-255 (0-150 diffuse, 151-255 retroreflective).
    pub reflectivity: u8,
    /// Flags: bits 5:4 the return number (0 internal/too close, 1, 2, 3),
    /// bits 3:2 intensity noise, bits 1:0 spatial noise.
    pub tag: u8,
    /// The laser line (0-5 on the Avia).
    pub line: u8,
}

/// One `livox_interfaces/msg/CustomMsg` (or `livox_ros_driver2/msg/
/// CustomMsg`, the same fields): what a Livox driver publishes with
/// `xfer_format = 1`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CustomMsg {
    /// Header stamp, whole seconds.
    pub sec: i32,
    /// Header stamp, nanoseconds.
    pub nanosec: u32,
    /// Header frame id.
    pub frame_id: String,
    /// Time of the first point, nanoseconds (the clock of the header
    /// stamp: the drivers stamp the header with it).
    pub timebase: u64,
    /// The driver's point count. Not checked against [`points`](Self::points):
    /// the sequence's own length is what the message holds.
    pub point_num: u32,
    /// Which lidar of the driver (its index when it reads several).
    pub lidar_id: u8,
    /// Reserved bytes.
    pub rsvd: [u8; 3],
    /// The points, in the order the sensor sent them.
    pub points: Vec<CustomPoint>,
}

impl CustomMsg {
    /// Parse the CDR message `data`; an error naming the field at which a
    /// truncated message ends, or a point count larger than the message
    /// could hold. Bytes after the last point are ignored (padding).
    pub fn parse(data: &[u8]) -> Result<Self, String> {
        let mut c = CdrReader::new(data)?;
        let sec = c.u32_named("header.stamp.sec")? as i32;
        let nanosec = c.u32_named("header.stamp.nanosec")?;
        let frame_id = c.string()?;
        let timebase = c.u64_named("timebase")?;
        let point_num = c.u32_named("point_num")?;
        let lidar_id = c.u8_named("lidar_id")?;
        let mut rsvd = [0; 3];
        for r in &mut rsvd {
            *r = c.u8_named("rsvd")?;
        }
        let n = c.u32_named("the length of points")? as usize;
        // The sequence starts aligned to 4 (after rsvd); n points take
        // 20 n - 1 bytes. Checked before allocating for n.
        let need = n.saturating_mul(POINT_STRIDE).saturating_sub(1);
        let have = c.remaining();
        if need > have {
            return Err(format!(
                "message is truncated: {n} points need {need} bytes but {have} remain"
            ));
        }
        // Every read below is in bounds (checked above); each still names
        // its field, as a read past the end could not panic anyway.
        let mut points = Vec::with_capacity(n);
        for _ in 0..n {
            points.push(CustomPoint {
                offset_time: c.u32_named("a point's offset_time")?,
                x: c.f32_named("a point's x")?,
                y: c.f32_named("a point's y")?,
                z: c.f32_named("a point's z")?,
                reflectivity: c.u8_named("a point's reflectivity")?,
                tag: c.u8_named("a point's tag")?,
                line: c.u8_named("a point's line")?,
            });
        }
        Ok(Self {
            sec,
            nanosec,
            frame_id,
            timebase,
            point_num,
            lidar_id,
            rsvd,
            points,
        })
    }

    /// The CDR message (little-endian encapsulation), laid out as
    /// [`super`] says.
    pub fn encode(&self) -> Vec<u8> {
        let mut w = CdrWriter::default();
        w.u32(self.sec as u32);
        w.u32(self.nanosec);
        w.string(&self.frame_id);
        w.u64(self.timebase);
        w.u32(self.point_num);
        w.u8(self.lidar_id);
        for r in self.rsvd {
            w.u8(r);
        }
        w.u32(self.points.len() as u32);
        for p in &self.points {
            w.u32(p.offset_time);
            w.f32(p.x);
            w.f32(p.y);
            w.f32(p.z);
            w.u8(p.reflectivity);
            w.u8(p.tag);
            w.u8(p.line);
        }
        w.finish()
    }

    /// The header stamp in nanoseconds.
    pub fn stamp_ns(&self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }

    /// The time of `p` after the header stamp, seconds: `timebase +
    /// offset_time - stamp` (exact in integers, then converted).
    pub fn time_of(&self, p: &CustomPoint) -> f32 {
        let ns = self.timebase as i128 + p.offset_time as i128 - self.stamp_ns() as i128;
        (ns as f64 * 1e-9) as f32
    }
}
