//! A sequence of frames with their poses.

use std::path::Path;
use std::time::{Duration, Instant};

use nalgebra::Isometry3;
use rayon::prelude::*;

use super::StageTimings;
use crate::cloud::Frame;
use crate::io::{self, FrameEntry};
use crate::Result;

/// Frames of one directory in timestamp order, with their poses when given.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// The frame files.
    pub entries: Vec<FrameEntry>,
    /// The parsed frames, same order.
    pub frames: Vec<Frame>,
    /// `T_world_sensor` per frame (matched by timestamp), when known.
    pub poses: Option<Vec<Isometry3<f64>>>,
}

impl Sequence {
    /// Load every `*.ply` frame of `dir` (in parallel) and, when `poses` is
    /// given, match each frame to a pose by timestamp within `tolerance`
    /// seconds. Parsing time is recorded in `timings` as stage "parse".
    pub fn load(
        dir: &Path,
        poses: Option<&Path>,
        tolerance: f64,
        timings: &mut StageTimings,
    ) -> Result<Self> {
        let entries = io::list_frames(dir)?;
        // Poses first: a missing pose is reported before any parsing work.
        let poses = match poses {
            Some(path) => {
                let stamped = io::read_tum(path)?;
                Some(io::match_poses(&entries, &stamped, tolerance, path)?)
            }
            None => None,
        };
        let bar = crate::progress::bar(entries.len(), "parse");
        let parsed: Vec<(Frame, Duration)> = entries
            .par_iter()
            .map(|e| {
                let start = Instant::now();
                let frame = io::read_frame(&e.path).map(|f| (f, start.elapsed()));
                bar.inc(1);
                frame
            })
            .collect::<Result<_>>()?;
        bar.finish_and_clear();
        tracing::debug!(frames = parsed.len(), dir = %dir.display(), "frames parsed");
        let mut frames = Vec::with_capacity(parsed.len());
        for (f, d) in parsed {
            timings.add("parse", d);
            frames.push(f);
        }
        Ok(Self {
            entries,
            frames,
            poses,
        })
    }

    /// A sequence of frames already in memory (e.g. from the simulator),
    /// with their poses when known. `origin` names the source in messages.
    pub fn from_frames(
        frames: Vec<Frame>,
        poses: Option<Vec<Isometry3<f64>>>,
        origin: &str,
    ) -> Result<Self> {
        if let Some(p) = &poses {
            if p.len() != frames.len() {
                return Err(crate::Error::Input(format!(
                    "{origin}: {} poses for {} frames",
                    p.len(),
                    frames.len()
                )));
            }
        }
        let entries = frames
            .iter()
            .map(|f| FrameEntry {
                path: Path::new(origin).join(format!("{}.ply", f.name)),
                name: f.name.clone(),
                stamp: f.stamp,
            })
            .collect();
        Ok(Self {
            entries,
            frames,
            poses,
        })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// Whether the sequence has no frame.
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The file a frame came from (for error messages).
    pub fn path(&self, index: usize) -> &Path {
        &self.entries[index].path
    }
}
