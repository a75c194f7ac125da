//! Step 2 of the paper's first-match decision ([`decide_with_hits`]): the
//! rule ladder of a point behind a reflective plane, one function per rule,
//! tried in the paper's order until one decides; then the dual-return rule
//! over the frame's two-return beams.
//!
//! [`decide_with_hits`]: super::decide_with_hits

use nalgebra::Point3;

use super::beam_test::Beam;
use super::frame_evidence::returns_along;
use super::hypotheses::{two_hypotheses, Verdict};
use super::mirror_support::{support_is_perpendicular, supports_itself};
use super::pane_edge::{near_pane_edge, real_by_space};
use super::past_extent::through_glass;
use super::past_pane::past_second_pane;
use super::{DecisionParams, SurfaceSupport};
use crate::classify::boundary::{beam_crossing, BeamPlanes};
use crate::classify::rule::Rule;
use crate::classify::space::{Occupancy, SensorFrameSpace};
use crate::classify::Class;
use crate::cloud::Frame;
use crate::reflect::echo_split::EchoSplit;
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// A rule's decision: the point's class and the rule that gave it.
type Decision = (Class, Rule);

/// What the ladder's rules share over one frame: the frame, its planes and
/// the evidence from the frame and the sequence.
pub(super) struct Ladder<'a> {
    pub(super) frame: &'a Frame,
    pub(super) scan: &'a OrganizedScan,
    pub(super) sensor: &'a SensorModel,
    pub(super) bounded: &'a [BoundedPlane],
    /// The planes' boundaries, for beams that cross a second pane.
    pub(super) one_sided: BeamPlanes<'a>,
    /// Per plane, the deepest Normal point of the frame behind it
    /// ([`room_depths`](super::room_depths)).
    pub(super) max_indoor: Vec<f64>,
    pub(super) params: &'a DecisionParams,
    /// Surfaces a mirror image may land on (the support test).
    pub(super) support: Option<&'a dyn SurfaceSupport>,
    /// The sequence's space seen directly, from this frame's pose.
    pub(super) space: Option<&'a SensorFrameSpace<'a>>,
}

/// A behind-plane point as the rules see it.
struct Behind<'a> {
    /// Its index in the frame.
    i: usize,
    /// The plane its beam crossed first, and that plane.
    plane: usize,
    bp: &'a BoundedPlane,
    /// Its position (sensor frame).
    p: Point3<f64>,
    /// The range at which its beam crosses the plane.
    t: f64,
    /// Whether its beam crossed no second pane before it: past a second
    /// pane the first one's mirror says nothing.
    single_pane: bool,
}

/// The point's mirror image through the plane, and the frame's returns
/// along the beam towards it.
struct Image {
    mirrored: Point3<f64>,
    mirrored_range: f64,
    /// [`returns_along`] the mirrored point's beam, when a test asks.
    along_beam: Option<(f64, f64)>,
    /// The frame has a return where the mirror image lies: the mirror
    /// hypothesis confirmed.
    on_beam: bool,
}

impl<'a> Ladder<'a> {
    /// The first rule that decides point `i`, behind plane `plane` (the
    /// first its beam crossed), in the paper's order; `None` where no
    /// evidence decides.
    pub(super) fn behind_plane(&self, i: usize, plane: usize) -> Option<Decision> {
        let pt = self.point(i, plane);
        if let Some(decision) = self.behind_mirror(&pt) {
            return Some(decision);
        }
        let image = self.image(&pt);
        self.two_hypotheses(&pt, &image)
            .or_else(|| self.depth(&pt))
            .or_else(|| self.frame_free_space(&pt, &image))
            .or_else(|| self.echo_strength(&pt))
            .or_else(|| self.seen_surface(&pt))
            .or_else(|| self.support(&pt, &image))
    }

    /// Point `i` behind plane `plane`: where its beam crosses the plane, and
    /// whether it crossed a second pane before it.
    fn point(&self, i: usize, plane: usize) -> Behind<'a> {
        let bp = &self.bounded[plane];
        let p = self.frame.points[i].position();
        let t = beam_crossing(&bp.plane, &p).unwrap_or(p.coords.norm());
        let single_pane = !self.one_sided.second_pane(
            &p,
            plane,
            t,
            self.params.glass_distance,
            self.params.behind_distance,
        );
        Behind {
            i,
            plane,
            bp,
            p,
            t,
            single_pane,
        }
    }

    /// The mirror image of `pt` and the frame's returns towards it.
    fn image(&self, pt: &Behind<'_>) -> Image {
        let params = self.params;
        let mirrored = pt.bp.plane.mirror(&pt.p);
        let along_beam = if params.free_space_test || params.support_test {
            returns_along(
                self.scan,
                self.sensor,
                self.frame,
                &mirrored,
                params.free_space_neighbourhood,
            )
        } else {
            None
        };
        let mirrored_range = mirrored.coords.norm();
        let on_beam = along_beam
            .is_some_and(|(closest, _)| (closest - mirrored_range).abs() <= params.support_range);
        Image {
            mirrored,
            mirrored_range,
            along_beam,
            on_beam,
        }
    }

    /// Mirror: behind a mirror nothing is real (a Reflection), unless the
    /// beam may have passed beside it and the space seen directly says the
    /// point is real (Normal). Only for beams that met this pane alone.
    fn behind_mirror(&self, pt: &Behind<'_>) -> Option<Decision> {
        if !(pt.bp.is_mirror() && pt.single_pane) {
            return None;
        }
        let seen_beside = near_pane_edge(pt.bp, &pt.p, pt.t, self.params.pane_edge_margin)
            .then(|| real_by_space(self.space, self.support, pt.bp, &pt.p, self.params))
            .flatten();
        Some(match seen_beside {
            Some(rule) => (Class::Normal, rule),
            None => (Class::Reflection, Rule::BehindMirror),
        })
    }

    /// Two hypotheses against the space seen directly (beams that met one
    /// pane, where the frame's own return does not already confirm the
    /// mirror image): when exactly one is refuted, the other decides.
    fn two_hypotheses(&self, pt: &Behind<'_>, image: &Image) -> Option<Decision> {
        let space = self
            .space
            .filter(|_| self.params.space_test && pt.single_pane && !image.on_beam)?;
        match two_hypotheses(space, self.support, &pt.bp.plane, &pt.p, self.params) {
            Verdict::Mirror => Some((Class::Reflection, Rule::RealRefuted)),
            Verdict::Real => Some((Class::Obstacle, Rule::MirrorRefuted)),
            Verdict::Open => None,
        }
    }

    /// Whether the frame's obstacle tests (depth, free space) apply to
    /// point `i`: to every return, or to last returns only (Zhao 2020).
    fn obstacle_tests_apply(&self, i: usize) -> bool {
        self.params.obstacle_tests_on_all_returns
            || self.frame.points[i].ret == 2
            || self.scan.second(self.scan.cell_of(i)).is_none()
    }

    /// Depth: a reflection lies as deep behind the plane as its object
    /// stands in front, so a point deeper than every Normal point of the
    /// frame is an Obstacle.
    fn depth(&self, pt: &Behind<'_>) -> Option<Decision> {
        let params = self.params;
        let depth = -pt.bp.plane.signed_distance(&pt.p);
        (self.obstacle_tests_apply(pt.i)
            && params.depth_test
            && depth > self.max_indoor[pt.plane] + params.depth_margin)
            .then_some((Class::Obstacle, Rule::Depth))
    }

    /// Free space in the frame: where the scan saw past the mirror image (a
    /// return farther along its beam), no real surface lies there to be
    /// reflected, and the point is an Obstacle.
    fn frame_free_space(&self, pt: &Behind<'_>, image: &Image) -> Option<Decision> {
        let params = self.params;
        if !(self.obstacle_tests_apply(pt.i) && params.free_space_test) {
            return None;
        }
        let (_, far) = image.along_beam?;
        let margin =
            params.free_space_margin + params.free_space_margin_ratio * image.mirrored_range;
        (far > image.mirrored_range + margin).then_some((Class::Obstacle, Rule::FrameFreeSpace))
    }

    /// Echo strength, where the landmark's echoes fall in two groups: a
    /// reflection off glass is far weaker than a transmitted echo, which
    /// tells floors and ceilings behind glass (their own mirror images)
    /// from their reflections. A beam that met a second pane is decided
    /// pane by pane, when configured.
    fn echo_strength(&self, pt: &Behind<'_>) -> Option<Decision> {
        let (frame, scan, i) = (self.frame, self.scan, pt.i);
        // A floor or ceiling seen directly is met as a horizontal surface
        // where the scan's neighbours span none, as the split's strengths.
        let level = || self.space.and_then(|s| s.level_incidence_cos(&pt.p));
        let strength = |split: &EchoSplit| {
            let cos = split.incidence_cos(scan, frame, i, level);
            split.reflected(frame.points[i].intensity, pt.p.coords.norm(), cos)
        };
        let reflected = if pt.single_pane {
            pt.bp.echo_split.and_then(|s| strength(&s))
        } else if self.params.echo_strength_past_second_pane {
            past_second_pane(
                self.bounded,
                &self.one_sided,
                pt.plane,
                &pt.p,
                pt.t,
                self.params,
                strength,
            )
        } else {
            None
        }?;
        let class = if reflected {
            Class::Reflection
        } else {
            self.real(pt)
        };
        Some((class, Rule::EchoStrength))
    }

    /// Seen surface: where the point was measured, a surface was seen
    /// directly from elsewhere, so it is real (a mirror image lands near
    /// some observed surface far more often than exactly on one, so this
    /// outranks support).
    fn seen_surface(&self, pt: &Behind<'_>) -> Option<Decision> {
        (self.params.seen_surface_test
            && pt.single_pane
            && self
                .space
                .is_some_and(|s| s.occupancy(&pt.p) == Occupancy::Occupied))
        .then(|| (self.real(pt), Rule::SeenSurface))
    }

    /// Support: the mirror image lands on an observed surface (a return at
    /// its range along its beam, or a surface within the support radius)
    /// other than the point's own, and not on one perpendicular to the
    /// plane: a Reflection.
    fn support(&self, pt: &Behind<'_>, image: &Image) -> Option<Decision> {
        let params = self.params;
        if !params.support_test || supports_itself(params, &pt.p, &image.mirrored) {
            return None;
        }
        let nearby = params.support_radius > 0.0
            && self
                .support
                .is_some_and(|s| s.near(&image.mirrored, params.support_radius));
        // The surface's shape is asked only of a supported image.
        let supported = (image.on_beam || nearby)
            && !support_is_perpendicular(
                self.support,
                &pt.bp.plane,
                &image.mirrored,
                params.support_radius,
                params.perpendicular_support_deg,
            );
        supported.then_some((Class::Reflection, Rule::Support))
    }

    /// A point found real where it was measured: an Obstacle seen through
    /// glass, or Normal, seen through an opening in the plane where the
    /// pane's extent overreaches its echoes.
    fn real(&self, pt: &Behind<'_>) -> Class {
        if through_glass(pt.bp, &pt.p, pt.t, self.params.seen_surface_echo_reach) {
            Class::Obstacle
        } else {
            Class::Normal
        }
    }
}

/// The dual-return rule: on a beam with two returns behind the same plane
/// whose far return is an Obstacle, the near one (more than `dual_gap`
/// nearer) is a Reflection: the strongest echo came back off the glass, the
/// last came through it.
pub(super) fn dual_return(
    frame: &Frame,
    scan: &OrganizedScan,
    beams: &[Beam],
    classes: &mut [Class],
    rules: &mut [Rule],
    dual_gap: f64,
) {
    for (_, a, b) in scan.dual_cells() {
        let (near, far) = if frame.points[a].range() <= frame.points[b].range() {
            (a, b)
        } else {
            (b, a)
        };
        let same_plane = matches!((beams[near], beams[far]),
            (Beam::Behind { plane: x }, Beam::Behind { plane: y }) if x == y);
        if same_plane
            && classes[far] == Class::Obstacle
            && classes[near] != Class::Obstacle
            && (frame.points[near].position() - frame.points[far].position()).norm() > dual_gap
        {
            (classes[near], rules[near]) = (Class::Reflection, Rule::DualReturn);
        }
    }
}
