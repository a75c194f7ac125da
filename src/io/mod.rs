//! Input and output at the edge of the library: the [`Dataset`] seam (where
//! a sequence's frames come from), 3DRef PLY frames, ROS 2
//! bags (rosbag2 directories, MCAP and sqlite3 `.db3` files), TUM and KITTI pose files, prediction labels and their confidences (`.prob`), and matching frames
//! to poses by timestamp.
//!
//! Every reader returns a [`crate::Error`] naming the file and what is wrong;
//! every writer writes to a temporary file and renames it into place, so a
//! failed run never leaves a half-written output.

pub mod atomic;
pub mod bag_message;
pub mod bag_topics;
pub(crate) mod cdr;
pub mod dataset;
pub mod db3;
pub mod frames;
pub mod kitti;
pub mod labels;
pub mod livox_custom;
pub mod map_ply;
pub mod mcap_file;
pub mod planes;
pub mod ply;
pub mod pointcloud2;
pub mod prob;
pub mod ros2_bag;
pub mod rosbag2;
pub mod tum;

pub use atomic::write_atomic;
pub use dataset::{Dataset, InMemory, PlyDir};
pub use frames::{
    frame_dir, interpolate, list_frames, match_poses, match_poses_with, parse_stamp,
    read_poses_for, release_poses, FrameEntry, PoseMatching,
};
pub use kitti::{parse_kitti, read_kitti};
pub use labels::{read_labels, write_labels};
pub use map_ply::{write_map_ply, MapPoint};
pub use planes::{read_planes, write_planes, PlaneKind, PlaneRecord};
pub use ply::{
    frame_sensor, parse_frame, parse_frame_full, read_frame, read_frame_full, read_frames,
    write_frame, write_frame_of, PlyEncoding,
};
pub use prob::{read_probs, read_probs_for, write_probs};
pub use ros2_bag::{read_bag_frames, read_bag_frames_with, BagKind, BagOptions, Driver, Ros2Bag};
pub use tum::{parse_tum, read_tum, write_tum, StampedPose};
