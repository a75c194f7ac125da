//! rosbag2's `sqlite3` storage (`.db3` files): the default storage of ROS 2
//! up to Humble, and what most recorded datasets hold.
//!
//! A `.db3` file is an SQLite database with (among others) the tables
//! `topics(id, name, type, serialization_format, ...)` and
//! `messages(id, topic_id, timestamp, data)`; `data` is the CDR-serialized
//! message exactly as in MCAP, so the frames come from the same
//! [`decode`](super::pointcloud2::decode). The file is
//! opened read-only; SQLite is compiled into specular (rusqlite's `bundled`
//! feature), so no system library is needed.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use rusqlite::{Connection, OpenFlags};

use super::bag_topics::TopicFrames;
use super::ros2_bag::SQLITE_MAGIC;
use crate::{Error, Result};

/// Gather the messages of one `.db3` file (a bag of its own, or one file of
/// a rosbag2 directory) into `frames`. Every error names `path`: not an
/// SQLite database, an SQLite database without rosbag2's tables, a
/// `PointCloud2` topic of another type, an undecodable message.
pub fn read_db3(path: &Path, frames: &mut TopicFrames) -> Result<()> {
    let mut head = Vec::with_capacity(SQLITE_MAGIC.len());
    std::fs::File::open(path)
        .and_then(|f| f.take(SQLITE_MAGIC.len() as u64).read_to_end(&mut head))
        .map_err(|e| Error::io(path, e))?;
    if head != SQLITE_MAGIC {
        return Err(Error::format(path, "not an SQLite database"));
    }
    let sql = |e: rusqlite::Error| Error::format(path, format!("SQLite: {e}"));
    let db = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(sql)?;
    let tables: Vec<String> = db
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table'")
        .and_then(|mut s| s.query_map([], |r| r.get(0))?.collect())
        .map_err(sql)?;
    for table in ["topics", "messages"] {
        if !tables.iter().any(|t| t == table) {
            return Err(Error::format(
                path,
                format!("an SQLite database but not a rosbag2 one: no table '{table}'"),
            ));
        }
    }
    let counts: HashMap<i64, i64> = db
        .prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id")
        .and_then(|mut s| s.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))?.collect())
        .map_err(sql)?;
    let topics: Vec<(i64, String, String, String)> = db
        .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
        .and_then(|mut s| {
            s.query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?, r.get(3)?)))?
                .collect()
        })
        .map_err(sql)?;
    let mut wanted = Vec::new();
    for (id, name, kind, encoding) in &topics {
        let n = counts.get(id).copied().unwrap_or(0).max(0) as usize;
        frames.note(path, name, kind, encoding, n)?;
        if frames.wants(name) {
            wanted.push((*id, name.as_str()));
        }
    }
    let mut query = db
        .prepare("SELECT timestamp, data FROM messages WHERE topic_id = ?1 ORDER BY timestamp, id")
        .map_err(sql)?;
    for (id, name) in wanted {
        let mut rows = query.query([id]).map_err(sql)?;
        while let Some(row) = rows.next().map_err(sql)? {
            let time: i64 = row.get(0).map_err(sql)?;
            let data = row.get_ref(1).map_err(sql)?;
            let data = data.as_blob().map_err(|e| {
                Error::format(
                    path,
                    format!("message at {time} ns: data is not a blob: {e}"),
                )
            })?;
            frames.push(path, name, time, data)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::{Frame, Point};
    use crate::io::ros2_bag::{encode_pointcloud2, POINTCLOUD2};

    fn frame(stamp: f64, n: usize) -> Frame {
        Frame {
            name: format!("{stamp:.6}"),
            stamp,
            points: (0..n)
                .map(|i| Point {
                    xyz: [i as f32, 2.0, -1.0],
                    intensity: i as f32,
                    ring: i as u16,
                    ret: 1,
                    label: 1,
                    time: 0.0,
                })
                .collect(),
            has_labels: true,
            dropped_non_finite: 0,
            intensity_scale: None,
        }
    }

    /// A minimal rosbag2 sqlite3 file: the two tables rosbag2 reads.
    fn write_db3(path: &Path, rows: &[(i64, &str, &str, Vec<u8>)]) {
        let db = Connection::open(path).unwrap();
        db.execute_batch(
            "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
                 serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
             CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
                 timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
        )
        .unwrap();
        let mut ids = HashMap::new();
        for (t, topic, kind, data) in rows {
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
                rusqlite::params![id, t, data],
            )
            .unwrap();
        }
    }

    #[test]
    fn messages_come_back_in_stamp_order_and_other_topics_are_listed() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("bag.db3");
        let (a, b) = (frame(10.5, 3), frame(11.25, 4));
        write_db3(
            &path,
            &[
                (11, "/points", POINTCLOUD2, encode_pointcloud2(&b, "lidar")),
                (10, "/points", POINTCLOUD2, encode_pointcloud2(&a, "lidar")),
                (10, "/chatter", "std_msgs/msg/String", vec![0, 1, 0, 0]),
            ],
        );
        let mut frames = TopicFrames::new("/points");
        read_db3(&path, &mut frames).unwrap();
        assert_eq!(
            frames.topic_list(),
            format!(
                "/chatter (std_msgs/msg/String, 1 messages), /points ({POINTCLOUD2}, 2 messages)"
            )
        );
        let got = frames.finish(&path).unwrap();
        assert_eq!(got.len(), 2);
        assert_eq!(got[0].points, a.points);
        assert_eq!(got[1].points, b.points);

        // Another topic of the wrong type is named with the file.
        let mut other = TopicFrames::new("/chatter");
        let err = read_db3(&path, &mut other).unwrap_err().to_string();
        assert!(
            err.contains("bag.db3") && err.contains("std_msgs/msg/String"),
            "{err}"
        );
    }

    #[test]
    fn a_corrupt_message_and_a_foreign_database_name_the_file() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("cut.db3");
        let mut data = encode_pointcloud2(&frame(3.0, 5), "lidar");
        data.truncate(data.len() / 2);
        write_db3(&path, &[(3_000_000_000, "/points", POINTCLOUD2, data)]);
        let err = read_db3(&path, &mut TopicFrames::new("/points"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("cut.db3") && err.contains("3000000000 ns"),
            "{err}"
        );

        let foreign = tmp.path().join("other.db3");
        Connection::open(&foreign)
            .unwrap()
            .execute_batch("CREATE TABLE topics(id INTEGER);")
            .unwrap();
        let err = read_db3(&foreign, &mut TopicFrames::new("/points"))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("other.db3") && err.contains("no table 'messages'"),
            "{err}"
        );
    }
}
