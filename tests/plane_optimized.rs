//! The plane-optimized pipeline: real frames, a synthetic mirror, and the
//! empty-map case.

mod common;

use nalgebra::{Isometry3, Point3, Vector3};
use specular::classify::mirror::mirror_reflections;
use specular::classify::Class;
use specular::cloud::{Frame, Point};
use specular::config::{Config, Method};
use specular::io::{self, PlyEncoding, StampedPose};
use specular::pipeline::registry::{self, DatasetSource};
use specular::pipeline::{run_plane_optimized, Sequence, StageTimings};
use specular::sensor::SensorModel;
use specular::sim::{LabelRule, SceneSource};

fn config(name: &str) -> Config {
    let mut c = Config::resolve(name).unwrap();
    c.method = Method::PlaneOptimized;
    c
}

fn load(dir: &std::path::Path, poses: &std::path::Path) -> Sequence {
    Sequence::load(dir, Some(poses), 0.01, &mut StageTimings::default()).unwrap()
}

/// The acceptance bar of the plane-optimized issue: every metric beats the
/// original code's plane-optimized result on the ten shared frames.
#[test]
fn default_config_beats_the_original_on_the_ten_shared_frames() {
    let Some(dir) = common::shared_frames() else {
        return;
    };
    let seq = load(&dir, &dir.join("hesai_pose.txt"));
    let out = run_plane_optimized(&seq, &config("default")).unwrap();
    let m = out.run.confusion.unwrap().metrics();
    let t = m.table();
    assert!(m.accuracy > 95.0, "{t}");
    assert!(m.reflection_removal > 90.1, "{t}");
    assert!(m.non_reflection_precision > 99.54, "{t}");
    assert!(m.indoor_precision > 99.55, "{t}");
    assert!(m.class(Class::Normal).iou > 96.8, "{t}");
    assert!(m.class(Class::Glass).iou > 63.1, "{t}");
    assert!(m.class(Class::Reflection).iou > 59.3, "{t}");
    assert!(m.class(Class::Obstacle).iou > 31.7, "{t}");
    // One window landmark, seen in every frame.
    assert_eq!(out.used.len(), 1);
    assert_eq!(out.map.landmarks[out.used[0]].observations, 10);
}

#[test]
fn paper_config_fuses_the_window_from_the_sample() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), &dir.join("poses.txt"));
    let mut c = config("paper");
    c.map.min_observations = 3; // the sample has three frames
    let out = run_plane_optimized(&seq, &c).unwrap();
    assert_eq!(out.used.len(), 1);
    let l = &out.map.landmarks[out.used[0]];
    assert_eq!(l.observations, 3);
    // World frame: the 3DRef window is the plane y ~ 4.98 facing -y.
    assert!(
        l.plane.normal.dot(&Vector3::new(0.0, -1.0, 0.0)) > 0.99,
        "{}",
        l.plane.normal
    );
    assert!((l.plane.d - 4.98).abs() < 0.1, "{}", l.plane.d);
}

#[test]
fn a_map_without_reflective_planes_classifies_everything_normal() {
    let dir = common::sample_dir();
    let seq = load(&dir.join("frames"), &dir.join("poses.txt"));
    let mut c = config("default");
    c.map.min_observations = 1000; // no landmark qualifies
    let out = run_plane_optimized(&seq, &c).unwrap();
    assert!(out.used.is_empty());
    for f in &out.run.frames {
        assert!(
            f.classes.iter().all(|&c| c == Class::Normal),
            "frame {}",
            f.name
        );
    }
}

/// Ray-box intersection (slab method): the entry range along a unit ray.
fn hit_box(o: &Point3<f64>, d: &Vector3<f64>, lo: &Point3<f64>, hi: &Point3<f64>) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        if d[k].abs() < 1e-12 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    (t0 <= t1 && t0 > 1e-9).then_some(t0)
}

fn box_distance(p: &Point3<f64>, lo: &Point3<f64>, hi: &Point3<f64>) -> f64 {
    // Distance to the box surface (0 on it).
    let inside = (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
    if inside {
        (0..3)
            .map(|k| (p[k] - lo[k]).min(hi[k] - p[k]))
            .fold(f64::INFINITY, f64::min)
    } else {
        (0..3)
            .map(|k| (lo[k] - p[k]).max(0.0).max(p[k] - hi[k]))
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt()
    }
}

/// A noise-free QT64 frame of a wall mirror at x = 4 (|y| < 3, |z| < 2) and
/// a box (`lo`..`hi`) beside the sensor: beams meeting the mirror return its surface echo
/// (first) and, where the mirrored ray meets the box, the reflection at the
/// total path length along the original beam (last). Beams meeting the box
/// directly return it; a back wall at x = -6 closes the room.
fn mirror_frame(sensor: &SensorModel, lo: &Point3<f64>, hi: &Point3<f64>) -> Frame {
    let mirror = specular::geometry::Plane::new(Vector3::new(-1.0, 0.0, 0.0), 4.0).unwrap();
    let o = Point3::origin();
    let mut points = Vec::new();
    let mut push = |p: Point3<f64>, ring: usize, ret: u8, label: u8| {
        points.push(Point {
            xyz: [p.x as f32, p.y as f32, p.z as f32],
            intensity: if label == 3 { 20.0 } else { 150.0 },
            ring: ring as u16,
            ret,
            label,
            time: 0.0,
        })
    };
    for ring in 0..sensor.rings() {
        for col in 0..sensor.columns {
            let d = sensor.beam_direction(ring, col);
            let direct_box = hit_box(&o, &d, lo, hi);
            let on_mirror = mirror.ray_intersection(&o, &d).filter(|&t| {
                let q = o + d * t;
                q.y.abs() < 3.0 && q.z.abs() < 2.0
            });
            match (direct_box, on_mirror) {
                (Some(tb), m) if m.is_none_or(|tm| tb < tm) => push(o + d * tb, ring, 1, 1),
                (_, Some(tm)) => {
                    let q = o + d * tm;
                    push(q, ring, 1, 3);
                    let r = mirror.mirror_vector(&d);
                    if let Some(tb) = hit_box(&q, &r, lo, hi) {
                        push(o + d * (tm + tb), ring, 2, 5);
                    }
                }
                _ => {
                    if d.x < -0.05 {
                        push(o + d * (-6.0 / d.x), ring, 1, 1);
                    }
                }
            }
        }
    }
    Frame {
        name: "1000.000000".into(),
        stamp: 1000.0,
        points,
        has_labels: true,
        dropped_non_finite: 0,
        intensity_scale: None,
    }
}

#[test]
fn reflections_of_a_box_are_mirrored_back_onto_the_box() {
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    // A board beside the sensor: its face towards +y is seen both directly
    // and in the mirror, so every reflection can be confirmed.
    let (lo, hi) = (Point3::new(0.5, -3.2, -1.5), Point3::new(3.5, -3.0, 1.0));
    let frame = mirror_frame(&sensor, &lo, &hi);
    let reflections = frame.points.iter().filter(|p| p.label == 5).count();
    assert!(
        reflections > 300,
        "scene too small: {reflections} reflections"
    );
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    io::write_frame(
        &frames.join("1000.000000.ply"),
        &frame,
        PlyEncoding::BinaryLittleEndian,
    )
    .unwrap();
    let poses = tmp.path().join("poses.txt");
    io::write_tum(
        &poses,
        &[StampedPose {
            stamp: 1000.0,
            pose: Isometry3::identity(),
        }],
    )
    .unwrap();
    let seq = load(&frames, &poses);
    let mut c = config("default");
    c.map.min_observations = 1;
    let out = run_plane_optimized(&seq, &c).unwrap();
    assert_eq!(out.used.len(), 1, "one mirror landmark");
    let classes = &out.run.frames[0].classes;
    let m = out.run.confusion.unwrap().metrics();
    assert!(m.class(Class::Reflection).recall > 90.0, "{}", m.table());
    assert!(m.class(Class::Glass).precision > 99.0, "{}", m.table());
    assert!(m.class(Class::Normal).recall > 99.0, "{}", m.table());
    // Mirrored back, every reflection lands on the box.
    let planes: Vec<_> = out
        .used
        .iter()
        .map(|&i| out.map.landmarks[i].bounded())
        .collect();
    let mirrored = mirror_reflections(&seq.frame(0).unwrap(), classes, &planes, 0.0);
    assert!(mirrored.len() * 10 > reflections * 9);
    for (i, q) in mirrored {
        assert!(
            box_distance(&q, &lo, &hi) < 0.02,
            "point {i} mirrored to {q}, off the box"
        );
    }
}

/// A room looking out through a coated window (reflectance 0.3, transmittance
/// 0.5: its echoes behind it form one strength group) must not be taken for
/// a mirror. Everything outside mirrors to beyond the room's walls, into
/// space nobody saw, so no point behind the window has its mirror image in
/// seen-free space; only the reflected paths through the room's walls show
/// that the ground and hedge outside are transmitted.
#[test]
fn a_window_looking_out_of_a_small_room_is_not_a_mirror() {
    let source = DatasetSource::Simulated {
        scene: SceneSource::Named("two-panes".into()),
        frames: Some(20),
        seed: None,
        // What is transmitted, physically: under 3DRef's rule the ground
        // outside is also an Obstacle where a reflection of the room's
        // floor lands on it, which no window test can see.
        labels: LabelRule::Physical,
        sensor: None,
    };
    let seq = Sequence::from_dataset(registry::dataset(&source).unwrap());
    let obstacles = |config: &Config| {
        let out = run_plane_optimized(&seq, config).unwrap();
        let m = out.run.confusion.unwrap().metrics();
        (m.class(Class::Obstacle).recall, m.table())
    };
    let (recall, table) = obstacles(&config("default"));
    assert!(recall > 20.0, "{table}");
}

/// Moving the world frame moves nothing: the map is fused relative to the
/// first pose, so poses given in a far-off frame (a map frame, UTM
/// coordinates) classify as the same poses near the origin do. The
/// merger's offset test compares plane offsets `d`, which grow with the
/// distance from the origin: fused in the world frame 2 km away, no two
/// observations of one window agree and the map loses its landmarks.
#[test]
fn a_far_off_world_frame_changes_nothing() {
    let seq = common::simulated_subset("office", (0..120).step_by(3));
    let shift = nalgebra::Translation3::new(2000.0, -1500.0, 40.0);
    let poses: Vec<Isometry3<f64>> = seq
        .poses
        .as_deref()
        .unwrap()
        .iter()
        .map(|p| shift * p)
        .collect();
    let far = Sequence::from_frames(seq.in_memory().unwrap().to_vec(), Some(poses), "far").unwrap();
    let c = config("default");
    let near = run_plane_optimized(&seq, &c).unwrap();
    let far = run_plane_optimized(&far, &c).unwrap();
    assert!(!near.used.is_empty());
    let observations = |o: &specular::pipeline::PlaneOptimizedOutput| -> Vec<usize> {
        o.used
            .iter()
            .map(|&i| o.map.landmarks[i].observations)
            .collect()
    };
    assert_eq!(observations(&far), observations(&near));
    let miou = |o: &specular::pipeline::PlaneOptimizedOutput| {
        o.run.confusion.as_ref().unwrap().metrics().miou
    };
    assert!(
        (miou(&far) - miou(&near)).abs() < 0.5,
        "{} vs {}",
        miou(&far),
        miou(&near)
    );
}

/// The glass-lined loop's north corridor under 2 cm of range noise, walked
/// once (404 frames): the map's plane of its 18 m glass wall is a moving
/// average of the last observations, each fitted near normal incidence, so
/// it keeps the tilt of the last views, and the glass drifts out of the band
/// in which echoes count as glass while what lies behind drifts in.
/// Refitted to the wall's glass echoes over the walk
/// (`map.evidence.refit_plane`), the glass is glass along its length
/// (glass IoU 96.2 against 91.9).
#[test]
fn a_long_glass_wall_under_range_noise_is_glass_along_its_length() {
    let mut scene = specular::sim::Scene::resolve("glass-loop").unwrap();
    scene.sensor.range_noise = 0.02;
    let sim = specular::sim::Simulator::new(&scene);
    let (frames, poses) = (466..870)
        .map(|k| {
            let f = sim.frame(k, scene.seed);
            (f.frame, f.pose.pose)
        })
        .unzip();
    let seq = Sequence::from_frames(frames, Some(poses), "noisy wall").unwrap();
    let glass = |config: &Config| {
        let out = run_plane_optimized(&seq, config).unwrap();
        let m = out.run.confusion.unwrap().metrics();
        (m.class(Class::Glass).iou, m.table())
    };
    let on = config("default");
    assert!(on.map.evidence.refit_plane);
    let (with, table) = glass(&on);
    assert!(with > 95.0, "{table}");
    let mut off = on.clone();
    off.map.evidence.refit_plane = false;
    let (without, table) = glass(&off);
    assert!(with > without + 2.0, "{with} against {without}\n{table}");
}

/// The lobby's north wall seen in its coated east facade appears behind
/// the glass as a plane with the building across the street showing
/// through it: the frontend fuses it into a reflective landmark outside
/// the building, which nothing behind ever proves transmitting, so it is
/// taken for a mirror and the building becomes Reflections. Its mirror
/// image across the facade is the north wall, seen directly: with
/// `map.ghosts` it is dropped, and the building is not called a
/// reflection behind a mirror (every third frame of the stretch that sees
/// it).
#[test]
fn a_wall_seen_in_coated_glass_is_no_landmark() {
    let seq = common::simulated_subset("lobby", (240..420).step_by(3));
    let run = |config: &Config| {
        let out = run_plane_optimized(&seq, config).unwrap();
        // Obstacles called reflections on the landmark's prior alone (it
        // taken for a mirror).
        let behind_mirror =
            out.run
                .rules
                .count(specular::classify::Rule::Prior, Class::Reflection, 6);
        let outside = out
            .planes
            .iter()
            .filter(|p| {
                let c = p.boundary.centroid().map(|c| p.chart.to_3d(&c));
                c.is_some_and(|c| c.x > 34.5)
            })
            .count();
        (
            behind_mirror,
            outside,
            out.ghost_lines(),
            out.run.rules.table(),
        )
    };
    let on = config("default");
    assert!(on.map.ghosts.enabled);
    let (behind_mirror, outside, ghosts, table) = run(&on);
    assert_eq!(outside, 0, "{table}");
    assert_eq!(ghosts.len(), 1, "{ghosts:?}");
    // With the weighed decision the facade itself (coated glass, R close
    // to T) gets a mirror probability that calls obstacles behind it
    // reflections on the prior alone: measured, not asserted (issue 38's
    // open problem).
    eprintln!("obstacles called reflections on the prior: {behind_mirror}");
    let mut off = on.clone();
    off.map.ghosts.enabled = false;
    let (_, outside, ghosts, table) = run(&off);
    assert!(outside >= 1, "{table}");
    assert!(ghosts.is_empty(), "{ghosts:?}");
}

/// The office's monitors are reflective landmarks whose fitted panes reach
/// about 0.1 m past the screens. Beams through that margin meet the wall
/// behind the desks: taken as transmissions, they made the screens glass
/// and that wall Obstacles seen through them. With `pane_edge_margin` such
/// beams are no evidence of transmission, the screens are mirrors, and the
/// wall seen past their edges is Normal (the south leg of the loop, every
/// second frame).
#[test]
fn a_wall_seen_past_a_screens_edge_is_not_behind_it() {
    let seq = common::simulated_subset("office", (0..240).step_by(2));
    let run = |config: &Config| {
        let out = run_plane_optimized(&seq, config).unwrap();
        let confusion = out.run.confusion.unwrap();
        let mirrors = out.planes.iter().filter(|p| p.is_mirror()).count();
        (
            confusion.by_label[1][6],
            mirrors,
            confusion.metrics().table(),
        )
    };
    let mut on = config("default");
    on.plane_map.decision_model = specular::classify::DecisionModel::Ladder;
    assert!(on.plane_map.decision.pane_edge_margin > 0.0);
    let (walls_on, mirrors_on, table_on) = run(&on);
    let mut off = on.clone();
    off.plane_map.decision.pane_edge_margin = 0.0;
    let (walls_off, mirrors_off, table_off) = run(&off);
    eprintln!("on: {walls_on} normal points called obstacles, {mirrors_on} mirrors\n{table_on}");
    eprintln!("off: {walls_off}, {mirrors_off} mirrors\n{table_off}");
    assert!(mirrors_on > mirrors_off);
    // The ladder decides by the echo split before the space seen directly
    // now that every landmark has one (physics where its echoes show one
    // group): the margin still keeps walls out, less than the fivefold of
    // the ladder's own mirror test.
    assert!(walls_on < walls_off, "{walls_on} on, {walls_off} off");
}
