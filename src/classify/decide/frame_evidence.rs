//! Evidence from the frame itself: its returns along the beam towards a
//! mirrored point, and its own Normal points as mirror support.

use nalgebra::Point3;

use super::SurfaceSupport;
use crate::classify::Class;
use crate::cloud::Frame;
use crate::sensor::{OrganizedScan, SensorModel};

/// Along the beams towards `q` (sensor frame): the range of the return
/// nearest to `q`'s range, and the smallest "farthest return" over the cells
/// within `neighbourhood` rings and columns of `q`'s cell (free space at `q`
/// is proven only if every one of them passes it). `None` when `q` is outside
/// the field of view or its own cell is empty.
pub(crate) fn returns_along(
    scan: &OrganizedScan,
    sensor: &SensorModel,
    frame: &Frame,
    q: &Point3<f64>,
    neighbourhood: usize,
) -> Option<(f64, f64)> {
    let ring = sensor.ring_of(q)?;
    let col = sensor.column_of(q.x, q.y) as isize;
    scan.first(scan.cell(ring, col))?;
    let rq = q.coords.norm();
    let k = neighbourhood as isize;
    let (mut closest, mut min_far) = (f64::INFINITY, f64::INFINITY);
    for r in ring as isize - k..=ring as isize + k {
        if r < 0 || r as usize >= scan.rings() {
            continue;
        }
        for c in col - k..=col + k {
            let cell = scan.cell(r as usize, c);
            let Some(first) = scan.first(cell) else {
                continue;
            };
            let r1 = frame.points[first].range();
            let r2 = scan.second(cell).map_or(r1, |j| frame.points[j].range());
            for x in [r1, r2] {
                if (x - rq).abs() < (closest - rq).abs() {
                    closest = x;
                }
            }
            min_far = min_far.min(r1.max(r2));
        }
    }
    Some((closest, min_far))
}

/// A k-d tree of a frame's Normal points (sensor frame).
pub(super) struct NormalPointIndex {
    tree: Option<kiddo::ImmutableKdTree<f64, 3>>,
}

impl NormalPointIndex {
    pub(super) fn new(frame: &Frame, classes: &[Class]) -> Self {
        let pts: Vec<[f64; 3]> = frame
            .points
            .iter()
            .zip(classes)
            .filter(|(_, c)| **c == Class::Normal)
            .map(|(p, _)| [p.xyz[0] as f64, p.xyz[1] as f64, p.xyz[2] as f64])
            .collect();
        let tree = if pts.is_empty() {
            None
        } else {
            kiddo::ImmutableKdTree::new_from_slice(&pts).ok()
        };
        Self { tree }
    }
}

impl SurfaceSupport for NormalPointIndex {
    fn near(&self, p: &Point3<f64>, radius: f64) -> bool {
        let Some(tree) = &self.tree else {
            return false;
        };
        let nn = tree
            .query(&[p.x, p.y, p.z])
            .nearest_one::<kiddo::SquaredEuclidean<f64>>()
            .execute();
        nn.distance <= radius * radius
    }
}
