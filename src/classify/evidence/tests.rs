//! The weighing on the synthetic pane of the decision tests: each built-in
//! test's sign, the landmark's prior, a custom test, and the threshold.

use nalgebra::{Isometry3, Point3};

use super::*;
use crate::classify::boundary::BeamPlanes;
use crate::classify::decide::tests::{frame, pane, room_space, split, two_panes};
use crate::classify::decide::{BeamHits, DecisionParams};
use crate::classify::evidence::ImageLanding;
use crate::classify::weighed::{decide_weighed, FrameContext};
use crate::classify::{Class, Decisions, SurfaceSupport};
use crate::reflect::BoundedPlane;
use crate::sensor::{OrganizedScan, SensorModel};

/// The weighed decisions for `points` behind `planes`, with the room in
/// front of the pane seen directly.
fn weighed(points: &[[f32; 3]], planes: &[BoundedPlane], weighing: &Weighing) -> Decisions {
    weighed_at(points, 10.0, planes, weighing)
}

/// [`weighed`] for points of echo intensity `intensity`.
fn weighed_at(
    points: &[[f32; 3]],
    intensity: f32,
    planes: &[BoundedPlane],
    weighing: &Weighing,
) -> Decisions {
    weighed_seeing(points, intensity, planes, weighing, None)
}

/// [`weighed_at`] with the surfaces `seen` directly (sensor frame).
fn weighed_seeing(
    points: &[[f32; 3]],
    intensity: f32,
    planes: &[BoundedPlane],
    weighing: &Weighing,
    seen: Option<&dyn SurfaceSupport>,
) -> Decisions {
    weighed_in(points, intensity, planes, weighing, seen, &room_space())
}

/// [`weighed_seeing`] with the space seen `space`.
fn weighed_in(
    points: &[[f32; 3]],
    intensity: f32,
    planes: &[BoundedPlane],
    weighing: &Weighing,
    seen: Option<&dyn SurfaceSupport>,
    space: &crate::classify::SpaceMap,
) -> Decisions {
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    let f = frame(points, intensity);
    let scan = OrganizedScan::build(&f, &sensor).unwrap();
    let params = DecisionParams::default();
    let beams = BeamPlanes::hulls(planes, 0.0);
    let hits = BeamHits::compute(&f, &scan, &beams, params.glass_distance);
    let view = space.in_sensor_frame(Isometry3::identity());
    let ctx = FrameContext {
        frame: &f,
        scan: &scan,
        sensor: &sensor,
        bounded: planes,
        hits: &hits,
        support: seen,
        space: Some(&view),
    };
    decide_weighed(&ctx, &params, weighing)
}

fn only(tests: &[&str]) -> Weighing {
    Weighing::from_params(&WeighingParams {
        tests: tests.iter().map(|s| s.to_string()).collect(),
        ..WeighingParams::default()
    })
    .unwrap()
}

/// A test that calls every point a reflection, as strongly as asked.
#[derive(Debug)]
struct Always(f64);

impl EvidenceTest for Always {
    fn name(&self) -> &str {
        "always"
    }
    fn weigh(&self, _: &BehindPoint<'_>) -> Option<f64> {
        Some(self.0)
    }
}

/// With no test, a point behind glass is as likely either: unclassified at
/// confidence 0.5; behind a mirror it is a reflection, nearly certain.
#[test]
fn the_landmark_prior_decides_without_evidence() {
    let point = [[5.5f32, 0.2, 0.3]];
    let mut planes = pane();
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Unclassified]);
    assert!((d.confidence[0] - 0.5).abs() < 1e-6);
    planes[0].mirror_probability = Some(1.0);
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Reflection]);
    assert_eq!(d.rules, [Rule::Prior]);
    assert!(d.confidence[0] > 0.99, "{:?}", d.confidence);
}

/// Behind glass, a point that no test weighs takes the share of
/// reflections the seen space decided among its landmark's echoes as its
/// prior (mixed with the landmark's mirror probability); a point a test
/// weighs keeps the landmark's prior, and a share of the echoes' strengths
/// takes precedence.
#[test]
fn an_untested_point_takes_the_decided_share() {
    let point = [[5.5f32, 0.2, 0.3]];
    let mut planes = pane();
    planes[0].mirror_probability = Some(0.0);
    planes[0].decided_share = Some(0.1);
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Obstacle]);
    assert_eq!(d.rules, [Rule::Prior]);
    assert!((d.confidence[0] - 0.9).abs() < 1e-6, "{:?}", d.confidence);
    // A test that weighs, however little, leaves the prior at 0.5.
    let nudged = only(&[]).with_test(Box::new(Always(0.1)));
    assert_eq!(
        weighed(&point, &planes, &nudged).classes,
        [Class::Reflection]
    );
    // The decided share is that of the landmark as glass: behind a likely
    // mirror an untested point is a reflection, at the mirror's odds.
    planes[0].mirror_probability = Some(0.9);
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Reflection]);
    assert!((d.confidence[0] - 0.91).abs() < 1e-6, "{:?}", d.confidence);
    planes[0].mirror_probability = Some(0.0);
    // The strengths' share, where it exists, is the prior of every point.
    planes[0].reflection_share = Some(0.8);
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Reflection]);
    assert!((d.confidence[0] - 0.8).abs() < 1e-6, "{:?}", d.confidence);
}

/// Behind a second pane, a point no test weighs takes the nearer pane's
/// share: it is no likelier real than one behind that pane alone.
#[test]
fn a_point_behind_two_panes_takes_the_nearer_ones_prior() {
    let point = [[6.5f32, 0.2, 0.3]];
    let mut planes = two_panes();
    planes[0].mirror_probability = Some(0.0);
    planes[0].reflection_share = Some(0.8);
    planes[1].mirror_probability = Some(0.0);
    planes[1].reflection_share = Some(0.1);
    let d = weighed(&point, &planes, &only(&[]));
    assert_eq!(d.classes, [Class::Reflection]);
    assert_eq!(d.rules, [Rule::Prior]);
    assert!((d.confidence[0] - 0.8).abs() < 1e-6, "{:?}", d.confidence);
}

/// Behind a second pane the echo strength still weighs, by the nearer
/// pane's groups: a reflection in it keeps its weak echo wherever it
/// appears (the "second pane" may be a facade seen through the first).
#[test]
fn behind_two_panes_the_echo_strength_weighs_by_the_nearer_pane() {
    let point = [[8.0f32, 0.2, 0.3]];
    let mut planes = two_panes();
    planes[0].echo_split = Some(split());
    let strength = only(&["echo-strength"]);
    let weak = weighed_at(&point, 1.0, &planes, &strength);
    assert_eq!(weak.classes, [Class::Reflection]);
    assert_eq!(weak.rules, [Rule::EchoStrength]);
    let strong = weighed_at(&point, 100.0, &planes, &strength);
    assert_eq!(strong.classes, [Class::Obstacle]);
    // Without the nearer pane's groups nothing weighs: an even tie.
    planes[0].echo_split = None;
    let none = weighed_at(&point, 1.0, &planes, &strength);
    assert_eq!(none.classes, [Class::Unclassified]);
}

/// The point's mirror image lands in the room, seen free: the seen-space
/// test calls it real (an Obstacle, with the test's confidence), and a
/// stronger custom test added from outside overrules it.
#[test]
fn tests_weigh_and_a_stronger_one_overrules() {
    let point = [[5.5f32, 0.2, 0.3]];
    let planes = pane();
    let seen = only(&["seen-space"]);
    let d = weighed(&point, &planes, &seen);
    assert_eq!(d.classes, [Class::Obstacle]);
    assert_eq!(d.rules, [Rule::RealRefuted]);
    let expected = 1.0 - SeenSpace::default().error;
    assert!(
        (d.confidence[0] as f64 - expected).abs() < 1e-6,
        "{:?}",
        d.confidence
    );
    // A custom test weighing less does not change the class ...
    let weak = only(&["seen-space"]).with_test(Box::new(Always(1.0)));
    assert_eq!(weighed(&point, &planes, &weak).classes, [Class::Obstacle]);
    // ... one weighing more does, and is reported as the deciding rule.
    let strong = only(&["seen-space"]).with_test(Box::new(Always(10.0)));
    let d = weighed(&point, &planes, &strong);
    assert_eq!(d.classes, [Class::Reflection]);
    assert_eq!(d.rules, [Rule::Weighed]);
    assert_eq!(strong.test_names(), ["seen-space", "always"]);
}

/// A posterior short of the threshold leaves the point unclassified.
#[test]
fn a_posterior_short_of_the_threshold_is_unclassified() {
    let point = [[5.5f32, 0.2, 0.3]];
    let planes = pane();
    let cautious = Weighing::from_params(&WeighingParams {
        tests: vec![],
        threshold: 0.9,
        ..WeighingParams::default()
    })
    .unwrap()
    .with_test(Box::new(Always(1.0)));
    let d = weighed(&point, &planes, &cautious);
    assert_eq!(d.classes, [Class::Unclassified]);
    let sure = cautious.with_test(Box::new(Always(2.0)));
    assert_eq!(weighed(&point, &planes, &sure).classes, [Class::Reflection]);
}

/// Unknown names and thresholds outside [0.5, 1) are refused.
#[test]
fn unknown_tests_and_bad_thresholds_are_refused() {
    let err = Weighing::from_params(&WeighingParams {
        tests: vec!["crystal-ball".into()],
        ..WeighingParams::default()
    })
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("crystal-ball") && err.contains("seen-space"),
        "{err}"
    );
    assert!(Weighing::from_params(&WeighingParams {
        threshold: 0.3,
        ..WeighingParams::default()
    })
    .is_err());
    assert!(Weighing::default()
        .test_names()
        .iter()
        .all(|n| TEST_NAMES.contains(n)));
}

/// The depth test favours a real point deeper than the room, and the
/// outcome weight is the log-odds of its error rate.
#[test]
fn depth_and_outcome_weight() {
    assert!((outcome_weight(0.1) - 9f64.ln()).abs() < 1e-12);
    assert_eq!(outcome_weight(0.5), 0.0);
    let planes = pane();
    // Nothing in front of the pane: the room is 0 m deep, the point 0.5 m.
    let d = weighed(&[[5.5f32, 0.2, 0.3]], &planes, &only(&["depth"]));
    assert_eq!(d.classes, [Class::Obstacle]);
    let _ = Point3::<f64>::origin();
}

/// A point behind glass at the height of a floor that runs on behind the
/// landmark is real (an Obstacle); without that floor the test says
/// nothing, and behind a mirror it weighs nothing.
#[test]
fn a_floor_running_on_behind_glass_makes_its_points_real() {
    let point = [[5.5f32, 0.2, 0.3]];
    let mut planes = pane();
    let weighing = only(&["level-surface"]);
    let d = weighed(&point, &planes, &weighing);
    assert_eq!(d.classes, [Class::Unclassified]);
    planes[0].levels_behind = vec![0.32];
    let d = weighed(&point, &planes, &weighing);
    assert_eq!(d.classes, [Class::Obstacle]);
    assert_eq!(d.rules, [Rule::LevelSurface]);
    planes[0].levels_behind = vec![0.6];
    let d = weighed(&point, &planes, &weighing);
    assert_eq!(d.classes, [Class::Unclassified]);
    planes[0].levels_behind = vec![0.32];
    planes[0].mirror_probability = Some(1.0);
    let d = weighed(&point, &planes, &weighing);
    assert_eq!(d.classes, [Class::Reflection]);
}

/// Surface points seen directly (sensor frame).
struct Seen(Vec<Point3<f64>>);

impl SurfaceSupport for Seen {
    fn near(&self, p: &Point3<f64>, radius: f64) -> bool {
        self.0.iter().any(|q| (q - p).norm() <= radius)
    }
}

/// A wall seen directly at `x` = const (`along_x` false) or `y` = const
/// (`along_x` true, running from x = -3 to the pane), sampled every 0.1 m.
fn wall(at: f64, along_x: bool) -> Seen {
    let mut points = Vec::new();
    for i in -30..=50 {
        for k in -10..=15 {
            let (u, z) = (i as f64 * 0.1, k as f64 * 0.1);
            points.push(match along_x {
                false if u.abs() <= 2.0 => Point3::new(at, u, z),
                false => continue,
                true if u < 5.0 => Point3::new(u, at, z),
                true => continue,
            });
        }
    }
    Seen(points)
}

/// A mirror image on the room's far wall, which it leaves when moved 1 m
/// along the normal, supports a reflection, at the odds of the test's two
/// rates times the landmark's share; an image on a side wall running along the normal stays on it
/// when moved and says nothing, as does an image in front of no surface.
#[test]
fn an_image_landing_only_where_mirrored_supports_a_reflection() {
    let planes = pane();
    let test = only(&["image-support"]);
    let far = wall(-3.0, false);
    // 8 m behind the pane at x = 5: its image is on the far wall at x = -3.
    let behind = [[13.0f32, 0.2, 0.3]];
    let d = weighed_seeing(&behind, 10.0, &planes, &test, Some(&far));
    assert_eq!(d.classes, [Class::Reflection]);
    assert_eq!(d.rules, [Rule::Support]);
    let rates = ImageSupport::default();
    let odds = rates.reflection_rate / rates.chance_rate;
    let expected = odds / (1.0 + odds);
    assert!(
        (d.confidence[0] as f64 - expected).abs() < 1e-5,
        "{:?}",
        d.confidence
    );
    // 3 m behind: its image at x = 2 is on no surface.
    let nearer = [[8.0f32, 0.2, 0.3]];
    let d = weighed_seeing(&nearer, 10.0, &planes, &test, Some(&far));
    assert_eq!(d.classes, [Class::Unclassified]);
    // On a side wall at y = 1.5 the image stays on the wall when moved.
    let side = wall(1.5, true);
    let beside = [[8.0f32, 1.5, 0.3]];
    let d = weighed_seeing(&beside, 10.0, &planes, &test, Some(&side));
    assert_eq!(d.classes, [Class::Unclassified]);
    // Its weight is a likelihood ratio: behind glass whose decided share
    // is 1 %, it adds to that share, not to even odds, and leaves the
    // point real.
    let mut rare = planes.clone();
    rare[0].mirror_probability = Some(0.0);
    rare[0].decided_share = Some(0.01);
    let d = weighed_seeing(&behind, 10.0, &rare, &test, Some(&far));
    assert_eq!(d.classes, [Class::Obstacle]);
    let prior_odds = 0.01 / 0.99;
    let expected = 1.0 / (1.0 + prior_odds * odds);
    assert!(
        (d.confidence[0] as f64 - expected).abs() < 1e-5,
        "{:?}",
        d.confidence
    );
    // Where a surface was seen at the measured position, the image says
    // nothing either (the seen-surface test weighs that).
    let mut both = far.0.clone();
    both.push(Point3::new(13.0, 0.2, 0.3));
    let d = weighed_seeing(&behind, 10.0, &planes, &test, Some(&Seen(both)));
    assert_eq!(d.classes, [Class::Unclassified]);
}

/// [`ImageLanding::lands`] checks only the end of the path seen free, as
/// the full seen-space test ([`ImageLanding::refuted`]) decides a path
/// towards a seen surface: the two agree on a grid of images around the
/// room's far wall, in front of it, behind it and in the room seen free,
/// where a thin post was seen.
#[test]
fn a_landing_is_refuted_only_by_its_end_seen_free() {
    let planes = pane();
    let space = room_space();
    let view = space.in_sensor_frame(Isometry3::identity());
    // The far wall, and a thin post in the room that the space map holds
    // as seen free (images there are refuted).
    let mut far = wall(-3.0, false);
    far.0.push(Point3::new(0.0, 0.0, 0.3));
    let seen_space = SeenSpace::default();
    let (mut landed, mut refuted) = (0, 0);
    for (px, py) in [(13.0, 0.2), (9.0, -1.0), (7.0, 1.5)] {
        let position = Point3::new(px, py, 0.3);
        let landing = ImageLanding::new(
            &view,
            Some(&far),
            &planes[0].plane,
            position,
            Point3::from(position.coords * (5.0 / px)),
            &seen_space,
            0.1,
        );
        for i in 0..=40 {
            for j in -8..=8 {
                let image = Point3::new(-5.0 + i as f64 * 0.25, j as f64 * 0.25, 0.3);
                let on = landing.on_seen_surface(&image);
                let full = on && !landing.refuted(&image);
                assert_eq!(landing.lands(&image), full, "{image}");
                landed += full as usize;
                refuted += (on && !full) as usize;
            }
        }
    }
    // Both outcomes occur: the grid tests the shortcut.
    assert!(
        landed > 0 && refuted > 0,
        "{landed} landed, {refuted} refuted"
    );
}

/// Where beams seen through the pane passed (confirmed transmissions from
/// the pane at x = 5 to a wall at x = 12), a point measured behind it is a
/// mirror image; one measured on the wall they ended on is real, and
/// without the space seen through glass the test does not speak.
#[test]
fn space_seen_through_the_glass_makes_a_reflection() {
    let planes = pane();
    let mut through = room_space().empty_like();
    for j in -10..=10 {
        for k in -10..=10 {
            let (y, z) = (0.2 + j as f64 * 0.03, 0.3 + k as f64 * 0.03);
            let (start, end) = (Point3::new(5.0, y, z), Point3::new(12.0, y * 2.4, z * 2.4));
            through.add_beam(&start, &end, 0.2, true);
        }
    }
    let mut space = room_space();
    space.set_through(through);
    let weighing = only(&["seen-through"]);
    // On the beams' way (x = 7.5), and on the wall they ended on.
    let points = [[7.5f32, 0.36, 0.54], [12.0, 0.48, 0.72]];
    let d = weighed_in(&points, 10.0, &planes, &weighing, None, &space);
    assert_eq!(d.classes[0], Class::Reflection);
    assert_eq!(d.rules[0], Rule::SeenThrough);
    assert_eq!(d.classes[1], Class::Obstacle);
    assert_eq!(d.rules[1], Rule::SeenThrough);
    let without = weighed_in(&points, 10.0, &planes, &weighing, None, &room_space());
    assert_eq!(without.classes, [Class::Unclassified; 2]);
}

/// A weak echo behind the pane is a reflection by its strength, but on a
/// surface seen through the glass it is labelled real whatever its path
/// (3DRef): there the echo strength does not speak, and the surface makes
/// it an Obstacle; behind a mirror it does not.
#[test]
fn on_a_surface_seen_through_the_glass_the_echo_strength_is_silent() {
    let mut planes = pane();
    planes[0].echo_split = Some(split());
    let point = [[8.0f32, 0.2, 0.3]];
    let strength = only(&["echo-strength"]);
    let weak = weighed_at(&point, 1.0, &planes, &strength);
    assert_eq!(weak.classes, [Class::Reflection]);
    let mut through = room_space().empty_like();
    let at = Point3::new(8.0, 0.2, 0.3);
    through.add_beam(&at, &at, 0.0, true);
    let mut space = room_space();
    space.set_through(through);
    let silent = weighed_in(&point, 1.0, &planes, &strength, None, &space);
    assert_eq!(silent.classes, [Class::Unclassified]);
    let both = only(&["echo-strength", "seen-through"]);
    let d = weighed_in(&point, 1.0, &planes, &both, None, &space);
    assert_eq!(d.classes, [Class::Obstacle]);
    assert_eq!(d.rules, [Rule::SeenThrough]);
    // Nothing is seen through a mirror: behind one the surface says
    // nothing, and the point is its reflection.
    planes[0].mirror_probability = Some(0.9);
    let mirror = weighed_in(&point, 1.0, &planes, &both, None, &space);
    assert_eq!(mirror.classes, [Class::Reflection]);
}
