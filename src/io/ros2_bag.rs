//! ROS 2 bags: dual-return frames as `sensor_msgs/msg/PointCloud2`
//! messages in CDR, in every form `ros2 bag record` leaves them.
//!
//! [`read_bag_frames`] takes a rosbag2 directory (its `metadata.yaml` names
//! the storage, `mcap` or `sqlite3`, and the storage files in order, several
//! when the recording was split; see [`super::rosbag2`]), a bare `.mcap`
//! file or a bare `.db3` file (see [`super::db3`]). What a path is comes from
//! its content (magic bytes, `metadata.yaml`), not its name.
//!
//! Fields read: `x y z` (float32/float64), `intensity`, `ring`, `return`
//! (or `ret`, 1 first / 2 last) and `label` when present (any numeric type).
//! A frame is named after its header stamp (`{:.6}` seconds), like a 3DRef
//! file stem.
//!
//! Points whose `x`, `y`, `z` or `intensity` is NaN or infinite (drivers
//! publish them for beams without a return, with `is_dense = false`), or
//! that lie exactly at the origin, are set aside and counted in
//! [`Frame::dropped_non_finite`], exactly as the PLY reader does (see
//! [`crate::cloud::set_aside_non_returns`]); the other points keep their
//! order and labels, and the dataset keeps where the ones set aside were
//! ([`Dataset::set_aside`]), so outputs keep one label per input point.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use super::dataset::{Dataset, InMemory};
use super::frames::FrameEntry;
use crate::cloud::{set_aside_non_returns, Frame, Point, SetAside};
use crate::{Error, Result};

/// The schema name of a ROS 2 point cloud.
pub const POINTCLOUD2: &str = "sensor_msgs/msg/PointCloud2";

/// The `ros2msg` schema text of `sensor_msgs/msg/PointCloud2` (with its
/// dependencies, in the concatenated form rosbag2 writes).
pub const POINTCLOUD2_SCHEMA: &str = "std_msgs/Header header\nuint32 height\nuint32 width\nsensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n================================================================================\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n================================================================================\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n================================================================================\nMSG: sensor_msgs/PointField\nuint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n";

/// The first bytes of an MCAP file.
pub(crate) const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
/// The first bytes of an SQLite 3 database (rosbag2's `.db3` storage).
pub(crate) const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";
/// The first bytes of a zstd frame (rosbag2's `--compression-mode file`).
const ZSTD_MAGIC: &[u8] = &[0x28, 0xb5, 0x2f, 0xfd];

/// Every `PointCloud2` message on `topic` of the bag at `path`, as frames in
/// timestamp order. `path` is a rosbag2 directory (or its `metadata.yaml`),
/// an MCAP file or an SQLite (`.db3`) file; see [`BagKind::of`].
pub fn read_bag_frames(path: &Path, topic: &str) -> Result<Vec<Frame>> {
    Ok(read_bag_frames_full(path, topic)?
        .into_iter()
        .map(|(frame, _)| frame)
        .collect())
}

/// [`read_bag_frames`], each frame with where its points set aside were
/// ([`SetAside`]).
pub fn read_bag_frames_full(path: &Path, topic: &str) -> Result<Vec<(Frame, SetAside)>> {
    let mut frames = TopicFrames::new(topic);
    match BagKind::of(path)? {
        BagKind::Mcap => super::mcap_file::read_mcap(path, &mut frames)?,
        BagKind::Sqlite3 => super::db3::read_db3(path, &mut frames)?,
        BagKind::Directory(dir) => {
            super::rosbag2::read_directory_into(&dir, &mut frames)?;
            return frames.finish_full(&dir);
        }
    }
    frames.finish_full(path)
}

/// A bag's point-cloud topic as a [`Dataset`]: the frames are decoded
/// when the bag is opened ([`read_bag_frames`]) and lent from memory.
#[derive(Debug, Clone)]
pub struct Ros2Bag {
    frames: InMemory,
}

impl Ros2Bag {
    /// The `PointCloud2` frames on `topic` of the bag at `path` (any form
    /// [`BagKind::of`] knows), named by their header stamps.
    pub fn open(path: &Path, topic: &str) -> Result<Self> {
        let (frames, aside) = read_bag_frames_full(path, topic)?.into_iter().unzip();
        let frames = InMemory::new(frames, None, &path.display().to_string())?;
        Ok(Self {
            frames: frames.with_set_aside(aside)?,
        })
    }
}

impl Dataset for Ros2Bag {
    fn entries(&self) -> &[FrameEntry] {
        self.frames.entries()
    }
    fn frame(&self, index: usize) -> Result<Cow<'_, Frame>> {
        self.frames.frame(index)
    }
    fn in_memory(&self) -> Option<&[Frame]> {
        self.frames.in_memory()
    }
    fn set_aside(&self, index: usize) -> Result<SetAside> {
        self.frames.set_aside(index)
    }
    fn origin(&self) -> String {
        self.frames.origin()
    }
}

/// The forms of ROS 2 bag that [`read_bag_frames`] reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BagKind {
    /// One MCAP file (`ros2 bag record -s mcap`, or any MCAP with CDR
    /// `PointCloud2` messages).
    Mcap,
    /// One SQLite file of rosbag2's `sqlite3` storage (`.db3`).
    Sqlite3,
    /// A rosbag2 directory: its `metadata.yaml` names the storage and files.
    Directory(PathBuf),
}

impl BagKind {
    /// What `path` is, from its content: a directory holding
    /// `metadata.yaml` (or that file itself), or a file starting with the
    /// MCAP or SQLite magic bytes. Anything else is an error naming `path`
    /// and what it is not.
    pub fn of(path: &Path) -> Result<BagKind> {
        if path.is_dir() {
            if path.join("metadata.yaml").is_file() {
                return Ok(BagKind::Directory(path.to_path_buf()));
            }
            return Err(Error::format(
                path,
                "a directory without metadata.yaml: not a rosbag2 bag (give the bag directory, an .mcap or a .db3 file)",
            ));
        }
        let mut head = Vec::with_capacity(16);
        std::fs::File::open(path)
            .and_then(|f| f.take(16).read_to_end(&mut head))
            .map_err(|e| Error::io(path, e))?;
        if head.starts_with(MCAP_MAGIC) {
            return Ok(BagKind::Mcap);
        }
        if head.starts_with(SQLITE_MAGIC) {
            return Ok(BagKind::Sqlite3);
        }
        if path.file_name().is_some_and(|n| n == "metadata.yaml") {
            let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
            return Ok(BagKind::Directory(
                dir.unwrap_or(Path::new(".")).to_path_buf(),
            ));
        }
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        let message = if head.starts_with(ZSTD_MAGIC) {
            "compressed with zstd as a whole (rosbag2 --compression-mode file): decompress it first (zstd -d)".to_string()
        } else if ext.eq_ignore_ascii_case("db3") {
            "not an SQLite database".to_string()
        } else if ext.eq_ignore_ascii_case("mcap") {
            "not an MCAP file".to_string()
        } else {
            "not a ROS 2 bag: neither an MCAP file, an SQLite database (.db3) nor a rosbag2 directory".to_string()
        };
        Err(Error::format(path, message))
    }
}

/// The frames of one topic gathered over a bag's storage files, with every
/// topic seen on the way (for the error that lists them).
pub struct TopicFrames {
    topic: String,
    frames: Vec<(Frame, SetAside)>,
    /// Topic name -> (type, messages).
    seen: BTreeMap<String, (String, usize)>,
}

impl TopicFrames {
    /// Gather the point clouds of `topic`.
    pub fn new(topic: &str) -> Self {
        Self {
            topic: topic.to_string(),
            frames: Vec::new(),
            seen: BTreeMap::new(),
        }
    }

    /// The topic gathered.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// Whether `name` is the topic gathered.
    pub fn wants(&self, name: &str) -> bool {
        name == self.topic
    }

    /// Note `messages` messages of topic `name` of type `kind` serialized
    /// as `encoding` in the storage file `path`; the topic gathered must be
    /// a CDR `PointCloud2`, else the error names `path` and what it is.
    pub fn note(
        &mut self,
        path: &Path,
        name: &str,
        kind: &str,
        encoding: &str,
        messages: usize,
    ) -> Result<()> {
        if self.wants(name) {
            check_type(path, name, kind, encoding)?;
        }
        let entry = self.seen.entry(name.to_string());
        entry.or_insert_with(|| (kind.to_string(), 0)).1 += messages;
        Ok(())
    }

    /// Decode one message of the topic gathered, found in `path` at
    /// `time_ns` (the bag's receive time, for the error message).
    pub fn push(&mut self, path: &Path, time_ns: i64, data: &[u8]) -> Result<()> {
        let frame = decode_pointcloud2_full(data).map_err(|m| {
            Error::format(path, format!("{} message at {time_ns} ns: {m}", self.topic))
        })?;
        self.frames.push(frame);
        Ok(())
    }

    /// The topics seen, as `name (type, N messages)`, comma-separated.
    pub fn topic_list(&self) -> String {
        if self.seen.is_empty() {
            return "the bag has none".into();
        }
        let list: Vec<String> = self
            .seen
            .iter()
            .map(|(name, (kind, n))| format!("{name} ({kind}, {n} messages)"))
            .collect();
        list.join(", ")
    }

    /// The frames in timestamp order; an error naming `path` when the topic
    /// had no message (listing the topics present) or two messages share a
    /// header stamp (their frames would have the same name).
    pub fn finish(self, path: &Path) -> Result<Vec<Frame>> {
        Ok(self
            .finish_full(path)?
            .into_iter()
            .map(|(frame, _)| frame)
            .collect())
    }

    /// [`finish`](Self::finish), each frame with where its points set
    /// aside were.
    pub fn finish_full(mut self, path: &Path) -> Result<Vec<(Frame, SetAside)>> {
        if self.frames.is_empty() {
            return Err(Error::format(
                path,
                format!(
                    "no messages on {}; topics: {}",
                    self.topic,
                    self.topic_list()
                ),
            ));
        }
        self.frames.sort_by(|a, b| a.0.stamp.total_cmp(&b.0.stamp));
        if let Some(w) = self.frames.windows(2).find(|w| w[0].0.name == w[1].0.name) {
            return Err(Error::format(
                path,
                format!(
                    "two messages on {} have the same header stamp {}",
                    self.topic, w[0].0.name
                ),
            ));
        }
        Ok(self.frames)
    }
}

/// The topic read must be a CDR `PointCloud2`.
pub(crate) fn check_type(path: &Path, topic: &str, kind: &str, encoding: &str) -> Result<()> {
    if kind == POINTCLOUD2 && encoding == "cdr" {
        return Ok(());
    }
    Err(Error::format(
        path,
        format!("topic {topic} is {kind} in {encoding}, not {POINTCLOUD2} in cdr"),
    ))
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
    decode_pointcloud2_full(data).map(|(frame, _)| frame)
}

/// [`decode_pointcloud2`], and where the points it set aside were.
pub fn decode_pointcloud2_full(data: &[u8]) -> std::result::Result<(Frame, SetAside), String> {
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
    let aside = set_aside_non_returns(&mut points);
    let stamp = sec as f64 + nanosec as f64 * 1e-9;
    let frame = Frame {
        name: format!("{stamp:.6}"),
        stamp,
        points,
        has_labels: label.is_some(),
        dropped_non_finite: aside.len(),
        intensity_scale: None,
    };
    Ok((frame, aside))
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
