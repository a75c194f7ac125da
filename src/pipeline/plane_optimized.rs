//! The paper's first pipeline, "Reflection Detection via Plane
//! Optimization": with external poses, fuse every frame's reflective planes
//! into a global map, then classify every frame against the map.
//!
//! 1. Detect reflective planes in each frame (sensor frame).
//! 2. Transform them to the world frame and fuse them into the map in
//!    timestamp order (`MapMerger`).
//! 3. Keep the landmarks observed often enough.
//! 4. Optionally gather the observed surfaces of all frames (mirror support).
//! 5. Classify every frame against the kept landmarks.

use std::sync::Arc;
use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};
use rayon::prelude::*;

use super::registry::{detector, merger, plane_map_classifier};
use super::single_scan::{check_frame, organize_and_detect};
use super::{FrameOutput, RunOutput, Sequence, StageTimings};
use crate::classify::boundary::BeamPlanes;
use crate::classify::mirror::mirror_reflections;
use crate::classify::{
    BeamHits, Class, Classifier, Decisions, FrameInput, Occupancy, PlaneMapClassifier, SpaceMap,
    WorldSupport,
};
use crate::config::{BoundaryMode, Config};
use crate::geometry::voxel::VoxelSet;
use crate::io::{MapPoint, PlaneKind};
use crate::map::{find_panes, gather_evidence, EvidenceFrame, PlaneMap, PlaneObservation};
use crate::reflect::echo_split::{echo_strength, is_mirror};
use crate::reflect::{planes_seen_from, BoundedPlane, Detection, EchoHistogram, EchoSplit};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::{Error, Result};

/// What the plane-optimized pipeline produces besides the classes.
#[derive(Debug, Clone)]
pub struct PlaneOptimizedOutput {
    /// Per-frame classes and timings.
    pub run: RunOutput,
    /// The fused map (every landmark, used or not).
    pub map: PlaneMap,
    /// Indices into `map.landmarks` of the landmarks used to classify.
    pub used: Vec<usize>,
    /// The used landmarks as bounded planes (world frame), with their
    /// evidence and panes when gathered; same order as `used`.
    pub planes: Vec<BoundedPlane>,
}

/// Run the plane-optimized pipeline. The sequence must carry poses.
pub fn run_plane_optimized(sequence: &Sequence, config: &Config) -> Result<PlaneOptimizedOutput> {
    let wall = Instant::now();
    let poses = sequence.poses.as_ref().ok_or_else(|| {
        Error::Input("the plane-optimized method needs a pose per frame (--poses FILE)".into())
    })?;
    let sensor = SensorModel::resolve(&config.sensor)?;
    for i in 0..sequence.len() {
        check_frame(sequence, i, config)?;
    }
    let detector = detector(config, &sensor);
    let mut timings = StageTimings::default();

    // 1. Per-frame detection (sensor frame), in parallel.
    let bar = crate::progress::bar(sequence.len(), "detect");
    let per_frame: Vec<(OrganizedScan, Detection, StageTimings)> = sequence
        .frames
        .par_iter()
        .map(|frame| {
            let out = organize_and_detect(frame, &sensor, detector.as_ref(), config.seed);
            bar.inc(1);
            out
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    for (_, _, t) in &per_frame {
        timings.merge(t);
    }

    // 2-3. Fuse into the map in timestamp order; keep well-observed landmarks.
    let start = Instant::now();
    let merger = merger(config);
    let mut map = PlaneMap::new();
    for (k, (_, detection, _)) in per_frame.iter().enumerate() {
        for obs in observations(detection, &poses[k], k) {
            merger.merge(&mut map, &obs);
        }
    }
    let used = map.reliable(poses, &config.map.selection());
    let mut map_planes: Vec<BoundedPlane> =
        used.iter().map(|&i| map.landmarks[i].bounded()).collect();
    timings.add("map", start.elapsed());
    tracing::info!(
        landmarks = map.landmarks.len(),
        used = used.len(),
        "reflective plane map fused"
    );

    // Transparency evidence of every used landmark over all frames, and the
    // panes found in it.
    if config.map.boundary != BoundaryMode::Hull {
        let start = Instant::now();
        let frames: Vec<EvidenceFrame<'_>> = (0..sequence.len())
            .map(|k| EvidenceFrame {
                frame: &sequence.frames[k],
                scan: &per_frame[k].0,
                pose: poses[k],
            })
            .collect();
        for bp in &mut map_planes {
            bp.evidence = gather_evidence(bp, &frames, &config.map.evidence).map(Arc::new);
        }
        timings.add("evidence", start.elapsed());
        if config.map.boundary == BoundaryMode::Panes {
            let start = Instant::now();
            for bp in &mut map_planes {
                // Without any decided evidence the hull stays the boundary.
                if let Some(grid) = bp.evidence.as_ref().filter(|g| g.is_decided()) {
                    let panes = find_panes(grid, &config.map.panes);
                    bp.panes = Some(Arc::new(panes.into_iter().map(|p| p.boundary).collect()));
                }
            }
            timings.add("panes", start.elapsed());
        }
    }

    // 4-5. Classify every frame against the map.
    let classifier = plane_map_classifier(config);
    let input = |k: usize| FrameInput {
        frame: &sequence.frames[k],
        scan: &per_frame[k].0,
        sensor: &sensor,
        detection: &per_frame[k].1,
        pose: poses[k],
        map_planes: &map_planes,
        support: None,
        space: None,
        beam_hits: None,
    };
    // The sequence's surface support, when used: the beam test of every
    // frame (shared with the classification), then the surfaces it found.
    let mut hits: Vec<BeamHits> = Vec::new();
    let mut support = None;
    let mut space = None;
    let p = classifier.params();
    if p.sequence_support || p.decision.space_test {
        let start = Instant::now();
        hits = (0..sequence.len())
            .into_par_iter()
            .map(|k| classifier.beam_hits(&input(k)))
            .collect();
        timings.add("beam test", start.elapsed());
    }
    if p.sequence_support {
        let start = Instant::now();
        let views = keyframes(poses, p.support_keyframe_move, p.support_keyframe_turn_deg);
        support = Some(sequence_support(&classifier, &views, &hits, &input));
        timings.add("support", start.elapsed());
    }
    // The space seen directly and the echo statistics behind each landmark,
    // both from the same keyframes.
    let space_views = keyframes(poses, p.space_keyframe_move, p.space_keyframe_turn_deg);
    if p.decision.space_test {
        let start = Instant::now();
        let map = seen_space(&classifier, &space_views, &hits, &input);
        timings.add("space", start.elapsed());
        tracing::info!(
            keyframes = space_views.len(),
            bricks = map.bricks(),
            "space seen directly"
        );
        space = Some(map);
    }
    let splits = match (&space, p.echo_split.enabled) {
        (Some(space), true) => {
            let start = Instant::now();
            let splits = fit_echo_splits(&classifier, &space_views, &hits, &input, space);
            timings.add("echo split", start.elapsed());
            Some(splits)
        }
        _ => None,
    };
    // The landmarks as classified: with their echo splits, when learned.
    let classified_planes: Vec<BoundedPlane> = match splits {
        Some(splits) => map_planes
            .iter()
            .zip(splits)
            .map(|(bp, (echo_split, mirror))| BoundedPlane {
                echo_split,
                mirror,
                ..bp.clone()
            })
            .collect(),
        None => map_planes.clone(),
    };
    let input = |k: usize| FrameInput {
        map_planes: &classified_planes,
        ..input(k)
    };
    let bar = crate::progress::bar(sequence.len(), "classify");
    let classified: Vec<(Decisions, std::time::Duration)> = (0..sequence.len())
        .into_par_iter()
        .map(|k| {
            let start = Instant::now();
            let decisions = classifier.classify(&FrameInput {
                support: support.as_ref(),
                space: space.as_ref(),
                beam_hits: hits.get(k),
                ..input(k)
            });
            bar.inc(1);
            (decisions, start.elapsed())
        })
        .collect();
    bar.finish_and_clear();
    let mut frames = Vec::with_capacity(sequence.len());
    for (k, (decisions, d)) in classified.into_iter().enumerate() {
        timings.add("classify", d);
        frames.push(FrameOutput {
            name: sequence.frames[k].name.clone(),
            classes: decisions.classes,
            rules: decisions.rules,
            planes: per_frame[k].1.planes.len(),
            candidates: per_frame[k].1.candidates.len(),
        });
    }
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    Ok(PlaneOptimizedOutput {
        run: RunOutput { frames, timings },
        map,
        used,
        planes: classified_planes,
    })
}

/// A frame's reflective planes as world-frame observations.
pub fn observations(
    detection: &Detection,
    pose: &Isometry3<f64>,
    frame: usize,
) -> Vec<PlaneObservation> {
    detection
        .planes
        .iter()
        .map(|rp| PlaneObservation {
            kind: PlaneKind::Reflective,
            plane: rp.bounded.plane.transformed(pose),
            boundary: rp.bounded.boundary_3d().iter().map(|p| pose * p).collect(),
            frame,
        })
        .collect()
}

/// Frames that see the scene from a new viewpoint: the first, then every
/// frame whose pose moved more than `min_move` metres or turned more than
/// `min_turn_deg` from the last one kept. Views from (nearly) the same place
/// add no surface the support does not have already.
pub fn keyframes(poses: &[Isometry3<f64>], min_move: f64, min_turn_deg: f64) -> Vec<usize> {
    let mut kept: Vec<usize> = Vec::new();
    for (k, pose) in poses.iter().enumerate() {
        let new_view = kept.last().is_none_or(|&last| {
            let rel = poses[last].inverse() * pose;
            rel.translation.vector.norm() > min_move
                || rel.rotation.angle().to_degrees() > min_turn_deg
        });
        if new_view {
            kept.push(k);
        }
    }
    kept
}

/// The observed surfaces of the keyframes (world frame), thinned by voxel;
/// `hits` holds every frame's beam test.
fn sequence_support<'a>(
    classifier: &PlaneMapClassifier,
    frames: &[usize],
    hits: &[BeamHits],
    input: &(dyn Fn(usize) -> FrameInput<'a> + Sync),
) -> WorldSupport {
    // Indices only (4 bytes a point): the world points are made as the
    // support consumes them, in frame order.
    let per_frame: Vec<Vec<u32>> = frames
        .par_iter()
        .map(|&k| classifier.surface_points(&input(k), &hits[k]))
        .collect();
    let params = classifier.params();
    let points = frames.iter().zip(&per_frame).flat_map(|(&k, indices)| {
        let inp = input(k);
        let (r, t) = rotation_translation(&inp.pose);
        let points = &inp.frame.points;
        indices
            .iter()
            .map(move |&i| Point3::from(r * points[i as usize].position().coords + t))
    });
    WorldSupport::build(points, params.support_voxel, params.decision.support_radius)
}

/// The space seen directly from the keyframes `frames` (world frame):
/// every beam that crosses no reflective pane marks its endpoint occupied
/// and carves the voxels before it; a beam that crosses a pane carves only
/// up to the pane. Of a beam's two returns only the nearer is used: the
/// farther may have passed an unmapped pane. `hits` holds every frame's beam
/// test.
fn seen_space<'a>(
    classifier: &PlaneMapClassifier,
    frames: &[usize],
    hits: &[BeamHits],
    input: &(dyn Fn(usize) -> FrameInput<'a> + Sync),
) -> SpaceMap {
    let p = classifier.params();
    let glass = p.decision.glass_distance;
    let mut space = SpaceMap::new(p.space_voxel, p.space_min_passes, p.space_block_hits);
    let min_stop = 2.0 * space.voxel();
    let stride = p.space_column_stride.max(1);
    for &k in frames {
        let inp = input(k);
        let planes = PlaneMapClassifier::planes_in_sensor_frame(&inp);
        let (r, t) = rotation_translation(&inp.pose);
        let origin = Point3::from(t);
        let points = &inp.frame.points;
        for (i, pt) in points.iter().enumerate() {
            let range = pt.range();
            if !(range > 0.0) {
                continue;
            }
            if inp
                .scan
                .partner(i)
                .is_some_and(|j| points[j].range() < range)
            {
                continue;
            }
            let pos = pt.position();
            let (end_range, hit) = match hits[k].get(i, &pos, &planes) {
                Some(h) if range >= h.range - glass => (h.range.min(range), false),
                _ => (range, true),
            };
            let end = Point3::from(r * (pos.coords * (end_range / range)) + t);
            // Every beam marks its surface; one in `stride` columns carves.
            let (_, col) = inp.scan.ring_column(inp.scan.cell_of(i));
            let stop = if col % stride == 0 {
                min_stop.max(p.space_stop_ratio * range)
            } else {
                f64::INFINITY
            };
            space.add_beam(&origin, &end, stop, hit);
        }
    }
    space
}

/// Each map plane's split of echoes behind it into reflected and
/// transmitted ones ([`EchoSplit`]), and whether it is a mirror, from the
/// keyframes `frames`: the strengths of every point behind the plane,
/// oriented by the points whose mirror image lies in seen-free space (they
/// cannot be reflections; a plane with almost none is a mirror).
fn fit_echo_splits<'a>(
    classifier: &PlaneMapClassifier,
    frames: &[usize],
    hits: &[BeamHits],
    input: &(dyn Fn(usize) -> FrameInput<'a> + Sync),
    space: &SpaceMap,
) -> Vec<(Option<EchoSplit>, bool)> {
    let p = classifier.params();
    let behind = p.decision.behind_distance;
    let glass = p.decision.glass_distance;
    let clearance = p.decision.space_clearance_ratio;
    let exponent = p.echo_split.range_exponent;
    let incidence = p.echo_split.incidence_correction;
    let n = frames.first().map_or(0, |&k| input(k).map_planes.len());
    // Per landmark: the strengths of all points behind it, and of its
    // anchors; summed over the keyframes by each worker, then merged (the
    // counts are integers, so the result does not depend on the threads).
    let empty = || vec![(EchoHistogram::default(), EchoHistogram::default()); n];
    let totals = frames
        .par_iter()
        .fold(empty, |mut out, &k| {
            let inp = input(k);
            let planes = PlaneMapClassifier::planes_in_sensor_frame(&inp);
            let view = space.in_sensor_frame(inp.pose);
            let beams = BeamPlanes::hulls(&planes, p.hull_margin);
            for (i, pt) in inp.frame.points.iter().enumerate() {
                let pos = pt.position();
                let Some(h) = hits[k].get(i, &pos, &planes) else {
                    continue;
                };
                let range = pos.coords.norm();
                // Only beams behind one pane: past a second one the mirror
                // of the first says nothing.
                if range - h.range <= behind
                    || beams.second_pane(&pos, h.plane, h.range, glass, behind)
                {
                    continue;
                }
                let cos = if incidence {
                    inp.scan.incidence_cos(inp.frame, i).unwrap_or(1.0)
                } else {
                    1.0
                };
                let strength = echo_strength(pt.intensity, range, exponent, cos);
                out[h.plane].0.add(strength);
                let mirrored = planes[h.plane].plane.mirror(&pos);
                if view.occupancy_clear_of(&mirrored, clearance * range) == Occupancy::Free {
                    out[h.plane].1.add(strength);
                }
            }
            out
        })
        .reduce(empty, |mut a, b| {
            for ((all, anchors), (all_b, anchors_b)) in a.iter_mut().zip(&b) {
                all.merge(all_b);
                anchors.merge(anchors_b);
            }
            a
        });
    totals
        .into_iter()
        .enumerate()
        .map(|(j, (all, anchors))| {
            let split = EchoSplit::fit(&all, &anchors, &p.echo_split);
            let mirror = is_mirror(&all, &anchors, &p.echo_split);
            tracing::debug!(
                plane = j,
                behind = all.total(),
                anchors = anchors.total(),
                ?split,
                mirror,
                "echo split"
            );
            (split, mirror)
        })
        .collect()
}

/// The classified map in the world frame ("around the corner"): Normal,
/// reflective-surface and Obstacle points where they were measured,
/// Reflections mirrored back through their plane; unclassified points are
/// left out. Thinned to one point per `voxel` per class (0 keeps all).
pub fn around_corner_map(
    sequence: &Sequence,
    classes: &[Vec<Class>],
    map_planes: &[BoundedPlane],
    hull_margin: f64,
    voxel: f64,
) -> Vec<MapPoint> {
    let Some(poses) = &sequence.poses else {
        return Vec::new();
    };
    // The mirrored reflections of every frame (the beam tests), in parallel.
    let mirrored: Vec<Vec<(usize, Point3<f64>)>> = (0..sequence.len().min(classes.len()))
        .into_par_iter()
        .map(|k| {
            let planes = planes_seen_from(map_planes, &poses[k]);
            mirror_reflections(&sequence.frames[k], &classes[k], &planes, hull_margin)
        })
        .collect();
    // Thinned in one pass in frame order, no per-point buffers in between.
    let mut thin = Thinning::new(voxel);
    for (k, mirrored) in mirrored.iter().enumerate() {
        let pose = poses[k];
        let (r, t) = rotation_translation(&pose);
        for (pt, &class) in sequence.frames[k].points.iter().zip(&classes[k]) {
            if matches!(class, Class::Normal | Class::Glass | Class::Obstacle) {
                thin.offer(Point3::from(r * pt.position().coords + t), class, false);
            }
        }
        for (_, q) in mirrored {
            thin.offer(pose * q, Class::Reflection, true);
        }
    }
    thin.kept
}

/// The accumulated classified map in the world frame: every classified point
/// where it was measured (reflections included, not mirrored); unclassified
/// points are left out. Thinned to one point per `voxel` per class (0 keeps
/// all). Empty without poses.
pub fn measured_map(sequence: &Sequence, classes: &[Vec<Class>], voxel: f64) -> Vec<MapPoint> {
    let Some(poses) = &sequence.poses else {
        return Vec::new();
    };
    let mut thin = Thinning::new(voxel);
    for k in 0..sequence.len().min(classes.len()) {
        for (pt, &class) in sequence.frames[k].points.iter().zip(&classes[k]) {
            if class != Class::Unclassified {
                thin.offer(poses[k] * pt.position(), class, false);
            }
        }
    }
    thin.kept
}

/// A pose as rotation matrix and translation: applied to every point of a
/// frame, the matrix is cheaper than the quaternion.
fn rotation_translation(pose: &Isometry3<f64>) -> (Matrix3<f64>, Vector3<f64>) {
    (
        pose.rotation.to_rotation_matrix().into_inner(),
        pose.translation.vector,
    )
}

/// Keeps the first point offered per (voxel, class, mirrored); a voxel of 0
/// (or less) keeps every point.
struct Thinning {
    seen: Option<VoxelSet>,
    kept: Vec<MapPoint>,
}

impl Thinning {
    fn new(voxel: f64) -> Self {
        Self {
            seen: (voxel > 0.0).then(|| VoxelSet::new(voxel)),
            kept: Vec::new(),
        }
    }

    #[inline]
    fn offer(&mut self, p: Point3<f64>, class: Class, mirrored: bool) {
        let tag = (class.id() & 0x7) | (mirrored as u8) << 3;
        if self
            .seen
            .as_mut()
            .is_none_or(|s| s.insert([p.x, p.y, p.z], tag))
        {
            self.kept.push(MapPoint {
                xyz: [p.x as f32, p.y as f32, p.z as f32],
                class,
                mirrored,
            });
        }
    }
}
