//! Where `detect` and `slam` read their frames: a 3DRef frame directory, a
//! ROS 2 bag or a simulated scene. One set of arguments and one way to open
//! them, so both commands take the same inputs.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Args;
use specular::config::Config;
use specular::io;
use specular::pipeline::registry::{self, DatasetSource};
use specular::pipeline::Sequence;
use specular::sensor::SensorModel;
use specular::sim::{LabelRule, SceneSource};

/// The frames to read: `--frames DIR`, `--bag PATH --topic NAME` or
/// `--scene NAME`.
#[derive(Args, Debug)]
pub struct InputArgs {
    /// Directory of 3DRef frames (`<timestamp>.ply`), or a 3DRef release
    /// sequence directory (`raw/seqN`: frames in `raycast/hesai/`, poses
    /// from `hesai_pose.txt` unless a pose file is given) or one of its
    /// sensor folders (`raw/seqN/raycast/ouster` or `.../livox`, poses
    /// from `raw/seqN/ouster_pose.txt` or `livox_pose.txt`).
    #[arg(long, required_unless_present_any = ["bag", "scene", "family"])]
    pub frames: Option<PathBuf>,
    /// ROS 2 bag of `sensor_msgs/msg/PointCloud2` frames (CDR), or of Livox
    /// `CustomMsg` frames (livox_ros2_driver's `livox_interfaces/msg/CustomMsg`,
    /// livox_ros_driver2's `livox_ros_driver2/msg/CustomMsg`), instead of
    /// `--frames`: a rosbag2 directory (`metadata.yaml` with mcap or sqlite3
    /// storage; split files are read in order), an `.mcap` file or a `.db3`
    /// file. Frames are named by their header stamp in seconds; the
    /// fields are read as `--driver` says (default: detected).
    #[arg(long, conflicts_with_all = ["frames", "scene", "family"], requires = "topic")]
    pub bag: Option<PathBuf>,
    /// The bag's point-cloud topic (for the Ouster driver, the first
    /// return's: `/ouster/points`).
    #[arg(long, requires = "bag", conflicts_with = "frames")]
    pub topic: Option<String>,
    /// The driver that wrote the bag, whose field layout is read (default:
    /// detected from the fields): generic (a `return` field), ouster
    /// (ouster-ros: second return on its own topic), livox
    /// (livox_ros_driver2: return in `tag` bits; a `CustomMsg` topic is
    /// always read as livox), hesai
    /// (HesaiLidar_ROS_2.0: both returns in one cloud, paired by order)
    /// or nebula (`return_type`). A bag without the named layout's fields
    /// is an error naming the fields it lacks.
    #[arg(long, value_enum, requires = "bag")]
    pub driver: Option<DriverArg>,
    /// The Ouster driver's second-return topic (default: the topic with
    /// `2` appended, `/ouster/points2`).
    #[arg(long, requires = "bag")]
    pub second_topic: Option<String>,
    /// A simulated scene instead of recorded frames: a built-in name
    /// (office, lobby, corridor, mirror-room, glass-loop, ...) or a scene
    /// TOML file. Frames are made as they are read, nothing is written;
    /// the scene's true poses (and labels) come with them, as the poses of
    /// `detect` and the ground truth of `slam`.
    #[arg(long, conflicts_with_all = ["frames", "bag", "family"])]
    pub scene: Option<String>,
    /// A scene family instead (`specular simulate --list-families`): the
    /// scene drawn for `--seed` (0-999 development, from 1000000 held
    /// out), simulated in memory like `--scene`.
    #[arg(long, conflicts_with_all = ["frames", "bag"])]
    pub family: Option<String>,
    /// Frames of `--scene` or `--family` (default: the scene's own count).
    #[arg(long)]
    pub scene_frames: Option<usize>,
    /// Range-noise seed of `--scene` (default: the scene's own); with
    /// `--family`, the family's seed (default 0), which draws the scene and
    /// its noise.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Which truth a simulated scene's labels carry: 3DRef's ray-cast rule
    /// (as the real data is labelled) or the echo's physical path.
    #[arg(long, value_enum, default_value_t = LabelsArg::Raycast3dref)]
    pub labels: LabelsArg,
    /// The sensor: a built-in model (pandar_qt64, ouster-os0-128,
    /// ouster-os0-128:2048, livox-avia, velodyne_hdl32e) or a sensor TOML.
    /// A simulated scene is simulated with it instead of its own; recorded
    /// frames are read as its (instead of the configuration's `sensor`;
    /// frames whose header names another sensor are refused).
    #[arg(long)]
    pub sensor: Option<String>,
    /// Leave frames whose points carry their times as measured: no
    /// deskewing (by default such a frame is moved to its stamp with the
    /// motion estimate: `slam`'s tracking velocity, then the velocity of
    /// the poses; `detect`'s poses). To see what deskewing does.
    #[arg(long)]
    pub no_deskew: bool,
}

/// The bag layouts on the command line (`--driver`).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DriverArg {
    /// specular's own layout: a `return` (or `ret`) field.
    Generic,
    /// ouster-ros: `x y z intensity t reflectivity ring ambient range`,
    /// return 2 on a second topic.
    Ouster,
    /// livox_ros_driver2: `x y z intensity tag line timestamp`, and both
    /// Livox drivers' `CustomMsg`.
    Livox,
    /// HesaiLidar_ROS_2.0: `x y z intensity ring timestamp`.
    Hesai,
    /// tier4 nebula: `x y z intensity return_type channel ... time_stamp`.
    Nebula,
}

impl From<DriverArg> for io::Driver {
    fn from(d: DriverArg) -> Self {
        match d {
            DriverArg::Generic => io::Driver::Generic,
            DriverArg::Ouster => io::Driver::Ouster,
            DriverArg::Livox => io::Driver::Livox,
            DriverArg::Hesai => io::Driver::Hesai,
            DriverArg::Nebula => io::Driver::Nebula,
        }
    }
}

/// The label rule of simulated frames on the command line.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabelsArg {
    /// 3DRef's ray-cast labelling rule (the default).
    #[value(name = "3dref")]
    Raycast3dref,
    /// The physical path of each echo.
    Physical,
}

impl From<LabelsArg> for LabelRule {
    fn from(l: LabelsArg) -> Self {
        match l {
            LabelsArg::Raycast3dref => LabelRule::Raycast3dref,
            LabelsArg::Physical => LabelRule::Physical,
        }
    }
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
    /// The frame directory, bag or scene given.
    pub fn path(&self) -> &Path {
        self.frames
            .as_deref()
            .or(self.bag.as_deref())
            .or(self.scene.as_deref().map(Path::new))
            .or(self.family.as_deref().map(Path::new))
            .unwrap_or(Path::new(""))
    }

    /// The configuration with `--sensor` as its `sensor` when given (the
    /// model of recorded frames that do not name their own).
    pub fn apply_sensor(&self, config: &mut Config) -> Result<()> {
        if let Some(name) = &self.sensor {
            SensorModel::resolve(name)?;
            config.sensor = name.clone();
        }
        Ok(())
    }

    /// Whether the input brings its own (true) poses: a simulated scene.
    pub fn has_own_poses(&self) -> bool {
        self.simulated().is_some()
    }

    /// The simulated scene given, if any.
    pub fn simulated(&self) -> Option<SceneSource> {
        match (&self.scene, &self.family) {
            (Some(scene), _) => Some(SceneSource::Named(scene.clone())),
            (None, Some(family)) => Some(SceneSource::Family {
                family: family.clone(),
                seed: self.seed.unwrap_or(0),
            }),
            (None, None) => None,
        }
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
    /// given (matched as `config.input` says; a simulated scene brings its
    /// true poses and takes no pose file). The dataset is chosen by
    /// kind ([`registry::dataset`]); its frames are read pass by pass,
    /// keeping at most `input.frame_cache_mb` of the frames read (a bag is
    /// decoded whole, its frames named by header stamp).
    pub fn open(&self, poses: Option<&Path>, config: &Config) -> Result<Sequence> {
        let source = match (&self.frames, &self.bag) {
            (Some(frames), _) => DatasetSource::Frames(frames.clone()),
            (None, Some(bag)) => DatasetSource::Bag {
                path: bag.clone(),
                topic: self.topic.clone().unwrap_or_default(),
                options: io::BagOptions {
                    driver: self.driver.map(Into::into),
                    second_topic: self.second_topic.clone(),
                },
            },
            (None, None) => match self.simulated() {
                Some(scene) => DatasetSource::Simulated {
                    // A family's seed draws its scene and its noise.
                    seed: if self.family.is_some() {
                        None
                    } else {
                        self.seed
                    },
                    scene,
                    frames: self.scene_frames,
                    labels: self.labels.into(),
                    sensor: self.sensor.clone(),
                },
                None => bail!(
                    "give --frames DIR, --bag PATH --topic NAME, --scene NAME or --family NAME"
                ),
            },
        };
        if self.simulated().is_none() && (self.scene_frames.is_some() || self.seed.is_some()) {
            bail!("--scene-frames and --seed apply to --scene or --family only");
        }
        if self.simulated().is_some() && poses.is_some() {
            let flag = if self.scene.is_some() {
                "--scene"
            } else {
                "--family"
            };
            bail!("{flag} brings its true poses: drop the pose file");
        }
        let dataset = registry::dataset(&source)?;
        if let (Some(given), Some(own), None) = (&self.sensor, dataset.sensor(), self.simulated()) {
            let given = SensorModel::resolve(given)?;
            if given.name != own.name {
                bail!(
                    "{}: the frames name sensor '{}' but --sensor says '{}'",
                    self.path().display(),
                    own.name,
                    given.name
                );
            }
        }
        let mut sequence =
            Sequence::from_dataset(dataset).with_frame_cache(config.input.frame_cache_mb);
        if self.no_deskew {
            sequence = sequence.without_deskew();
        }
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
