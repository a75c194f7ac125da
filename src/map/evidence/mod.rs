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
//!
//! The room: this module holds the parameters and the gathering (a
//! gatherer per landmark, one frame's votes, their total and its
//! decision); `votes` reads one frame, `crossings` opens the plane where
//! the sensor itself passed through it.

mod crossings;
#[cfg(test)]
mod tests;
mod votes;

pub use crossings::{open_where_crossed, passed_through, path_crossings};
use votes::{sum_glass_echoes, vote_frame, EchoAtIncidence, IntensityCounts, Votes};

use std::collections::BTreeMap;

use nalgebra::{Isometry3, Point2, Point3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::cloud::Frame;
use crate::geometry::fit::PlaneSums;
use crate::geometry::grid::EvidenceGrid;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// Settings of the evidence grid: `[map.evidence]` sets the cell, the
/// margin and the votes a cell needs; the rest are the method's constants,
/// [`EvidenceParams::METHOD`] (the evidence grid bounds the panes of
/// `map.boundary = "panes"`; the paper's hulls use none of it).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(from = "EvidenceKeys", into = "EvidenceKeys")]
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
    /// A single echo on the plane stronger than the landmark's glass echoes
    /// met at the same incidence is opaque (wall-like)
    /// ([`EvidenceGrid::is_opaque_echo`]); where no glass echo was met at
    /// that incidence, one brighter than this many times the median glass
    /// echo is.
    pub opaque_intensity_ratio: f64,
    /// Single echoes within this angle of normal incidence cast no vote
    /// (glass echoes peak there), degrees.
    pub peak_angle_deg: f64,
    /// Whether a single echo on the plane that is no stronger than the
    /// landmark's glass echoes met at the same incidence votes "glass"
    /// ([`GLASS_ECHO_QUANTILE`]): where a pane's transmitted beams find
    /// nothing behind it (the sky above a facade), its glass answers with
    /// single echoes only. Compared by strength (range-corrected) within an
    /// incidence bin, because the floor, ceiling or a wall where the
    /// infinite plane cuts them also return echoes "on the plane", weaker
    /// than the glass's bright near-normal echoes but stronger than its
    /// faint oblique ones.
    pub weak_single_echo_votes: bool,
    /// A transparent region with fewer surface echoes than this share of its
    /// transparent votes is an opening, not glass.
    pub min_echo_fraction: f64,
    /// Transparent cells farther than this from any surface echo are open
    /// space, not glass, m (0: no bound).
    pub echo_reach: f64,
    /// A transparent cell at the edge of its region whose own surface
    /// echoes are fewer than this share of what its neighbours' echo rate
    /// predicts for its passes is an opening (0: off): glass echoes at a
    /// rate that changes smoothly over a pane, openings never echo (the air
    /// above a railing, the gap beside a mirror-clad column, passed by the
    /// same beams as the glass).
    pub echo_deficit_ratio: f64,
    /// ... when that rate predicts at least this many echoes.
    pub echo_deficit_min_expected: f64,
    /// The rate a cell is held to is that of the cells with surface echoes
    /// within this distance, m.
    pub echo_deficit_reach: f64,
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
    /// Refit each landmark's plane to its glass echoes over the whole
    /// sequence (Cauchy-weighted by their distance from the map's plane),
    /// in a pass before the evidence is gathered against it (no refit
    /// without evidence: `map.boundary = "hull"`). The map's plane is the
    /// paper's moving average of the last observations, each fitted to the
    /// small patch near normal incidence where the pane echoes: a long
    /// glass wall seen a part at a time keeps the tilt of its last views,
    /// and under 2 cm of range noise its far end leaves the band in which
    /// echoes count as glass.
    pub refit_plane: bool,
    /// Glass echoes a landmark needs over the sequence to be refitted.
    pub refit_min_echoes: u64,
    /// A refit may turn the plane by at most this much, degrees, and move
    /// it by at most the surface band at its echoes: farther is not the
    /// same surface, and the map's plane is kept.
    pub refit_max_angle_deg: f64,
}

/// The keys of `[map.evidence]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EvidenceKeys {
    /// Cell edge length, m.
    cell: f64,
    /// The grid covers the landmark's hull grown by this much, m.
    margin: f64,
    /// Votes (cell and neighbours) needed to decide a cell.
    min_votes: u32,
}

impl From<EvidenceKeys> for EvidenceParams {
    fn from(k: EvidenceKeys) -> Self {
        Self {
            cell: k.cell,
            margin: k.margin,
            min_votes: k.min_votes,
            ..Self::METHOD
        }
    }
}

impl From<EvidenceParams> for EvidenceKeys {
    fn from(p: EvidenceParams) -> Self {
        Self {
            cell: p.cell,
            margin: p.margin,
            min_votes: p.min_votes,
        }
    }
}

impl EvidenceParams {
    /// The evidence grid's method (the fields' docs say what each does):
    /// a return within 0.1 m of the crossing is on the plane, 0.1 m beyond
    /// it behind; passes vote within 0.15 m of the hull; a single echo 3
    /// times brighter than the median glass echo is opaque, one within 5
    /// deg of normal incidence casts no vote, a weaker one votes "glass"
    /// where it is no stronger than the landmark's glass echoes at its
    /// incidence;
    /// a transparent region returning fewer than 1 surface echo in 200
    /// passes is an opening, and so are transparent cells more than 1 m
    /// from any glass echo and edge cells echoing less than a tenth of the
    /// rate of the echoing cells within 0.6 m (at least 30 echoes
    /// predicted); at most 4 million cells; a cell without votes is decided
    /// by its neighbours only inside a region; no bare-pass or echo-normal
    /// test; an echo on two landmarks votes for the one its beam meets
    /// nearer normal incidence; the plane is open 0.5 m either side of
    /// where the sensor crossed it (a door leaf's width); only beams that
    /// meet the plane before any other reflective landmark vote; each plane
    /// is refitted to its glass echoes (at least 200, by at most 3 deg).
    /// `cell` 0.2 m, `margin` 1.5 m and `min_votes` 3, as
    /// `configs/default.toml` sets them.
    pub const METHOD: Self = Self {
        cell: 0.2,
        margin: 1.5,
        min_votes: 3,
        surface_band: 0.1,
        behind: 0.1,
        pass_margin: 0.15,
        opaque_intensity_ratio: 3.0,
        peak_angle_deg: 5.0,
        weak_single_echo_votes: true,
        min_echo_fraction: 0.005,
        echo_reach: 1.0,
        echo_deficit_ratio: 0.1,
        echo_deficit_min_expected: 30.0,
        echo_deficit_reach: 0.6,
        max_cells: 4_000_000,
        fill_between_votes_only: true,
        bare_pass_max_deg: 10.0,
        min_bare_passes: 3,
        echo_normal_max_deg: 0.0,
        echo_owner_test: true,
        crossing_radius: 0.5,
        direct_only: true,
        refit_plane: true,
        refit_min_echoes: 200,
        refit_max_angle_deg: 3.0,
    };

    /// The grid with every test beyond the votes off (no opening tests,
    /// no echo ownership, no crossing, every beam votes, no refit): what
    /// the evidence grid's unit tests start from.
    pub const BARE: Self = Self {
        min_echo_fraction: 0.0,
        echo_reach: 0.0,
        echo_deficit_ratio: 0.0,
        fill_between_votes_only: false,
        bare_pass_max_deg: 0.0,
        min_bare_passes: 0,
        echo_owner_test: false,
        crossing_radius: 0.0,
        direct_only: false,
        refit_plane: false,
        weak_single_echo_votes: false,
        ..Self::METHOD
    };
}

impl Default for EvidenceParams {
    /// `[map.evidence]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("map.evidence")
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
    /// The range exponent of the frame's echo strengths
    /// ([`IntensityScale::range_exponent`](crate::cloud::IntensityScale::range_exponent)).
    pub range_exponent: f64,
}

impl<'a> EvidenceFrame<'a> {
    /// Frame `frame` of `sensor` at `pose`, its strengths on the scale the
    /// frame declares, else the sensor's.
    pub fn new(
        frame: &'a Frame,
        scan: &'a OrganizedScan,
        pose: Isometry3<f64>,
        sensor: &SensorModel,
    ) -> Self {
        Self {
            frame,
            scan,
            pose,
            range_exponent: frame
                .intensity_scale
                .unwrap_or(sensor.intensity)
                .range_exponent(),
        }
    }
}

/// A single echo votes "glass" ([`EvidenceParams::weak_single_echo_votes`])
/// when its strength is at most this quantile of the landmark's glass
/// echoes in its incidence bin: the glass echoes' upper tail (dirt, a
/// brighter pane) still counts, a wall's typical echo does not.
pub const GLASS_ECHO_QUANTILE: f64 = 0.9;

/// Fewest glass echoes an incidence bin needs before single echoes there
/// are compared with them.
pub const MIN_GLASS_ECHOES_PER_BIN: u64 = 30;

/// Single echoes are compared with the glass echoes of an incidence bin
/// only where those (up to [`GLASS_ECHO_QUANTILE`]) are at least this much
/// weaker than the median return behind them, decades: glass answers a
/// few per cent and passes most of the rest, so its echo is much weaker
/// than what lies behind it, while a surface with a strong diffuse echo
/// (a glossy panel) is as strong as a wall, and weak single echoes on it
/// say nothing.
pub const GLASS_BELOW_BEHIND_DECADES: f64 = 0.5;

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
    /// The landmark's boundary centroid (world frame): the reference of
    /// its glass echoes' sums.
    reference: Point3<f64>,
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
    /// Their strengths per incidence bin, and those of the returns behind
    /// them.
    glass_strengths: EchoAtIncidence,
    behind_strengths: EchoAtIncidence,
    /// The range exponent of the strengths (frames share one scale).
    range_exponent: f64,
    /// Single echoes on the plane: count per (cell, intensity bits,
    /// incidence bin, strength bits).
    single_echoes: BTreeMap<(usize, u32, u8, u32), u32>,
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
        empty.echo_deficit_ratio = params.echo_deficit_ratio;
        empty.echo_deficit_min_expected = params.echo_deficit_min_expected;
        empty.echo_deficit_reach = params.echo_deficit_reach;
        empty.fill_between_votes_only = params.fill_between_votes_only;
        empty.min_bare_passes = if params.bare_pass_max_deg > 0.0 {
            params.min_bare_passes
        } else {
            0
        };
        let reference = landmark
            .boundary
            .centroid()
            .map_or(landmark.chart.origin, |c| landmark.chart.to_3d(&c));
        Some(Self {
            landmark: landmark.clone(),
            others: Vec::new(),
            empty,
            params: *params,
            reference,
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
        let (landmark, others) = self.in_sensor_frame(f);
        let votes = vote_frame(&mut grid, &landmark, &others, f, &self.params);
        FrameVotes { grid, votes }
    }

    /// Empty sums of the landmark's glass echoes (world frame), to add
    /// frames' [`glass_echo_sums`](Self::glass_echo_sums) to.
    pub fn empty_sums(&self) -> PlaneSums {
        PlaneSums::new(self.reference)
    }

    /// One frame's glass echoes of the landmark, summed for its refit
    /// ([`EvidenceParams::refit_plane`]): a pass that reads only the points
    /// with a second return, far cheaper than [`votes`](Self::votes).
    pub fn glass_echo_sums(&self, f: &EvidenceFrame<'_>) -> PlaneSums {
        let (landmark, others) = self.in_sensor_frame(f);
        let mut sums = self.empty_sums();
        sum_glass_echoes(&self.empty, &landmark, &others, f, &self.params, &mut sums);
        sums
    }

    /// The landmark and the others in frame `f`'s sensor frame.
    fn in_sensor_frame(&self, f: &EvidenceFrame<'_>) -> (BoundedPlane, Vec<BoundedPlane>) {
        let to_sensor = f.pose.inverse();
        let others = self
            .others
            .iter()
            .map(|o| o.transformed(&to_sensor))
            .collect();
        (self.landmark.transformed(&to_sensor), others)
    }

    /// The plane through the landmark's glass echoes `sums` (of the whole
    /// sequence), when the refit is on ([`EvidenceParams::refit_plane`]),
    /// there are `refit_min_echoes` of them, they span a plane, and it lies
    /// within `refit_max_angle_deg` of the landmark's plane and within the
    /// surface band of it at the echoes' centroid.
    pub fn refitted_plane(&self, sums: &PlaneSums) -> Option<crate::geometry::Plane> {
        let p = &self.params;
        if !p.refit_plane || sums.count() < p.refit_min_echoes {
            return None;
        }
        let (fit, spread) = sums.fit()?;
        // Echoes along a strip (one row of a scan) do not fix a plane.
        if !(spread[1] > 100.0 * spread[0].max(1e-12)) {
            return None;
        }
        let plane = &self.landmark.plane;
        let fit = if fit.normal.dot(&plane.normal) < 0.0 {
            fit.flipped()
        } else {
            fit
        };
        let centroid = fit.project(&sums.centroid()?);
        let close = fit.normal.dot(&plane.normal) >= p.refit_max_angle_deg.to_radians().cos()
            && plane.signed_distance(&centroid).abs() <= p.surface_band;
        close.then_some(fit)
    }

    /// An empty total to add frames' votes to.
    pub fn total(&self) -> EvidenceTotal {
        EvidenceTotal {
            grid: self.empty.clone(),
            params: self.params,
            glass_echoes: IntensityCounts::default(),
            glass_strengths: Default::default(),
            behind_strengths: Default::default(),
            range_exponent: 0.0,
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
        self.range_exponent = v.votes.range_exponent;
        for (bin, strength, behind) in v.votes.glass_echo_strength {
            self.glass_strengths[bin as usize].add(strength);
            self.behind_strengths[bin as usize].add(behind);
        }
        for (uv, intensity, bin, strength) in v.votes.single_echoes {
            if let Some(k) = self.grid.index(&uv) {
                *self
                    .single_echoes
                    .entry((k, intensity.to_bits(), bin, strength.to_bits()))
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
            glass_strengths,
            behind_strengths,
            range_exponent,
            single_echoes,
        } = self;
        // Single echoes on the plane: opaque when brighter than the
        // landmark's glass echoes by the ratio (all opaque when the
        // landmark has no dual-return glass echo to compare with); glass
        // when no stronger than its glass echoes at the same incidence.
        let glass_at: Vec<Option<f64>> = glass_strengths
            .iter()
            .zip(&behind_strengths)
            .map(|(glass, behind)| {
                let upper = glass.quantile(GLASS_ECHO_QUANTILE)?;
                let weak = upper + GLASS_BELOW_BEHIND_DECADES <= behind.median()?;
                (glass.len() >= MIN_GLASS_ECHOES_PER_BIN && weak).then_some(upper)
            })
            .collect();
        grid.glass_strength_at = std::array::from_fn(|b| glass_at[b].map(|g| g as f32));
        grid.range_exponent = range_exponent;
        let glass_median = glass_echoes.median();
        grid.glass_echo_intensity = glass_median.map(|m| m as f32);
        let threshold = glass_median.map(|m| m * params.opaque_intensity_ratio);
        grid.opaque_intensity = threshold.map(|t| t as f32);
        grid.peak_cos = params.peak_angle_deg.to_radians().cos();
        for ((k, bits, bin, strength), n) in single_echoes {
            let intensity = f32::from_bits(bits);
            let strength = f32::from_bits(strength) as f64;
            // Against the glass echoes at the same incidence where they
            // tell, else against their median intensity.
            let opaque = match glass_at[bin as usize] {
                Some(g) => strength > g,
                None => threshold.is_none_or(|th| intensity as f64 > th),
            };
            if opaque {
                grid.vote_at(k, 0, n);
            } else if params.weak_single_echo_votes && glass_at[bin as usize].is_some() {
                grid.vote_echo_at(k, n);
            }
        }
        grid.finalize();
        grid
    }
}
