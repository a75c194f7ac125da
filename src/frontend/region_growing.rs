//! Region growing on the organized grid (PCL's `RegionGrowing`, with grid
//! neighbours instead of a k-nearest search).
//!
//! Cells are visited as seeds from the flattest (smallest surface
//! variation) up. A segment grows from its seed to every grid neighbour
//! whose point is close (the normal estimation's gap, and within
//! `max_plane_distance` of the current cell's tangent plane) and whose
//! normal is within `max_angle_deg` of the current cell's. Like PCL, a
//! neighbour with a high surface variation (an edge or corner) joins the
//! segment but does not grow it further, so segments stop at creases.

use serde::{Deserialize, Serialize};

use super::filter::CellCloud;
use super::normals::{NormalParams, OrganizedNormals};

/// Region-growing thresholds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionParams {
    /// Largest angle between neighbouring normals, degrees.
    pub max_angle_deg: f64,
    /// Largest distance of a neighbour from the current cell's tangent
    /// plane, m.
    pub max_plane_distance: f64,
    /// Cells with a larger surface variation join but do not grow a
    /// segment (the smallest eigenvalue's share of the neighbourhood's
    /// covariance, dimensionless).
    pub max_curvature: f64,
    /// Segments with fewer cells are dropped.
    pub min_segment: usize,
}

impl Default for RegionParams {
    /// `[extractor.region]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("extractor.region")
    }
}

/// Number of buckets of the curvature ordering of seeds.
const BUCKETS: usize = 256;

/// Segments of the valid cells not `excluded`, largest first (ties: the
/// segment found first). Each segment lists its cells. Deterministic.
pub fn grow_regions(
    cells: &CellCloud,
    normals: &OrganizedNormals,
    excluded: &[bool],
    gap: &NormalParams,
    params: &RegionParams,
) -> Vec<Vec<usize>> {
    let n = cells.cells();
    let usable = |c: usize| normals.is_valid(c) && !excluded.get(c).copied().unwrap_or(false);
    // Seeds from the flattest up: a counting sort on the surface variation
    // (in [0, 1/3]); within a bucket, cell order.
    let mut counts = [0usize; BUCKETS + 1];
    let bucket =
        |c: usize| ((normals.curvature[c] * 3.0 * BUCKETS as f32) as usize).min(BUCKETS - 1);
    for c in (0..n).filter(|&c| usable(c)) {
        counts[bucket(c) + 1] += 1;
    }
    for b in 0..BUCKETS {
        counts[b + 1] += counts[b];
    }
    let mut order = vec![0usize; counts[BUCKETS]];
    for c in (0..n).filter(|&c| usable(c)) {
        let b = bucket(c);
        order[counts[b]] = c;
        counts[b] += 1;
    }

    let cos_max = params.max_angle_deg.to_radians().cos() as f32;
    let max_dist = params.max_plane_distance as f32;
    let max_curv = params.max_curvature as f32;
    let mut label = vec![u32::MAX; n];
    // Members of the kept segments, back to back; small segments are
    // truncated away as soon as they stop growing (no allocation per
    // segment).
    let mut members: Vec<usize> = Vec::new();
    let mut ranges: Vec<(usize, usize)> = Vec::new();
    let mut stack: Vec<usize> = Vec::new();
    let mut next_id = 0u32;
    let min_segment = params.min_segment.max(1);
    for &seed in &order {
        if label[seed] != u32::MAX {
            continue;
        }
        let id = next_id;
        next_id += 1;
        let start = members.len();
        members.push(seed);
        label[seed] = id;
        stack.clear();
        stack.push(seed);
        while let Some(cur) = stack.pop() {
            let p = cells.xyz(cur);
            let nc = normals.normals[cur];
            let g = gap.gap(cells.range(cur));
            let g2 = g * g;
            cells.for_each_neighbour(cur, |nb| {
                if label[nb] != u32::MAX || !usable(nb) {
                    return;
                }
                let q = cells.xyz(nb);
                let r = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                if r[0] * r[0] + r[1] * r[1] + r[2] * r[2] > g2 {
                    return;
                }
                if (nc[0] * r[0] + nc[1] * r[1] + nc[2] * r[2]).abs() > max_dist {
                    return;
                }
                let nn = normals.normals[nb];
                if nc[0] * nn[0] + nc[1] * nn[1] + nc[2] * nn[2] < cos_max {
                    return;
                }
                label[nb] = id;
                members.push(nb);
                if normals.curvature[nb] <= max_curv {
                    stack.push(nb);
                }
            });
        }
        if members.len() - start >= min_segment {
            ranges.push((start, members.len()));
        } else {
            members.truncate(start);
        }
    }
    // Stable: equal sizes keep their discovery order.
    ranges.sort_by_key(|r| std::cmp::Reverse(r.1 - r.0));
    ranges
        .into_iter()
        .map(|(s, e)| members[s..e].to_vec())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::filter::CellCloud;
    use crate::frontend::testing::{cast, Rect};
    use crate::sensor::{OrganizedScan, SensorModel};
    use nalgebra::Point3;

    #[test]
    fn two_perpendicular_walls_are_two_segments() {
        // Walls x = 3 and y = 3 meeting in a corner at (3, 3).
        let frame = cast(
            &[
                Rect::between(Point3::new(3.0, -4.0, -1.0), Point3::new(3.0, 3.0, 2.0)),
                Rect::between(Point3::new(-4.0, 3.0, -1.0), Point3::new(3.0, 3.0, 2.0)),
            ],
            0.005,
        );
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let cells = CellCloud::build(&frame, &scan, &vec![false; frame.points.len()]);
        let mut normals = OrganizedNormals::default();
        let gap = NormalParams::default();
        normals.estimate(&cells, &gap);
        let excluded = vec![false; cells.cells()];
        let segments = grow_regions(&cells, &normals, &excluded, &gap, &RegionParams::default());
        assert_eq!(
            segments.len(),
            2,
            "{:?}",
            segments.iter().map(Vec::len).collect::<Vec<_>>()
        );
        for s in &segments {
            // Each segment lies on one wall: all x ≈ 3 or all y ≈ 3.
            let on_x = s
                .iter()
                .filter(|&&c| (cells.xyz(c)[0] - 3.0).abs() < 0.05)
                .count();
            let on_y = s
                .iter()
                .filter(|&&c| (cells.xyz(c)[1] - 3.0).abs() < 0.05)
                .count();
            assert!(
                on_x.max(on_y) as f64 >= 0.98 * s.len() as f64,
                "{on_x} {on_y} {}",
                s.len()
            );
        }
    }
}
