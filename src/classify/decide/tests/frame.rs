//! The frame's own tests on small synthetic scenes: free space in the
//! frame, depth, mirror-image support, the dual-return rule and the
//! unseen continuation of a pane; each fails when its rule is off.

use super::*;

/// The frame's free-space test with a margin that grows with range: the
/// frame sees a wall 0.15 m beyond the mirror image of a point 8 m behind
/// the pane (3 m in front of the sensor), as an error of half a degree in
/// the plane's orientation puts it. A fixed 0.1 m margin calls the point
/// an Obstacle; 5 % of the range more leaves it to the other evidence.
#[test]
fn the_free_space_margin_grows_with_the_mirrored_range() {
    let planes = pane();
    let behind = Point3::new(13.0f64, 0.2, 0.3);
    let mirrored = planes[0].plane.mirror(&behind);
    let wall = mirrored.coords * ((mirrored.coords.norm() + 0.15) / mirrored.coords.norm());
    let points = [
        [behind.x as f32, behind.y as f32, behind.z as f32],
        [wall.x as f32, wall.y as f32, wall.z as f32],
    ];
    let fixed = DecisionParams {
        free_space_test: true,
        obstacle_tests_on_all_returns: true,
        ..rule_only(false)
    };
    let d = decide_in(&points, 50.0, &planes, &fixed, &SpaceMap::new(0.1, 2, 1));
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Obstacle, Rule::FrameFreeSpace)
    );
    let growing = DecisionParams {
        free_space_margin_ratio: 0.05,
        ..fixed
    };
    let d = decide_in(&points, 50.0, &planes, &growing, &SpaceMap::new(0.1, 2, 1));
    assert_eq!(d.classes[0], Class::Unclassified);
}

/// The decisions for points given with their return number (1 or 2; the
/// same direction pairs two returns of one beam).
fn decide_returns(points: &[([f32; 3], u8)], params: &DecisionParams) -> Decisions {
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    let xyz: Vec<[f32; 3]> = points.iter().map(|p| p.0).collect();
    let mut f = frame(&xyz, 50.0);
    for (point, &(_, ret)) in f.points.iter_mut().zip(points) {
        point.ret = ret;
    }
    let scan = OrganizedScan::build(&f, &sensor).unwrap();
    let planes = pane();
    let beams = BeamPlanes::hulls(&planes, 0.0);
    let hits = BeamHits::compute(&f, &scan, &beams, params.glass_distance);
    decide_with_hits(&f, &scan, &sensor, &planes, &hits, params, None, None)
}

/// The depth test (Zhao 2020): a point behind the pane deeper than any
/// indoor point is in front of it is an Obstacle. The room reaches 3 m in
/// front of the pane (a Normal point at x = 2); a point 4 m behind it is
/// deeper.
#[test]
fn a_point_deeper_than_the_room_is_an_obstacle() {
    let points = [([2.0f32, -1.0, 0.0], 1), ([9.0, 0.2, 0.3], 1)];
    let on = DecisionParams {
        depth_test: true,
        depth_margin: 0.1,
        obstacle_tests_on_all_returns: true,
        ..rule_only(false)
    };
    let d = decide_returns(&points, &on);
    assert_eq!((d.classes[1], d.rules[1]), (Class::Obstacle, Rule::Depth));
    assert_eq!(
        decide_returns(&points, &rule_only(false)).classes[1],
        Class::Unclassified
    );
    // A point 2 m behind is shallower than the room: the test is silent.
    let shallow = [([2.0f32, -1.0, 0.0], 1), ([7.0, 0.2, 0.3], 1)];
    assert_eq!(
        decide_returns(&shallow, &on).classes[1],
        Class::Unclassified
    );
}

/// Support: a point behind the pane whose mirror image lands on a Normal
/// point of the frame is a Reflection; off, it is undecided.
#[test]
fn a_mirror_image_on_an_observed_surface_is_a_reflection() {
    let planes = pane();
    let behind = Point3::new(7.0f64, 0.2, 0.3);
    let image = planes[0].plane.mirror(&behind);
    let points = [
        ([behind.x as f32, behind.y as f32, behind.z as f32], 1),
        ([image.x as f32, image.y as f32 + 0.05, image.z as f32], 1),
    ];
    let on = DecisionParams {
        support_test: true,
        support_radius: 0.316,
        ..rule_only(false)
    };
    let d = decide_returns(&points, &on);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Reflection, Rule::Support)
    );
    assert_eq!(
        decide_returns(&points, &rule_only(false)).classes[0],
        Class::Unclassified
    );
}

/// A point 0.12 m behind the pane (a wall behind a glass leaf parked
/// against it) has its mirror image 0.24 m from itself, within the support
/// radius: whatever surface lies there (here a Normal point 0.2 m in front
/// of the pane), the point's own surface would support the image as well,
/// so it is no evidence of a reflection. With
/// `support_excludes_own_surface` the point stays undecided, without it
/// the support calls it a Reflection. A point 2 m behind is supported as
/// before.
#[test]
fn a_mirror_image_beside_the_point_itself_is_no_support() {
    let planes = pane();
    let points = [([5.12f32, 0.2, 0.3], 1), ([4.8, 0.2, 0.45], 1)];
    let support = DecisionParams {
        support_test: true,
        support_radius: 0.316,
        behind_distance: 0.1,
        ..rule_only(false)
    };
    let own = DecisionParams {
        support_excludes_own_surface: true,
        ..support
    };
    let d = decide_returns(&points, &support);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Reflection, Rule::Support)
    );
    let d = decide_returns(&points, &own);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Unclassified, Rule::Undecided)
    );
    // Far behind, the image lies on a surface of its own.
    let behind = Point3::new(7.0f64, 0.2, 0.3);
    let image = planes[0].plane.mirror(&behind);
    let far = [
        ([behind.x as f32, behind.y as f32, behind.z as f32], 1),
        ([image.x as f32, image.y as f32 + 0.05, image.z as f32], 1),
    ];
    let d = decide_returns(&far, &own);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Reflection, Rule::Support)
    );
}

/// A horizontal surface (a shelf, a floor) continuing across the pane is
/// its own mirror image: a point on its far side and the reflection of
/// its near side land at the same place. The sequence saw the shelf in
/// front of the pane (z = -0.8, x = 2..4) and a wall facing the pane
/// (x = 2). With `perpendicular_support_deg` the shelf is no evidence and
/// the point on its continuation stays undecided; without it the support
/// calls it a Reflection. The wall supports its image either way.
#[test]
fn support_from_a_surface_perpendicular_to_the_pane_is_no_evidence() {
    let planes = pane();
    let mut seen = Vec::new();
    for i in 0..=40 {
        for j in 0..=28 {
            let (u, v) = (f64::from(i) * 0.05, f64::from(j) * 0.05);
            seen.push(Point3::new(2.0 + u, -0.5 + v, -0.8));
            seen.push(Point3::new(2.0, -0.5 + v, 0.015 * f64::from(i)));
        }
    }
    let world = crate::classify::support::WorldSupport::build(seen, 0.05, 0.316);
    let view = world.in_sensor_frame(Isometry3::identity());
    let on_shelf = Point3::new(7.0f64, 0.2, -0.8);
    let facing_wall = Point3::new(8.0f64, 0.2, 0.3);
    let xyz = [on_shelf, facing_wall].map(|p| [p.x as f32, p.y as f32, p.z as f32]);
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    let f = frame(&xyz, 50.0);
    let scan = OrganizedScan::build(&f, &sensor).unwrap();
    let beams = BeamPlanes::hulls(&planes, 0.0);
    let support = DecisionParams {
        support_test: true,
        support_radius: 0.316,
        ..rule_only(false)
    };
    let perpendicular = DecisionParams {
        perpendicular_support_deg: 15.0,
        ..support
    };
    let decide = |params: &DecisionParams| {
        let hits = BeamHits::compute(&f, &scan, &beams, params.glass_distance);
        let d = decide_with_hits(
            &f,
            &scan,
            &sensor,
            &planes,
            &hits,
            params,
            Some(&view),
            None,
        );
        [0, 1].map(|i| (d.classes[i], d.rules[i]))
    };
    let supported = (Class::Reflection, Rule::Support);
    assert_eq!(decide(&support), [supported, supported]);
    assert_eq!(
        decide(&perpendicular),
        [(Class::Unclassified, Rule::Undecided), supported]
    );
}

/// The dual-return rule: where a beam's far return is an Obstacle behind
/// the pane, its near return behind the same pane is a Reflection.
#[test]
fn the_near_return_of_an_obstacle_beam_is_a_reflection() {
    // Two returns along one direction: 1 m and 4 m behind the pane; the
    // far one deeper than the room (a Normal point 3 m in front).
    let dir = Vector3::new(1.0f64, 0.04, 0.06).normalize();
    let at = |x: f64| {
        let p = dir * (x / dir.x);
        [p.x as f32, p.y as f32, p.z as f32]
    };
    let points = [([2.0f32, -1.0, 0.0], 1), (at(6.0), 1), (at(9.0), 2)];
    let depth_only = DecisionParams {
        depth_test: true,
        depth_margin: 0.1,
        ..rule_only(false)
    };
    let without = decide_returns(&points, &depth_only);
    assert_eq!(without.classes[2], Class::Obstacle);
    assert_eq!(without.classes[1], Class::Unclassified);
    let with = decide_returns(
        &points,
        &DecisionParams {
            dual_return_rule: true,
            ..depth_only
        },
    );
    assert_eq!(
        (with.classes[1], with.rules[1]),
        (Class::Reflection, Rule::DualReturn)
    );
}

/// Glass may continue past the last echo (a tall pane's top above the
/// sensor gives none). A point behind the plane 0.3 m above the pane's
/// seen top, whose mirror image lands on a surface the frame saw, is a
/// Reflection with the rule on; without it, or where the evidence saw an
/// opaque plane there, it is Normal.
#[test]
fn a_point_past_the_seen_extent_is_a_reflection_when_its_mirror_image_is_supported() {
    // Behind the plane at (6, 0, 2.76): its beam crosses x = 5 at z = 2.3,
    // above the pane's top (z = 2). Its mirror image (4, 0, 2.76) is a
    // surface the frame saw.
    let points = [[6.0f32, 0.0, 2.76], [4.0, 0.0, 2.76]];
    let run = |planes: &[BoundedPlane], unseen_extent: f64| {
        let params = DecisionParams {
            support_test: true,
            support_radius: 0.3,
            unseen_extent,
            unseen_extent_beside: unseen_extent,
            ..rule_only(false)
        };
        decide_in(&points, 50.0, planes, &params, &SpaceMap::new(0.1, 2, 1))
    };
    let d = run(&pane(), 1.0);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Reflection, Rule::PastSeenExtent)
    );
    assert_eq!(d.classes[1], Class::Normal);
    let d = run(&pane(), 0.0);
    assert_eq!((d.classes[0], d.rules[0]), (Class::Normal, Rule::NoPane));
    // Out of reach: 0.2 m past the top is within 0.25 m, 0.3 m is not.
    let d = run(&pane(), 0.25);
    assert_eq!(d.classes[0], Class::Normal);
    // Opaque votes where the beam crosses: a wall strip above the pane.
    let mut planes = pane();
    let chart = planes[0].chart;
    let mut grid = empty_grid();
    grid.vote(&chart.to_2d(&Point3::new(5.0, 0.0, 2.3)), 0, 5);
    grid.finalize();
    planes[0].evidence = Some(std::sync::Arc::new(grid));
    let d = run(&planes, 1.0);
    assert_eq!((d.classes[0], d.rules[0]), (Class::Normal, Rule::NoPane));
}

/// Glass continues unseen farther above a pane than beside or below it:
/// the sensor met the plane head-on where it passed, and glass meets a
/// floor or a parapet at its foot. The point of the test above, moved so
/// that its beam crosses the plane 0.3 m beside the pane (at the pane's
/// height) or 0.3 m below its foot, is behind unseen glass only where the
/// reach beside and below goes that far, however far the reach above goes.
#[test]
fn a_point_beside_or_below_the_seen_extent_needs_the_reach_beside() {
    // Behind the plane at (6, 2.76, 0.5): its beam crosses x = 5 at
    // y = 2.3, beside the pane (y up to 2); at (6, 0, -1.56) it crosses at
    // z = -1.3, below the pane's foot (z = -1). Their mirror images
    // (x = 4) are surfaces the frame saw.
    let points = [
        [6.0f32, 2.76, 0.5],
        [4.0, 2.76, 0.5],
        [6.0, 0.0, -1.56],
        [4.0, 0.0, -1.56],
    ];
    let run = |unseen_extent_beside: f64| {
        let params = DecisionParams {
            support_test: true,
            support_radius: 0.3,
            unseen_extent: 4.0,
            unseen_extent_beside,
            ..rule_only(false)
        };
        decide_in(&points, 50.0, &pane(), &params, &SpaceMap::new(0.1, 2, 1))
    };
    let d = run(0.25);
    for i in [0, 2] {
        assert_eq!((d.classes[i], d.rules[i]), (Class::Normal, Rule::NoPane));
    }
    let d = run(1.0);
    for i in [0, 2] {
        assert_eq!(
            (d.classes[i], d.rules[i]),
            (Class::Reflection, Rule::PastSeenExtent)
        );
    }
}

/// Past the seen extent the sequence's space decides too: where the point
/// was measured, other beams saw free space, so it is a mirror image.
#[test]
fn a_point_past_the_seen_extent_in_seen_free_space_is_a_reflection() {
    // Space behind the plane seen free from a pose beyond it.
    let mut space = SpaceMap::new(0.1, 2, 1);
    let origin = Point3::new(9.0, 0.0, 2.76);
    for j in -5..=5 {
        for k in -5..=5 {
            let end = Point3::new(5.2, j as f64 * 0.05, 2.76 + k as f64 * 0.05);
            space.add_beam(&origin, &end, 0.0, false);
        }
    }
    let run = |unseen_extent: f64| {
        let params = DecisionParams {
            unseen_extent,
            ..rule_only(true)
        };
        decide_in(&[[6.0, 0.0, 2.76]], 50.0, &pane(), &params, &space)
    };
    let d = run(1.0);
    assert_eq!(
        (d.classes[0], d.rules[0]),
        (Class::Reflection, Rule::RealRefuted)
    );
    assert_eq!(run(0.0).classes, [Class::Normal]);
}
