//! Bags written byte by byte as drivers write them: MCAP and rosbag2
//! sqlite3 files of CDR `PointCloud2` messages (or of another type, the
//! `_as` writers), point records laid out field by field.

use std::collections::BTreeMap;
use std::path::Path;

use specular::io::pointcloud2::RawCloud;
use specular::io::ros2_bag::{POINTCLOUD2, POINTCLOUD2_SCHEMA};

/// One message: topic, bag time (ns) and CDR bytes.
pub type Message = (&'static str, u64, Vec<u8>);

/// An MCAP bag of `messages` (one channel per topic).
pub fn write_mcap(path: &Path, messages: &[Message]) {
    write_mcap_as(path, POINTCLOUD2, POINTCLOUD2_SCHEMA, messages);
}

/// An MCAP bag of `messages` of type `kind` (its `ros2msg` schema text
/// `schema`), one channel per topic.
pub fn write_mcap_as(path: &Path, kind: &str, schema: &str, messages: &[Message]) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = mcap::Writer::new(file).unwrap();
    let schema = w.add_schema(kind, "ros2msg", schema.as_bytes()).unwrap();
    let mut channels = BTreeMap::new();
    for (k, (topic, t, data)) in messages.iter().enumerate() {
        let channel = *channels.entry(*topic).or_insert_with(|| {
            w.add_channel(schema, topic, "cdr", &BTreeMap::new())
                .unwrap()
        });
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: k as u32,
            log_time: *t,
            publish_time: *t,
        };
        w.write_to_known_channel(&header, data).unwrap();
    }
    w.finish().unwrap();
}

/// A rosbag2 sqlite3 file of `messages`.
pub fn write_db3(path: &Path, messages: &[Message]) {
    write_db3_as(path, POINTCLOUD2, messages);
}

/// A rosbag2 sqlite3 file of `messages` whose topics are of type `kind`.
pub fn write_db3_as(path: &Path, kind: &str, messages: &[Message]) {
    let db = rusqlite::Connection::open(path).unwrap();
    db.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
             serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
             timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    )
    .unwrap();
    let mut ids = BTreeMap::new();
    for (topic, t, data) in messages {
        let next = ids.len() as i64 + 1;
        let id = *ids.entry(*topic).or_insert_with(|| {
            db.execute(
                "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                rusqlite::params![next, topic, kind],
            )
            .unwrap();
            next
        });
        db.execute(
            "INSERT INTO messages (topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
            rusqlite::params![id, *t as i64, data],
        )
        .unwrap();
    }
}

/// Point records of a fixed size, written field by field at offsets.
pub struct Records {
    pub step: usize,
    pub data: Vec<u8>,
}

impl Records {
    pub fn new(step: usize) -> Self {
        Self {
            step,
            data: Vec::new(),
        }
    }
    /// Start a record (zero padding between fields, as a C struct).
    pub fn next(&mut self) -> &mut Self {
        self.data.resize(self.data.len() + self.step, 0);
        self
    }
    pub fn put(&mut self, offset: usize, bytes: &[u8]) -> &mut Self {
        let at = self.data.len() - self.step + offset;
        self.data[at..at + bytes.len()].copy_from_slice(bytes);
        self
    }
    pub fn f32(&mut self, offset: usize, v: f32) -> &mut Self {
        self.put(offset, &v.to_le_bytes())
    }
    pub fn f64(&mut self, offset: usize, v: f64) -> &mut Self {
        self.put(offset, &v.to_le_bytes())
    }
    pub fn u32(&mut self, offset: usize, v: u32) -> &mut Self {
        self.put(offset, &v.to_le_bytes())
    }
    pub fn u16(&mut self, offset: usize, v: u16) -> &mut Self {
        self.put(offset, &v.to_le_bytes())
    }
    pub fn u8(&mut self, offset: usize, v: u8) -> &mut Self {
        self.put(offset, &[v])
    }
    pub fn xyz(&mut self, p: [f32; 3]) -> &mut Self {
        self.f32(0, p[0]).f32(4, p[1]).f32(8, p[2])
    }
}

/// A CDR cloud of `records` with `fields`, stamped `sec.nanosec`.
pub fn cloud(
    stamp: (i32, u32),
    shape: (u32, u32),
    fields: &[(&str, u32, u8)],
    records: &Records,
) -> Vec<u8> {
    RawCloud {
        sec: stamp.0,
        nanosec: stamp.1,
        frame_id: "lidar",
        height: shape.0,
        width: shape.1,
        fields,
        point_step: records.step as u32,
        data: &records.data,
        is_dense: false,
    }
    .encode()
}

/// The point at `range` metres along azimuth `az` and elevation `el`
/// (degrees).
pub fn at(range: f32, az: f32, el: f32) -> [f32; 3] {
    let (a, e) = (az.to_radians(), el.to_radians());
    [
        range * e.cos() * a.cos(),
        range * e.cos() * a.sin(),
        range * e.sin(),
    ]
}

pub fn azimuth(p: [f32; 3]) -> f32 {
    p[1].atan2(p[0]).to_degrees()
}

pub fn bag_time(stamp: (i32, u32)) -> u64 {
    stamp.0 as u64 * 1_000_000_000 + stamp.1 as u64
}
