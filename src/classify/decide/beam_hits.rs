//! The beam test of a frame: for every point, the first reflective plane
//! its beam crosses inside the plane's extent (or its unseen
//! continuation), kept in four bytes a point.

use nalgebra::Point3;

use crate::classify::boundary::{beam_crossing, BeamPlanes};
use crate::cloud::Frame;
use crate::reflect::BoundedPlane;
use crate::sensor::OrganizedScan;

/// Where a point's beam first crosses a reflective plane inside its
/// boundary: the plane's index and the range of the crossing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamHit {
    /// Index of the plane.
    pub plane: usize,
    /// Range from the sensor at which the beam crosses it, m.
    pub range: f64,
}

/// The beam test of one frame (step 1 of [`decide`](super::decide)): for every point, the
/// first plane its beam crosses inside its boundary. Computed once, it
/// serves both the decision and whatever else needs the same test (the
/// sequence's surface support). Four bytes a point: the crossing range is
/// recomputed on demand, with the same arithmetic, so it is bit-identical.
#[derive(Debug, Clone, Default)]
pub struct BeamHits {
    /// Plane index per point, `NO_PLANE` where the beam crosses none.
    first: Vec<u32>,
}

const NO_PLANE: u32 = u32::MAX;
/// Flag on a plane index: the beam crosses the plane's unseen continuation
/// ([`BeamPlanes::first_unseen`]), not its reflective extent.
const UNSEEN: u32 = 1 << 31;

impl BeamHits {
    /// The first crossings of `planes` up to `reach` beyond each point of
    /// `frame` ([`BeamPlanes::first_hit`]).
    pub fn compute(
        frame: &Frame,
        scan: &OrganizedScan,
        planes: &BeamPlanes<'_>,
        reach: f64,
    ) -> Self {
        let columns = scan.columns();
        let planes = planes.clone().with_reach(reach);
        let first = frame
            .points
            .iter()
            .enumerate()
            .map(|(i, pt)| {
                let (ring, col) = scan.ring_column(scan.cell_of(i));
                let p = pt.position();
                match planes.first_hit(&p, Some((ring, col, columns))) {
                    Some((k, _)) => k as u32,
                    None => planes
                        .first_unseen(&p, reach)
                        .map_or(NO_PLANE, |(k, _)| k as u32 | UNSEEN),
                }
            })
            .collect();
        Self { first }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.first.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.first.is_empty()
    }

    /// The crossing of point `i` (at `p`, sensor frame) with `planes`, the
    /// planes the test ran against.
    #[inline]
    pub fn get(&self, i: usize, p: &Point3<f64>, planes: &[BoundedPlane]) -> Option<BeamHit> {
        let k = *self.first.get(i)?;
        if k == NO_PLANE || k & UNSEEN != 0 {
            return None;
        }
        let plane = k as usize;
        let range = beam_crossing(&planes.get(plane)?.plane, p)?;
        Some(BeamHit { plane, range })
    }

    /// For a point whose beam crosses no plane inside its extent: the plane
    /// whose unseen continuation it crossed on its way, if the beam test
    /// looked for one ([`BeamPlanes::with_unseen_extent`]). The point may
    /// lie behind glass that gave no echo.
    #[inline]
    pub fn unseen(&self, i: usize, p: &Point3<f64>, planes: &[BoundedPlane]) -> Option<BeamHit> {
        let k = *self.first.get(i)?;
        if k == NO_PLANE || k & UNSEEN == 0 {
            return None;
        }
        let plane = (k & !UNSEEN) as usize;
        let range = beam_crossing(&planes.get(plane)?.plane, p)?;
        Some(BeamHit { plane, range })
    }
}
