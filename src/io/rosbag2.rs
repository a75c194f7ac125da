//! rosbag2 directories: what `ros2 bag record` writes, a `metadata.yaml`
//! beside one or more storage files.
//!
//! `metadata.yaml` holds `rosbag2_bagfile_information`: the
//! `storage_identifier` (`mcap` or `sqlite3`), the storage files in
//! recording order (`relative_file_paths`, several when the recording was
//! split by size or duration) and the topics with their types and message
//! counts (`topics_with_message_count`). Every listed file is read, in order,
//! with the reader of its storage ([`super::mcap_file::read_mcap`],
//! [`super::db3::read_db3`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::bag_message::check_type;
use super::bag_topics::TopicFrames;
use super::mcap_file::read_mcap;
use crate::cloud::Frame;
use crate::{Error, Result};

/// `metadata.yaml` as rosbag2 writes it: everything is under one key.
#[derive(Debug, Deserialize)]
struct MetadataFile {
    rosbag2_bagfile_information: Metadata,
}

/// The part of a bag's `rosbag2_bagfile_information` that specular uses
/// (other keys are ignored, so every rosbag2 version from Foxy on reads).
#[derive(Debug, Clone, Deserialize)]
pub struct Metadata {
    /// rosbag2's metadata format version (4 in Foxy ... 9 in Jazzy).
    pub version: u32,
    /// The storage plugin: `mcap` or `sqlite3`.
    pub storage_identifier: String,
    /// The storage files in recording order, relative to the bag directory.
    pub relative_file_paths: Vec<String>,
    /// The topics recorded, with their message counts (may be absent in a
    /// hand-made file; the storage files are read either way).
    #[serde(default)]
    pub topics_with_message_count: Vec<TopicWithCount>,
    /// `file` or `message` for a compressed bag; empty (or absent) when not.
    #[serde(default)]
    pub compression_mode: Option<String>,
    /// The compressor of a compressed bag (`zstd`).
    #[serde(default)]
    pub compression_format: Option<String>,
}

/// One entry of `topics_with_message_count`.
#[derive(Debug, Clone, Deserialize)]
pub struct TopicWithCount {
    /// The topic's name, type and serialization.
    pub topic_metadata: TopicMetadata,
    /// How many messages the bag holds on it.
    #[serde(default)]
    pub message_count: u64,
}

/// A topic as `metadata.yaml` describes it.
#[derive(Debug, Clone, Deserialize)]
pub struct TopicMetadata {
    /// Topic name, e.g. `/points`.
    pub name: String,
    /// Message type, e.g. `sensor_msgs/msg/PointCloud2`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Serialization format, `cdr` for ROS 2.
    #[serde(default)]
    pub serialization_format: String,
}

/// The storage plugins specular reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Storage {
    /// MCAP files (`.mcap`; the default from ROS 2 Iron on).
    Mcap,
    /// SQLite files (`.db3`; the default up to Humble).
    Sqlite3,
}

impl Metadata {
    /// Parse `metadata.yaml` text; `path` names the file in errors.
    pub fn parse(path: &Path, text: &str) -> Result<Self> {
        let file: MetadataFile = yaml_serde::from_str(text)
            .map_err(|e| Error::format(path, format!("not a rosbag2 metadata.yaml: {e}")))?;
        Ok(file.rosbag2_bagfile_information)
    }

    /// Read and parse the `metadata.yaml` at `path`.
    pub fn read(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(path, &text)
    }

    /// The storage plugin; an error naming `path` (the metadata file) for
    /// any other than `mcap` and `sqlite3`.
    pub fn storage(&self, path: &Path) -> Result<Storage> {
        match self.storage_identifier.as_str() {
            "mcap" => Ok(Storage::Mcap),
            "sqlite3" => Ok(Storage::Sqlite3),
            other => Err(Error::format(
                path,
                format!(
                    "storage_identifier '{}' is not mcap or sqlite3",
                    crate::error::excerpt(other)
                ),
            )),
        }
    }

    /// The topics listed, as `name (type, N messages)`, comma-separated.
    fn topic_list(&self) -> String {
        let list: Vec<String> = self
            .topics_with_message_count
            .iter()
            .map(|t| {
                let m = &t.topic_metadata;
                format!("{} ({}, {} messages)", m.name, m.kind, t.message_count)
            })
            .collect();
        list.join(", ")
    }

    /// An error naming `path` unless `topic` is listed as a CDR point
    /// cloud of a supported type (`PointCloud2` or a Livox `CustomMsg`,
    /// [`MessageKind`](super::bag_message::MessageKind); nothing is
    /// checked when no topic is listed).
    fn check_topic(&self, path: &Path, topic: &str) -> Result<()> {
        if self.topics_with_message_count.is_empty() {
            return Ok(());
        }
        let found = self
            .topics_with_message_count
            .iter()
            .find(|t| t.topic_metadata.name == topic);
        match found {
            Some(t) => check_type(
                path,
                topic,
                &t.topic_metadata.kind,
                &t.topic_metadata.serialization_format,
            )
            .map(|_| ()),
            None => Err(Error::format(
                path,
                format!("no topic {topic}; topics: {}", self.topic_list()),
            )),
        }
    }
}

/// The storage files of the bag in `dir` listed by `metadata` (read from
/// `meta`), in order; an error naming `meta` for a listed file that does not
/// exist. A path is relative to the bag directory, or (rosbag2 before
/// format version 4, which listed `bag/bag_0.db3`) to its parent.
pub fn storage_files(dir: &Path, meta: &Path, metadata: &Metadata) -> Result<Vec<PathBuf>> {
    if metadata.relative_file_paths.is_empty() {
        return Err(Error::format(meta, "relative_file_paths lists no file"));
    }
    metadata
        .relative_file_paths
        .iter()
        .map(|rel| {
            // Only files of the bag: a relative path down from the bag
            // directory (or, in the old form, starting with its name).
            let inside = Path::new(rel)
                .components()
                .all(|c| matches!(c, std::path::Component::Normal(_)));
            if rel.is_empty() || !inside {
                return Err(Error::format(
                    meta,
                    format!(
                        "relative_file_paths lists {}, which is not a path inside the bag directory {}",
                        crate::error::excerpt(rel),
                        dir.display()
                    ),
                ));
            }
            let own_name = dir.file_name().is_some_and(|n| {
                Path::new(rel).components().next()
                    == Some(std::path::Component::Normal(n))
            });
            let here = dir.join(rel);
            let beside = dir.parent().filter(|_| own_name).map(|p| p.join(rel));
            match beside {
                _ if here.is_file() => Ok(here),
                Some(p) if p.is_file() => Ok(p),
                _ => Err(Error::format(
                    meta,
                    format!(
                        "relative_file_paths lists {rel}, which is not a file in {}",
                        dir.display()
                    ),
                )),
            }
        })
        .collect()
}

/// Every `PointCloud2` message on the topic of `frames` in the rosbag2
/// directory `dir`, as frames in timestamp order: `metadata.yaml` is read
/// and checked (storage, compression, the topic's presence and type, the
/// files listed) before any storage file is opened.
pub fn read_directory(dir: &Path, mut frames: TopicFrames) -> Result<Vec<Frame>> {
    read_directory_into(dir, &mut frames)?;
    frames.finish(dir)
}

/// [`read_directory`], gathering into `frames` (the caller finishes them).
pub fn read_directory_into(dir: &Path, frames: &mut TopicFrames) -> Result<()> {
    let meta = dir.join("metadata.yaml");
    let metadata = Metadata::read(&meta)?;
    let storage = metadata.storage(&meta)?;
    let mode = metadata.compression_mode.as_deref().unwrap_or("");
    if !mode.is_empty() && !mode.eq_ignore_ascii_case("none") {
        let format = metadata.compression_format.as_deref().unwrap_or("");
        return Err(Error::format(
            &meta,
            format!(
                "compression_mode '{}' ({}) is not supported: decompress the bag first (ros2 bag convert)",
                crate::error::excerpt(mode),
                crate::error::excerpt(format)
            ),
        ));
    }
    let topic = frames.topic().to_string();
    metadata.check_topic(&meta, &topic)?;
    for file in storage_files(dir, &meta, &metadata)? {
        match storage {
            Storage::Mcap => read_mcap(&file, frames)?,
            Storage::Sqlite3 => super::db3::read_db3(&file, frames)?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const META: &str = "rosbag2_bagfile_information:
  version: 5
  storage_identifier: sqlite3
  relative_file_paths:
    - bag_0.db3
    - bag_1.db3
  duration:
    nanoseconds: 0
  message_count: 4
  topics_with_message_count:
    - topic_metadata:
        name: /points
        type: sensor_msgs/msg/PointCloud2
        serialization_format: cdr
        offered_qos_profiles: \"- history: 3\\n  depth: 0\"
      message_count: 3
    - topic_metadata:
        name: /imu
        type: sensor_msgs/msg/Imu
        serialization_format: cdr
        offered_qos_profiles: \"\"
      message_count: 1
  compression_format: \"\"
  compression_mode: \"\"
";

    #[test]
    fn metadata_parses_and_checks_the_topic() {
        let path = Path::new("bag/metadata.yaml");
        let m = Metadata::parse(path, META).unwrap();
        assert_eq!(m.version, 5);
        assert_eq!(m.storage(path).unwrap(), Storage::Sqlite3);
        assert_eq!(m.relative_file_paths, ["bag_0.db3", "bag_1.db3"]);
        assert!(m.check_topic(path, "/points").is_ok());
        let err = m.check_topic(path, "/nope").unwrap_err().to_string();
        assert!(
            err.starts_with("bag/metadata.yaml: no topic /nope"),
            "{err}"
        );
        assert!(
            err.contains("/points (sensor_msgs/msg/PointCloud2, 3 messages)"),
            "{err}"
        );
        assert!(
            err.contains("/imu (sensor_msgs/msg/Imu, 1 messages)"),
            "{err}"
        );
        let err = m.check_topic(path, "/imu").unwrap_err().to_string();
        assert!(err.contains("sensor_msgs/msg/Imu"), "{err}");
    }

    #[test]
    fn bad_metadata_names_the_file_and_the_key() {
        let path = Path::new("x/metadata.yaml");
        let m = Metadata::parse(path, &META.replace("sqlite3", "foo")).unwrap();
        let err = m.storage(path).unwrap_err().to_string();
        assert_eq!(
            err,
            "x/metadata.yaml: storage_identifier 'foo' is not mcap or sqlite3"
        );
        let no_files = META.replace("relative_file_paths", "other_paths");
        let err = Metadata::parse(path, &no_files).unwrap_err().to_string();
        assert!(
            err.starts_with("x/metadata.yaml: ") && err.contains("relative_file_paths"),
            "{err}"
        );
        let err = Metadata::parse(path, "[1, 2").unwrap_err().to_string();
        assert!(
            err.starts_with("x/metadata.yaml: not a rosbag2 metadata.yaml"),
            "{err}"
        );
    }

    #[test]
    fn listed_files_resolve_in_the_bag_or_its_parent() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("bag");
        std::fs::create_dir(&dir).unwrap();
        std::fs::write(dir.join("bag_0.db3"), b"").unwrap();
        std::fs::write(dir.join("bag_1.db3"), b"").unwrap();
        let meta = dir.join("metadata.yaml");
        let mut m = Metadata::parse(&meta, META).unwrap();
        let files = storage_files(&dir, &meta, &m).unwrap();
        assert_eq!(files, [dir.join("bag_0.db3"), dir.join("bag_1.db3")]);
        // Old rosbag2: paths relative to the bag's parent.
        m.relative_file_paths = vec!["bag/bag_1.db3".into()];
        assert_eq!(
            storage_files(&dir, &meta, &m).unwrap(),
            [tmp.path().join("bag/bag_1.db3")]
        );
        m.relative_file_paths = vec!["bag_0.db3".into(), "bag_2.db3".into()];
        let err = storage_files(&dir, &meta, &m).unwrap_err().to_string();
        assert!(
            err.contains("metadata.yaml") && err.contains("lists bag_2.db3"),
            "{err}"
        );
        m.relative_file_paths.clear();
        assert!(storage_files(&dir, &meta, &m).is_err());
    }
}
