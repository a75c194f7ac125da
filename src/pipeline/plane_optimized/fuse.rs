//! Steps 2 and 3: the reflective plane map. The frames' observations are
//! fused into landmarks in timestamp order (the configured [`MapMerger`]),
//! the landmarks observed often enough are kept, and each kept landmark is
//! bounded: by its fused hull (the paper), or by the transparency evidence
//! gathered over the whole sequence and the panes found in it.
//!
//! [`MapMerger`]: crate::map::MapMerger

use std::sync::Arc;
use std::time::Instant;

use nalgebra::{Isometry3, Point3, Vector3};

use super::detect::FrameSummary;
use crate::config::Config;
use crate::geometry::fit::PlaneSums;
use crate::map::{
    find_panes, open_where_crossed, BoundaryMode, EvidenceFrame, EvidenceGatherer, EvidenceTotal,
    PlaneMap,
};
use crate::pipeline::registry::merger;
use crate::pipeline::{Sequence, StageTimings};
use crate::reflect::BoundedPlane;
use crate::sensor::SensorModel;
use crate::Result;

/// The fused map: every landmark, the indices of those kept, and the kept
/// ones as bounded planes (world frame, same order as `used`).
pub(super) struct FusedMap {
    pub(super) map: PlaneMap,
    pub(super) used: Vec<usize>,
    pub(super) planes: Vec<BoundedPlane>,
}

/// Fuse every frame's observations into the map in timestamp order and
/// keep the well-observed landmarks.
pub(super) fn fuse(
    summaries: &[FrameSummary],
    poses: &[Isometry3<f64>],
    config: &Config,
    sensor: &SensorModel,
    timings: &mut StageTimings,
) -> FusedMap {
    let start = Instant::now();
    let merger = merger(config);
    let mut map = PlaneMap::new();
    // The merger compares plane offsets `d`, which depend on where the
    // world origin is (planes whose normals differ by half a degree differ
    // by 0.44 m in `d` 50 m from it): fuse in a frame whose origin is the
    // first pose, as the paper's data has it, so that moving the world
    // frame (a map frame, UTM coordinates) changes nothing.
    let anchor = poses
        .first()
        .map_or_else(Vector3::zeros, |p| p.translation.vector);
    let to_local = Isometry3::translation(-anchor.x, -anchor.y, -anchor.z);
    for summary in summaries {
        for obs in &summary.observations {
            merger.merge(&mut map, &obs.transformed(&to_local));
        }
    }
    let to_world = to_local.inverse();
    for landmark in &mut map.landmarks {
        landmark.transform(&to_world);
    }
    let used = map.reliable(poses, &config.map.selection().for_sensor(sensor));
    let planes: Vec<BoundedPlane> = used.iter().map(|&i| map.landmarks[i].bounded()).collect();
    timings.add("map", start.elapsed());
    tracing::info!(
        landmarks = map.landmarks.len(),
        used = used.len(),
        "reflective plane map fused"
    );
    FusedMap { map, used, planes }
}

/// Bound the kept landmarks as `config.map.boundary` says: the transparency
/// evidence of every landmark over all frames, and the panes found in it
/// (nothing to do for the hull).
pub(super) fn bound(
    sequence: &Sequence,
    sensor: &SensorModel,
    planes: &mut [BoundedPlane],
    config: &Config,
    timings: &mut StageTimings,
) -> Result<()> {
    if config.map.boundary == BoundaryMode::Hull {
        return Ok(());
    }
    gather_evidence(sequence, sensor, planes, config, timings)?;
    if config.map.boundary == BoundaryMode::Panes {
        let start = Instant::now();
        for bp in planes {
            // Without any decided evidence the hull stays the boundary.
            if let Some(grid) = bp.evidence.as_ref().filter(|g| g.is_decided()) {
                let panes = find_panes(grid, &config.map.panes);
                bp.panes = Some(Arc::new(panes.into_iter().map(|p| p.boundary).collect()));
            }
        }
        timings.add("panes", start.elapsed());
    }
    Ok(())
}

/// Gather the transparency evidence of every landmark in `planes` (world
/// frame) in one pass over the sequence; with `map.evidence.refit_plane`,
/// first refit the planes to their glass echoes (a lighter pass).
fn gather_evidence(
    sequence: &Sequence,
    sensor: &SensorModel,
    planes: &mut [BoundedPlane],
    config: &Config,
    timings: &mut StageTimings,
) -> Result<()> {
    if config.map.evidence.refit_plane {
        refit_planes(sequence, sensor, planes, config, timings)?;
    }
    let totals = evidence_pass(sequence, sensor, planes, config, timings)?;
    let poses = sequence.poses.as_deref().unwrap_or_default();
    let path: Vec<Point3<f64>> = poses
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let start = Instant::now();
    for (bp, total) in planes.iter_mut().zip(totals) {
        bp.evidence = total.map(|t| Arc::new(t.finish()));
        // Where the sensor passed through the plane, it is open.
        open_where_crossed(bp, &path, config.map.evidence.crossing_radius);
    }
    timings.add("evidence", start.elapsed());
    Ok(())
}

/// One evidence gatherer per landmark of `planes`, aware of the others.
fn gatherers(planes: &[BoundedPlane], config: &Config) -> Vec<Option<EvidenceGatherer>> {
    planes
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
        .collect()
}

/// Refit every landmark's plane to its glass echoes over the sequence
/// (`map.evidence.refit_plane`): a pass over the points with a second
/// return, summing the echoes in frame order, then each plane whose refit
/// is accepted replaced, its boundary projected onto it.
fn refit_planes(
    sequence: &Sequence,
    sensor: &SensorModel,
    planes: &mut [BoundedPlane],
    config: &Config,
    timings: &mut StageTimings,
) -> Result<()> {
    let gatherers = gatherers(planes, config);
    if gatherers.iter().all(Option::is_none) {
        return Ok(());
    }
    let mut sums: Vec<Option<PlaneSums>> = gatherers
        .iter()
        .map(|g| g.as_ref().map(EvidenceGatherer::empty_sums))
        .collect();
    per_landmark_pass(
        sequence,
        sensor,
        &gatherers,
        ("plane refit", "refit"),
        timings,
        EvidenceGatherer::glass_echo_sums,
        |total: &mut PlaneSums, s| total.merge(&s),
        &mut sums,
    )?;
    for ((bp, g), s) in planes.iter_mut().zip(&gatherers).zip(&sums) {
        let (Some(g), Some(s)) = (g, s) else {
            continue;
        };
        if let Some(fit) = g.refitted_plane(s) {
            let boundary = bp.boundary_3d();
            tracing::debug!(
                turned_deg = fit.normal.angle(&bp.plane.normal).to_degrees(),
                moved_m = boundary
                    .first()
                    .map_or(0.0, |q| bp.plane.signed_distance(&fit.project(q))),
                old = ?bp.plane,
                new = ?fit,
                "landmark plane refitted to its glass echoes"
            );
            *bp = BoundedPlane::from_points(fit, boundary);
        }
    }
    Ok(())
}

/// One pass over the sequence: every landmark's evidence totals.
fn evidence_pass(
    sequence: &Sequence,
    sensor: &SensorModel,
    planes: &[BoundedPlane],
    config: &Config,
    timings: &mut StageTimings,
) -> Result<Vec<Option<EvidenceTotal>>> {
    let gatherers = gatherers(planes, config);
    let mut totals: Vec<Option<EvidenceTotal>> = gatherers
        .iter()
        .map(|g| g.as_ref().map(EvidenceGatherer::total))
        .collect();
    if gatherers.iter().any(Option::is_some) {
        per_landmark_pass(
            sequence,
            sensor,
            &gatherers,
            ("evidence", "evidence"),
            timings,
            EvidenceGatherer::votes,
            EvidenceTotal::add,
            &mut totals,
        )?;
    }
    Ok(totals)
}

/// One pass over every frame of the sequence: each landmark's gatherer
/// reads the frame (`read`, in parallel across frames), and its result is
/// added to the landmark's total in frame order (`add`). `stage` names the
/// pass's progress bar and its timing.
#[allow(clippy::too_many_arguments)]
fn per_landmark_pass<T: Send, A>(
    sequence: &Sequence,
    sensor: &SensorModel,
    gatherers: &[Option<EvidenceGatherer>],
    (pass, stage): (&'static str, &'static str),
    timings: &mut StageTimings,
    read: impl Fn(&EvidenceGatherer, &EvidenceFrame<'_>) -> T + Sync,
    add: impl Fn(&mut A, T),
    totals: &mut [Option<A>],
) -> Result<()> {
    let poses = sequence.poses.as_deref().unwrap_or_default();
    let reading = sequence.stream_all(
        pass,
        |k, frame| {
            let mut t = StageTimings::default();
            let scan = sequence.timed_scan(k, frame, sensor, &mut t)?;
            let start = Instant::now();
            let f = EvidenceFrame::new(frame, &scan, poses[k], sensor);
            let per_landmark: Vec<Option<T>> = gatherers
                .iter()
                .map(|g| g.as_ref().map(|g| read(g, &f)))
                .collect();
            t.add(stage, start.elapsed());
            Ok((per_landmark, t))
        },
        |_, _, (per_landmark, t)| {
            timings.merge(&t);
            let start = Instant::now();
            for (total, x) in totals.iter_mut().zip(per_landmark) {
                if let (Some(total), Some(x)) = (total, x) {
                    add(total, x);
                }
            }
            timings.add(stage, start.elapsed());
            Ok(())
        },
    )?;
    timings.add_reading(reading);
    Ok(())
}
