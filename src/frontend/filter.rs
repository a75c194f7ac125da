//! The filtered organized cloud: what is left for plane extraction once the
//! reflections are out.
//!
//! The paper extracts ordinary planes "from filtered point clouds": the
//! candidate points of the reflective detector (beams whose returns
//! disagree) and the points measured *through* a detected reflective plane
//! (reflections and obstacles behind glass) are removed first. What remains
//! is kept on the sensor's ring × column grid, one point per cell (the first
//! return, or the last where the first was removed), so that neighbourhoods
//! are grid lookups.

use nalgebra::Point3;

use crate::cloud::Frame;
use crate::reflect::Detection;
use crate::sensor::OrganizedScan;

/// Marker for an empty cell.
const NONE: u32 = u32::MAX;

/// Which points of `frame` reflections touched: the detection's candidates
/// and every point more than `behind_margin` metres behind a detected
/// reflective plane whose beam crosses the plane inside its boundary.
/// `true` = removed.
pub fn reflection_mask(frame: &Frame, detection: &Detection, behind_margin: f64) -> Vec<bool> {
    let mut removed = vec![false; frame.points.len()];
    for &i in &detection.candidates {
        if let Some(r) = removed.get_mut(i as usize) {
            *r = true;
        }
    }
    if detection.planes.is_empty() {
        return removed;
    }
    for (i, p) in frame.points.iter().enumerate() {
        if removed[i] {
            continue;
        }
        let p = p.position();
        for rp in &detection.planes {
            let b = &rp.bounded;
            let s = b.plane.signed_distance(&p);
            if s >= -behind_margin {
                continue;
            }
            // The beam from the origin crosses the plane at λ p, λ ∈ (0, 1):
            // s(λ p) = λ n·p + d = 0 with d > 0 > n·p.
            let np = b.plane.normal.dot(&p.coords);
            if !(np < 0.0) {
                continue;
            }
            let q = Point3::from(p.coords * (-b.plane.d / np));
            if b.bounds(&q, 0.0) {
                removed[i] = true;
                break;
            }
        }
    }
    removed
}

/// At most one kept point per (ring, column) cell, with its position and
/// range stored per cell for cache-friendly neighbourhood scans.
#[derive(Debug, Clone)]
pub struct CellCloud {
    rings: usize,
    columns: usize,
    index: Vec<u32>,
    xyz: Vec<[f32; 3]>,
    range: Vec<f32>,
    kept: usize,
}

impl CellCloud {
    /// The cells of `scan` with the points `removed` does not flag: the
    /// first return of a cell, or its last return where the first is
    /// removed. `removed` is indexed by point (see [`reflection_mask`]).
    pub fn build(frame: &Frame, scan: &OrganizedScan, removed: &[bool]) -> Self {
        let cells = scan.rings() * scan.columns();
        let mut index = vec![NONE; cells];
        let mut xyz = vec![[f32::NAN; 3]; cells];
        let mut range = vec![f32::NAN; cells];
        let mut kept = 0;
        let is_kept = |i: usize| !removed.get(i).copied().unwrap_or(true);
        for cell in 0..cells {
            let pick = scan
                .first(cell)
                .filter(|&i| is_kept(i))
                .or_else(|| scan.second(cell).filter(|&i| is_kept(i)));
            if let Some(i) = pick {
                let p = frame.points[i].xyz;
                index[cell] = i as u32;
                xyz[cell] = p;
                range[cell] = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
                kept += 1;
            }
        }
        Self {
            rings: scan.rings(),
            columns: scan.columns(),
            index,
            xyz,
            range,
            kept,
        }
    }

    /// Number of rings (rows).
    #[inline]
    pub fn rings(&self) -> usize {
        self.rings
    }

    /// Number of columns.
    #[inline]
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Number of cells (`rings × columns`).
    #[inline]
    pub fn cells(&self) -> usize {
        self.index.len()
    }

    /// Cells holding a kept point.
    #[inline]
    pub fn kept(&self) -> usize {
        self.kept
    }

    /// The frame's point index kept in `cell`.
    #[inline]
    pub fn point(&self, cell: usize) -> Option<u32> {
        let i = self.index[cell];
        (i != NONE).then_some(i)
    }

    /// Position of the kept point of `cell` (NaN when empty).
    #[inline]
    pub fn xyz(&self, cell: usize) -> [f32; 3] {
        self.xyz[cell]
    }

    /// Range of the kept point of `cell` (NaN when empty).
    #[inline]
    pub fn range(&self, cell: usize) -> f32 {
        self.range[cell]
    }

    /// Position of the kept point of `cell` as `f64`.
    #[inline]
    pub fn position(&self, cell: usize) -> Point3<f64> {
        let p = self.xyz[cell];
        Point3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    }

    /// Call `f` with each of the up to 8 grid neighbours of `cell` (ring
    /// ± 1, column ± 1, the column wrapping at the seam), empty cells
    /// included, row by row.
    #[inline]
    pub fn for_each_neighbour(&self, cell: usize, mut f: impl FnMut(usize)) {
        let cols = self.columns;
        let (r, c) = (cell / cols, cell % cols);
        let left = if c == 0 { cols - 1 } else { c - 1 };
        let right = if c + 1 == cols { 0 } else { c + 1 };
        let row = r * cols;
        if r > 0 {
            let up = row - cols;
            f(up + left);
            f(up + c);
            f(up + right);
        }
        f(row + left);
        f(row + right);
        if r + 1 < self.rings {
            let down = row + cols;
            f(down + left);
            f(down + c);
            f(down + right);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;
    use crate::reflect::{BoundedPlane, ReflectivePlane};
    use crate::sensor::SensorModel;
    use nalgebra::Vector3;

    use crate::cloud::test_point as point;

    #[test]
    fn candidates_and_points_behind_a_detected_pane_are_removed() {
        // A pane x = 2 (facing the origin), 1 m wide around y = 0.
        let plane = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 2.0).unwrap();
        let corners = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)];
        let bounded =
            BoundedPlane::from_points(plane, corners.iter().map(|&(y, z)| Point3::new(2.0, y, z)));
        let frame = Frame {
            name: "t".into(),
            points: vec![
                point(2.0, 0.0, 0.0, 32, 1), // candidate (on the glass)
                point(5.0, 0.0, 0.1, 32, 2), // behind the pane, through it
                point(5.0, 4.0, 0.0, 30, 1), // behind the plane, beside the pane
                point(1.0, 0.0, 0.0, 20, 1), // in front
            ],
            ..Default::default()
        };
        let detection = Detection {
            candidates: vec![0],
            planes: vec![ReflectivePlane {
                bounded,
                inliers: vec![0],
            }],
        };
        let removed = reflection_mask(&frame, &detection, 0.1);
        assert_eq!(removed, vec![true, true, false, false]);
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let cells = CellCloud::build(&frame, &scan, &removed);
        assert_eq!(cells.kept(), 2);
        let c = scan.cell_of(2);
        assert_eq!(cells.point(c), Some(2));
        assert!((cells.range(c) - 41f32.sqrt()).abs() < 1e-5);
        // Both returns of cell 0 removed: the cell is empty.
        assert_eq!(cells.point(scan.cell_of(0)), None);
    }

    #[test]
    fn neighbours_wrap_around_the_seam_and_stop_at_the_last_ring() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = Frame {
            points: vec![point(1.0, 0.0, 0.0, 0, 1)],
            ..Default::default()
        };
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let cells = CellCloud::build(&frame, &scan, &[false]);
        let mut got = Vec::new();
        cells.for_each_neighbour(0, |c| got.push(c)); // ring 0, column 0
        assert_eq!(got, vec![599, 1, 600 + 599, 600, 601]);
    }
}
