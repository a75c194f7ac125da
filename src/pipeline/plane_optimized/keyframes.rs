//! Step 4: what the keyframes saw. From frames that see the scene from a
//! new viewpoint, passes over the sequence gather what classification
//! needs beyond the map: the surfaces observed (a mirror's support), the
//! space seen directly (no reflection can lie in it), and each landmark's
//! split of the echoes behind it into reflected and transmitted ones.

use std::time::Instant;

use nalgebra::{Isometry3, Point3};

use super::world_maps::rotation_translation;
use crate::classify::{
    BeamHits, EchoCounting, FrameInput, PlaneMapClassifier, SpaceMap, SupportBuilder, WorldSupport,
};
use crate::cloud::Frame;
use crate::map::{
    find_ghosts, glass_or_mirror, passed_through, BehindEchoes, Ghost, GhostParams, GlassOrMirror,
    LandedStrengths, ThroughBeam,
};
use crate::pipeline::{Sequence, StageTimings};
use crate::reflect::{BoundedPlane, Detection, EchoHistogram};
use crate::sensor::{OrganizedScan, SensorModel};
use crate::Result;

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
pub(super) struct FrameViews<'a> {
    pub(super) sequence: &'a Sequence,
    pub(super) sensor: &'a SensorModel,
    pub(super) classifier: &'a PlaneMapClassifier,
    pub(super) poses: &'a [Isometry3<f64>],
}

/// The detection the plane-map classifier is given: it classifies against
/// the map, not the frame's own planes.
static NO_DETECTION: Detection = Detection {
    candidates: Vec::new(),
    planes: Vec::new(),
};
/// What the keyframes saw, as the classifier takes it.
pub(super) struct Seen {
    /// The observed surfaces (world frame), when the classifier uses them.
    pub(super) support: Option<WorldSupport>,
    /// The space seen directly, when the classifier tests it.
    pub(super) space: Option<SpaceMap>,
    /// The landmarks as classified: with their echo splits, when learned.
    pub(super) planes: Vec<BoundedPlane>,
    /// The ghosts dropped (indices into the planes passed in; `planes`
    /// holds the others, in order).
    pub(super) ghosts: Vec<Ghost>,
}

impl<'a> FrameViews<'a> {
    /// What the keyframes saw, against the kept landmarks `planes`: the
    /// observed surfaces (mirror support) and the space seen directly, when
    /// the classifier uses them, and the landmarks with their echo splits
    /// when learned (a mirror the sensor passed through is glass after all,
    /// when `crossing_radius` opens crossings).
    pub(super) fn what_keyframes_saw(
        &self,
        planes: Vec<BoundedPlane>,
        crossing_radius: f64,
        ghosts: &GhostParams,
        timings: &mut StageTimings,
    ) -> Result<Seen> {
        let p = self.classifier.params();
        let poses = self.poses;
        let support = if p.sequence_support {
            // Every frame that moved (a stationary repeat adds nothing).
            let frames = keyframes(poses, 0.0, 0.0);
            Some(self.sequence_support(&frames, &planes, timings)?)
        } else {
            None
        };
        let space_frames = keyframes(poses, p.space_keyframe_move, p.space_keyframe_turn_deg);
        let space = if p.decision.space_test {
            let space = self.seen_space(&space_frames, &planes, timings)?;
            tracing::info!(
                keyframes = space_frames.len(),
                bricks = space.bricks(),
                levels = ?space.levels().heights(),
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
        let (planes, ghosts) = drop_ghosts(planes, &path, ghosts, support.as_ref());
        let crossings_open = crossing_radius > 0.0;
        // The landmarks as classified: with their echo splits, when learned.
        // The space seen through glass, carved by the echo split's pass.
        let mut through = space
            .as_ref()
            .filter(|_| p.echo_split.is_some())
            .map(SpaceMap::empty_like);
        let planes: Vec<BoundedPlane> = match (&space, p.echo_split.is_some()) {
            (Some(space), true) => self
                .echo_splits(
                    &space_frames,
                    &planes,
                    space,
                    support.as_ref(),
                    timings,
                    through.as_mut(),
                )?
                .into_iter()
                .zip(&planes)
                .map(|((estimate, levels_behind), bp)| BoundedPlane {
                    echo_split: estimate.echo_split,
                    // Nobody walks through a mirror.
                    mirror_probability: Some(if crossings_open && passed_through(bp, &path) {
                        0.0
                    } else {
                        estimate.mirror_probability
                    }),
                    levels_behind,
                    reflection_share: estimate.reflection_share,
                    decided_share: estimate.decided_share,
                    ..bp.clone()
                })
                .collect(),
            _ => planes,
        };
        let mut space = space;
        if let (Some(space), Some(through)) = (space.as_mut(), through) {
            space.set_through(through);
        }
        Ok(Seen {
            support,
            space,
            planes,
            ghosts,
        })
    }

    /// The classifier's input for frame `k` against `planes` (no support,
    /// space or precomputed beam test).
    pub(super) fn input<'b>(
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
                // What a frame adds to the pass's result is part of the
                // stage too (it runs on the calling thread, in order).
                let start = Instant::now();
                consume(out);
                cpu.add(stage, d + start.elapsed());
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
        if p.decision.support_behind_test {
            builder = builder.with_behind(p.decision.support_behind);
        }
        self.pass(
            frames,
            planes,
            "support",
            timings,
            |input, hits| {
                let (r, t) = rotation_translation(&input.pose);
                let points = &input.frame.points;
                let world = self
                    .classifier
                    .surface_points(input, hits)
                    .into_iter()
                    .map(|i| Point3::from(r * points[i as usize].position().coords + t))
                    .collect::<Vec<_>>();
                (Point3::from(t), world)
            },
            |(origin, points)| builder.extend(origin, points),
        )?;
        let start = Instant::now();
        let support = builder.finish();
        timings.add("support", start.elapsed());
        Ok(support)
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

    /// Each plane's glass-or-mirror estimate ([`glass_or_mirror()`]) from
    /// the keyframes `frames`: the strengths of every point behind the
    /// plane and of the direct echoes, and the points behind it that the
    /// space seen directly calls real, counted per frame by
    /// [`EchoCounting`] and summed here.
    fn echo_splits(
        &self,
        frames: &[usize],
        planes: &[BoundedPlane],
        space: &SpaceMap,
        support: Option<&WorldSupport>,
        timings: &mut StageTimings,
        mut through: Option<&mut SpaceMap>,
    ) -> Result<Vec<(GlassOrMirror, Vec<f64>)>> {
        let p = self.classifier.params();
        // The frames of a sequence share one intensity scale: the first
        // keyframe's, as its source says (a PLY comment, the simulator),
        // else the sensor model's.
        let declared = match frames.first() {
            Some(&k) => self.sequence.frame(k)?.intensity_scale,
            None => None,
        };
        let scale = declared.unwrap_or(self.sensor.intensity);
        // Called with the split configured.
        let split = p.echo_split.unwrap_or_default();
        let exponent = split.range_exponent.resolve(scale);
        tracing::info!(
            range_exponent = exponent,
            scale = scale.name(),
            "echo strengths"
        );
        // Per landmark: the strengths of all points behind it, and of its
        // anchors, summed over the keyframes (integer counts: the result
        // does not depend on the order or the threads).
        let mut totals = vec![BehindEchoes::default(); planes.len()];
        // The strengths of the direct echoes (no pane on the beam), what a
        // mirror's images look like.
        let mut direct = EchoHistogram::default();
        // Per landmark: the strengths of its echoes by voxel, for the
        // surfaces seen through it once its split is known.
        let mut landed = vec![LandedStrengths::default(); planes.len()];
        let voxel = space.voxel();
        let counting = EchoCounting {
            params: p,
            split: &split,
            range_exponent: exponent,
            space,
            support,
        };
        self.pass(
            frames,
            planes,
            "echo split",
            timings,
            |inp, hits| counting.count_frame(inp, hits),
            |(frame_counts, frame_direct)| {
                for ((total, strengths), frame) in
                    totals.iter_mut().zip(&mut landed).zip(&frame_counts)
                {
                    total.merge(frame);
                    if let Some(map) = through.as_deref_mut() {
                        carve_through(map, &frame.through, p.space_stop_ratio);
                        for echo in &frame.landed {
                            strengths.add(echo, voxel);
                        }
                    }
                }
                direct.merge(&frame_direct);
            },
        )?;
        Ok(totals
            .into_iter()
            .zip(&landed)
            .enumerate()
            .map(|(j, (t, strengths))| {
                let estimate = glass_or_mirror(&t, &direct, &split, &p.mirror, exponent);
                // Nothing is seen through a mirror: its strong echoes are
                // bright reflections.
                let glass_split = estimate
                    .echo_split
                    .as_ref()
                    .filter(|_| !estimate.is_mirror());
                if let (Some(map), Some(split)) = (through.as_deref_mut(), glass_split) {
                    for surface in strengths.surfaces(split, voxel).into_iter().flatten() {
                        map.add_beam(&surface, &surface, 0.0, true);
                    }
                }
                tracing::debug!(
                    plane = j,
                    behind_median = t.all.quantile(0.5),
                    direct_median = direct.quantile(0.5),
                    behind = t.all.total(),
                    anchors = t.anchors.total(),
                    inside = t.inside.total(),
                    transmitted_inside = t.transmitted.total(),
                    ?estimate,
                    transmitted_at_level = ?t.transmitted_at_level,
                    "glass or mirror"
                );
                (estimate, t.levels_behind(space.levels().heights()))
            })
            .collect())
    }
}

/// The planes without the ghosts among them ([`find_ghosts`] against the
/// sequence's surfaces seen directly), and the ghosts.
fn drop_ghosts(
    planes: Vec<BoundedPlane>,
    path: &[Point3<f64>],
    params: &GhostParams,
    support: Option<&WorldSupport>,
) -> (Vec<BoundedPlane>, Vec<Ghost>) {
    let ghosts = match support {
        Some(support) => find_ghosts(&planes, path, params, |p, r| support.near_world(p, r)),
        None => Vec::new(),
    };
    for g in &ghosts {
        tracing::info!(
            plane = g.ghost,
            glass = g.glass,
            share = g.share,
            "ghost landmark dropped: a reflection of seen surfaces"
        );
    }
    let planes = planes
        .into_iter()
        .enumerate()
        .filter(|(i, _)| !ghosts.iter().any(|g| g.ghost == *i))
        .map(|(_, p)| p)
        .collect();
    (planes, ghosts)
}

/// Carve a frame's confirmed transmissions (`beams`) into `map`, the space
/// seen through glass: each from the pane to its echo, stopping short of it
/// by `stop_ratio` of its range (at least two voxels), as the space seen
/// directly does; its end a surface.
fn carve_through(map: &mut SpaceMap, beams: &[ThroughBeam], stop_ratio: f64) {
    let min_stop = 2.0 * map.voxel();
    for b in beams {
        let point = |v: [f32; 3]| Point3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2]));
        let stop = min_stop.max(stop_ratio * f64::from(b.range));
        map.add_beam(&point(b.start), &point(b.end), stop, true);
    }
}
