//! A sequence of frames with their poses, read pass by pass.
//!
//! A whole 3DRef sequence (thousands of 1-2 MB frames) does not fit in
//! memory, and the methods do not need it to: each pass over the sequence
//! (detect, gather evidence, classify) reads a window of frames, works on
//! them in parallel and hands the results on in sequence order before the
//! next window is read ([`Sequence::stream`]). The frames come from a
//! [`Dataset`] (a PLY directory, a bag, the simulator, frames in memory):
//! the pipelines read frames only through a sequence, and a sequence only
//! through its dataset. Frames the dataset lends (it holds them) are used
//! as they are; frames it makes (parsed, simulated) are kept in a bounded
//! cache, the first ones of the sequence, up to a budget of bytes.
//!
//! A frame whose points carry their times ([`Point::time`](crate::cloud::Point::time))
//! is handed out deskewed ([`crate::slam::deskew`]) when the sequence has
//! poses: moved to its stamp with the velocity of its poses (the motion to
//! the next frame over their interval, averaged over the intervals around
//! it: [`smoothed_velocity`](crate::slam::deskew::smoothed_velocity)), so every pass, the classification
//! included, sees the deskewed points. The cache keeps the frames as read,
//! so new poses (the SLAM's estimate) deskew anew. Frames without times
//! are handed out as read.

use std::borrow::Cow;
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::StageTimings;
use crate::cloud::{Frame, SetAside};
use crate::io::{self, Dataset, FrameEntry, InMemory, PlyDir};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::Result;

mod frame_cache;

use frame_cache::{megabytes, FrameCache};

/// Frames of one sequence in timestamp order, with their poses when given.
#[derive(Clone)]
pub struct Sequence {
    /// The frame files (or, for frames not read from files, their names).
    pub entries: Vec<FrameEntry>,
    /// `T_world_sensor` per frame (matched by timestamp), when known.
    pub poses: Option<Vec<Isometry3<f64>>>,
    /// Whether frames with per-point times are deskewed with the poses
    /// (on unless [`without_deskew`](Self::without_deskew)).
    deskew: bool,
    /// Where the frames come from.
    dataset: Arc<dyn Dataset>,
    /// The frames the dataset made, kept between passes up to a budget.
    cache: Arc<FrameCache>,
}

impl std::fmt::Debug for Sequence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sequence")
            .field("origin", &self.dataset.origin())
            .field("frames", &self.entries.len())
            .field("poses", &self.poses.is_some())
            .finish()
    }
}

/// Megabytes of parsed frames a sequence read from files keeps by default
/// ([`Sequence::with_frame_cache`]).
pub const DEFAULT_FRAME_CACHE_MB: f64 = 256.0;

/// Input handling: how frames find their poses and how many parsed frames
/// a sequence keeps (the `[input]` section of the configuration).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputParams {
    /// A frame is matched to the pose with the nearest timestamp, which must
    /// be within this many seconds, s.
    pub pose_tolerance: f64,
    /// A frame with no pose within `pose_tolerance` gets one interpolated
    /// between the poses before and after it (SLERP) when they are at most
    /// this many seconds apart, s; beyond, the run stops naming the frame
    /// (with 0 no two poses are that close: never interpolate).
    pub pose_interpolation_gap: f64,
    /// Frames read from files are kept in memory after their first read,
    /// up to this many megabytes of points, so later passes over the
    /// sequence do not parse them again; beyond it frames are re-read at
    /// every pass (memory stays bounded whatever the sequence length), MB.
    pub frame_cache_mb: f64,
}

impl InputParams {
    /// How frames find their poses.
    pub fn pose_matching(&self) -> crate::io::PoseMatching {
        crate::io::PoseMatching {
            tolerance: self.pose_tolerance,
            max_gap: self.pose_interpolation_gap,
            max_translation: crate::io::frames::MAX_POSE_TRANSLATION,
            max_speed: crate::io::frames::MAX_SPEED,
        }
    }
}

impl Default for InputParams {
    /// `[input]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("input")
    }
}

/// Frames handled at once by [`Sequence::stream`]: enough to keep every
/// thread busy, few enough that the frames in flight stay a small,
/// fixed amount of memory.
pub fn stream_window() -> usize {
    (4 * rayon::current_num_threads()).max(8)
}

impl Sequence {
    /// The frames of `dataset`, with its own poses when it brings them,
    /// keeping up to [`DEFAULT_FRAME_CACHE_MB`] of the frames it makes.
    pub fn new(dataset: impl Dataset + 'static) -> Self {
        Self::from_dataset(Arc::new(dataset))
    }

    /// [`new`](Self::new) for a dataset already shared.
    pub fn from_dataset(dataset: Arc<dyn Dataset>) -> Self {
        let entries = dataset.entries().to_vec();
        let poses = dataset.poses();
        let cache = FrameCache::new(entries.len(), megabytes(DEFAULT_FRAME_CACHE_MB));
        Self {
            entries,
            poses,
            deskew: true,
            dataset,
            cache: Arc::new(cache),
        }
    }

    /// The `*.ply` frames of `dir` (or of the 3DRef release layout
    /// `dir/raycast/hesai/`, see [`io::frame_dir`]) and, when `poses` is
    /// given, each frame's pose (TUM, matched by timestamp as `matching`
    /// says, or KITTI, by order; [`io::read_poses_for`]). Nothing is
    /// parsed: every pass reads the frames it needs ([`PlyDir`]).
    pub fn open(
        dir: &Path,
        poses: Option<&Path>,
        matching: impl Into<io::PoseMatching>,
    ) -> Result<Self> {
        let mut frames = PlyDir::open(dir)?;
        // Poses first: a missing pose is reported before any parsing work.
        if let Some(path) = poses {
            frames = frames.with_poses(path, matching.into())?;
        }
        Ok(Self::new(frames))
    }

    /// Keep at most `megabytes` of the frames the dataset makes between
    /// passes (0: make every frame at every pass). No effect on frames the
    /// dataset holds in memory.
    pub fn with_frame_cache(mut self, megabytes_kept: f64) -> Self {
        self.cache = Arc::new(FrameCache::new(
            self.entries.len(),
            megabytes(megabytes_kept),
        ));
        self
    }

    /// The same frames handed out as read, never deskewed with the poses
    /// (the SLAM's tracking deskews with its own motion estimate, and must
    /// not see true poses a simulated sequence brings).
    pub fn without_deskew(mut self) -> Self {
        self.deskew = false;
        self
    }

    /// Whether frames with per-point times are deskewed (on unless
    /// [`without_deskew`](Self::without_deskew)); the SLAM's tracking
    /// follows it too.
    pub fn deskew_enabled(&self) -> bool {
        self.deskew
    }

    /// Whether frame `index` (`frame`, as read) is handed out deskewed:
    /// it carries per-point times, the sequence has poses and deskewing
    /// is on.
    fn deskews(&self, index: usize, frame: &Frame) -> bool {
        self.deskew
            && self.poses.is_some()
            && *self.cache.timed[index].get_or_init(|| crate::slam::deskew::is_timed(frame))
    }

    /// `frame` (frame `index` as read) deskewed with the velocity of the
    /// sequence's poses when [`deskews`](Self::deskews) says so.
    fn deskewed<'a>(&self, index: usize, frame: Cow<'a, Frame>) -> Cow<'a, Frame> {
        if !self.deskews(index, &frame) {
            return frame;
        }
        let Some(poses) = &self.poses else {
            return frame;
        };
        use crate::slam::deskew::{smoothed_velocity, velocity_window, VELOCITY_HALF_WINDOW};
        let n = poses.len().min(self.entries.len());
        let w = velocity_window(n, index, VELOCITY_HALF_WINDOW);
        let stamps: Vec<f64> = self.entries[w.clone()].iter().map(|e| e.stamp).collect();
        let velocity = smoothed_velocity(
            &poses[w.clone()],
            &stamps,
            index - w.start,
            VELOCITY_HALF_WINDOW,
        );
        Cow::Owned(crate::slam::deskew::deskewed(&frame, &velocity))
    }

    /// Like [`open`](Self::open), then parse every frame (in parallel) and
    /// keep them in memory: for small sequences read many times (tests,
    /// benchmarks). Parsing time is recorded in `timings` as stage "parse".
    pub fn load(
        dir: &Path,
        poses: Option<&Path>,
        tolerance: f64,
        timings: &mut StageTimings,
    ) -> Result<Self> {
        let sequence = Self::open(dir, poses, tolerance)?;
        let bar = crate::progress::bar(sequence.len(), "parse");
        let parsed: Vec<(Frame, SetAside, Duration)> = sequence
            .entries
            .par_iter()
            .map(|e| {
                let start = Instant::now();
                let frame = io::read_frame_full(&e.path).map(|(f, a)| (f, a, start.elapsed()));
                bar.inc(1);
                frame
            })
            .collect::<Result<_>>()?;
        bar.finish_and_clear();
        let mut frames = Vec::with_capacity(parsed.len());
        let mut aside = Vec::with_capacity(parsed.len());
        for (f, a, d) in parsed {
            timings.add("parse", d);
            frames.push(f);
            aside.push(a);
        }
        let origin = sequence.dataset.origin();
        let held = InMemory::with_entries(sequence.entries, frames, sequence.poses, &origin)?
            .with_set_aside(aside)?;
        Ok(Self::new(held))
    }

    /// A sequence of frames already in memory (e.g. from the simulator),
    /// with their poses when known ([`InMemory`]). `origin` names the
    /// source in messages.
    pub fn from_frames(
        frames: Vec<Frame>,
        poses: Option<Vec<Isometry3<f64>>>,
        origin: &str,
    ) -> Result<Self> {
        Ok(Self::new(InMemory::new(frames, poses, origin)?))
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the sequence has no frame.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The file a frame came from (for error messages).
    pub fn path(&self, index: usize) -> &Path {
        &self.entries[index].path
    }

    /// Frame names (file stems), sequence order.
    pub fn names(&self) -> Vec<String> {
        self.entries.iter().map(|e| e.name.clone()).collect()
    }

    /// The dataset the frames come from.
    pub fn dataset(&self) -> &dyn Dataset {
        self.dataset.as_ref()
    }

    /// The sensor model of the frames: the dataset's when it knows it
    /// (the simulator), else the configuration's `sensor`.
    pub fn sensor(&self, config: &crate::config::Config) -> Result<SensorModel> {
        match self.dataset.sensor() {
            Some(model) => Ok(model),
            None => SensorModel::resolve(&config.sensor),
        }
    }

    /// The frames, when the dataset holds them all in memory (`None` when
    /// they are read or made at every pass).
    pub fn in_memory(&self) -> Option<&[Frame]> {
        self.dataset.in_memory()
    }

    /// Where the points of frame `index` (`frame`, as this sequence gave
    /// it) that its reader set aside were in its input
    /// ([`Dataset::set_aside`]): nothing asked of the dataset for a frame
    /// that set none aside. An error naming the file when the dataset's
    /// answer does not fit the frame (the file changed while it was read).
    pub fn set_aside(&self, index: usize, frame: &Frame) -> Result<SetAside> {
        if frame.dropped_non_finite == 0 {
            return Ok(SetAside::default());
        }
        let aside = self.dataset.set_aside(index)?;
        if aside.len() != frame.dropped_non_finite || aside.labels.len() != aside.len() {
            return Err(crate::Error::format(
                self.path(index),
                format!(
                    "the frame changed while it was read ({} points set aside, then {})",
                    frame.dropped_non_finite,
                    aside.len()
                ),
            ));
        }
        Ok(aside)
    }

    /// Frame `index`: lent from the dataset or the cache, or made by the
    /// dataset (the error names the frame).
    pub fn frame(&self, index: usize) -> Result<Cow<'_, Frame>> {
        self.fetch(index).map(|(frame, _)| frame)
    }

    /// Frame `index` and, when the dataset made it (read its file), the
    /// time that took; deskewed when [`deskews`](Self::deskews) says so.
    fn fetch(&self, index: usize) -> Result<(Cow<'_, Frame>, Option<Duration>)> {
        let (frame, read) = self.fetch_as_read(index)?;
        Ok((self.deskewed(index, frame), read))
    }

    /// [`fetch`](Self::fetch) without deskewing: the frame as read.
    fn fetch_as_read(&self, index: usize) -> Result<(Cow<'_, Frame>, Option<Duration>)> {
        let cache = &self.cache;
        if let Some(frame) = cache.frames[index].get() {
            return Ok((Cow::Borrowed(frame), None));
        }
        let start = Instant::now();
        let frame = match self.dataset.frame(index)? {
            // Held by the dataset: nothing to keep.
            Cow::Borrowed(frame) => return Ok((Cow::Borrowed(frame), None)),
            Cow::Owned(frame) => frame,
        };
        let read = start.elapsed();
        let bytes = frame.points.len() * std::mem::size_of::<crate::cloud::Point>();
        let frame = match cache.keep(&cache.frames[index], frame, bytes) {
            Ok(kept) => Cow::Borrowed(kept),
            Err(frame) => Cow::Owned(frame),
        };
        Ok((frame, Some(read)))
    }

    /// Frame `index` as measured: `frame` itself (as this sequence gave
    /// it) unless it was handed out deskewed, then the frame as read. Its
    /// points' directions are their beams' (the grid cells of an
    /// [`OrganizedScan`]); the points are the same, in the same order.
    pub fn as_measured<'a>(&'a self, index: usize, frame: &'a Frame) -> Result<Cow<'a, Frame>> {
        if !self.deskews(index, frame) {
            return Ok(Cow::Borrowed(frame));
        }
        Ok(self.fetch_as_read(index)?.0)
    }

    /// [`scan`](Self::scan), its time added to `timings` as the stage
    /// "pair" (every pass over the frames starts with it).
    pub fn timed_scan(
        &self,
        index: usize,
        frame: &Frame,
        sensor: &SensorModel,
        timings: &mut StageTimings,
    ) -> Result<Cow<'_, OrganizedScan>> {
        let start = Instant::now();
        let scan = self.scan(index, frame, sensor)?;
        timings.add("pair", start.elapsed());
        Ok(scan)
    }

    /// The organized scan of frame `index` (`frame`, as this sequence gave
    /// it; its cells from the frame as measured, [`as_measured`](Self::as_measured)):
    /// kept with the frame when the frame is kept, so later passes do
    /// not pair its returns again; built otherwise.
    pub fn scan(
        &self,
        index: usize,
        frame: &Frame,
        sensor: &SensorModel,
    ) -> Result<Cow<'_, OrganizedScan>> {
        // A deskewed frame's points have moved off their beams: its grid
        // cells come from the frame as measured.
        let measured = self.as_measured(index, frame)?;
        let frame: &Frame = &measured;
        let cache = &self.cache;
        if cache.frames[index].get().is_none() {
            return OrganizedScan::build(frame, sensor).map(Cow::Owned);
        }
        let cell = &cache.scans[index];
        if let Some(scan) = cell.get() {
            return Ok(Cow::Borrowed(scan));
        }
        let scan = OrganizedScan::build(frame, sensor)?;
        let bytes = scan.heap_bytes();
        Ok(match cache.keep(cell, scan, bytes) {
            Ok(kept) => Cow::Borrowed(kept),
            Err(scan) => Cow::Owned(scan),
        })
    }

    /// One pass over the frames `indices` (sequence order): `work` runs on
    /// each frame in parallel, a window of frames at a time, and `consume`
    /// receives every frame with its result in the order of `indices`
    /// before the next window is read. Only a window of frames is ever in
    /// memory. The first error (reading a frame, `work` or `consume`) ends
    /// the pass. Returns the time spent reading frames from their files;
    /// `stage` labels the progress bar.
    pub fn stream<T, W, C>(
        &self,
        indices: &[usize],
        stage: &'static str,
        work: W,
        mut consume: C,
    ) -> Result<Duration>
    where
        T: Send,
        W: Fn(usize, &Frame) -> Result<T> + Sync,
        C: FnMut(usize, &Frame, T) -> Result<()>,
    {
        let bar = crate::progress::bar(indices.len(), stage);
        let mut reading = Duration::ZERO;
        for window in indices.chunks(stream_window()) {
            let results: Vec<(Cow<'_, Frame>, T, Duration)> = window
                .par_iter()
                .map(|&k| {
                    let (frame, read) = self.fetch(k)?;
                    let out = work(k, &frame).map_err(|e| self.naming_file(k, e))?;
                    bar.inc(1);
                    Ok((frame, out, read.unwrap_or_default()))
                })
                .collect::<Result<_>>()?;
            for (&k, (frame, out, read)) in window.iter().zip(results) {
                reading += read;
                consume(k, &frame, out)?;
            }
        }
        bar.finish_and_clear();
        Ok(reading)
    }

    /// `error` of the work on frame `index`, naming the frame's file when
    /// it does not already (e.g. a ring beyond the sensor's, found while
    /// pairing the returns, named only the frame).
    fn naming_file(&self, index: usize, error: crate::Error) -> crate::Error {
        let path = self.path(index);
        match error {
            crate::Error::Input(msg) if !msg.contains(&path.display().to_string()) => {
                crate::Error::format(path, msg)
            }
            other => other,
        }
    }

    /// [`stream`](Self::stream) over every frame.
    pub fn stream_all<T, W, C>(&self, stage: &'static str, work: W, consume: C) -> Result<Duration>
    where
        T: Send,
        W: Fn(usize, &Frame) -> Result<T> + Sync,
        C: FnMut(usize, &Frame, T) -> Result<()>,
    {
        let all: Vec<usize> = (0..self.len()).collect();
        self.stream(&all, stage, work, consume)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Point;
    use crate::io::PlyEncoding;

    /// A pass hands every frame on in the order asked for, whatever the
    /// windows and threads, and the first bad frame ends it with its name.
    #[test]
    fn a_pass_is_in_order_and_stops_at_a_bad_frame() {
        let dir = tempfile::tempdir().unwrap();
        let n = 2 * stream_window() + 3;
        for k in 0..n {
            let frame = Frame {
                name: format!("{}.000000", 100 + k),
                stamp: (100 + k) as f64,
                points: vec![
                    Point {
                        xyz: [k as f32 + 1.0, 0.0, 0.0],
                        ret: 1,
                        ..Default::default()
                    };
                    k + 1
                ],
                has_labels: false,
                dropped_non_finite: 0,
                intensity_scale: None,
            };
            let path = dir.path().join(format!("{}.ply", frame.name));
            io::write_frame(&path, &frame, PlyEncoding::BinaryLittleEndian).unwrap();
        }
        // Two frames' worth of cache: the first two are kept, the rest read
        // at every pass.
        let sequence = Sequence::open(dir.path(), None, 0.0)
            .unwrap()
            .with_frame_cache(4e-6 * std::mem::size_of::<Point>() as f64);
        assert_eq!(sequence.len(), n);
        assert!(matches!(sequence.frame(0).unwrap(), Cow::Borrowed(_)));
        assert!(matches!(sequence.frame(1).unwrap(), Cow::Borrowed(_)));
        assert!(matches!(sequence.frame(2).unwrap(), Cow::Owned(_)));
        assert!(matches!(sequence.frame(5).unwrap(), Cow::Owned(_)));
        let every_other: Vec<usize> = (0..n).step_by(2).collect();
        let mut seen = Vec::new();
        sequence
            .stream(
                &every_other,
                "test",
                |k, frame| Ok((k, frame.points.len())),
                |k, frame, (kk, len)| {
                    assert_eq!((k, len), (kk, frame.points.len()));
                    seen.push((k, len));
                    Ok(())
                },
            )
            .unwrap();
        let expected: Vec<(usize, usize)> = every_other.iter().map(|&k| (k, k + 1)).collect();
        assert_eq!(seen, expected);

        // Cut one frame short: the pass stops with its file named.
        let bad = sequence.path(n - 2).to_path_buf();
        let bytes = std::fs::read(&bad).unwrap();
        std::fs::write(&bad, &bytes[..bytes.len() - 5]).unwrap();
        let err = sequence
            .stream_all("test", |_, _| Ok(()), |_, _, ()| Ok(()))
            .unwrap_err()
            .to_string();
        assert!(err.contains(bad.to_str().unwrap()), "{err}");
    }
}
