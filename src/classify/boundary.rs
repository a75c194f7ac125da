//! Which reflective plane a beam passes through, and where.
//!
//! Two boundary models: the convex hull of the plane's evidence in its chart
//! (the paper), or Zhao 2020's "glass window", a ring × column box of the
//! organized scan around the plane's inliers.

use nalgebra::{Point2, Point3, Vector3};

use crate::geometry::Plane;
use crate::reflect::BoundedPlane;
use crate::sensor::OrganizedScan;

/// A ring × column box of the organized scan; the column range may wrap
/// around the azimuth seam.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Window {
    /// Lowest ring inside.
    pub ring_lo: usize,
    /// Highest ring inside.
    pub ring_hi: usize,
    /// First column inside.
    pub col_start: usize,
    /// Number of columns inside, counted from `col_start` with wrap-around.
    pub col_len: usize,
}

impl Window {
    /// The smallest box holding every cell of `points` (indices into the
    /// scan's frame), grown by `ring_pad` rings; the column range is the
    /// shortest circular arc covering the points' columns. A window narrower
    /// than `min_cols` columns is widened to the full revolution (Zhao 2020:
    /// a narrow window is not trusted to bound the glass).
    pub fn around(
        scan: &OrganizedScan,
        points: &[u32],
        ring_pad: usize,
        min_cols: usize,
    ) -> Option<Self> {
        let cols = scan.columns();
        let mut used = vec![false; cols];
        let (mut lo, mut hi) = (usize::MAX, 0usize);
        for &i in points {
            let (r, c) = scan.ring_column(scan.cell_of(i as usize));
            used[c] = true;
            lo = lo.min(r);
            hi = hi.max(r);
        }
        if lo == usize::MAX {
            return None;
        }
        // The largest run of unused columns (circular) is outside the window.
        let (mut best_gap, mut best_end) = (0usize, 0usize);
        let mut run = 0usize;
        for k in 0..2 * cols {
            if used[k % cols] {
                run = 0;
            } else {
                run += 1;
                if run > best_gap && run <= cols {
                    best_gap = run;
                    best_end = k % cols;
                }
            }
        }
        let (col_start, col_len) = if best_gap == 0 {
            (0, cols)
        } else {
            ((best_end + 1) % cols, cols - best_gap)
        };
        let (col_start, col_len) = if col_len < min_cols {
            (0, cols)
        } else {
            (col_start, col_len)
        };
        Some(Self {
            ring_lo: lo.saturating_sub(ring_pad),
            ring_hi: (hi + ring_pad).min(scan.rings() - 1),
            col_start,
            col_len,
        })
    }

    /// Whether a (ring, column) cell is inside.
    #[inline]
    pub fn contains(&self, ring: usize, col: usize, columns: usize) -> bool {
        ring >= self.ring_lo
            && ring <= self.ring_hi
            && (col + columns - self.col_start) % columns < self.col_len
    }
}

/// The reflective planes of one frame with their boundary model, answering
/// "which plane does this beam cross first, and at what range".
#[derive(Debug, Clone)]
pub struct BeamPlanes<'a> {
    planes: &'a [BoundedPlane],
    /// Per plane, the chart box outside which its boundary says no.
    extents: Vec<(Point2<f64>, Point2<f64>)>,
    windows: Option<Vec<Window>>,
    margin: f64,
    reach: f64,
    /// How far beyond a plane's reflective extent its unseen continuation
    /// reaches (0: none), with the chart boxes that bound it.
    unseen_reach: f64,
    unseen_extents: Vec<(Point2<f64>, Point2<f64>)>,
}

impl<'a> BeamPlanes<'a> {
    /// Hull boundaries grown by `margin` metres.
    pub fn hulls(planes: &'a [BoundedPlane], margin: f64) -> Self {
        Self {
            planes,
            extents: planes.iter().map(|bp| bp.extent_2d(margin)).collect(),
            windows: None,
            margin,
            reach: f64::INFINITY,
            unseen_reach: 0.0,
            unseen_extents: Vec::new(),
        }
    }

    /// Window boundaries, one per plane.
    pub fn windows(planes: &'a [BoundedPlane], windows: Vec<Window>) -> Self {
        Self {
            planes,
            extents: Vec::new(),
            windows: Some(windows),
            margin: 0.0,
            reach: f64::INFINITY,
            unseen_reach: 0.0,
            unseen_extents: Vec::new(),
        }
    }

    /// Ignore crossings farther than `reach` beyond the point itself: for a
    /// point in front of every plane the answer is the same ("in front"),
    /// and the boundary test is skipped.
    pub fn with_reach(mut self, reach: f64) -> Self {
        self.reach = reach;
        self
    }

    /// Also answer [`BeamPlanes::first_unseen`]: crossings up to `reach`
    /// above a plane's reflective extent (along its chart's `v` axis, up a
    /// wall) and up to `beside` to either side of it and below it, where
    /// the plane may be glass that no echo showed
    /// ([`BoundedPlane::beyond_seen_extent_2d`]; hull boundaries only, 0:
    /// none). A sensor carried past a wall meets it near normal incidence
    /// only near its own height: a tall pane's top gives no echo, while
    /// beside a pane it met the plane head-on where it passed, and below it
    /// glass meets a floor or a parapet.
    pub fn with_unseen_extent(mut self, reach: f64, beside: f64) -> Self {
        if reach > 0.0 && self.windows.is_none() {
            let side = beside.max(0.0);
            self.unseen_reach = reach.max(side);
            self.unseen_extents = self
                .planes
                .iter()
                .map(|bp| {
                    let (lo, hi) = bp.extent_2d(self.margin.max(0.0));
                    (
                        Point2::new(lo.x - side, lo.y - side),
                        Point2::new(hi.x + side, hi.y + reach),
                    )
                })
                .collect();
        }
        self
    }

    /// The planes.
    pub fn planes(&self) -> &'a [BoundedPlane] {
        self.planes
    }

    /// The nearest plane crossed by the beam from the sensor origin towards
    /// `p` inside its boundary, not farther than the point plus the reach:
    /// `(plane index, range of the crossing)`.
    /// `cell` is the point's (ring, column) for window boundaries.
    pub fn first_hit(
        &self,
        p: &Point3<f64>,
        cell: Option<(usize, usize, usize)>,
    ) -> Option<(usize, f64)> {
        // A point more than `reach` in front of a plane that faces the sensor
        // cannot be on or behind it along its beam (|r - t| >= |s|): skip
        // such planes without a ray intersection.
        let relevant =
            |bp: &BoundedPlane| bp.plane.d <= 0.0 || bp.plane.signed_distance(p) <= self.reach;
        if !self.planes.iter().any(relevant) {
            return None;
        }
        let range = p.coords.norm();
        if !(range > 0.0) {
            return None;
        }
        let dir: Vector3<f64> = p.coords / range;
        let origin = Point3::origin();
        let mut best: Option<(usize, f64)> = None;
        for (k, bp) in self.planes.iter().enumerate() {
            if !relevant(bp) {
                continue;
            }
            let Some(t) = crossing_along(&bp.plane, &dir) else {
                continue;
            };
            if t > range + self.reach || best.is_some_and(|(_, bt)| bt <= t) {
                continue;
            }
            let inside = match (&self.windows, cell) {
                (Some(w), Some((ring, col, columns))) => w[k].contains(ring, col, columns),
                (Some(_), None) => false,
                (None, _) => {
                    let uv = bp.chart.to_2d(&(origin + dir * t));
                    let (lo, hi) = self.extents[k];
                    let boxed = uv.x >= lo.x && uv.x <= hi.x && uv.y >= lo.y && uv.y <= hi.y;
                    boxed && bp.bounds_2d(&uv, self.margin)
                }
            };
            if inside {
                best = Some((k, t));
            }
        }
        best
    }
}

impl BeamPlanes<'_> {
    /// The nearest plane the beam towards `p` crosses more than `behind`
    /// before reaching `p`, within the unseen continuation of its extent
    /// ([`BeamPlanes::with_unseen_extent`]): `(plane index, range of the
    /// crossing)`. For a beam that crosses no plane inside its extent: if
    /// this finds one, the point may lie behind glass nobody saw.
    pub fn first_unseen(&self, p: &Point3<f64>, behind: f64) -> Option<(usize, f64)> {
        if !(self.unseen_reach > 0.0) {
            return None;
        }
        let range = p.coords.norm();
        if !(range > 0.0) {
            return None;
        }
        let dir: Vector3<f64> = p.coords / range;
        let origin = Point3::origin();
        let mut best: Option<(usize, f64)> = None;
        for (k, bp) in self.planes.iter().enumerate() {
            // A point on the sensor's side of a plane that faces the sensor
            // is not behind it: no ray intersection needed.
            if bp.plane.d > 0.0 && bp.plane.signed_distance(p) >= 0.0 {
                continue;
            }
            let Some(t) = crossing_along(&bp.plane, &dir) else {
                continue;
            };
            if t >= range - behind || best.is_some_and(|(_, bt)| bt <= t) {
                continue;
            }
            let uv = bp.chart.to_2d(&(origin + dir * t));
            let (lo, hi) = self.unseen_extents[k];
            let boxed = uv.x >= lo.x && uv.x <= hi.x && uv.y >= lo.y && uv.y <= hi.y;
            if boxed && bp.beyond_seen_extent_2d(&uv, self.unseen_reach) {
                best = Some((k, t));
            }
        }
        best
    }

    /// Whether the beam towards `p`, which crosses plane `first` at range
    /// `t`, meets another pane between `glass` beyond that crossing and
    /// `behind` before `p`: past a second pane the first one's mirror says
    /// nothing about the point.
    pub fn second_pane(
        &self,
        p: &Point3<f64>,
        first: usize,
        t: f64,
        glass: f64,
        behind: f64,
    ) -> bool {
        self.crosses_between(p, first, t + glass, p.coords.norm() - behind)
    }

    /// Whether the beam towards `p` crosses a plane other than `skip` inside
    /// its boundary at a range strictly between `lo` and `hi`: a beam that
    /// passed one pane and met a second before its return (glass behind
    /// glass, glass then mirror).
    pub fn crosses_between(&self, p: &Point3<f64>, skip: usize, lo: f64, hi: f64) -> bool {
        self.crossings_between(p, skip, lo, hi).next().is_some()
    }

    /// The nearest plane other than `skip` that the beam towards `p` crosses
    /// inside its boundary strictly between ranges `lo` and `hi`, with the
    /// range of the crossing.
    pub fn nearest_between(
        &self,
        p: &Point3<f64>,
        skip: usize,
        lo: f64,
        hi: f64,
    ) -> Option<(usize, f64)> {
        self.crossings_between(p, skip, lo, hi)
            .min_by(|a, b| a.1.total_cmp(&b.1))
    }

    /// Every crossing of the beam towards `p` with a plane other than `skip`
    /// inside its boundary strictly between ranges `lo` and `hi`.
    fn crossings_between<'s>(
        &'s self,
        p: &Point3<f64>,
        skip: usize,
        lo: f64,
        hi: f64,
    ) -> impl Iterator<Item = (usize, f64)> + 's {
        let range = p.coords.norm();
        let valid = range > 0.0 && hi > lo;
        let dir: Vector3<f64> = if valid {
            p.coords / range
        } else {
            Vector3::zeros()
        };
        let origin = Point3::origin();
        self.planes
            .iter()
            .enumerate()
            .filter(move |(k, _)| valid && *k != skip)
            .filter_map(move |(k, bp)| {
                let t = crossing_along(&bp.plane, &dir)?;
                if !(t > lo && t < hi) {
                    return None;
                }
                let uv = bp.chart.to_2d(&(origin + dir * t));
                let (a, b) = self.extents.get(k).copied().unwrap_or((uv, uv));
                let boxed = uv.x >= a.x && uv.x <= b.x && uv.y >= a.y && uv.y <= b.y;
                (boxed && bp.bounds_2d(&uv, self.margin)).then_some((k, t))
            })
    }
}

/// Range at which the beam from the sensor origin through `p` crosses
/// `plane` (`None` when parallel or behind the sensor): the same arithmetic
/// as [`BeamPlanes::first_hit`], so the same value bit for bit.
#[inline]
pub fn beam_crossing(plane: &Plane, p: &Point3<f64>) -> Option<f64> {
    let range = p.coords.norm();
    if !(range > 0.0) {
        return None;
    }
    crossing_along(plane, &(p.coords / range))
}

/// Range along the unit direction `dir` from the origin to `plane`.
#[inline]
fn crossing_along(plane: &Plane, dir: &Vector3<f64>) -> Option<f64> {
    plane.ray_intersection(&Point3::origin(), dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_contains_wraps_around_the_seam() {
        let w = Window {
            ring_lo: 2,
            ring_hi: 4,
            col_start: 590,
            col_len: 20,
        };
        assert!(w.contains(3, 595, 600));
        assert!(w.contains(3, 5, 600));
        assert!(!w.contains(3, 20, 600));
        assert!(!w.contains(5, 0, 600));
    }

    /// A beam test kept as plane indices gives back the crossing range of
    /// `first_hit` bit for bit (the decision compares it with the point's
    /// range), on random points against two overlapping squares.
    #[test]
    fn beam_hits_give_back_first_hit_exactly() {
        use crate::classify::decide::BeamHits;
        use crate::cloud::{Frame, Point};
        use crate::sensor::{OrganizedScan, SensorModel};
        let square = |x: f64, tilt: f64| {
            let plane = Plane::new(Vector3::new(-1.0, tilt, 0.0).normalize(), x).unwrap();
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            BoundedPlane::from_points(
                plane,
                corners
                    .iter()
                    .map(|&(y, z)| plane.project(&Point3::new(x, y, z))),
            )
        };
        let planes = vec![square(2.0, 0.1), square(3.0, -0.2)];
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let mut rng = crate::rng::SplitMix64::new(11);
        let points: Vec<Point> = (0..2000)
            .map(|_| Point {
                xyz: [
                    (rng.unit() * 6.0 - 1.0) as f32,
                    (rng.unit() * 3.0 - 1.5) as f32,
                    (rng.unit() * 1.0 - 0.5) as f32,
                ],
                intensity: 10.0,
                ring: 0,
                ret: 1,
                label: 1,
                time: 0.0,
            })
            .collect();
        let frame = Frame {
            name: "random".into(),
            points,
            ..Frame::default()
        };
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let beams = BeamPlanes::hulls(&planes, 0.05);
        let hits = BeamHits::compute(&frame, &scan, &beams, 0.1);
        let reach = beams.clone().with_reach(0.1);
        let mut crossed = 0;
        for (i, pt) in frame.points.iter().enumerate() {
            let p = pt.position();
            let expected = reach.first_hit(&p, None);
            let got = hits.get(i, &p, &planes).map(|h| (h.plane, h.range));
            assert_eq!(
                got.map(|(k, t)| (k, t.to_bits())),
                expected.map(|(k, t)| (k, t.to_bits()))
            );
            crossed += expected.is_some() as usize;
        }
        assert!(crossed > 100, "too few beams cross a plane: {crossed}");
    }
}
