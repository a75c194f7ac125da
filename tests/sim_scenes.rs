//! Scene files and the built-in scenes: odd numbers in a scene file never
//! panic (property test), the built-in scenes build, their label shares
//! match 3DRef's, their reflective planes face the trajectory and their
//! trajectories turn smoothly.

use std::path::Path;

use glam::DVec3;
use specular::sim::{label, Scene, Simulator};

#[test]
fn builtin_scenes_build_and_benchmark_scenes_are_long_enough() {
    for name in specular::sim::builtin::names() {
        let scene = Scene::resolve(name).unwrap();
        assert_eq!(scene.name, name);
        assert!(!scene.description.is_empty(), "{name}");
    }
    for name in ["office", "corridor", "mirror-room", "lobby"] {
        let frames = Scene::resolve(name).unwrap().frames;
        assert!(frames >= 600, "{name}: {frames} frames");
    }
    // The glass-lined corridor loop of the behind-the-glass benchmark.
    let frames = Scene::resolve("glass-loop").unwrap().frames;
    assert!(frames >= 1000, "glass-loop: {frames} frames");
    let e = Scene::resolve("no-such-scene").unwrap_err().to_string();
    assert!(e.contains("office") && e.contains("no-such-scene"), "{e}");
}

#[test]
fn office_label_shares_match_the_3dref_hesai_statistics() {
    // Every 20th frame of the sequence (the full table is in
    // datasets/README.md).
    let scene = Scene::resolve("office").unwrap();
    let sim = Simulator::new(&scene);
    let counts = (0..scene.frames)
        .step_by(20)
        .map(|k| specular::sim::LabelCounts::of(&sim.frame(k, scene.seed).frame))
        .fold(specular::sim::LabelCounts::default(), |a, b| a.merge(b));
    let s = counts.shares();
    eprintln!("{}", counts.table_row("office (every 20th frame)"));
    assert!((0.74..0.83).contains(&s.normal), "{s:?}");
    assert!((0.03..0.08).contains(&s.glass_mirror), "{s:?}");
    assert!((0.03..0.11).contains(&s.reflection), "{s:?}");
    assert!((0.015..0.055).contains(&s.obstacle), "{s:?}");
}

/// A scene whose numbers are filled in by the property test below.
const TEMPLATE: &str = r#"
[sensor]
model = "pandar_qt64"
range_noise = {0}
crop_range = {1}
intensity_gain = {2}
detection_threshold = {3}
[trajectory]
waypoints = [[{4}, 1.0, 1.0], [3.0, {5}, 1.0]]
speed = {6}
heading_smoothing = {7}
[materials]
wall = { type = "diffuse", reflectivity = {8} }
win = { type = "glass", reflectance = {9}, transmittance = {10}, echo_peak = {11}, echo_width_deg = {12}, echo_lobe = {13} }
[[rooms]]
min = [0.0, 0.0, 0.0]
max = [{14}, 3.0, {15}]
yaw_deg = {16}
material = "wall"
sides = { "-x" = "win" }
[[walls]]
from = [{17}, 0.5]
to = [2.0, 0.5]
height = {18}
material = "win"
"#;

fn toml_number(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{v:?}")
    }
}

/// Values of the template's numbers that make a valid scene.
const VALID: [f64; 19] = [
    0.01, 25.0, 20000.0, 3.0, 1.0, 1.5, 1.0, 1.0, 0.6, 0.2, 0.6, 1.0, 3.0, 8.0, 4.0, 2.5, 10.0,
    0.5, 2.0,
];

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(96))]

    /// Whatever the numbers, a scene is either rejected with an error
    /// naming the file or simulated without panicking (valid numbers with
    /// up to three replaced by odd ones).
    #[test]
    fn arbitrary_numbers_in_a_scene_never_panic(
        changes in proptest::collection::vec(
            (
                0..19usize,
                proptest::prop_oneof![
                    proptest::prelude::Just(0.0),
                    proptest::prelude::Just(-1.0),
                    proptest::prelude::Just(1e300),
                    proptest::prelude::Just(-1e-300),
                    proptest::prelude::Just(f64::NAN),
                    proptest::prelude::Just(f64::INFINITY),
                    0.0..5.0f64,
                    -10.0..100.0f64,
                ],
            ),
            0..4,
        )
    ) {
        let mut values = VALID;
        for (i, v) in changes {
            values[i] = v;
        }
        let mut text = TEMPLATE.to_string();
        for (i, v) in values.iter().enumerate().rev() {
            text = text.replace(&format!("{{{i}}}"), &toml_number(*v));
        }
        match Scene::from_toml(&text, Path::new("fuzz.toml")) {
            Ok(scene) => {
                let sim = Simulator::new(&scene);
                let f = sim.frame(0, 1);
                proptest::prop_assert!(f
                    .frame
                    .points
                    .iter()
                    .all(|p| p.xyz.iter().all(|c| c.is_finite())
                        && (0.0..=255.0).contains(&p.intensity)));
            }
            Err(e) => proptest::prop_assert!(e.to_string().contains("fuzz.toml"), "{}", e),
        }
    }
}

#[test]
fn the_fuzz_template_is_valid_with_its_default_numbers() {
    let mut text = TEMPLATE.to_string();
    for (i, v) in VALID.iter().enumerate().rev() {
        text = text.replace(&format!("{{{i}}}"), &toml_number(*v));
    }
    let scene = Scene::from_toml(&text, Path::new("fuzz.toml")).unwrap();
    assert!(Simulator::new(&scene).frame(0, 1).frame.points.len() > 30_000);
}

#[test]
fn every_reflective_plane_is_seen_from_the_side_its_normal_faces() {
    let scene = Scene::resolve("lobby").unwrap();
    let sim = Simulator::new(&scene);
    let planes = specular::sim::TruePlanes::of(&scene);
    assert_eq!(planes.groups.len(), 10);
    let mut checked = 0;
    for k in (0..scene.frames).step_by(25) {
        let f = sim.frame(k, 1);
        let o = f.pose.pose.translation.vector;
        let o = DVec3::new(o.x, o.y, o.z);
        for t in &f.truth {
            // The physical surface echoes (3DRef's rule also gives a
            // surface's label to a point just behind it).
            if matches!(
                t.physical,
                label::GLASS | label::MIRROR | label::OTHER_REFLECTIVE
            ) {
                let g = &planes.groups[planes.group_of[t.surface as usize].unwrap()];
                assert!(g.normal.dot(o) + g.d > 0.0, "{:?} seen from behind", g.kind);
                checked += 1;
            }
        }
    }
    assert!(checked > 10_000, "{checked}");
}

/// The benchmark trajectories turn the sensor gradually: no frame-to-frame
/// heading change above 20 degrees (200 deg/s at 10 Hz, a brisk turn of a
/// hand-pushed trolley; the old corridor turned 180 degrees in one frame at
/// its far end), and no frame moves more than 0.2 m.
#[test]
fn benchmark_trajectories_turn_and_move_smoothly() {
    for name in ["office", "corridor", "mirror-room", "lobby", "glass-loop"] {
        let scene = Scene::resolve(name).unwrap();
        let sim = Simulator::new(&scene);
        let (mut max_turn, mut max_step) = (0.0f64, 0.0f64);
        for k in 1..scene.frames {
            let rel = sim.pose(k - 1).pose.inverse() * sim.pose(k).pose;
            max_turn = max_turn.max(rel.rotation.angle().to_degrees());
            max_step = max_step.max(rel.translation.vector.norm());
        }
        assert!(
            max_turn < 20.0,
            "{name}: turns {max_turn:.1} deg in one frame"
        );
        assert!(max_step < 0.2, "{name}: moves {max_step:.2} m in one frame");
    }
}
