//! The paper's first pipeline, "Reflection Detection via Plane
//! Optimization": with external poses, fuse every frame's reflective planes
//! into a global map, then classify every frame against the map.
//!
//! 1. Detect reflective planes in each frame (sensor frame).
//! 2. Transform them to the world frame and fuse them into the map in
//!    timestamp order (`MapMerger`).
//! 3. Keep the landmarks observed often enough; gather each one's
//!    transparency evidence and find its panes.
//! 4. From keyframes: the observed surfaces (mirror support), the space
//!    seen directly, and each landmark's echo-strength split.
//! 5. Classify every frame against the kept landmarks.
//!
//! Every step that reads frames is a pass over the sequence
//! ([`Sequence::stream`]): a window of frames at a time, in parallel, with
//! only what must outlive the pass kept (the frames' reflective planes, the
//! evidence grids, the space and support maps). Memory does not grow with
//! the number of frames times their points, so a whole 3DRef sequence runs
//! in the memory of a few frames plus the map.
//!
//! One file per step: [`detect`] (1), `fuse` (2, 3 and the landmarks'
//! boundaries), [`keyframes`](mod@keyframes) (4), `classify_pass` (5); [`world_maps`]
//! holds the classified maps a run writes.

mod classify_pass;
pub mod detect;
mod fuse;
pub mod keyframes;
pub mod world_maps;

use std::time::Instant;

pub use detect::observations;
pub use keyframes::keyframes;
pub use world_maps::{around_corner_map, measured_map, AroundCornerMap, MeasuredMap};

use super::registry::plane_map_classifier;
use super::{FrameSink, RunOutput, Sequence, StageTimings};
use crate::config::Config;
use crate::map::{Ghost, PlaneMap};
use crate::reflect::BoundedPlane;
use crate::{Error, Result};
use keyframes::FrameViews;

/// What the plane-optimized pipeline produces besides the classes.
#[derive(Debug, Clone)]
pub struct PlaneOptimizedOutput {
    /// Scores, timings and (when collected) the per-frame classes.
    pub run: RunOutput,
    /// The fused map (every landmark, used or not).
    pub map: PlaneMap,
    /// Indices into `map.landmarks` of the landmarks used to classify.
    pub used: Vec<usize>,
    /// The used landmarks as bounded planes (world frame), with their
    /// evidence and panes when gathered; same order as `used`.
    pub planes: Vec<BoundedPlane>,
    /// Landmarks dropped as reflections of seen surfaces in other glass
    /// (`map.ghosts`): `ghost` and `glass` index `map.landmarks`.
    pub ghosts: Vec<Ghost>,
}

impl PlaneOptimizedOutput {
    /// One line per landmark whose glass-or-mirror probability was
    /// estimated, with the share of reflections behind it where the echo
    /// strengths tell it (the prior of every point behind it), else where
    /// the seen space decides it (the prior of points no test weighs).
    pub fn mirror_lines(&self) -> Vec<String> {
        self.used
            .iter()
            .zip(&self.planes)
            .filter_map(|(&i, bp)| {
                let p = bp.mirror_probability?;
                let id = self.map.landmarks.get(i).map_or(i, |l| l.id);
                let kind = if p > 0.5 { "mirror" } else { "glass" };
                let share = match (bp.reflection_share, bp.decided_share) {
                    (Some(r), _) => {
                        format!("; reflections {:.0} % of the echoes behind it", 100.0 * r)
                    }
                    (None, Some(r)) => format!(
                        "; reflections {:.0} % of the echoes behind it the seen space decides",
                        100.0 * r
                    ),
                    _ => String::new(),
                };
                Some(format!(
                    "landmark {id}: {kind} (P(mirror) = {p:.3}, from its echoes{share})"
                ))
            })
            .collect()
    }

    /// One line per ghost landmark dropped, for the report and the console:
    /// which landmark, seen in which glass, and how much of it mirrors onto
    /// surfaces seen directly.
    pub fn ghost_lines(&self) -> Vec<String> {
        self.ghosts
            .iter()
            .map(|g| {
                let id = |i: usize| self.map.landmarks.get(i).map_or(i, |l| l.id);
                format!(
                    "landmark {} dropped as a ghost: the reflection of surfaces seen directly in landmark {} ({:.0} % of its extent mirrors onto them)",
                    id(g.ghost),
                    id(g.glass),
                    100.0 * g.share
                )
            })
            .collect()
    }
}

/// Run the plane-optimized pipeline and keep every frame's classes. The
/// sequence must carry poses.
pub fn run_plane_optimized(sequence: &Sequence, config: &Config) -> Result<PlaneOptimizedOutput> {
    let mut frames = Vec::with_capacity(sequence.len());
    let mut out = run_plane_optimized_into(sequence, config, &mut frames)?;
    out.run.frames = frames;
    Ok(out)
}

/// Run the plane-optimized pipeline, handing every frame's classes to
/// `sink` in sequence order (the returned run holds scores and timings, no
/// frames). The sequence must carry poses.
pub fn run_plane_optimized_into(
    sequence: &Sequence,
    config: &Config,
    sink: &mut dyn FrameSink,
) -> Result<PlaneOptimizedOutput> {
    let wall = Instant::now();
    let poses = sequence.poses.as_ref().ok_or_else(|| {
        Error::Input("the plane-optimized method needs a pose per frame (--poses FILE)".into())
    })?;
    let sensor = sequence.sensor(config)?;
    let mut timings = StageTimings::default();

    // 1. Detect every frame's reflective planes (sensor frame) and carry
    //    them to the world frame: all that is kept of a frame.
    let frames = detect::detect_frames(sequence, config, &sensor, poses, &mut timings)?;

    // 2-3. Fuse them into the map in timestamp order; keep the landmarks
    //      observed often enough.
    let mut fused = fuse::fuse(&frames, poses, config, &sensor, &mut timings);

    // Bound each kept landmark: its hull, or the transparency evidence of
    // all frames and the panes found in it.
    fuse::bound(sequence, &sensor, &mut fused.planes, config, &mut timings)?;

    // 4. What the keyframes saw: surfaces, free space, echo strengths.
    let classifier = plane_map_classifier(config)?;
    let views = FrameViews {
        sequence,
        sensor: &sensor,
        classifier: &classifier,
        poses,
    };
    let crossing_radius = config.map.evidence.crossing_radius;
    let seen = views.what_keyframes_saw(
        fused.planes,
        crossing_radius,
        &config.map.ghosts,
        &mut timings,
    )?;

    // 5. Classify every frame against the map.
    let score = classify_pass::classify_frames(&views, &seen, &frames, sink, &mut timings)?;

    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    Ok(PlaneOptimizedOutput {
        run: score.finish(Vec::new(), timings),
        map: fused.map,
        used: fused
            .used
            .iter()
            .enumerate()
            .filter(|(i, _)| !seen.ghosts.iter().any(|g| g.ghost == *i))
            .map(|(_, &l)| l)
            .collect(),
        ghosts: seen
            .ghosts
            .iter()
            .map(|g| Ghost {
                ghost: fused.used[g.ghost],
                glass: fused.used[g.glass],
                share: g.share,
            })
            .collect(),
        planes: seen.planes,
    })
}
