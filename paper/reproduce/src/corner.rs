//! Data of the "mapping around the corner" figure: the plane-optimized
//! result of a sequence as two world-frame maps, reflections as measured
//! and mirrored back, cut to a horizontal slab around the sensor height so
//! the floor and ceiling do not hide the walls and furniture.

use std::path::Path;

use serde::Serialize;

use specular::classify::Class;
use specular::config::Config;
use specular::io::MapPoint;
use specular::pipeline::plane_optimized::{around_corner_map, measured_map};
use specular::pipeline::{PlaneOptimizedOutput, Sequence};
use specular::viz::corner::around_corner_png;
use specular::Result;

/// Half-height of the slab drawn, metres around the mean sensor height.
const SLAB: f64 = 0.8;

/// What the figure shows, in numbers (deterministic, for `results.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CornerSummary {
    /// Map points in the slab (both panels, after voxel thinning).
    pub points: usize,
    /// Reflection points drawn where they were measured.
    pub reflections_measured: usize,
    /// Reflection points drawn mirrored back.
    pub reflections_mirrored: usize,
    /// Reflective planes drawn.
    pub planes: usize,
}

/// Draw the figure of `po` (the plane-optimized run of `sequence` with
/// `config`) into `path`.
pub fn draw(
    path: &Path,
    sequence: &Sequence,
    po: &PlaneOptimizedOutput,
    config: &Config,
) -> Result<CornerSummary> {
    let classes: Vec<Vec<Class>> = po.run.frames.iter().map(|f| f.classes.clone()).collect();
    let voxel = config.output.map_voxel;
    let trajectory: Vec<[f64; 2]> = sequence
        .poses
        .iter()
        .flatten()
        .map(|p| [p.translation.x, p.translation.y])
        .collect();
    let heights: Vec<f64> = sequence
        .poses
        .iter()
        .flatten()
        .map(|p| p.translation.z)
        .collect();
    let z0 = heights.iter().sum::<f64>() / heights.len().max(1) as f64;
    let in_slab = |p: &MapPoint| (f64::from(p.xyz[2]) - z0).abs() < SLAB;
    let before: Vec<MapPoint> = measured_map(sequence, &classes, voxel)?
        .into_iter()
        .filter(in_slab)
        .collect();
    let after: Vec<MapPoint> = around_corner_map(
        sequence,
        &classes,
        &po.planes,
        config.plane_map.hull_margin,
        voxel,
    )?
    .into_iter()
    .filter(in_slab)
    .collect();
    around_corner_png(path, &before, &after, &po.planes, &trajectory)?;
    let reflections = |m: &[MapPoint]| m.iter().filter(|p| p.class == Class::Reflection).count();
    Ok(CornerSummary {
        points: before.len() + after.len(),
        reflections_measured: reflections(&before),
        reflections_mirrored: reflections(&after),
        planes: po.planes.len(),
    })
}
