//! Evidence on a synthetic pane: openings where the sensor crossed, bare
//! passes, echoes of another surface.

use super::*;
use nalgebra::Point3;

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
                    time: 0.0,
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
    let plane = crate::geometry::Plane::new(nalgebra::Vector3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
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
    let f = EvidenceFrame::new(&frame, &scan, Isometry3::identity(), &sensor);
    let params = EvidenceParams::BARE;
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
    let f = EvidenceFrame::new(&frame, &scan, Isometry3::identity(), &sensor);
    let off = EvidenceParams::BARE;
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
    let f = EvidenceFrame::new(&frame, &scan, Isometry3::identity(), &sensor);
    let off = EvidenceParams::BARE;
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

/// A landmark whose plane is off the pane of [`pane_frame`] (turned by 1
/// degree about the vertical and 3 cm behind it, as a moving average of
/// partial views leaves a long wall) is refitted onto the pane's glass
/// echoes (x = 5): with the refit on, the plane comes back to within a
/// millimetre and a hundredth of a degree; with it off, there is no refit.
/// A turn beyond `refit_max_angle_deg` is refused.
#[test]
fn a_plane_off_its_glass_echoes_is_refitted_onto_them() {
    use crate::geometry::Plane;
    use crate::sensor::SensorModel;
    use nalgebra::{Rotation3, Vector3};
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    let frame = pane_frame(&sensor);
    let scan = OrganizedScan::build(&frame, &sensor).unwrap();
    let f = EvidenceFrame::new(&frame, &scan, Isometry3::identity(), &sensor);
    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 1f64.to_radians());
    let off =
        Plane::from_point_normal(&Point3::new(5.03, 0.0, 0.0), &(turn * -Vector3::x())).unwrap();
    let landmark = BoundedPlane::from_points(
        off,
        [(-1.8, -1.2), (0.4, -1.2), (0.4, 1.2), (-1.8, 1.2)]
            .iter()
            .map(|&(y, z)| Point3::new(5.0, y, z)),
    );
    let refit = |params: &EvidenceParams| {
        let gatherer = EvidenceGatherer::new(&landmark, params).unwrap();
        gatherer.refitted_plane(&gatherer.glass_echo_sums(&f))
    };
    let on = EvidenceParams {
        refit_plane: true,
        ..EvidenceParams::BARE
    };
    let fit = refit(&on).expect("a refit");
    let pane = Plane::new(-Vector3::x(), 5.0).unwrap();
    assert!(
        fit.normal.angle(&pane.normal).to_degrees() < 0.01,
        "{fit:?}"
    );
    assert!((fit.d - pane.d).abs() < 1e-3, "{fit:?}");
    assert_eq!(refit(&EvidenceParams::BARE), None);
    let strict = EvidenceParams {
        refit_max_angle_deg: 0.5,
        ..on
    };
    assert_eq!(refit(&strict), None);
    let few = EvidenceParams {
        refit_min_echoes: 1_000_000,
        ..on
    };
    assert_eq!(refit(&few), None);
}

/// A single echo on the plane votes "glass" where it is no stronger than
/// the landmark's glass echoes met at the same incidence, and those are
/// much weaker than what lies behind them (a pane above the sky); not
/// where it is stronger (a wall strip), not at an incidence no glass echo
/// was met at, and not at all when the landmark's echoes are as strong as
/// what lies behind them (a glossy panel, whose neighbouring walls are no
/// stronger than its echoes).
#[test]
fn weak_single_echoes_vote_glass_only_against_weak_glass_echoes_at_their_incidence() {
    let params = EvidenceParams::METHOD;
    let gatherer = EvidenceGatherer::new(&pane_landmark(), &params).unwrap();
    let (glass_at, wall_at, elsewhere) = (
        Point2::new(-1.0, 0.0),
        Point2::new(0.0, 0.5),
        Point2::new(-0.5, -0.8),
    );
    let votes_with_behind = |behind: f32| {
        let mut votes = Votes::default();
        for _ in 0..100 {
            votes.glass_echo_intensity.push(10.0);
            votes.glass_echo_strength.push((3, 1.0, behind));
        }
        for _ in 0..5 {
            votes.single_echoes.push((glass_at, 5.0, 3, 1.0));
            votes.single_echoes.push((wall_at, 5.0, 3, 2.0));
            votes.single_echoes.push((elsewhere, 5.0, 6, 0.5));
        }
        let mut total = gatherer.total();
        total.add(FrameVotes {
            grid: gatherer.empty.empty_like(),
            votes,
        });
        total.finish()
    };
    let weak_glass = votes_with_behind(3.0);
    assert_eq!(weak_glass.echoes_near(&glass_at, 0.0), 5);
    assert_eq!(weak_glass.echoes_near(&wall_at, 0.0), 0);
    assert_eq!(weak_glass.echoes_near(&elsewhere, 0.0), 0);
    let glossy = votes_with_behind(1.2);
    assert_eq!(glossy.echoes_near(&glass_at, 0.0), 0);
    let off = EvidenceParams {
        weak_single_echo_votes: false,
        ..params
    };
    let gatherer = EvidenceGatherer::new(&pane_landmark(), &off).unwrap();
    let mut votes = Votes::default();
    votes.glass_echo_intensity.push(10.0);
    votes.single_echoes.push((glass_at, 5.0, 3, 1.0));
    let mut total = gatherer.total();
    total.add(FrameVotes {
        grid: gatherer.empty.empty_like(),
        votes,
    });
    assert_eq!(total.finish().echoes_near(&glass_at, 0.0), 0);
}

/// The incidence bins are 10 degrees wide, the last holding everything
/// from 80 degrees on, whichever side the beam meets the plane from.
#[test]
fn incidence_bins_are_ten_degrees_wide() {
    use crate::geometry::grid::incidence_bin;
    assert_eq!(incidence_bin(1.0), 0);
    assert_eq!(incidence_bin(-1.0), 0);
    assert_eq!(incidence_bin(35f64.to_radians().cos()), 3);
    assert_eq!(incidence_bin(-35f64.to_radians().cos()), 3);
    assert_eq!(incidence_bin(0.0), 8);
}
