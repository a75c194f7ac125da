//! The paper's second pipeline, "Reflection SLAM": poses from the planes
//! themselves, then the same classification as the plane-optimized
//! pipeline with the estimated poses.
//!
//! 1. Front end, per frame and in parallel (it does not depend on the
//!    pose): organize the scan, detect the reflective planes, extract the
//!    ground and ordinary planes from the filtered cloud
//!    ([`frame_features`]). A frame whose points carry their times is
//!    first deskewed with tracking's velocity ([`crate::slam::deskew`]),
//!    so its front end runs in order, just before it is tracked.
//! 2. Tracking, in timestamp order ([`Tracker`]): predict, register to the
//!    previous frame, register to the map, update the map, close loops
//!    ([`track_sequence`]).
//! 3. Back-end: the whole pose-plane graph of tracking solved at once by
//!    the configured [`Backend`], then the frames between keyframes placed
//!    against the solved planes ([`optimize_tracked`]).
//! 4. Classification: the plane-optimized pipeline run with the estimated
//!    poses ([`classify_with_poses`]); frames with per-point times are
//!    deskewed with the velocity of the estimated poses
//!    ([`Sequence`]'s frames).

use std::time::{Duration, Instant};

use nalgebra::{Isometry3, Vector6};

use super::plane_optimized::run_plane_optimized_into;
use super::registry::{detector, extractor, frame_seed, merger, rejector};
use super::single_scan::{check_dual_returns, check_points, organize_and_detect};
use super::{FrameSink, PlaneOptimizedOutput, Sequence, StageTimings};
use crate::backend::{backend, Backend, BackendParams, FactorGraph, SolveReport};
use crate::cloud::Frame;
use crate::config::Config;
use crate::frontend::{reflective_planes, ExtractorParams, FramePlane, PlaneExtractor};
use crate::map::PlaneMap;
use crate::reflect::ReflectiveDetector;
use crate::sensor::SensorModel;
use crate::slam::deskew::{deskewed, is_timed, smoothed_velocities, VELOCITY_HALF_WINDOW};
use crate::slam::graph::{optimized_poses, segment_graph, tracking_graph, update_map};
use crate::slam::loop_closure::merge_duplicates;
use crate::slam::{FrameReport, LoopConstraint, PointParams, ScanSamples, Tracker, TrackingLog};
use crate::Result;
use rayon::prelude::*;

/// What the SLAM pipeline produces.
#[derive(Debug, Clone)]
pub struct SlamOutput {
    /// Estimated `T_world_sensor` per frame, sequence order: the back-end's
    /// result.
    pub poses: Vec<Isometry3<f64>>,
    /// The poses of tracking alone, before the back-end.
    pub tracked_poses: Vec<Isometry3<f64>>,
    /// What the back-end did (`None` for fewer than two frames).
    pub backend: Option<SolveReport>,
    /// The back-end's factor graph, with tracking's estimates as its values.
    pub graph: FactorGraph,
    /// The final plane map (ordinary, ground and reflective landmarks).
    pub map: PlaneMap,
    /// One report per frame.
    pub reports: Vec<FrameReport>,
    /// The verified loop closures (the back-end's loop factors).
    pub loops: Vec<LoopConstraint>,
    /// Duplicate landmarks merged before the final batch (merges at the
    /// loop closures themselves are in the frames' reports).
    pub merged_at_end: usize,
    /// Processing time per frame: front end plus tracking (CPU time).
    pub frame_times: Vec<Duration>,
    /// Time per stage.
    pub timings: StageTimings,
}

/// Seed of the extractor's RANSAC for a frame (distinct from the
/// detector's).
fn extractor_seed(seed: u64, name: &str) -> u64 {
    frame_seed(seed ^ 0x9e37_79b9_7f4a_7c15, name)
}

/// What tracking needs of one frame (sensor frame).
#[derive(Debug, Clone, Default)]
pub struct FrameFeatures {
    /// Ground, ordinary and reflective planes.
    pub planes: Vec<FramePlane>,
    /// Surface samples for the directions the planes leave free (`None`
    /// when the point term is off).
    pub samples: Option<ScanSamples>,
}

/// The features of one frame (sensor frame): ground and ordinary planes
/// from `extractor`, then the reflective planes of `detector` (their
/// largest patches, see [`reflective_planes`]; `extractor_params` gives the
/// gap and acceptance rule), and the surface samples of `points` when it is
/// on. Also returns the time spent per stage.
pub fn frame_features(
    frame: &Frame,
    sensor: &SensorModel,
    detector: &dyn ReflectiveDetector,
    extractor: &dyn PlaneExtractor,
    extractor_params: &ExtractorParams,
    points: &PointParams,
    seed: u64,
) -> Result<(FrameFeatures, StageTimings)> {
    frame_features_measured(
        frame,
        frame,
        sensor,
        detector,
        extractor,
        extractor_params,
        points,
        seed,
    )
}

/// [`frame_features`] of a deskewed `frame` whose grid cells come from
/// `measured`, the frame as measured (its points in the same order; see
/// [`crate::slam::deskew`]).
#[allow(clippy::too_many_arguments)]
pub fn frame_features_measured(
    frame: &Frame,
    measured: &Frame,
    sensor: &SensorModel,
    detector: &dyn ReflectiveDetector,
    extractor: &dyn PlaneExtractor,
    extractor_params: &ExtractorParams,
    points: &PointParams,
    seed: u64,
) -> Result<(FrameFeatures, StageTimings)> {
    let (scan, detection, mut t) = organize_and_detect(frame, measured, sensor, detector, seed)?;
    let start = Instant::now();
    let mut planes = extractor.extract(frame, &scan, &detection, extractor_seed(seed, &frame.name));
    planes.extend(reflective_planes(frame, &detection, extractor_params));
    t.add("extract", start.elapsed());
    let start = Instant::now();
    let samples = points
        .enabled
        .then(|| ScanSamples::sample(frame, &scan, points.sample_voxel, points.min_range));
    t.add("sample points", start.elapsed());
    t.frames = 1;
    Ok((FrameFeatures { planes, samples }, t))
}

/// Run Reflection SLAM over `sequence` (its poses, if any, are not used):
/// tracking ([`track_sequence`]), then the batch back-end
/// ([`optimize_tracked`]). The first frame gets pose `origin` (identity
/// when `None`).
pub fn run_slam(
    sequence: &Sequence,
    config: &Config,
    origin: Option<Isometry3<f64>>,
) -> Result<SlamOutput> {
    let wall = Instant::now();
    // 1-2. Front end and tracking, frame by frame.
    let tracked = track_sequence(sequence, config, origin)?;
    // 3. The batch back-end over the whole pose-plane graph.
    let mut out = optimize_tracked(tracked, config)?;
    out.timings.wall = wall.elapsed();
    Ok(out)
}

/// The front end and tracking of Reflection SLAM over `sequence` (with the
/// sliding window when configured), without the batch back-end.
///
/// Frames whose points carry their times are deskewed (unless the
/// sequence's deskewing is off, [`Sequence::without_deskew`]) in two
/// passes: the first deskews each frame with the velocity tracking has
/// reached (constant velocity, as KISS-ICP), which extrapolates the
/// motion of the sweep from the frames before it; the second tracks the
/// sequence again with every frame deskewed with the motion the first
/// found over its own sweep (from its pose to the next one's, averaged
/// over the intervals around it, [`smoothed_velocities`]). A frame's sweep runs from its stamp on (the
/// simulator's and Ouster's convention), so tracking alone can only guess
/// its motion: where the sensor turns while it walks, the constant
/// body-frame twist of the last interval points the translation one
/// interval's turn off (4.5° at 45 deg/s), a bias the second pass does
/// not have. Sequences without per-point times are tracked once, as
/// before.
pub fn track_sequence(
    sequence: &Sequence,
    config: &Config,
    origin: Option<Isometry3<f64>>,
) -> Result<Tracked> {
    if !sequence.deskew_enabled() {
        return track_pass(sequence, config, origin, Deskew::Off);
    }
    let first = track_pass(sequence, config, origin, Deskew::Tracking)?;
    if first.timed_frames == 0 {
        return Ok(first);
    }
    let poses: Vec<Isometry3<f64>> = first.log.frames.iter().map(|f| f.pose).collect();
    let stamps: Vec<f64> = sequence.entries.iter().map(|e| e.stamp).collect();
    let velocities = smoothed_velocities(&poses, &stamps, VELOCITY_HALF_WINDOW);
    let mut second = track_pass(sequence, config, origin, Deskew::Given(&velocities))?;
    // Both passes' work counts.
    second.timings.merge_stages(&first.timings);
    for (t, f) in second.frame_times.iter_mut().zip(&first.frame_times) {
        *t += *f;
    }
    Ok(second)
}

/// Where tracking takes the velocity that deskews a frame with per-point
/// times.
#[derive(Clone, Copy)]
enum Deskew<'a> {
    /// Frames are tracked as read.
    Off,
    /// The velocity tracking has reached (the front end of such frames
    /// runs in order, just before each is tracked).
    Tracking,
    /// One body-frame twist per second per frame.
    Given(&'a [Vector6<f64>]),
}

/// One pass of the front end and tracking over `sequence`, frames with
/// per-point times deskewed as `deskew` says.
fn track_pass(
    sequence: &Sequence,
    config: &Config,
    origin: Option<Isometry3<f64>>,
    deskew: Deskew<'_>,
) -> Result<Tracked> {
    let wall = Instant::now();
    // Never deskewed with the poses the sequence may bring (a simulation's
    // true ones): tracking deskews with its own estimate.
    let sequence = &sequence.clone().without_deskew();
    let sensor = sequence.sensor(config)?;
    let detector = detector(config, &sensor);
    let extractor = extractor(config);
    let mut timings = StageTimings::default();
    let mut tracker = new_tracker(config, origin)?;
    let mut reports = Vec::with_capacity(sequence.len());
    let mut frame_times = Vec::with_capacity(sequence.len());
    let mut second_returns = 0;
    let mut timed_frames = 0;
    let features_of = |frame: &Frame, velocity: Option<&Vector6<f64>>| {
        let start = Instant::now();
        let straight = velocity.map(|v| deskewed(frame, v));
        let took = start.elapsed();
        let (features, mut t) = frame_features_measured(
            straight.as_ref().unwrap_or(frame),
            frame,
            &sensor,
            detector.as_ref(),
            extractor.as_ref(),
            &config.extractor,
            &config.slam.points,
            config.seed,
        )?;
        if straight.is_some() {
            t.add("deskew", took);
        }
        Ok((features, t))
    };
    // 1. The front end, a window of frames at a time in parallel (it does
    // not depend on the pose), then 2. tracking of the window in order:
    // only a frame's planes outlive its window.
    let reading = sequence.stream_all(
        "track",
        |k, frame| {
            check_points(sequence, k, frame, &sensor)?;
            match deskew {
                // Deskewed with tracking's velocity: in order, when tracked.
                Deskew::Tracking if is_timed(frame) => Ok(None),
                Deskew::Given(v) if is_timed(frame) => features_of(frame, v.get(k)).map(Some),
                _ => features_of(frame, None).map(Some),
            }
        },
        |_, frame, features| {
            let (features, t) = match features {
                Some(done) => done,
                None => features_of(frame, Some(&tracker.velocity()))?,
            };
            timed_frames += usize::from(is_timed(frame));
            timings.merge(&t);
            second_returns += frame.second_returns();
            let start = Instant::now();
            let seed = frame_seed(config.seed ^ 0x51a4, &frame.name);
            // The frame's own stamp (not only its samples'): timing and
            // gaps work with the point term off too.
            let report = tracker.track_at(
                Some(frame.stamp),
                features.planes,
                features.samples.as_ref(),
                seed,
            );
            let track = start.elapsed();
            timings.add("track", track);
            frame_times.push(t.stages.iter().map(|(_, d)| *d).sum::<Duration>() + track);
            reports.push(report);
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    check_dual_returns(sequence, second_returns, config)?;
    tracing::info!(
        frames = reports.len(),
        landmarks = tracker.map().landmarks.len(),
        degenerate = reports.iter().filter(|r| r.is_degenerate()).count(),
        "tracked"
    );
    let (map, log) = tracker.into_parts();
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    Ok(Tracked {
        map,
        log,
        reports,
        frame_times,
        timings,
        timed_frames,
    })
}

/// The tracker of `config` (its rejector, merger and, when configured,
/// sliding-window back-end), the first frame at `origin` (identity when
/// `None`).
fn new_tracker(config: &Config, origin: Option<Isometry3<f64>>) -> Result<Tracker> {
    Ok(Tracker::new(
        config.slam,
        rejector(config),
        merger(config),
        origin.unwrap_or_else(Isometry3::identity),
    )
    .with_window(
        backend(config.backend.name, &config.backend)?,
        config.backend,
    ))
}

/// What tracking alone produced, before the batch back-end.
#[derive(Debug, Clone)]
pub struct Tracked {
    /// The tracker's map.
    pub map: PlaneMap,
    /// Observations and odometry (the back-end's input).
    pub log: TrackingLog,
    /// One report per frame.
    pub reports: Vec<FrameReport>,
    /// Processing time per frame (front end plus tracking).
    pub frame_times: Vec<Duration>,
    /// Time per stage.
    pub timings: StageTimings,
    /// Frames whose points carry their times (deskewed unless the
    /// sequence's deskewing is off).
    pub timed_frames: usize,
}

/// Run the batch back-end of `config` on a tracking result (step 3: the
/// whole pose-plane graph at once). Tracking does not depend on the
/// back-end unless a sliding window is configured, so back-ends can be
/// compared on one tracking run by cloning it.
pub fn optimize_tracked(tracked: Tracked, config: &Config) -> Result<SlamOutput> {
    let named = || backend(config.backend.name, &config.backend);
    optimize_tracked_with(tracked, config, &named)
}

/// Makes the back-end a batch solve uses (one per solve; the solves between
/// keyframes run in parallel). [`optimize_tracked`] makes the one named in
/// `[backend] name`; any [`Backend`] can be passed, e.g. one defined
/// outside this crate (`tests/custom_backend.rs`).
pub type MakeBackend<'a> = dyn Fn() -> Result<Box<dyn Backend>> + Sync + 'a;

/// [`optimize_tracked`] with the back-end that `make` makes instead of the
/// configured one (the rest of `[backend]`, e.g. the plane factor, still
/// applies).
pub fn optimize_tracked_with(
    tracked: Tracked,
    config: &Config,
    make: &MakeBackend<'_>,
) -> Result<SlamOutput> {
    let Tracked {
        mut map,
        mut log,
        reports,
        frame_times,
        mut timings,
        ..
    } = tracked;
    // Tracking's poses as the sliding window left them.
    let poses: Vec<Isometry3<f64>> = log.frames.iter().map(|f| f.pose).collect();
    let start = Instant::now();
    // After a loop closure the same plane may still be two landmarks
    // (mapped twice after the last re-solve): one again before the batch.
    let merged = if log.loops.is_empty() {
        0
    } else {
        merge_duplicates(&mut map, &mut log, &config.slam.loop_closure)
            .merged
            .len()
    };
    // The pose-plane graph of tracking: its observations, odometry and loops.
    let graph = tracking_graph(&log, &map, &config.backend)?;
    // Solve it at once; the map's planes move to the result.
    let (mut optimized, report) = optimize_batch(&graph, &mut map, make, &poses)?;
    // The frames between keyframes, placed against the solved planes.
    if report.is_some() {
        place_between_keyframes(&log, &map, &config.backend, make, &mut optimized)?;
    }
    timings.add("backend", start.elapsed());
    Ok(SlamOutput {
        poses: optimized,
        tracked_poses: poses,
        backend: report,
        graph,
        map,
        reports,
        loops: log.loops,
        merged_at_end: merged,
        frame_times,
        timings,
    })
}

/// Optimise the graph of a tracking run ([`tracking_graph`]) with the
/// back-end `make` makes; the map's planes move to the result. Returns the
/// poses in frame order and the back-end's report (`None`, tracked poses
/// unchanged, for fewer than two frames).
pub fn optimize_batch(
    graph: &FactorGraph,
    map: &mut PlaneMap,
    make: &MakeBackend<'_>,
    tracked: &[Isometry3<f64>],
) -> Result<(Vec<Isometry3<f64>>, Option<SolveReport>)> {
    if tracked.len() < 2 {
        return Ok((tracked.to_vec(), None));
    }
    let solver = make()?;
    let (values, report) = solver.optimize(graph, &graph.values)?;
    tracing::info!(
        backend = solver.name(),
        initial = report.initial_cost,
        cost = report.final_cost,
        iterations = report.iterations,
        "back-end"
    );
    update_map(map, &values);
    Ok((optimized_poses(&values, tracked), Some(report)))
}

/// After the keyframes and the map are optimised, place the frames between
/// keyframes (and after the last one): each span is optimised on its own
/// against the optimised planes, its keyframes held fixed, from the poses
/// `poses` (tracking re-anchored on the keyframes), which it updates. Does
/// nothing when every frame is a keyframe.
pub fn place_between_keyframes(
    log: &TrackingLog,
    map: &PlaneMap,
    params: &BackendParams,
    make: &MakeBackend<'_>,
    poses: &mut [Isometry3<f64>],
) -> Result<()> {
    let n = log.frames.len().min(poses.len());
    let keyframes: Vec<usize> = (0..n).filter(|&k| log.frames[k].keyframe).collect();
    if keyframes.len() == n {
        return Ok(());
    }
    let mut spans: Vec<(std::ops::Range<usize>, bool)> = keyframes
        .windows(2)
        .filter(|w| w[1] > w[0] + 1)
        .map(|w| (w[0]..w[1] + 1, true))
        .collect();
    if let Some(&last) = keyframes.last() {
        if last + 1 < n {
            spans.push((last..n, false));
        }
    }
    let initial: &[Isometry3<f64>] = poses;
    let placed: Vec<Vec<(usize, Isometry3<f64>)>> = spans
        .par_iter()
        .map(|(span, closed)| {
            let graph = segment_graph(log, span.clone(), *closed, initial, map, params)?;
            let solver = make()?;
            let (values, _) = solver.optimize(&graph, &graph.values)?;
            Ok(span
                .clone()
                .filter_map(|k| values.poses.get(&(k as u32)).map(|p| (k, *p)))
                .collect())
        })
        .collect::<Result<_>>()?;
    for (k, pose) in placed.into_iter().flatten() {
        poses[k] = pose;
    }
    Ok(())
}

/// Classify every frame with the plane-optimized pipeline using `poses`
/// (e.g. the SLAM estimate) instead of the sequence's own poses, which are
/// restored afterwards; every frame's classes go to `sink`.
pub fn classify_with_poses(
    sequence: &mut Sequence,
    poses: Vec<Isometry3<f64>>,
    config: &Config,
    sink: &mut dyn FrameSink,
) -> Result<PlaneOptimizedOutput> {
    let saved = sequence.poses.replace(poses);
    let out = run_plane_optimized_into(sequence, config, sink);
    sequence.poses = saved;
    out
}
