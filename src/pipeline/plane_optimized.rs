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

use std::sync::Arc;
use std::time::Instant;

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::registry::{detector, frame_seed, merger, plane_map_classifier};
use super::single_scan::{check_dual_returns, check_points};
use super::{FrameOutput, FrameSink, RunOutput, RunScore, Sequence, StageTimings};
use crate::classify::boundary::BeamPlanes;
use crate::classify::decide::{two_hypotheses, SurfaceSupport, Verdict};
use crate::classify::mirror::mirror_reflections;
use crate::classify::{
    BeamHits, Class, Classifier, FrameInput, Occupancy, PlaneMapClassifier, SpaceMap,
    SupportBuilder, WorldSupport,
};
use crate::cloud::Frame;
use crate::config::{BoundaryMode, Config};
use crate::geometry::voxel::VoxelSet;
use crate::io::{MapPoint, PlaneKind};
use crate::map::{
    find_panes, open_where_crossed, passed_through, EvidenceFrame, EvidenceGatherer, EvidenceTotal,
    PlaneMap, PlaneObservation,
};
use crate::reflect::echo_split::{echo_strength, is_mirror};
use crate::reflect::{planes_seen_from, BoundedPlane, Detection, EchoHistogram, EchoSplit};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::{Error, Result};

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
}

/// What the detection pass keeps of a frame: its reflective planes as
/// world-frame observations, and how many it found.
struct FrameSummary {
    observations: Vec<PlaneObservation>,
    planes: usize,
    candidates: usize,
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
    let detector = detector(config, &sensor);
    let mut timings = StageTimings::default();

    // 1. Per-frame detection (sensor frame); a frame's planes are all that
    // is kept of it.
    let mut summaries = Vec::with_capacity(sequence.len());
    let mut second_returns = 0;
    let reading = sequence.stream_all(
        "detect",
        |k, frame| {
            check_points(sequence, k, frame)?;
            let mut t = StageTimings::default();
            let start = Instant::now();
            let scan = sequence.scan(k, frame, &sensor)?;
            t.add("pair", start.elapsed());
            let start = Instant::now();
            let detection = detector.detect(frame, &scan, frame_seed(config.seed, &frame.name));
            t.add("detect", start.elapsed());
            let summary = FrameSummary {
                observations: observations(&detection, &poses[k], k),
                planes: detection.planes.len(),
                candidates: detection.candidates.len(),
            };
            Ok((summary, t))
        },
        |_, frame, (summary, t)| {
            timings.merge(&t);
            second_returns += frame.second_returns();
            summaries.push(summary);
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    check_dual_returns(sequence, second_returns, config)?;

    // 2-3. Fuse into the map in timestamp order; keep well-observed landmarks.
    let start = Instant::now();
    let merger = merger(config);
    let mut map = PlaneMap::new();
    for summary in &summaries {
        for obs in &summary.observations {
            merger.merge(&mut map, obs);
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
        gather_evidence(sequence, &sensor, &mut map_planes, config, &mut timings)?;
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

    // 4. What the keyframes saw: surfaces, free space, echo strengths.
    let classifier = plane_map_classifier(config);
    let p = classifier.params();
    let views = FrameViews {
        sequence,
        sensor: &sensor,
        classifier: &classifier,
        poses,
    };
    let support = if p.sequence_support {
        let frames = keyframes(poses, p.support_keyframe_move, p.support_keyframe_turn_deg);
        Some(views.sequence_support(&frames, &map_planes, &mut timings)?)
    } else {
        None
    };
    let space_frames = keyframes(poses, p.space_keyframe_move, p.space_keyframe_turn_deg);
    let space = if p.decision.space_test {
        let space = views.seen_space(&space_frames, &map_planes, &mut timings)?;
        tracing::info!(
            keyframes = space_frames.len(),
            bricks = space.bricks(),
            "space seen directly"
        );
        Some(space)
    } else {
        None
    };
    let path: Vec<Point3<f64>> = poses
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let crossings_open = config.map.evidence.crossing_radius > 0.0;
    // The landmarks as classified: with their echo splits, when learned.
    let classified_planes: Vec<BoundedPlane> = match (&space, p.echo_split.enabled) {
        (Some(space), true) => views
            .echo_splits(
                &space_frames,
                &map_planes,
                space,
                support.as_ref(),
                &mut timings,
            )?
            .into_iter()
            .zip(&map_planes)
            .map(|((echo_split, mirror), bp)| BoundedPlane {
                echo_split,
                // Nobody walks through a mirror.
                mirror: mirror && !(crossings_open && passed_through(bp, &path)),
                ..bp.clone()
            })
            .collect(),
        _ => map_planes,
    };

    // 5. Classify every frame against the map.
    sink.begin(&classified_planes)?;
    let mut score = RunScore::default();
    let reading = sequence.stream_all(
        "classify",
        |k, frame| {
            let mut t = StageTimings::default();
            let start = Instant::now();
            let scan = sequence.scan(k, frame, &sensor)?;
            t.add("pair", start.elapsed());
            let start = Instant::now();
            let decisions = classifier.classify(&FrameInput {
                support: support.as_ref(),
                space: space.as_ref(),
                ..views.input(k, frame, &scan, &classified_planes)
            });
            t.add("classify", start.elapsed());
            Ok((decisions, t))
        },
        |k, frame, (decisions, t)| {
            timings.merge(&t);
            let output = FrameOutput {
                name: frame.name.clone(),
                classes: decisions.classes,
                rules: decisions.rules,
                planes: summaries[k].planes,
                candidates: summaries[k].candidates,
            };
            score.add(sequence.path(k), frame, &output);
            let start = Instant::now();
            sink.frame(k, frame, Some(&poses[k]), output)?;
            timings.add("write outputs", start.elapsed());
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    timings.frames = sequence.len();
    timings.wall = wall.elapsed();
    Ok(PlaneOptimizedOutput {
        run: score.finish(Vec::new(), timings),
        map,
        used,
        planes: classified_planes,
    })
}

/// Gather the transparency evidence of every landmark in `planes` (world
/// frame) in one pass over the sequence.
fn gather_evidence(
    sequence: &Sequence,
    sensor: &SensorModel,
    planes: &mut [BoundedPlane],
    config: &Config,
    timings: &mut StageTimings,
) -> Result<()> {
    let poses = sequence.poses.as_deref().unwrap_or_default();
    let gatherers: Vec<Option<EvidenceGatherer>> = planes
        .iter()
        .enumerate()
        .map(|(k, bp)| {
            let others: Vec<BoundedPlane> = planes
                .iter()
                .enumerate()
                .filter(|(j, _)| *j != k)
                .map(|(_, o)| o.clone())
                .collect();
            EvidenceGatherer::new(bp, &config.map.evidence).map(|g| g.with_others(&others))
        })
        .collect();
    let mut totals: Vec<Option<EvidenceTotal>> = gatherers
        .iter()
        .map(|g| g.as_ref().map(EvidenceGatherer::total))
        .collect();
    if gatherers.iter().any(Option::is_some) {
        let reading = sequence.stream_all(
            "evidence",
            |k, frame| {
                let mut t = StageTimings::default();
                let start = Instant::now();
                let scan = sequence.scan(k, frame, sensor)?;
                t.add("pair", start.elapsed());
                let start = Instant::now();
                let f = EvidenceFrame {
                    frame,
                    scan: &scan,
                    pose: poses[k],
                };
                let votes: Vec<_> = gatherers
                    .iter()
                    .map(|g| g.as_ref().map(|g| g.votes(&f)))
                    .collect();
                t.add("evidence", start.elapsed());
                Ok((votes, t))
            },
            |_, _, (votes, t)| {
                timings.merge(&t);
                for (total, v) in totals.iter_mut().zip(votes) {
                    if let (Some(total), Some(v)) = (total, v) {
                        total.add(v);
                    }
                }
                Ok(())
            },
        )?;
        timings.add_reading(reading);
    }
    let path: Vec<Point3<f64>> = poses
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    for (bp, total) in planes.iter_mut().zip(totals) {
        bp.evidence = total.map(|t| Arc::new(t.finish()));
        // Where the sensor passed through the plane, it is open.
        open_where_crossed(bp, &path, config.map.evidence.crossing_radius);
    }
    Ok(())
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

/// What the keyframe passes share: the sequence, how to pair a frame's
/// returns, the classifier's beam test and the poses.
struct FrameViews<'a> {
    sequence: &'a Sequence,
    sensor: &'a SensorModel,
    classifier: &'a PlaneMapClassifier,
    poses: &'a [Isometry3<f64>],
}

/// The detection the plane-map classifier is given: it classifies against
/// the map, not the frame's own planes.
static NO_DETECTION: Detection = Detection {
    candidates: Vec::new(),
    planes: Vec::new(),
};

impl<'a> FrameViews<'a> {
    /// The classifier's input for frame `k` against `planes` (no support,
    /// space or precomputed beam test).
    fn input<'b>(
        &'b self,
        k: usize,
        frame: &'b Frame,
        scan: &'b OrganizedScan,
        planes: &'b [BoundedPlane],
    ) -> FrameInput<'b> {
        FrameInput {
            frame,
            scan,
            sensor: self.sensor,
            detection: &NO_DETECTION,
            pose: self.poses[k],
            map_planes: planes,
            support: None,
            space: None,
            beam_hits: None,
        }
    }

    /// One pass over the keyframes `frames`: `work` gets each frame's
    /// input with its beam test against `planes`.
    fn pass<T: Send>(
        &self,
        frames: &[usize],
        planes: &[BoundedPlane],
        stage: &'static str,
        timings: &mut StageTimings,
        work: impl Fn(&FrameInput<'_>, &BeamHits) -> T + Sync,
        mut consume: impl FnMut(T),
    ) -> Result<()> {
        let mut cpu = StageTimings::default();
        let reading = self.sequence.stream(
            frames,
            stage,
            |k, frame| {
                let start = Instant::now();
                let scan = self.sequence.scan(k, frame, self.sensor)?;
                let input = self.input(k, frame, &scan, planes);
                let hits = self.classifier.beam_hits(&input);
                Ok((work(&input, &hits), start.elapsed()))
            },
            |_, _, (out, d)| {
                cpu.add(stage, d);
                consume(out);
                Ok(())
            },
        )?;
        timings.merge(&cpu);
        timings.add_reading(reading);
        Ok(())
    }

    /// The observed surfaces of the keyframes `frames` (world frame),
    /// thinned by voxel.
    fn sequence_support(
        &self,
        frames: &[usize],
        planes: &[BoundedPlane],
        timings: &mut StageTimings,
    ) -> Result<WorldSupport> {
        let p = self.classifier.params();
        let mut builder = SupportBuilder::new(p.support_voxel, p.decision.support_radius);
        self.pass(
            frames,
            planes,
            "support",
            timings,
            |input, hits| {
                let (r, t) = rotation_translation(&input.pose);
                let points = &input.frame.points;
                self.classifier
                    .surface_points(input, hits)
                    .into_iter()
                    .map(|i| Point3::from(r * points[i as usize].position().coords + t))
                    .collect::<Vec<_>>()
            },
            |points| builder.extend(points),
        )?;
        Ok(builder.finish())
    }

    /// The space seen directly from the keyframes `frames` (world frame):
    /// every beam that crosses no reflective pane marks its endpoint
    /// occupied and carves the voxels before it; a beam that crosses a pane
    /// carves only up to the pane. Of a beam's two returns only the nearer
    /// is used: the farther may have passed an unmapped pane.
    fn seen_space(
        &self,
        frames: &[usize],
        planes: &[BoundedPlane],
        timings: &mut StageTimings,
    ) -> Result<SpaceMap> {
        let p = self.classifier.params();
        let glass = p.decision.glass_distance;
        let mut space = SpaceMap::new(p.space_voxel, p.space_min_passes, p.space_block_hits);
        let min_stop = 2.0 * space.voxel();
        let stride = p.space_column_stride.max(1);
        self.pass(
            frames,
            planes,
            "space",
            timings,
            |inp, hits| {
                let sensor_planes = PlaneMapClassifier::planes_in_sensor_frame(inp);
                let (r, t) = rotation_translation(&inp.pose);
                let points = &inp.frame.points;
                let mut beams = Vec::with_capacity(points.len());
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
                    // Behind a pane, or behind a plane's unseen
                    // continuation where glass may be: carve to the plane.
                    let crossing =
                        hits.get(i, &pos, &sensor_planes)
                            .or(hits.unseen(i, &pos, &sensor_planes));
                    let (end_range, hit) = match crossing {
                        Some(h) if range >= h.range - glass => (h.range.min(range), false),
                        _ => (range, true),
                    };
                    let end = Point3::from(r * (pos.coords * (end_range / range)) + t);
                    // Every beam marks its surface; one in `stride` columns
                    // carves.
                    let (_, col) = inp.scan.ring_column(inp.scan.cell_of(i));
                    let stop = if col % stride == 0 {
                        min_stop.max(p.space_stop_ratio * range)
                    } else {
                        f64::INFINITY
                    };
                    beams.push((end, stop, hit));
                }
                (Point3::from(t), beams)
            },
            |(origin, beams)| {
                for (end, stop, hit) in beams {
                    space.add_beam(&origin, &end, stop, hit);
                }
            },
        )?;
        Ok(space)
    }

    /// Each plane's split of echoes behind it into reflected and
    /// transmitted ones ([`EchoSplit`]), and whether it is a mirror, from
    /// the keyframes `frames`: the strengths of every point behind the
    /// plane, oriented by the points whose mirror image lies in seen-free
    /// space (they cannot be reflections; a plane with almost none is a
    /// mirror).
    fn echo_splits(
        &self,
        frames: &[usize],
        planes: &[BoundedPlane],
        space: &SpaceMap,
        support: Option<&WorldSupport>,
        timings: &mut StageTimings,
    ) -> Result<Vec<(Option<EchoSplit>, bool)>> {
        let p = self.classifier.params();
        let behind = p.decision.behind_distance;
        let glass = p.decision.glass_distance;
        let clearance = p.decision.space_clearance_ratio;
        let exponent = p.echo_split.range_exponent;
        let incidence = p.echo_split.incidence_correction;
        // Per landmark: the strengths of all points behind it, and of its
        // anchors, summed over the keyframes (integer counts: the result
        // does not depend on the order or the threads).
        let blocked_paths = p.echo_split.mirror_blocked_paths;
        let empty =
            || vec![(EchoHistogram::default(), EchoHistogram::default(), 0u64); planes.len()];
        let mut totals = empty();
        self.pass(
            frames,
            planes,
            "echo split",
            timings,
            |inp, hits| {
                let mut out = empty();
                let sensor_planes = PlaneMapClassifier::planes_in_sensor_frame(inp);
                let view = space.in_sensor_frame(inp.pose);
                let seen = support.map(|s| s.in_sensor_frame(inp.pose));
                let seen = seen.as_ref().map(|s| s as &dyn SurfaceSupport);
                let beams = BeamPlanes::hulls(&sensor_planes, p.hull_margin);
                for (i, pt) in inp.frame.points.iter().enumerate() {
                    let pos = pt.position();
                    let Some(h) = hits.get(i, &pos, &sensor_planes) else {
                        continue;
                    };
                    let range = pos.coords.norm();
                    // Only beams behind one pane: past a second one the
                    // mirror of the first says nothing.
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
                    let mirrored = sensor_planes[h.plane].plane.mirror(&pos);
                    // A glass echo of a second pane behind this one is
                    // transmitted by this one, but its strength is that
                    // pane's echo, not a surface's: no anchor.
                    let on_other_pane =
                        beams.crosses_between(&pos, h.plane, range - glass, range + glass);
                    if on_other_pane {
                        continue;
                    }
                    let anchor =
                        view.occupancy_clear_of(&mirrored, clearance * range) == Occupancy::Free;
                    if anchor {
                        out[h.plane].1.add(strength);
                    }
                    let transmitted = if blocked_paths {
                        let plane = &sensor_planes[h.plane].plane;
                        two_hypotheses(&view, seen, plane, &pos, &p.decision) == Verdict::Real
                    } else {
                        anchor
                    };
                    out[h.plane].2 += u64::from(transmitted);
                }
                out
            },
            |frame_counts| {
                for ((all, anchors, transmitted), (all_f, anchors_f, transmitted_f)) in
                    totals.iter_mut().zip(&frame_counts)
                {
                    all.merge(all_f);
                    anchors.merge(anchors_f);
                    *transmitted += transmitted_f;
                }
            },
        )?;
        Ok(totals
            .into_iter()
            .enumerate()
            .map(|(j, (all, anchors, transmitted))| {
                let split = EchoSplit::fit(&all, &anchors, &p.echo_split);
                let mirror = is_mirror(&all, transmitted, &p.echo_split);
                tracing::debug!(
                    plane = j,
                    behind = all.total(),
                    anchors = anchors.total(),
                    transmitted,
                    ?split,
                    mirror,
                    "echo split"
                );
                (split, mirror)
            })
            .collect())
    }
}

/// The classified map in the world frame ("around the corner"), built a
/// frame at a time: Normal, reflective-surface and Obstacle points where
/// they were measured, Reflections mirrored back through their plane;
/// unclassified points are left out. Thinned to one point per `voxel` per
/// class (0 keeps all), so it grows with the space mapped, not with the
/// frames.
pub struct AroundCornerMap {
    planes: Vec<BoundedPlane>,
    hull_margin: f64,
    thin: Thinning,
}

impl AroundCornerMap {
    /// An empty map against the reflective `planes` (world frame).
    pub fn new(planes: &[BoundedPlane], hull_margin: f64, voxel: f64) -> Self {
        Self {
            planes: planes.to_vec(),
            hull_margin,
            thin: Thinning::new(voxel),
        }
    }

    /// Add a frame with its pose and classes.
    pub fn add(&mut self, frame: &Frame, pose: &Isometry3<f64>, classes: &[Class]) {
        let planes = planes_seen_from(&self.planes, pose);
        let mirrored = mirror_reflections(frame, classes, &planes, self.hull_margin);
        let (r, t) = rotation_translation(pose);
        for (pt, &class) in frame.points.iter().zip(classes) {
            if matches!(class, Class::Normal | Class::Glass | Class::Obstacle) {
                self.thin
                    .offer(Point3::from(r * pt.position().coords + t), class, false);
            }
        }
        for (_, q) in mirrored {
            self.thin.offer(pose * q, Class::Reflection, true);
        }
    }

    /// The map's points, in the order they were kept.
    pub fn into_points(self) -> Vec<MapPoint> {
        self.thin.kept
    }
}

/// The accumulated classified map in the world frame, built a frame at a
/// time: every classified point where it was measured (reflections
/// included, not mirrored); unclassified points are left out. Thinned to
/// one point per `voxel` per class (0 keeps all).
pub struct MeasuredMap {
    thin: Thinning,
}

impl MeasuredMap {
    /// An empty map.
    pub fn new(voxel: f64) -> Self {
        Self {
            thin: Thinning::new(voxel),
        }
    }

    /// Add a frame with its pose and classes.
    pub fn add(&mut self, frame: &Frame, pose: &Isometry3<f64>, classes: &[Class]) {
        for (pt, &class) in frame.points.iter().zip(classes) {
            if class != Class::Unclassified {
                self.thin.offer(pose * pt.position(), class, false);
            }
        }
    }

    /// The map's points, in the order they were kept.
    pub fn into_points(self) -> Vec<MapPoint> {
        self.thin.kept
    }
}

/// [`AroundCornerMap`] of a sequence and its classes (empty without poses).
pub fn around_corner_map(
    sequence: &Sequence,
    classes: &[Vec<Class>],
    map_planes: &[BoundedPlane],
    hull_margin: f64,
    voxel: f64,
) -> Result<Vec<MapPoint>> {
    let Some(poses) = &sequence.poses else {
        return Ok(Vec::new());
    };
    let mut map = AroundCornerMap::new(map_planes, hull_margin, voxel);
    for k in 0..sequence.len().min(classes.len()) {
        map.add(&*sequence.frame(k)?, &poses[k], &classes[k]);
    }
    Ok(map.into_points())
}

/// [`MeasuredMap`] of a sequence and its classes (empty without poses).
pub fn measured_map(
    sequence: &Sequence,
    classes: &[Vec<Class>],
    voxel: f64,
) -> Result<Vec<MapPoint>> {
    let Some(poses) = &sequence.poses else {
        return Ok(Vec::new());
    };
    let mut map = MeasuredMap::new(voxel);
    for k in 0..sequence.len().min(classes.len()) {
        map.add(&*sequence.frame(k)?, &poses[k], &classes[k]);
    }
    Ok(map.into_points())
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
