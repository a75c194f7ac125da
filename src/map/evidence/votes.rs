//! One frame's votes for one landmark: beams that cross the plane and
//! return from behind it, surface echoes with a return behind them, and
//! single echoes on the plane, whose weighing needs the whole sequence (the
//! landmark's glass echo intensity), kept as exact intensity counts.

use std::collections::BTreeMap;

use nalgebra::{Point2, Point3, Vector3};

use super::{EvidenceFrame, EvidenceParams};
use crate::geometry::fit::PlaneSums;
use crate::geometry::grid::{incidence_bin, strength_on_plane, EvidenceGrid, INCIDENCE_BINS};
use crate::map::direct::passed_another;
use crate::reflect::BoundedPlane;

/// Votes of one frame that need the whole sequence to be weighed.
#[derive(Debug, Default)]
pub(super) struct Votes {
    /// Intensities of surface echoes with a return behind the plane.
    pub(super) glass_echo_intensity: Vec<f32>,
    /// The same echoes' incidence bins and strengths, with the strength
    /// of the return behind each ([`EchoAtIncidence`]).
    pub(super) glass_echo_strength: Vec<(u8, f32, f32)>,
    /// Single echoes on the plane: chart position, intensity, incidence bin
    /// and strength.
    pub(super) single_echoes: Vec<(Point2<f64>, f32, u8, f32)>,
    /// The range exponent of the strengths (the frame's).
    pub(super) range_exponent: f64,
}

/// A multiset of intensities, counted per distinct value: its median is
/// exact, and its size is the number of distinct values, not of echoes.
#[derive(Debug, Clone, Default)]
pub(super) struct IntensityCounts {
    /// Count per value, keyed in `f32::total_cmp` order.
    counts: BTreeMap<i32, u64>,
    len: u64,
}

/// Glass echo strengths per incidence bin ([`incidence_bin`]), exact
/// counts like [`IntensityCounts`].
pub(super) type EchoAtIncidence = [IntensityCounts; INCIDENCE_BINS];

impl IntensityCounts {
    pub(super) fn add(&mut self, x: f32) {
        *self.counts.entry(total_order_key(x)).or_insert(0) += 1;
        self.len += 1;
    }

    /// The value at position `len / 2` in sorted order (the upper median
    /// for an even count), `None` when empty.
    pub(super) fn median(&self) -> Option<f64> {
        self.quantile(0.5)
    }

    /// The value at position `floor(len · q)` in sorted order (`q` in
    /// [0, 1)), `None` when empty.
    pub(super) fn quantile(&self, q: f64) -> Option<f64> {
        let at = ((self.len as f64 * q).floor() as u64).min(self.len.saturating_sub(1));
        let mut seen = 0;
        for (&key, &n) in &self.counts {
            seen += n;
            if seen > at {
                return Some(from_total_order_key(key) as f64);
            }
        }
        None
    }

    /// Number of values.
    pub(super) fn len(&self) -> u64 {
        self.len
    }
}

/// A key whose integer order is `f32::total_cmp`'s order.
fn total_order_key(x: f32) -> i32 {
    let bits = x.to_bits() as i32;
    bits ^ (((bits >> 31) as u32) >> 1) as i32
}

/// The inverse of [`total_order_key`].
fn from_total_order_key(key: i32) -> f32 {
    f32::from_bits((key ^ (((key >> 31) as u32) >> 1) as i32) as u32)
}

/// Where the beam of one point meets the landmark's plane.
struct Crossing {
    /// The point (sensor frame), its beam direction and signed distance
    /// from the plane.
    x: Point3<f64>,
    dir: Vector3<f64>,
    sd: f64,
    /// Range of the crossing, its chart position, and the point's range
    /// beyond it (negative in front).
    t: f64,
    uv: Point2<f64>,
    s: f64,
}

/// The tests every pass over a frame applies to the points near one
/// landmark (`plane` in the frame's sensor frame, `others` too).
struct PlaneTests<'a> {
    plane: &'a BoundedPlane,
    others: &'a [BoundedPlane],
    f: &'a EvidenceFrame<'a>,
    p: &'a EvidenceParams,
    echo_normal_cos: Option<f64>,
}

impl<'a> PlaneTests<'a> {
    fn new(
        plane: &'a BoundedPlane,
        others: &'a [BoundedPlane],
        f: &'a EvidenceFrame<'a>,
        p: &'a EvidenceParams,
    ) -> Self {
        let echo_normal_cos =
            (p.echo_normal_max_deg > 0.0).then(|| p.echo_normal_max_deg.to_radians().cos());
        Self {
            plane,
            others,
            f,
            p,
            echo_normal_cos,
        }
    }

    /// Where point `x`'s beam meets the plane inside `grid`, when it can
    /// vote: not a point farther than the surface band in front of the
    /// plane (one dot product tells, since |r - t| >= |n·x + d|; the 1e-9
    /// covers round-off), and, with `direct_only`, a beam that met no other
    /// landmark first.
    #[inline]
    fn crossing(&self, x: Point3<f64>, grid: &EvidenceGrid) -> Option<Crossing> {
        let (plane, p) = (self.plane, self.p);
        let sd = plane.plane.signed_distance(&x);
        if p.behind >= 0.0 && sd * plane.plane.d > 0.0 && sd.abs() > p.surface_band + 1e-9 {
            return None;
        }
        let r = x.coords.norm();
        if !(r > 0.0) {
            return None;
        }
        let dir = x.coords / r;
        let t = plane.plane.ray_intersection(&Point3::origin(), &dir)?;
        let uv = plane.chart.to_2d(&Point3::from(dir * t));
        if grid.index(&uv).is_none()
            || (p.direct_only && passed_another(self.others, &dir, t, p.surface_band))
        {
            return None;
        }
        Some(Crossing {
            x,
            dir,
            sd,
            t,
            uv,
            s: r - t,
        })
    }

    /// Whether point `i`, on the plane (`c`), with the other return `j` of
    /// its beam, is a glass echo: a surface echo with that return behind
    /// the plane, on a surface that lies along the plane (not one crossing
    /// it), and not the echo of another landmark its beam meets nearer
    /// normal incidence.
    #[inline]
    fn is_glass_echo(&self, i: usize, j: usize, c: &Crossing) -> bool {
        self.f.frame.points[j].range() - c.t > self.p.behind
            && !self.crosses(i)
            && !self.owned_by_other(&c.x, &c.dir)
    }

    /// Whether the surface around point `i` crosses the plane rather than
    /// lying on it (unknown surfaces do not).
    fn crosses(&self, i: usize) -> bool {
        self.echo_normal_cos.is_some_and(|cos| {
            self.f
                .scan
                .faces(self.f.frame, i, &self.plane.plane.normal, cos)
                == Some(false)
        })
    }

    /// Whether the echo at `x` (beam `dir`) lies on another landmark that
    /// its beam meets nearer normal incidence.
    fn owned_by_other(&self, x: &Point3<f64>, dir: &Vector3<f64>) -> bool {
        let here = self.plane.plane.normal.dot(dir).abs();
        self.p.echo_owner_test
            && self.others.iter().any(|o| {
                o.plane.signed_distance(x).abs() <= self.p.surface_band
                    && o.plane.normal.dot(dir).abs() > here
                    && o.bounds_2d(&o.chart.to_2d(x), 0.0)
            })
    }
}

/// Add one frame's transparent votes and collect its echoes on the plane;
/// `plane` is the landmark in the frame's sensor frame (same chart
/// coordinates as the grid).
pub(super) fn vote_frame(
    grid: &mut EvidenceGrid,
    plane: &BoundedPlane,
    others: &[BoundedPlane],
    f: &EvidenceFrame<'_>,
    p: &EvidenceParams,
) -> Votes {
    let tests = PlaneTests::new(plane, others, f, p);
    let cos_peak = p.peak_angle_deg.to_radians().cos();
    let bare_cos = (p.bare_pass_max_deg > 0.0).then(|| p.bare_pass_max_deg.to_radians().cos());
    let mut votes = Votes {
        range_exponent: f.range_exponent,
        ..Votes::default()
    };
    for (i, pt) in f.frame.points.iter().enumerate() {
        let Some(c) = tests.crossing(pt.position(), grid) else {
            continue;
        };
        if c.s > p.behind {
            // A beam through the plane: glass, or open space where the plane
            // has no surface at all. Only near the landmark's own boundary
            // (where dual returns found the surface) does it count.
            if plane.boundary.signed_distance(&c.uv) <= p.pass_margin {
                grid.vote(&c.uv, 1, 0);
            } else {
                grid.vote_open(&c.uv);
            }
            // Near normal incidence without an echo from the plane: bare.
            if bare_cos.is_some_and(|cos| plane.plane.normal.dot(&c.dir).abs() >= cos) {
                let echoed = f
                    .scan
                    .partner(i)
                    .is_some_and(|j| (f.frame.points[j].range() - c.t).abs() <= p.surface_band);
                if !echoed {
                    grid.vote_bare(&c.uv);
                }
            }
        } else if c.s.abs() <= p.surface_band {
            match f.scan.partner(i) {
                // The beam ended on the plane.
                None => {
                    let cos = plane.plane.normal.dot(&c.dir);
                    if cos.abs() < cos_peak {
                        votes.single_echoes.push((
                            c.uv,
                            pt.intensity,
                            incidence_bin(cos),
                            strength_on_plane(pt.intensity, c.t, f.range_exponent) as f32,
                        ));
                    }
                }
                Some(j) => {
                    if tests.is_glass_echo(i, j, &c) {
                        grid.vote_echo(&c.uv);
                        votes.glass_echo_intensity.push(pt.intensity);
                        let behind = &f.frame.points[j];
                        votes.glass_echo_strength.push((
                            incidence_bin(plane.plane.normal.dot(&c.dir)),
                            strength_on_plane(pt.intensity, c.t, f.range_exponent) as f32,
                            strength_on_plane(behind.intensity, behind.range(), f.range_exponent)
                                as f32,
                        ));
                    }
                }
            }
        }
    }
    votes
}

/// Add one frame's glass echoes of the landmark to `sums` (world frame),
/// Cauchy-weighted by their distance from the plane, for its refit
/// ([`EvidenceParams::refit_plane`]): the echoes [`vote_frame`] counts as
/// glass, found among the points with a second return only. Only glass
/// echoes sample the pane itself: single echoes within the band are also
/// the floor meeting the wall, sills, mullions and the wall strips between
/// panes, which pull the plane off the glass.
pub(super) fn sum_glass_echoes(
    extent: &EvidenceGrid,
    plane: &BoundedPlane,
    others: &[BoundedPlane],
    f: &EvidenceFrame<'_>,
    p: &EvidenceParams,
    sums: &mut PlaneSums,
) {
    let tests = PlaneTests::new(plane, others, f, p);
    for (i, pt) in f.frame.points.iter().enumerate() {
        let Some(j) = f.scan.partner(i) else {
            continue;
        };
        let Some(c) = tests.crossing(pt.position(), extent) else {
            continue;
        };
        if c.s.abs() <= p.surface_band && tests.is_glass_echo(i, j, &c) {
            let z = 2.0 * c.sd / p.surface_band;
            sums.add(&(f.pose * c.x), 1.0 / (1.0 + z * z));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The median of the whole multiset, as the in-memory gathering took it.
    fn median_of_all(v: &mut [f32]) -> Option<f64> {
        if v.is_empty() {
            return None;
        }
        let mid = v.len() / 2;
        v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
        Some(v[mid] as f64)
    }

    proptest! {
        /// Counting intensities per distinct value gives exactly the median
        /// of all of them, for whole-number and fractional intensities.
        #[test]
        fn counted_median_is_the_median_of_all(
            whole in proptest::collection::vec(0u8..=255, 0..300),
            fractional in proptest::collection::vec(-5.0f32..300.0, 0..50),
        ) {
            let mut all: Vec<f32> = whole.iter().map(|&x| x as f32).collect();
            all.extend(&fractional);
            let mut counts = IntensityCounts::default();
            for &x in &all {
                counts.add(x);
            }
            prop_assert_eq!(counts.median(), median_of_all(&mut all));
        }

        /// A counted quantile is the value at its position among all of
        /// them, sorted.
        #[test]
        fn counted_quantile_is_the_quantile_of_all(
            all in proptest::collection::vec(-5.0f32..300.0, 1..200),
            q in 0.0f64..1.0,
        ) {
            let mut counts = IntensityCounts::default();
            for &x in &all {
                counts.add(x);
            }
            let mut sorted = all.clone();
            sorted.sort_by(|a, b| a.total_cmp(b));
            let at = ((all.len() as f64 * q).floor() as usize).min(all.len() - 1);
            prop_assert_eq!(counts.quantile(q), Some(sorted[at] as f64));
            prop_assert_eq!(counts.len(), all.len() as u64);
        }

        /// The order key sorts like `f32::total_cmp` and round-trips.
        #[test]
        fn order_key_sorts_like_total_cmp(a in any::<f32>(), b in any::<f32>()) {
            prop_assert_eq!(total_order_key(a).cmp(&total_order_key(b)), a.total_cmp(&b));
            prop_assert_eq!(from_total_order_key(total_order_key(a)).to_bits(), a.to_bits());
        }
    }
}
