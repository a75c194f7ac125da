//! Transparency evidence of a plane landmark, gathered over all frames.
//!
//! A reflective plane is an infinite plane; the paper bounds it by the convex
//! hull of its candidate points, so wall on the same plane is called glass
//! and glass beyond the candidates is missed. The scans say more: where a
//! beam crosses the plane and returns from *behind* it, or where a surface
//! echo on the plane has a second return behind it, the plane is transparent
//! or reflective there (a beam through the plane counts only near the
//! landmark's hull, since beyond it the "plane" may be open space); where a
//! beam ends *on* the plane with a single
//! return as bright as an ordinary surface, it is opaque, and a single weak
//! echo like the plane's glass echoes is glass with nothing behind it in
//! range. "Bright" is relative to the landmark's own glass echoes (the
//! median intensity of its surface echoes that have a return behind them),
//! so no sensor-specific intensity scale is assumed. Echoes near normal
//! incidence are not used: glass peaks there like a wall. Votes are counted
//! on a grid in the landmark's chart.

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Point2, Point3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::direct::passed_another;
use crate::cloud::Frame;
use crate::geometry::grid::EvidenceGrid;
use crate::reflect::BoundedPlane;
use crate::sensor::OrganizedScan;

/// Settings of the evidence grid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvidenceParams {
    /// Cell edge length, m.
    pub cell: f64,
    /// The grid covers the landmark's hull grown by this much, m.
    pub margin: f64,
    /// Votes (cell and neighbours) needed to decide a cell.
    pub min_votes: u32,
    /// A return within this range of the crossing is on the plane, m.
    pub surface_band: f64,
    /// A return this far beyond the crossing is behind the plane, m.
    pub behind: f64,
    /// Beams passing the plane vote "transparent" only within this distance
    /// of the landmark's hull (beyond it they may cross open space); surface
    /// echoes vote anywhere on the grid, m.
    pub pass_margin: f64,
    /// A single echo on the plane brighter than this many times the median
    /// glass echo is opaque (wall-like); a dimmer one is glass.
    pub opaque_intensity_ratio: f64,
    /// Single echoes within this angle of normal incidence cast no vote
    /// (glass echoes peak there), degrees.
    pub peak_angle_deg: f64,
    /// Whether a weak single echo on the plane votes "glass". Off by default:
    /// where the infinite plane cuts the floor, ceiling or a wall at a
    /// grazing angle, those surfaces return weak echoes "on the plane" too.
    pub weak_single_echo_votes: bool,
    /// A transparent region with fewer surface echoes than this share of its
    /// transparent votes is an opening, not glass.
    pub min_echo_fraction: f64,
    /// Transparent cells farther than this from any surface echo are open
    /// space, not glass, m (0: no bound).
    pub echo_reach: f64,
    /// Upper bound on the grid size (cells).
    pub max_cells: usize,
    /// A cell without votes of its own is decided by its neighbours only
    /// inside a region (voted cells on opposite sides), never at its edge:
    /// the 3 x 3 majority otherwise grows every pane by a cell (0.2 m)
    /// beyond its last vote, over the wall around a whiteboard or a
    /// screen.
    pub fill_between_votes_only: bool,
    /// Beams through the plane within this angle of its normal that bring
    /// no echo from it are bare passes, degrees (0: off): glass and mirrors
    /// return a strong specular echo there, openings none.
    pub bare_pass_max_deg: f64,
    /// A transparent cell with at least this many bare passes over it and
    /// its neighbours, and no surface echo among them, is an opening (the
    /// wall between two screens on one plane, the gap beside a pane).
    pub min_bare_passes: u32,
    /// A surface echo votes "glass" only if the surface around it (its
    /// neighbours in the scan) is within this angle of the plane, degrees
    /// (0: no test). Where another pane or a wall cuts the plane, its echoes
    /// lie on the plane along the line of the cut; without this test they
    /// grow a phantom pane around that line.
    pub echo_normal_max_deg: f64,
    /// An echo on the plane that lies on another reflective landmark too
    /// (within its surface band, inside its boundary) votes only for the
    /// one its beam meets nearer normal incidence: glass echoes peak there,
    /// so where two panes cut each other the echoes are the facing pane's.
    pub echo_owner_test: bool,
    /// Where the sensor's path crosses the landmark's plane, the plane is
    /// open: cells within this horizontal distance of the crossing, from
    /// the ground up to this far above it, are an opening (a door the
    /// sensor passed through, not glass), m (0: off). Assumes the world's
    /// z axis points up.
    pub crossing_radius: f64,
    /// Only beams that meet the plane before any other reflective landmark
    /// vote: past a window or mirror a reflected echo with a transmitted
    /// return behind it looks like glass on any plane (see
    /// [`direct`](super::direct)).
    pub direct_only: bool,
}

impl Default for EvidenceParams {
    fn default() -> Self {
        Self {
            cell: 0.2,
            margin: 1.5,
            min_votes: 3,
            surface_band: 0.1,
            behind: 0.1,
            pass_margin: 0.15,
            opaque_intensity_ratio: 3.0,
            peak_angle_deg: 5.0,
            weak_single_echo_votes: false,
            min_echo_fraction: 0.0,
            echo_reach: 0.0,
            max_cells: 4_000_000,
            fill_between_votes_only: false,
            bare_pass_max_deg: 0.0,
            min_bare_passes: 0,
            echo_normal_max_deg: 0.0,
            echo_owner_test: false,
            crossing_radius: 0.0,
            direct_only: false,
        }
    }
}

/// One frame to gather evidence from.
#[derive(Debug, Clone, Copy)]
pub struct EvidenceFrame<'a> {
    /// The frame (sensor-frame points).
    pub frame: &'a Frame,
    /// Its organized scan (return pairing).
    pub scan: &'a OrganizedScan,
    /// `T_world_sensor`.
    pub pose: Isometry3<f64>,
}

/// Evidence for `landmark` (world frame) over `frames`; `None` when the
/// landmark has no usable boundary extent.
pub fn gather_evidence(
    landmark: &BoundedPlane,
    frames: &[EvidenceFrame<'_>],
    params: &EvidenceParams,
) -> Option<EvidenceGrid> {
    let gatherer = EvidenceGatherer::new(landmark, params)?;
    let votes: Vec<FrameVotes> = frames.par_iter().map(|f| gatherer.votes(f)).collect();
    let mut total = gatherer.total();
    for v in votes {
        total.add(v);
    }
    Some(total.finish())
}

/// Gathers one landmark's evidence frame by frame, so a sequence is read
/// once and never held: [`votes`](Self::votes) reads a frame (in parallel
/// with others), [`EvidenceTotal::add`] sums the votes. What the total
/// keeps grows with the grid and the distinct echo intensities (a few
/// hundred for a sensor that reports whole numbers), not with the frames.
#[derive(Debug, Clone)]
pub struct EvidenceGatherer {
    landmark: BoundedPlane,
    /// The other reflective landmarks (world frame), for the owner test.
    others: Vec<BoundedPlane>,
    empty: EvidenceGrid,
    params: EvidenceParams,
}

/// One frame's votes for one landmark.
#[derive(Debug)]
pub struct FrameVotes {
    grid: EvidenceGrid,
    votes: Votes,
}

/// The votes of a landmark summed over the frames so far.
#[derive(Debug, Clone)]
pub struct EvidenceTotal {
    grid: EvidenceGrid,
    params: EvidenceParams,
    /// Intensities of surface echoes with a return behind the plane.
    glass_echoes: IntensityCounts,
    /// Single echoes on the plane: count per (cell, intensity bits).
    single_echoes: BTreeMap<(usize, u32), u32>,
}

impl EvidenceGatherer {
    /// A gatherer for `landmark` (world frame); `None` when it has no
    /// usable boundary extent.
    pub fn new(landmark: &BoundedPlane, params: &EvidenceParams) -> Option<Self> {
        let vs = landmark.boundary.vertices();
        let (mut lo, mut hi) = (
            Point2::new(f64::INFINITY, f64::INFINITY),
            Point2::new(f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for v in vs {
            lo = Point2::new(lo.x.min(v.x), lo.y.min(v.y));
            hi = Point2::new(hi.x.max(v.x), hi.y.max(v.y));
        }
        let m = params.margin;
        let mut empty = EvidenceGrid::new(
            Point2::new(lo.x - m, lo.y - m),
            Point2::new(hi.x + m, hi.y + m),
            params.cell,
            params.min_votes,
            params.max_cells,
        )?;
        empty.min_echo_fraction = params.min_echo_fraction;
        empty.echo_reach = params.echo_reach;
        empty.fill_between_votes_only = params.fill_between_votes_only;
        empty.min_bare_passes = if params.bare_pass_max_deg > 0.0 {
            params.min_bare_passes
        } else {
            0
        };
        Some(Self {
            landmark: landmark.clone(),
            others: Vec::new(),
            empty,
            params: *params,
        })
    }

    /// The same gatherer aware of the other reflective landmarks (world
    /// frame) that an echo on this one's plane may belong to
    /// ([`EvidenceParams::echo_owner_test`]) or a beam may pass before it
    /// ([`EvidenceParams::direct_only`]).
    pub fn with_others(mut self, others: &[BoundedPlane]) -> Self {
        if self.params.echo_owner_test || self.params.direct_only {
            self.others = others.to_vec();
        }
        self
    }

    /// One frame's votes.
    pub fn votes(&self, f: &EvidenceFrame<'_>) -> FrameVotes {
        let mut grid = self.empty.empty_like();
        let to_sensor = f.pose.inverse();
        let others: Vec<BoundedPlane> = self
            .others
            .iter()
            .map(|o| o.transformed(&to_sensor))
            .collect();
        let votes = vote_frame(
            &mut grid,
            &self.landmark.transformed(&to_sensor),
            &others,
            f,
            &self.params,
        );
        FrameVotes { grid, votes }
    }

    /// An empty total to add frames' votes to.
    pub fn total(&self) -> EvidenceTotal {
        EvidenceTotal {
            grid: self.empty.clone(),
            params: self.params,
            glass_echoes: IntensityCounts::default(),
            single_echoes: BTreeMap::new(),
        }
    }
}

impl EvidenceTotal {
    /// Add one frame's votes (the order of frames does not matter).
    pub fn add(&mut self, v: FrameVotes) {
        self.grid.add(&v.grid);
        for x in v.votes.glass_echo_intensity {
            self.glass_echoes.add(x);
        }
        for (uv, intensity) in v.votes.single_echoes {
            if let Some(k) = self.grid.index(&uv) {
                *self
                    .single_echoes
                    .entry((k, intensity.to_bits()))
                    .or_insert(0) += 1;
            }
        }
    }

    /// The landmark's evidence grid, decided.
    pub fn finish(self) -> EvidenceGrid {
        let Self {
            mut grid,
            params,
            glass_echoes,
            single_echoes,
        } = self;
        // Single echoes on the plane: opaque when brighter than the
        // landmark's glass echoes by the ratio, glass otherwise (all opaque
        // when the landmark has no dual-return glass echo to compare with).
        let glass_median = glass_echoes.median();
        grid.glass_echo_intensity = glass_median.map(|m| m as f32);
        let threshold = glass_median.map(|m| m * params.opaque_intensity_ratio);
        grid.opaque_intensity = threshold.map(|t| t as f32);
        grid.peak_cos = params.peak_angle_deg.to_radians().cos();
        for ((k, bits), n) in single_echoes {
            let intensity = f32::from_bits(bits);
            match threshold {
                Some(th) if (intensity as f64) <= th => {
                    if params.weak_single_echo_votes {
                        grid.vote_echo_at(k, n)
                    }
                }
                _ => grid.vote_at(k, 0, n),
            }
        }
        grid.finalize();
        grid
    }
}

/// Mark as an opening the cells of `landmark`'s decided evidence where the
/// sensor path `path` (positions, world frame, in order) crosses its plane:
/// within `radius` horizontally of a crossing and below `radius` above it.
/// The sensor passed through there, so whatever the votes say, it is no
/// glass (a glass door's open leaf, which the closed leaf's echoes would
/// otherwise keep inside the pane). Returns the number of crossings used.
pub fn open_where_crossed(landmark: &mut BoundedPlane, path: &[Point3<f64>], radius: f64) -> usize {
    if radius <= 0.0 {
        return 0;
    }
    let Some(grid) = landmark.evidence.as_deref() else {
        return 0;
    };
    let crossings: Vec<Point3<f64>> = path_crossings(landmark, path)
        .filter(|x| grid.index(&landmark.chart.to_2d(x)).is_some())
        .collect();
    if crossings.is_empty() {
        return 0;
    }
    let mut grid = grid.clone();
    for k in 0..grid.len() {
        let c = landmark.chart.to_3d(&grid.centre(k));
        let open = crossings.iter().any(|x| {
            let (dx, dy) = (c.x - x.x, c.y - x.y);
            dx * dx + dy * dy <= radius * radius && c.z <= x.z + radius
        });
        if open {
            grid.set_open(k);
        }
    }
    landmark.evidence = Some(std::sync::Arc::new(grid));
    crossings.len()
}

/// Where the sensor path `path` (positions, world frame, in order) crosses
/// `landmark`'s plane.
pub fn path_crossings<'a>(
    landmark: &'a BoundedPlane,
    path: &'a [Point3<f64>],
) -> impl Iterator<Item = Point3<f64>> + 'a {
    let plane = landmark.plane;
    path.windows(2).filter_map(move |w| {
        let (a, b) = (plane.signed_distance(&w[0]), plane.signed_distance(&w[1]));
        (a * b < 0.0).then(|| w[0] + (w[1] - w[0]) * (a / (a - b)))
    })
}

/// Whether the sensor path passed through `landmark` inside its convex
/// boundary: then it has an opening, and it is no mirror.
pub fn passed_through(landmark: &BoundedPlane, path: &[Point3<f64>]) -> bool {
    path_crossings(landmark, path)
        .any(|x| landmark.boundary.signed_distance(&landmark.chart.to_2d(&x)) <= 0.0)
}

/// Votes of one frame that need the whole sequence to be weighed.
#[derive(Debug, Default)]
struct Votes {
    /// Intensities of surface echoes with a return behind the plane.
    glass_echo_intensity: Vec<f32>,
    /// Single echoes on the plane: chart position and intensity.
    single_echoes: Vec<(Point2<f64>, f32)>,
}

/// A multiset of intensities, counted per distinct value: its median is
/// exact, and its size is the number of distinct values, not of echoes.
#[derive(Debug, Clone, Default)]
struct IntensityCounts {
    /// Count per value, keyed in `f32::total_cmp` order.
    counts: BTreeMap<i32, u64>,
    len: u64,
}

impl IntensityCounts {
    fn add(&mut self, x: f32) {
        *self.counts.entry(total_order_key(x)).or_insert(0) += 1;
        self.len += 1;
    }

    /// The value at position `len / 2` in sorted order (the upper median
    /// for an even count), `None` when empty.
    fn median(&self) -> Option<f64> {
        let mid = self.len / 2;
        let mut seen = 0;
        for (&key, &n) in &self.counts {
            seen += n;
            if seen > mid {
                return Some(from_total_order_key(key) as f64);
            }
        }
        None
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

/// Add one frame's transparent votes and collect its echoes on the plane;
/// `plane` is the landmark in the frame's sensor frame (same chart
/// coordinates as the grid).
fn vote_frame(
    grid: &mut EvidenceGrid,
    plane: &BoundedPlane,
    others: &[BoundedPlane],
    f: &EvidenceFrame<'_>,
    p: &EvidenceParams,
) -> Votes {
    let origin = Point3::origin();
    let cos_peak = p.peak_angle_deg.to_radians().cos();
    let bare_cos = (p.bare_pass_max_deg > 0.0).then(|| p.bare_pass_max_deg.to_radians().cos());
    let echo_normal_cos =
        (p.echo_normal_max_deg > 0.0).then(|| p.echo_normal_max_deg.to_radians().cos());
    // Whether the echo at `x` (beam `dir`) lies on another landmark that
    // its beam meets nearer normal incidence.
    let owned_by_other = |x: &Point3<f64>, dir: &nalgebra::Vector3<f64>| {
        let here = plane.plane.normal.dot(dir).abs();
        p.echo_owner_test
            && others.iter().any(|o| {
                o.plane.signed_distance(x).abs() <= p.surface_band
                    && o.plane.normal.dot(dir).abs() > here
                    && o.bounds_2d(&o.chart.to_2d(x), 0.0)
            })
    };
    // Whether the surface around point `i` crosses the plane rather than
    // lying on it (unknown surfaces do not).
    let crosses = |i: usize| {
        echo_normal_cos.is_some_and(|c| {
            f.scan
                .local_normal(f.frame, i)
                .is_some_and(|n| n.dot(&plane.plane.normal).abs() < c)
        })
    };
    let mut votes = Votes::default();
    // A point on the sensor's side of the plane lies at least its distance
    // from the plane in front of the crossing along its beam (|r - t| >=
    // |n·x + d|): farther than the surface band it casts no vote, which one
    // dot product tells without the crossing (the 1e-9 covers round-off).
    let d = plane.plane.d;
    let skip_front = p.behind >= 0.0;
    for (i, pt) in f.frame.points.iter().enumerate() {
        let x = pt.position();
        let sd = plane.plane.signed_distance(&x);
        if skip_front && sd * d > 0.0 && sd.abs() > p.surface_band + 1e-9 {
            continue;
        }
        let r = x.coords.norm();
        if !(r > 0.0) {
            continue;
        }
        let dir = x.coords / r;
        let Some(t) = plane.plane.ray_intersection(&origin, &dir) else {
            continue;
        };
        let uv = plane.chart.to_2d(&(origin + dir * t));
        if grid.index(&uv).is_none()
            || (p.direct_only && passed_another(others, &dir, t, p.surface_band))
        {
            continue;
        }
        let s = r - t;
        if s > p.behind {
            // A beam through the plane: glass, or open space where the plane
            // has no surface at all. Only near the landmark's own boundary
            // (where dual returns found the surface) does it count.
            if plane.boundary.signed_distance(&uv) <= p.pass_margin {
                grid.vote(&uv, 1, 0);
            } else {
                grid.vote_open(&uv);
            }
            // Near normal incidence without an echo from the plane: bare.
            if bare_cos.is_some_and(|c| plane.plane.normal.dot(&dir).abs() >= c) {
                let echoed = f
                    .scan
                    .partner(i)
                    .is_some_and(|j| (f.frame.points[j].range() - t).abs() <= p.surface_band);
                if !echoed {
                    grid.vote_bare(&uv);
                }
            }
        } else if s.abs() <= p.surface_band {
            match f.scan.partner(i) {
                // A surface echo with a return behind the plane: glass.
                Some(j)
                    if f.frame.points[j].range() - t > p.behind
                        && !crosses(i)
                        && !owned_by_other(&x, &dir) =>
                {
                    grid.vote_echo(&uv);
                    votes.glass_echo_intensity.push(pt.intensity);
                }
                Some(_) => {}
                // The beam ended on the plane.
                None => {
                    if plane.plane.normal.dot(&dir).abs() < cos_peak {
                        votes.single_echoes.push((uv, pt.intensity));
                    }
                }
            }
        }
    }
    votes
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// One scan of a pane at x = 5 seen head-on (a weak glass echo per beam)
    /// with a wall at x = 7 behind it (the second return), over azimuths
    /// -20..5 degrees and elevations up to about 17 degrees.
    fn pane_frame(sensor: &crate::sensor::SensorModel) -> Frame {
        let mut points = Vec::new();
        for ring in 0..sensor.rings() {
            for column in 0..sensor.columns {
                let d = sensor.beam_direction(ring, column);
                let az = d.y.atan2(d.x).to_degrees();
                if !(-20.0..=5.0).contains(&az) || d.z.abs() > 0.3 {
                    continue;
                }
                for (x, intensity, ret) in [(5.0, 10.0f32, 1u8), (7.0, 100.0, 2)] {
                    let p = d * (x / d.x);
                    points.push(crate::cloud::Point {
                        xyz: [p.x as f32, p.y as f32, p.z as f32],
                        intensity,
                        ring: ring as u16,
                        ret,
                        label: 0,
                    });
                }
            }
        }
        Frame {
            name: "pane".into(),
            points,
            ..Frame::default()
        }
    }

    /// The landmark of [`pane_frame`]'s pane: x = 5, facing the sensor,
    /// y from -1.8 to 0.4 and z from -1.2 to 1.2.
    fn pane_landmark() -> BoundedPlane {
        let plane =
            crate::geometry::Plane::new(nalgebra::Vector3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
        BoundedPlane::from_points(
            plane,
            [(-1.8, -1.2), (0.4, -1.2), (0.4, 1.2), (-1.8, 1.2)]
                .iter()
                .map(|&(y, z)| Point3::new(5.0, y, z)),
        )
    }

    /// Where the sensor walked through the pane, its evidence is an
    /// opening: below and beside the crossing, not above it or a metre
    /// away; and a landmark walked through is passed through.
    #[test]
    fn where_the_sensor_crossed_the_plane_it_is_open() {
        use crate::geometry::grid::Surface;
        use crate::sensor::SensorModel;
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = pane_frame(&sensor);
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let mut pane = pane_landmark();
        let f = EvidenceFrame {
            frame: &frame,
            scan: &scan,
            pose: Isometry3::identity(),
        };
        let params = EvidenceParams::default();
        let evidence = gather_evidence(&pane, &[f], &params).unwrap();
        pane.evidence = Some(std::sync::Arc::new(evidence));
        let state = |pane: &BoundedPlane, y: f64, z: f64| {
            let uv = pane.chart.to_2d(&Point3::new(5.0, y, z));
            pane.evidence.as_ref().unwrap().state(&uv)
        };
        let (door, above, aside) = ((-0.8, -0.5), (-0.8, 0.9), (0.1, -0.5));
        for (y, z) in [door, above, aside] {
            assert_eq!(state(&pane, y, z), Surface::Transparent, "({y}, {z})");
        }
        let through = [Point3::new(4.0, -0.8, 0.0), Point3::new(6.0, -0.8, 0.0)];
        let beside = [Point3::new(4.0, -0.8, 0.0), Point3::new(4.5, 3.0, 0.0)];
        assert!(passed_through(&pane, &through));
        assert!(!passed_through(&pane, &beside));
        assert_eq!(open_where_crossed(&mut pane, &beside, 0.5), 0);
        assert_eq!(open_where_crossed(&mut pane, &through, 0.5), 1);
        assert_eq!(state(&pane, door.0, door.1), Surface::Open);
        assert_eq!(state(&pane, above.0, above.1), Surface::Transparent);
        assert_eq!(state(&pane, aside.0, aside.1), Surface::Transparent);
    }

    /// Beams that pass the plane near its normal without an echo from it
    /// passed an opening: the pane of [`pane_frame`] keeps its glass echoes
    /// only left of azimuth -8 degrees; right of it (within 5 degrees of
    /// the normal) the beams reach the wall behind with no echo. With bare
    /// passes counted that stretch is open; without, it is glass like the
    /// rest.
    #[test]
    fn bare_passes_near_normal_incidence_are_an_opening() {
        use crate::geometry::grid::Surface;
        use crate::sensor::SensorModel;
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let mut frame = pane_frame(&sensor);
        frame.points.retain(|p| {
            let az = (p.xyz[1] as f64).atan2(p.xyz[0] as f64).to_degrees();
            p.ret == 2 || az < -8.0
        });
        for p in &mut frame.points {
            let az = (p.xyz[1] as f64).atan2(p.xyz[0] as f64).to_degrees();
            if az >= -8.0 {
                p.ret = 1;
            }
        }
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let pane = pane_landmark();
        let f = EvidenceFrame {
            frame: &frame,
            scan: &scan,
            pose: Isometry3::identity(),
        };
        let off = EvidenceParams::default();
        let on = EvidenceParams {
            bare_pass_max_deg: 10.0,
            min_bare_passes: 3,
            ..off
        };
        let state = |params: &EvidenceParams, az_deg: f64| {
            let grid = gather_evidence(&pane, &[f], params).unwrap();
            let y = 5.0 * az_deg.to_radians().tan();
            grid.state(&pane.chart.to_2d(&Point3::new(5.0, y, 0.0)))
        };
        assert_eq!(state(&off, 2.0), Surface::Transparent);
        assert_eq!(state(&on, 2.0), Surface::Open);
        assert_eq!(state(&on, -15.0), Surface::Transparent);
    }

    /// A pane at x = 5 seen head-on (glass echo, and a return from a wall
    /// at x = 7 behind it) cuts a landmark at y ≈ -0.5 along a vertical
    /// line: the pane's echoes on that line lie on the landmark's plane,
    /// but their surface crosses it. They vote glass for the landmark
    /// (a phantom pane) only with both the normal and the owner test off.
    #[test]
    fn echoes_of_a_surface_crossing_the_plane_are_not_its_glass() {
        use crate::geometry::Plane;
        use crate::sensor::SensorModel;
        use nalgebra::Vector3;
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = pane_frame(&sensor);
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        // The landmark's plane holds one column's beams exactly.
        let column = sensor.column_of(1.0, -0.1);
        let az = sensor.column_azimuth_deg(column).to_radians();
        let y0 = 5.0 * az.tan();
        let plane = Plane::new(Vector3::new(0.0, 1.0, 0.0), -y0).unwrap();
        let corners = [(4.0, -1.0), (6.0, -1.0), (6.0, 1.0), (4.0, 1.0)];
        let landmark =
            BoundedPlane::from_points(plane, corners.iter().map(|&(x, z)| Point3::new(x, y0, z)));
        let f = EvidenceFrame {
            frame: &frame,
            scan: &scan,
            pose: Isometry3::identity(),
        };
        let off = EvidenceParams::default();
        let on = EvidenceParams {
            echo_normal_max_deg: 45.0,
            ..off
        };
        let without = gather_evidence(&landmark, &[f], &off).unwrap();
        assert!(without.glass_echo_intensity.is_some());
        let with = gather_evidence(&landmark, &[f], &on).unwrap();
        assert_eq!(with.glass_echo_intensity, None);
        // The owner test: the pane at x = 5 is a landmark too, and the beams
        // meet it nearer normal incidence, so the echoes are its own.
        let pane = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
        let pane = BoundedPlane::from_points(
            pane,
            [(-3.0, -2.0), (1.0, -2.0), (1.0, 2.0), (-3.0, 2.0)]
                .iter()
                .map(|&(y, z)| Point3::new(5.0, y, z)),
        );
        let owner = EvidenceParams {
            echo_owner_test: true,
            ..off
        };
        let votes = |params: &EvidenceParams| {
            let gatherer = EvidenceGatherer::new(&landmark, params)
                .unwrap()
                .with_others(std::slice::from_ref(&pane));
            let mut total = gatherer.total();
            total.add(gatherer.votes(&f));
            total.finish().glass_echo_intensity
        };
        assert!(votes(&off).is_some());
        assert_eq!(votes(&owner), None);
    }

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

        /// The order key sorts like `f32::total_cmp` and round-trips.
        #[test]
        fn order_key_sorts_like_total_cmp(a in any::<f32>(), b in any::<f32>()) {
            prop_assert_eq!(total_order_key(a).cmp(&total_order_key(b)), a.total_cmp(&b));
            prop_assert_eq!(from_total_order_key(total_order_key(a)).to_bits(), a.to_bits());
        }
    }
}
