//! ROS 2 bags: dual-return frames as `sensor_msgs/msg/PointCloud2`
//! messages in CDR, in every form `ros2 bag record` leaves them, laid out
//! as the drivers write them; or as the Livox drivers' `CustomMsg`
//! ([`super::livox_custom`], read with the Livox layout whatever the
//! options; the topic's type says which, [`super::bag_message`]).
//!
//! [`read_bag_frames`] takes a rosbag2 directory (its `metadata.yaml` names
//! the storage, `mcap` or `sqlite3`, and the storage files in order, several
//! when the recording was split; see [`super::rosbag2`]), a bare `.mcap`
//! file or a bare `.db3` file (see [`super::db3`]). What a path is comes from
//! its content (magic bytes, `metadata.yaml`), not its name.
//!
//! The fields are read as the driver that wrote them lays them out (Ouster,
//! Livox, Hesai, nebula or specular's generic layout with a `return`
//! field), named in [`BagOptions`] or detected from the fields; see
//! [`super::pointcloud2::drivers`]. The Ouster driver publishes the second
//! return on a topic of its own, paired here by header stamp
//! ([`super::bag_topics::TopicFrames`]).
//!
//! Points that cannot be returns are set aside and counted in
//! [`Frame::dropped_non_finite`] (see [`crate::cloud::set_aside_non_returns`]);
//! the dataset keeps where they were ([`Dataset::set_aside`]), so outputs
//! keep one label per input point.

use std::borrow::Cow;
use std::io::Read;
use std::path::{Path, PathBuf};

pub use super::bag_topics::BagOptions;
use super::bag_topics::TopicFrames;
use super::dataset::{Dataset, InMemory};
use super::frames::FrameEntry;
pub use super::pointcloud2::drivers::Driver;
pub use super::pointcloud2::{
    decode_pointcloud2, decode_pointcloud2_full, encode_pointcloud2, POINTCLOUD2,
    POINTCLOUD2_SCHEMA,
};
use crate::cloud::{Frame, SetAside};
use crate::{Error, Result};

/// The first bytes of an MCAP file.
pub(crate) const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";
/// The first bytes of an SQLite 3 database (rosbag2's `.db3` storage).
pub(crate) const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";
/// The first bytes of a zstd frame (rosbag2's `--compression-mode file`).
const ZSTD_MAGIC: &[u8] = &[0x28, 0xb5, 0x2f, 0xfd];

/// Every point-cloud message (`PointCloud2` or Livox `CustomMsg`) on
/// `topic` of the bag at `path`, as frames in
/// timestamp order. `path` is a rosbag2 directory (or its `metadata.yaml`),
/// an MCAP file or an SQLite (`.db3`) file; see [`BagKind::of`]. The layout
/// is detected from the fields ([`read_bag_frames_with`] names it).
pub fn read_bag_frames(path: &Path, topic: &str) -> Result<Vec<Frame>> {
    read_bag_frames_with(path, topic, &BagOptions::default())
}

/// [`read_bag_frames`] with the layout (and Ouster's second topic) in
/// `options`.
pub fn read_bag_frames_with(path: &Path, topic: &str, options: &BagOptions) -> Result<Vec<Frame>> {
    Ok(read_bag_frames_full(path, topic, options)?
        .into_iter()
        .map(|(frame, _)| frame)
        .collect())
}

/// [`read_bag_frames_with`], each frame with where its points set aside
/// were ([`SetAside`]).
pub fn read_bag_frames_full(
    path: &Path,
    topic: &str,
    options: &BagOptions,
) -> Result<Vec<(Frame, SetAside)>> {
    let mut frames = TopicFrames::with_options(topic, options.clone());
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
    /// The `PointCloud2` (or Livox `CustomMsg`) frames on `topic` of the
    /// bag at `path` (any form
    /// [`BagKind::of`] knows), named by their header stamps, the layout
    /// detected from the fields.
    pub fn open(path: &Path, topic: &str) -> Result<Self> {
        Self::open_with(path, topic, &BagOptions::default())
    }

    /// [`Ros2Bag::open`] with the layout (and Ouster's second topic) in
    /// `options`.
    pub fn open_with(path: &Path, topic: &str, options: &BagOptions) -> Result<Self> {
        let (frames, aside) = read_bag_frames_full(path, topic, options)?
            .into_iter()
            .unzip();
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
