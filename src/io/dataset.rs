//! The [`Dataset`] seam: where a sequence's frames come from.
//!
//! A dataset knows its frames' names and timestamps without reading them,
//! and gives frame `i` on demand: lent when it holds the frames, made
//! (parsed, decoded, simulated) when asked otherwise. Poses and the sensor
//! model are optional. Labels travel inside the frames
//! ([`Frame::has_labels`] and each point's `label`).
//!
//! The pipelines never see a dataset directly: a
//! [`Sequence`](crate::pipeline::Sequence) wraps one, keeps a bounded cache
//! of the frames it made and streams them pass by pass, so memory stays
//! bounded whatever the dataset's length. The implementations:
//!
//! | type | frames |
//! |---|---|
//! | [`PlyDir`] | a 3DRef frame directory or release sequence (`raw/seqN`), parsed on demand |
//! | [`InMemory`] | frames already parsed or made (tests, benchmarks, the demo) |
//! | [`Ros2Bag`](crate::io::ros2_bag::Ros2Bag) | a ROS 2 bag's `PointCloud2` topic |
//! | [`SimDataset`](crate::sim::SimDataset) | the simulator, one frame at a time, with its true poses |
//!
//! A new kind is a type implementing [`Dataset`] (see
//! `tests/custom_dataset.rs`) and, to be chosen on the command line, one
//! arm in [`registry::dataset`](crate::pipeline::registry::dataset).

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use super::frames::{frame_dir, list_frames, read_poses_for, FrameEntry, PoseMatching};
use super::ply::{read_frame, read_frame_full};
use crate::cloud::{Frame, SetAside};
use crate::sensor::SensorModel;
use crate::{Error, Result};

/// A source of frames: length, frame `i`, and what else it knows.
///
/// `frame` is called from several threads at once (a pass works on a
/// window of frames in parallel), hence `Send + Sync`. It is called once
/// per frame per pass, never per point.
pub trait Dataset: Send + Sync {
    /// Every frame's name, timestamp and file (or a name standing for
    /// one), in time order; known without reading a frame.
    fn entries(&self) -> &[FrameEntry];

    /// Frame `index`: borrowed when the dataset holds it, owned when made
    /// on demand (the [`Sequence`](crate::pipeline::Sequence) then keeps
    /// what fits its cache). The error names the frame.
    fn frame(&self, index: usize) -> Result<Cow<'_, Frame>>;

    /// `T_world_sensor` of every frame, when the dataset brings its own
    /// (the simulator's truth); `None` leaves them to a pose file.
    fn poses(&self) -> Option<Vec<Isometry3<f64>>> {
        None
    }

    /// The sensor the frames were taken with, when the dataset knows it
    /// (the simulator does); `None` means the configuration's `sensor`.
    fn sensor(&self) -> Option<SensorModel> {
        None
    }

    /// Every frame, when the dataset holds them all in memory.
    fn in_memory(&self) -> Option<&[Frame]> {
        None
    }

    /// Where the points of frame `index` that are not in
    /// [`Frame::points`] (counted in [`Frame::dropped_non_finite`]) were in
    /// its input, so its outputs keep one entry per input point. Asked
    /// only for a frame that set points aside (never on clean data, so it
    /// may re-read the frame). The default knows nothing: an error for a
    /// frame that set points aside, rather than labels shifted against
    /// their points.
    fn set_aside(&self, index: usize) -> Result<SetAside> {
        let frame = self.frame(index)?;
        if frame.dropped_non_finite == 0 {
            return Ok(SetAside::default());
        }
        Err(Error::Input(format!(
            "{}: frame {} set {} points aside but the dataset does not say where they were, so its labels cannot be written in input order",
            self.origin(),
            frame.name,
            frame.dropped_non_finite
        )))
    }

    /// Where the frames come from, for messages (a path or a name).
    fn origin(&self) -> String;

    /// Number of frames.
    fn len(&self) -> usize {
        self.entries().len()
    }

    /// Whether there is no frame.
    fn is_empty(&self) -> bool {
        self.entries().is_empty()
    }
}

/// The `*.ply` frames of a directory, parsed when asked for. Nothing is
/// read when it is opened but the file list, the first frame's header (the
/// sensor it names, `comment sensor NAME`) and the poses, when given.
#[derive(Debug, Clone)]
pub struct PlyDir {
    dir: PathBuf,
    entries: Vec<FrameEntry>,
    poses: Option<Vec<Isometry3<f64>>>,
    sensor: Option<SensorModel>,
}

impl PlyDir {
    /// The frames of `dir`, or of the 3DRef release layout
    /// `dir/raycast/hesai/` ([`frame_dir`]). Errors when the directory
    /// is unreadable, holds no frame or a stem is not a timestamp.
    pub fn open(dir: &Path) -> Result<Self> {
        let dir = frame_dir(dir);
        let entries = list_frames(&dir)?;
        let sensor = match entries.first() {
            Some(e) => match super::ply::frame_sensor(&e.path)? {
                Some(name) => Some(SensorModel::resolve(&name).map_err(|err| {
                    Error::format(&e.path, format!("its header names sensor '{name}': {err}"))
                })?),
                None => None,
            },
            None => None,
        };
        Ok(Self {
            dir,
            entries,
            poses: None,
            sensor,
        })
    }

    /// Each frame's pose from the file `poses` (TUM matched by timestamp
    /// as `matching` says, or KITTI by order; [`read_poses_for`]).
    pub fn with_poses(mut self, poses: &Path, matching: PoseMatching) -> Result<Self> {
        self.poses = Some(read_poses_for(&self.entries, poses, matching)?);
        Ok(self)
    }

    /// The directory the frames are in.
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

impl Dataset for PlyDir {
    fn entries(&self) -> &[FrameEntry] {
        &self.entries
    }

    fn frame(&self, index: usize) -> Result<Cow<'_, Frame>> {
        read_frame(&self.entries[index].path).map(Cow::Owned)
    }

    fn set_aside(&self, index: usize) -> Result<SetAside> {
        read_frame_full(&self.entries[index].path).map(|(_, aside)| aside)
    }

    fn poses(&self) -> Option<Vec<Isometry3<f64>>> {
        self.poses.clone()
    }

    fn sensor(&self) -> Option<SensorModel> {
        self.sensor.clone()
    }

    fn origin(&self) -> String {
        self.dir.display().to_string()
    }
}

/// Frames already in memory, with their poses when known: parsed ahead
/// (small sequences read many times), decoded from a bag, or made by the
/// simulator.
#[derive(Debug, Clone)]
pub struct InMemory {
    origin: String,
    entries: Vec<FrameEntry>,
    frames: Vec<Frame>,
    poses: Option<Vec<Isometry3<f64>>>,
    /// Per frame, where its points set aside were (empty: none known).
    set_aside: Vec<SetAside>,
}

impl InMemory {
    /// `frames` in time order, their `poses` when known (one per frame).
    /// `origin` names the source in messages; a frame's entry is
    /// `origin/<name>.ply`.
    pub fn new(
        frames: Vec<Frame>,
        poses: Option<Vec<Isometry3<f64>>>,
        origin: &str,
    ) -> Result<Self> {
        let entries = frames
            .iter()
            .map(|f| FrameEntry {
                path: Path::new(origin).join(format!("{}.ply", f.name)),
                name: f.name.clone(),
                stamp: f.stamp,
            })
            .collect();
        Self::with_entries(entries, frames, poses, origin)
    }

    /// `frames` with their `entries` (same length, same order).
    pub fn with_entries(
        entries: Vec<FrameEntry>,
        frames: Vec<Frame>,
        poses: Option<Vec<Isometry3<f64>>>,
        origin: &str,
    ) -> Result<Self> {
        if entries.len() != frames.len() {
            return Err(Error::Input(format!(
                "{origin}: {} entries for {} frames",
                entries.len(),
                frames.len()
            )));
        }
        if let Some(p) = &poses {
            if p.len() != frames.len() {
                return Err(Error::Input(format!(
                    "{origin}: {} poses for {} frames",
                    p.len(),
                    frames.len()
                )));
            }
        }
        Ok(Self {
            origin: origin.to_string(),
            entries,
            frames,
            poses,
            set_aside: Vec::new(),
        })
    }

    /// Where each frame's points set aside were (one per frame, same
    /// order; see [`Dataset::set_aside`]), as the reader that made the
    /// frames said.
    pub fn with_set_aside(mut self, set_aside: Vec<SetAside>) -> Result<Self> {
        if set_aside.len() != self.frames.len() {
            return Err(Error::Input(format!(
                "{}: {} set-aside lists for {} frames",
                self.origin,
                set_aside.len(),
                self.frames.len()
            )));
        }
        self.set_aside = set_aside;
        Ok(self)
    }
}

impl Dataset for InMemory {
    fn entries(&self) -> &[FrameEntry] {
        &self.entries
    }

    fn frame(&self, index: usize) -> Result<Cow<'_, Frame>> {
        Ok(Cow::Borrowed(&self.frames[index]))
    }

    fn poses(&self) -> Option<Vec<Isometry3<f64>>> {
        self.poses.clone()
    }

    fn in_memory(&self) -> Option<&[Frame]> {
        Some(&self.frames)
    }

    fn set_aside(&self, index: usize) -> Result<SetAside> {
        let frame = &self.frames[index];
        match self.set_aside.get(index) {
            Some(aside) => Ok(aside.clone()),
            None if frame.dropped_non_finite == 0 => Ok(SetAside::default()),
            None => Err(Error::Input(format!(
                "{}: frame {} set {} points aside but the dataset does not say where they were, so its labels cannot be written in input order",
                self.origin, frame.name, frame.dropped_non_finite
            ))),
        }
    }

    fn origin(&self) -> String {
        self.origin.clone()
    }
}
