//! Where `detect` and `slam` read their frames: a 3DRef frame directory or
//! a ROS 2 bag. One set of arguments and one way to open them, so both
//! commands take the same inputs.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Args;
use specular::config::Config;
use specular::io;
use specular::pipeline::registry::{self, DatasetSource};
use specular::pipeline::Sequence;

/// The frames to read: `--frames DIR` or `--bag PATH --topic NAME`.
#[derive(Args, Debug)]
pub struct InputArgs {
    /// Directory of 3DRef frames (`<timestamp>.ply`), or a 3DRef release
    /// sequence directory (`raw/seqN`: frames in `raycast/hesai/`, poses
    /// from `hesai_pose.txt` unless a pose file is given).
    #[arg(long, required_unless_present = "bag")]
    pub frames: Option<PathBuf>,
    /// ROS 2 bag of `sensor_msgs/msg/PointCloud2` frames (CDR), instead of
    /// `--frames`: a rosbag2 directory (`metadata.yaml` with mcap or sqlite3
    /// storage; split files are read in order), an `.mcap` file or a `.db3`
    /// file. Frames are named by their header stamp in seconds.
    #[arg(long, conflicts_with = "frames", requires = "topic")]
    pub bag: Option<PathBuf>,
    /// The bag's point-cloud topic.
    #[arg(long, requires = "bag", conflicts_with = "frames")]
    pub topic: Option<String>,
}

/// A pose file and where it came from.
#[derive(Debug, Clone)]
pub struct PoseFile {
    /// The file.
    pub path: PathBuf,
    /// Found in a 3DRef release directory, not given on the command line.
    pub from_release: bool,
}

impl InputArgs {
    /// The frame directory or bag given.
    pub fn path(&self) -> &Path {
        self.frames
            .as_deref()
            .or(self.bag.as_deref())
            .unwrap_or(Path::new(""))
    }

    /// The pose file: `given`, else a 3DRef release directory's own.
    pub fn pose_file(&self, given: Option<&Path>) -> Option<PoseFile> {
        match (given, &self.frames) {
            (Some(path), _) => Some(PoseFile {
                path: path.to_path_buf(),
                from_release: false,
            }),
            (None, Some(frames)) => io::release_poses(frames).map(|path| PoseFile {
                path,
                from_release: true,
            }),
            (None, None) => None,
        }
    }

    /// The frames as a sequence, with each frame's pose from `poses` when
    /// given (matched as `config.input` says). The dataset is chosen by
    /// kind ([`registry::dataset`]); its frames are read pass by pass,
    /// keeping at most `input.frame_cache_mb` of the frames read (a bag is
    /// decoded whole, its frames named by header stamp).
    pub fn open(&self, poses: Option<&Path>, config: &Config) -> Result<Sequence> {
        let source = match (&self.frames, &self.bag) {
            (Some(frames), _) => DatasetSource::Frames(frames.clone()),
            (None, Some(bag)) => DatasetSource::Bag {
                path: bag.clone(),
                topic: self.topic.clone().unwrap_or_default(),
            },
            (None, None) => bail!("give --frames DIR or --bag PATH --topic NAME"),
        };
        let mut sequence = Sequence::from_dataset(registry::dataset(&source)?)
            .with_frame_cache(config.input.frame_cache_mb);
        if let Some(path) = poses {
            let matching = config.input.pose_matching();
            sequence.poses = Some(io::read_poses_for(&sequence.entries, path, matching)?);
        }
        if sequence.is_empty() {
            bail!("{}: no frames", self.path().display());
        }
        Ok(sequence)
    }
}
