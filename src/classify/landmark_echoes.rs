//! What one keyframe adds to each landmark's glass-or-mirror estimate
//! ([`glass_or_mirror`](crate::map::glass_or_mirror())): the echoes behind
//! it ([`BehindEchoes`]: which points count, which crossed it well inside
//! its extent, which are anchors, which the seen space calls transmitted or
//! reflected) and the strengths of the room's direct echoes. The pipeline
//! sums these over the keyframes; the tests they rest on are the
//! classifier's, so they live here.

use nalgebra::Point3;

use super::boundary::BeamPlanes;
use super::decide::{near_pane_edge, BeamHit, BeamHits, SurfaceSupport};
use super::evidence::seen_space::CLEARANCE_RATIO;
use super::evidence::{moved_off, ImageLanding};
use super::plane_map::{PlaneMapClassifier, PlaneMapParams};
use super::space::{Occupancy, SensorFrameSpace, SpaceMap};
use super::support::WorldSupport;
use super::FrameInput;
use crate::map::glass_or_mirror::{ThroughBeam, IMAGE_NULL_SHIFTS};
use crate::map::{BehindEchoes, LandedEcho};
use crate::reflect::echo_split::echo_strength;
use crate::reflect::{BoundedPlane, EchoHistogram, EchoSplitParams};

/// What counting a keyframe's echoes takes besides the frame: the
/// classifier's settings, how strengths are computed, and what the
/// sequence saw directly. One for the whole pass; it counts frames on any
/// thread.
pub struct EchoCounting<'a> {
    /// The plane-map classifier's settings: its decision distances, hull
    /// margin, pane-edge margin and seen-space test.
    pub params: &'a PlaneMapParams,
    /// The echo split's settings (the incidence correction).
    pub split: &'a EchoSplitParams,
    /// The range exponent of the strengths (resolved for the sequence's
    /// intensity scale).
    pub range_exponent: f64,
    /// The space seen directly (world frame).
    pub space: &'a SpaceMap,
    /// The observed surfaces (world frame), when gathered.
    pub support: Option<&'a WorldSupport>,
}

/// One frame's view of the landmarks and of what the sequence saw.
struct FrameView<'a> {
    input: &'a FrameInput<'a>,
    /// The landmarks in the sensor frame, facing the sensor.
    planes: &'a [BoundedPlane],
    /// Their hulls, for beams that meet a second pane.
    beams: &'a BeamPlanes<'a>,
    /// The space seen directly, from this frame's pose.
    space: &'a SensorFrameSpace<'a>,
    /// The observed surfaces, from this frame's pose.
    seen: Option<&'a dyn SurfaceSupport>,
}

impl EchoCounting<'_> {
    /// The echoes behind each of `input`'s map planes in this frame (one
    /// entry per plane, in order) and the strengths of its direct echoes
    /// (beams that cross no pane, one column in four); `hits` is the
    /// frame's beam test against those planes. Integer counts: their sum
    /// over frames does not depend on the order.
    pub fn count_frame(
        &self,
        input: &FrameInput<'_>,
        hits: &BeamHits,
    ) -> (Vec<BehindEchoes>, EchoHistogram) {
        let mut behind = vec![BehindEchoes::default(); input.map_planes.len()];
        let mut direct = EchoHistogram::default();
        let planes = PlaneMapClassifier::planes_in_sensor_frame(input);
        let space = self.space.in_sensor_frame(input.pose);
        let seen = self.support.map(|s| s.in_sensor_frame(input.pose));
        let beams = BeamPlanes::hulls(&planes, self.params.hull_margin);
        let view = FrameView {
            input,
            planes: &planes,
            beams: &beams,
            space: &space,
            seen: seen.as_ref().map(|s| s as &dyn SurfaceSupport),
        };
        for (i, pt) in input.frame.points.iter().enumerate() {
            let pos = pt.position();
            match hits.get(i, &pos, &planes) {
                Some(h) => self.count_behind(&view, i, h, &mut behind[h.plane]),
                // One column in four is plenty for the room's echoes.
                None if i % 4 == 0 => {
                    direct.add(self.strength(input, i, &pos, &space));
                }
                None => {}
            }
        }
        (behind, direct)
    }

    /// The echo strength of `input`'s point `i` at `pos` (sensor frame), a
    /// floor or ceiling seen directly (`space`) met at the incidence of its
    /// level where the scan's neighbours span no surface.
    fn strength(
        &self,
        input: &FrameInput<'_>,
        i: usize,
        pos: &Point3<f64>,
        space: &SensorFrameSpace<'_>,
    ) -> f64 {
        let level = || space.level_incidence_cos(pos);
        let cos = self.split.incidence_cos(input.scan, input.frame, i, level);
        echo_strength(
            input.frame.points[i].intensity,
            pos.coords.norm(),
            self.range_exponent,
            cos,
        )
    }

    /// Add point `i`, whose beam crossed landmark `h.plane` first, to that
    /// landmark's echoes `stats` when it lies behind that pane alone.
    fn count_behind(&self, view: &FrameView<'_>, i: usize, h: BeamHit, stats: &mut BehindEchoes) {
        let decision = &self.params.decision;
        let (behind, glass) = (decision.behind_distance, decision.glass_distance);
        let pos = view.input.frame.points[i].position();
        let range = pos.coords.norm();
        // Only beams behind one pane: past a second one the mirror of the
        // first says nothing.
        if range - h.range <= behind
            || view
                .beams
                .second_pane(&pos, h.plane, h.range, glass, behind)
        {
            return;
        }
        // A beam near the extent's edge may have passed beside the
        // landmark: no evidence of what it does to light.
        let near_edge = near_pane_edge(
            &view.planes[h.plane],
            &pos,
            h.range,
            decision.pane_edge_margin,
        );
        let strength = self.strength(view.input, i, &pos, view.space);
        stats.all.add(strength);
        if !near_edge {
            stats.inside.add(strength);
        }
        let mirrored = view.planes[h.plane].plane.mirror(&pos);
        // A glass echo of a second pane behind this one is transmitted by
        // this one, but its strength is that pane's echo, not a surface's:
        // no anchor.
        let on_other_pane = view
            .beams
            .crosses_between(&pos, h.plane, range - glass, range + glass);
        if on_other_pane {
            return;
        }
        if !near_edge {
            let w = view.input.pose * pos;
            stats.landed.push(LandedEcho {
                position: [w.x as f32, w.y as f32, w.z as f32],
                strength: strength as f32,
            });
        }
        let anchor = view
            .space
            .occupancy_clear_of(&mirrored, CLEARANCE_RATIO * range)
            == Occupancy::Free;
        if anchor {
            stats.anchors.add(strength);
        }
        if !near_edge {
            self.count_seen(view, h, pos, &mirrored, strength, stats);
        }
    }

    /// Count an echo behind landmark `h.plane`, well inside its extent, as
    /// the seen space decides it: a confirmed transmission, an image on a
    /// seen surface (a confirmed reflection), and how many of its images
    /// moved off the mirror position land on one by chance.
    fn count_seen(
        &self,
        view: &FrameView<'_>,
        h: BeamHit,
        pos: Point3<f64>,
        mirrored: &Point3<f64>,
        strength: f64,
        stats: &mut BehindEchoes,
    ) {
        let range = pos.coords.norm();
        let landing = ImageLanding::new(
            view.space,
            view.seen,
            &view.planes[h.plane].plane,
            pos,
            Point3::from(pos.coords * (h.range / range)),
            &self.params.weighing.seen_space,
            self.params.weighing.level_surface.tolerance,
        );
        // Every echo's image moved off the mirror position: how often such
        // images land on a seen surface by chance. Counted over every echo
        // inside, whatever the seen space makes of its own image, as the
        // rates were measured (docs/decision.md, "Chance landings").
        for shift in IMAGE_NULL_SHIFTS {
            if landing.lands(&moved_off(landing.plane, mirrored, shift)) {
                stats.imaged_by_chance += 1;
            }
        }
        if landing.refuted(mirrored) {
            // Real where measured: its mirror image refuted by the seen
            // space, its measured position not.
            if !landing.refuted(&pos) {
                stats.transmitted.add(strength);
                let pose = &view.input.pose;
                let (a, b) = (pose * landing.crossing, pose * pos);
                stats.through.push(ThroughBeam {
                    start: [a.x as f32, a.y as f32, a.z as f32],
                    end: [b.x as f32, b.y as f32, b.z as f32],
                    range: range as f32,
                });
                if let Some(k) = view.space.level_of(&pos, landing.level_tolerance) {
                    *stats.at_level(k) += 1;
                }
            }
            return;
        }
        // A reflection: its mirror image lies on a surface seen directly.
        if landing.on_seen_surface(mirrored) {
            stats.imaged += 1;
        }
    }
}
