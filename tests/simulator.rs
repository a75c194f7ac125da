//! The simulator's physics, labels, determinism and errors.
//!
//! Most tests run a "lab" scene without range noise, so geometric relations
//! hold to float precision: a room with a window (and a box outside), a wall
//! mirror and a whiteboard.

use std::path::Path;
use std::process::Command;

use glam::DVec3;
use specular::cloud::{Frame, Point};
use specular::sim::{label, simulate, MaterialKind, Scene, Simulation, Simulator};

const LAB: &str = r#"
name = "lab"
seed = 3

[sensor]
model = "pandar_qt64"
range_noise = NOISE
crop_range = 25.0

[trajectory]
waypoints = [[2.5, 2.0, 1.1], [7.0, 4.0, 1.1]]
speed = 0.8

[materials]
wall = { type = "diffuse", reflectivity = 0.6 }
floor = { type = "diffuse", reflectivity = 0.3 }
outside = { type = "diffuse", reflectivity = 0.5 }
glass = { type = "glass", reflectance = 0.3, transmittance = 0.55 }
mirror = { type = "mirror", reflectance = 0.9 }
board = { type = "other-reflective", reflectivity = 0.4, reflectance = 0.2 }

[[rooms]]
min = [0.0, 0.0, 0.0]
max = [10.0, 6.0, 3.0]
material = "wall"
floor = "floor"
sides = { "+y" = "glass" }

[[walls]]
from = [0.02, 1.0]
to = [0.02, 5.0]
base = 0.3
height = 2.2
material = "mirror"

[[walls]]
from = [3.0, 0.03]
to = [6.0, 0.03]
base = 0.9
height = 1.2
material = "board"

[[floors]]
min = [-20.0, 6.0]
max = [30.0, 30.0]
z = 0.0
material = "outside"

[[boxes]]
min = [2.0, 11.0, 0.0]
max = [8.0, 14.0, 6.0]
material = "outside"
"#;

fn lab(noise: f64) -> Scene {
    Scene::from_toml(
        &LAB.replace("NOISE", &noise.to_string()),
        Path::new("lab.toml"),
    )
    .unwrap()
}

/// World position of a point of frame `k`.
fn world(run: &Simulation, k: usize, p: &Point) -> DVec3 {
    let w = run.poses[k].pose * p.position();
    DVec3::new(w.x, w.y, w.z)
}

fn plane_distance(scene: &Scene, surface: u32, p: DVec3) -> f64 {
    let s = &scene.surfaces[surface as usize];
    s.normal.dot(p) + s.d
}

/// Whether `p` (on or near the surface's plane) lies within its polygon's
/// bounding box, grown by `tol`.
fn within_bounds(scene: &Scene, surface: u32, p: DVec3, tol: f64) -> bool {
    let s = &scene.surfaces[surface as usize];
    let lo = s.vertices.iter().fold(DVec3::INFINITY, |a, v| a.min(*v));
    let hi = s
        .vertices
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, v| a.max(*v));
    p.cmpge(lo - tol).all() && p.cmple(hi + tol).all()
}

fn kind(scene: &Scene, surface: u32) -> MaterialKind {
    scene.material_of(&scene.surfaces[surface as usize]).kind
}

/// Mirror `x` through the plane of `surface`.
fn mirror_through(scene: &Scene, surface: u32, x: DVec3) -> DVec3 {
    let m = &scene.surfaces[surface as usize];
    x - m.normal * (2.0 * (m.normal.dot(x) + m.d))
}

/// Beam directions of a fan around `origin`.
fn fan(n: usize) -> impl Iterator<Item = DVec3> {
    (0..n).map(move |i| {
        let az = std::f64::consts::TAU * i as f64 / n as f64;
        let el = -0.6 + 1.2 * ((i * 37) % n) as f64 / n as f64;
        DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    })
}

#[test]
fn reflection_echoes_mirrored_through_their_plane_land_exactly_on_the_hit_surface() {
    let scene = lab(0.0);
    let sim = Simulator::new(&scene);
    let (mut single, mut double) = (0, 0);
    for origin in [DVec3::new(2.5, 2.0, 1.1), DVec3::new(7.0, 4.5, 1.6)] {
        for dir in fan(20_000) {
            let mut echoes = Vec::new();
            sim.tracer().trace(origin, dir, &mut echoes);
            for e in echoes.iter().filter(|e| e.label == label::REFLECTION) {
                // Reported along the original beam at the full path length.
                let x = origin + dir * e.range;
                let m = &scene.surfaces[e.via as usize];
                // Always behind the reflector.
                assert!((m.normal.dot(origin) + m.d) * (m.normal.dot(x) + m.d) < 0.0);
                if e.bounces == 1 {
                    let back = mirror_through(&scene, e.via, x);
                    assert!(plane_distance(&scene, e.surface, back).abs() < 1e-9);
                    assert!(within_bounds(&scene, e.surface, back, 1e-9));
                    single += 1;
                } else {
                    assert_eq!(e.bounces, 2, "at most two bounces");
                    double += 1;
                }
            }
        }
    }
    assert!(
        single > 2000 && double > 10,
        "{single} single, {double} double"
    );
}

#[test]
fn reflection_points_mirrored_through_their_plane_land_on_the_hit_surface() {
    let scene = lab(0.0);
    let res = scene.sensor.model.range_resolution;
    let run = simulate(&scene, Some(6), None).unwrap();
    let (mut checked, mut exact) = (0, 0);
    for k in 0..run.frames.len() {
        for (p, t) in run.frames[k].points.iter().zip(&run.truth[k]) {
            if p.label != label::REFLECTION || t.bounces != 1 {
                continue;
            }
            let back = mirror_through(&scene, t.via, world(&run, k, p));
            // Without noise the point is exact (up to its f32 storage) unless
            // its echo merged with another one within the range resolution.
            let off = plane_distance(&scene, t.surface, back).abs();
            assert!(off < res, "mirrored point {off} m off its surface");
            assert!(within_bounds(&scene, t.surface, back, res));
            checked += 1;
            if off < 1e-4 {
                exact += 1;
            }
        }
    }
    assert!(checked > 1000, "only {checked} reflection points checked");
    assert!(
        exact as f64 > 0.95 * checked as f64,
        "{exact} of {checked} exact"
    );
}

/// A single large glass pane on the plane y = 6 and nothing else.
const PANE: &str = r#"
[sensor]
model = "pandar_qt64"
range_noise = 0.0
[trajectory]
waypoints = [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]]
speed = 1.0
[materials]
glass = { type = "glass", reflectance = 0.1, transmittance = 0.8, echo_peak = 1.0, echo_width_deg = 3.0, echo_diffuse = 0.03, echo_lobe = 8.0 }
[[polygons]]
vertices = [[-100.0, 6.0, -50.0], [100.0, 6.0, -50.0], [100.0, 6.0, 50.0], [-100.0, 6.0, 50.0]]
material = "glass"
"#;

#[test]
fn glass_surface_echo_is_strongest_at_normal_incidence() {
    let scene = Scene::from_toml(PANE, Path::new("pane.toml")).unwrap();
    let sim = Simulator::new(&scene);
    let hit = DVec3::new(5.0, 6.0, 1.5);
    for distance in [4.0, 20.0] {
        let mut last = f64::INFINITY;
        let mut detected = Vec::new();
        for deg in 0..85 {
            // Same path length to the same glass point, increasing incidence.
            let a = (deg as f64).to_radians();
            let dir = DVec3::new(a.sin(), a.cos(), 0.0);
            let echoes = sim.beam_echoes(hit - dir * distance, dir);
            assert!(echoes.len() <= 1, "only the glass is there");
            if let Some(e) = echoes.first() {
                assert_eq!(e.label, label::GLASS);
                assert!((e.range - distance).abs() < 1e-9);
                assert!(e.signal < last, "not decreasing at {deg} deg");
                last = e.signal;
                detected.push(deg);
            } else {
                last = 0.0; // once too weak, it stays undetected
            }
        }
        // Near: the broad lobe is seen up to a few tens of degrees. Far: only
        // the specular peak is strong enough, within a few degrees.
        let widest = *detected.last().unwrap();
        assert_eq!(detected[0], 0);
        assert_eq!(detected.len(), widest + 1, "{detected:?}");
        if distance < 5.0 {
            assert!((20..60).contains(&widest), "{detected:?}");
        } else {
            assert!((3..10).contains(&widest), "{detected:?}");
        }
    }
}

#[test]
fn range_to_an_object_behind_glass_equals_the_range_without_glass() {
    let with = lab(0.0);
    let without = Scene::from_toml(
        &LAB.replace("NOISE", "0.0")
            .replace("sides = { \"+y\" = \"glass\" }", "omit = [\"+y\"]"),
        Path::new("lab-open.toml"),
    )
    .unwrap();
    let (a, b) = (Simulator::new(&with), Simulator::new(&without));
    let origin = DVec3::new(5.0, 3.0, 1.1);
    let mut compared = 0;
    for i in 0..2000 {
        let az = 0.2 + 2.7 * i as f64 / 2000.0; // towards +y, through the window
        let el = -0.3 + 0.6 * ((i * 7) % 2000) as f64 / 2000.0;
        let dir = DVec3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
        // Raw echoes, before the sensor merges close ones.
        let (mut through, mut direct) = (Vec::new(), Vec::new());
        a.tracer().trace(origin, dir, &mut through);
        b.tracer().trace(origin, dir, &mut direct);
        let behind = through
            .into_iter()
            .find(|e| e.label == label::OBSTACLE_BEHIND_GLASS);
        if let Some(e) = behind {
            let d = direct
                .iter()
                .find(|d| {
                    d.label == label::NORMAL
                        && without.surfaces[d.surface as usize].origin
                            == with.surfaces[e.surface as usize].origin
                })
                .expect("the obstacle is seen directly without the glass");
            assert!((d.range - e.range).abs() < 1e-9);
            assert!(d.signal > e.signal, "glass must attenuate");
            compared += 1;
        }
    }
    assert!(compared > 500, "only {compared} beams compared");
}

#[test]
fn labels_match_the_path_of_the_echo() {
    // The physical truth of every point, and its 3DRef label beside it.
    let scene = lab(0.0);
    let run = simulate(&scene, Some(4), None).unwrap();
    let res = scene.sensor.model.range_resolution;
    let mut seen = [0usize; 7];
    for k in 0..run.frames.len() {
        for (p, t) in run.frames[k].points.iter().zip(&run.truth[k]) {
            seen[t.physical as usize] += 1;
            check_3dref_label(&scene, p.label, t);
            let x = world(&run, k, p);
            let hit = kind(&scene, t.surface);
            let direct = t.via == specular::sim::echo::NO_SURFACE;
            match t.physical {
                label::NORMAL => {
                    assert!(direct && hit == MaterialKind::Diffuse);
                    // Reached straight: the point is on its surface.
                    assert!(plane_distance(&scene, t.surface, x).abs() < 1e-3);
                    assert!(within_bounds(&scene, t.surface, x, 1e-3));
                }
                label::GLASS | label::MIRROR | label::OTHER_REFLECTIVE => {
                    let want = match t.physical {
                        label::GLASS => MaterialKind::Glass,
                        label::MIRROR => MaterialKind::Mirror,
                        _ => MaterialKind::OtherReflective,
                    };
                    assert_eq!(hit, want);
                    // Echoes within the range resolution behind the surface
                    // merge with it, pulling the point back by up to that.
                    assert!(plane_distance(&scene, t.surface, x).abs() < res);
                    assert_eq!(t.bounces, 0);
                }
                label::REFLECTION => {
                    assert!(kind(&scene, t.via).is_reflective());
                    assert!(t.bounces >= 1);
                }
                label::OBSTACLE_BEHIND_GLASS => {
                    assert_eq!(kind(&scene, t.via), MaterialKind::Glass);
                    assert_eq!(hit, MaterialKind::Diffuse);
                    assert_eq!(t.bounces, 0);
                    // The straight path through glass: on the surface (up to
                    // a merge with the glass echo itself).
                    assert!(plane_distance(&scene, t.surface, x).abs() < res);
                }
                l => panic!("unexpected label {l}"),
            }
        }
    }
    for l in 1..=6 {
        assert!(seen[l] > 0, "label {l} never produced: {seen:?}");
    }
}

/// 3DRef's ray-cast label against the physical truth of a point: the
/// same on opaque surfaces and reflective surfaces; behind a mirror a
/// Reflection; behind glass a Reflection or an Obstacle (the rule asks
/// whether a surface is there, not which echo was stronger). A point that
/// lies within 0.15 m of the first reflective surface on its ray (an echo
/// merged with that surface's) takes that surface's label.
fn check_3dref_label(scene: &specular::sim::Scene, l: u8, t: &specular::sim::PointTruth) {
    let surface = matches!(l, label::GLASS | label::MIRROR | label::OTHER_REFLECTIVE);
    let ok = match t.physical {
        label::NORMAL | label::GLASS | label::MIRROR | label::OTHER_REFLECTIVE => l == t.physical,
        label::REFLECTION => match kind(scene, t.via) {
            MaterialKind::Glass => {
                l == label::REFLECTION || l == label::OBSTACLE_BEHIND_GLASS || surface
            }
            _ => l == label::REFLECTION || surface,
        },
        label::OBSTACLE_BEHIND_GLASS => l == label::OBSTACLE_BEHIND_GLASS || surface,
        _ => false,
    };
    assert!(
        ok,
        "3DRef label {l} for a point of physical label {}",
        t.physical
    );
}

#[test]
fn return_two_is_stored_only_where_it_differs_from_return_one() {
    for noise in [0.0, 0.02] {
        let scene = lab(noise);
        let res = scene.sensor.model.range_resolution;
        let run = simulate(&scene, Some(3), None).unwrap();
        let mut pairs = 0;
        for f in &run.frames {
            for (i, p) in f.points.iter().enumerate() {
                if p.ret != 2 {
                    continue;
                }
                let q = &f.points[i - 1];
                assert_eq!(
                    (q.ret, q.ring),
                    (1, p.ring),
                    "return 2 without its return 1"
                );
                let (dp, dq) = (p.position().coords, q.position().coords);
                assert!(
                    dp.normalize().dot(&dq.normalize()) > 1.0 - 1e-9,
                    "not one beam"
                );
                assert!((dp.norm() - dq.norm()).abs() > res);
                pairs += 1;
            }
        }
        assert!(pairs > 100, "only {pairs} second returns");
    }
}

fn same_points(a: &Frame, b: &Frame) -> bool {
    a.name == b.name && a.points == b.points
}

#[test]
fn same_seed_same_frames_different_seed_different_noise() {
    let scene = lab(0.02);
    let a = simulate(&scene, Some(3), Some(7)).unwrap();
    let b = simulate(&scene, Some(3), Some(7)).unwrap();
    // One thread gives the same result as many.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let c = pool.install(|| simulate(&scene, Some(3), Some(7)).unwrap());
    let d = simulate(&scene, Some(3), Some(8)).unwrap();
    for k in 0..3 {
        assert!(same_points(&a.frames[k], &b.frames[k]));
        assert!(same_points(&a.frames[k], &c.frames[k]));
        assert!(!same_points(&a.frames[k], &d.frames[k]));
        // The seed changes the noise, nothing else.
        assert_eq!(a.poses[k], d.poses[k]);
    }
    assert_eq!(a.planes, d.planes);
}

#[test]
fn range_noise_has_the_scene_sigma() {
    let scene = lab(0.02);
    let run = simulate(&scene, Some(2), None).unwrap();
    let (mut n, mut sum, mut sum2) = (0.0, 0.0, 0.0);
    for k in 0..2 {
        let pose = &run.poses[k].pose;
        let o = pose.translation.vector;
        let o = DVec3::new(o.x, o.y, o.z);
        for (p, t) in run.frames[k].points.iter().zip(&run.truth[k]) {
            if p.label != label::NORMAL {
                continue;
            }
            // The true range: where the beam meets the surface's plane.
            let d = pose.rotation * p.position().coords.normalize();
            let d = DVec3::new(d.x, d.y, d.z);
            let s = &scene.surfaces[t.surface as usize];
            let truth = -(s.normal.dot(o) + s.d) / s.normal.dot(d);
            let e = p.range() - truth;
            n += 1.0;
            sum += e;
            sum2 += e * e;
        }
    }
    let mean = sum / n;
    let sigma = (sum2 / n - mean * mean).sqrt();
    assert!(mean.abs() < 1e-3, "bias {mean}");
    assert!((sigma - 0.02).abs() < 1e-3, "sigma {sigma}");
}

#[test]
fn true_planes_face_the_trajectory_and_are_observed() {
    let scene = lab(0.0);
    let run = simulate(&scene, Some(5), None).unwrap();
    let kinds: Vec<&str> = run
        .planes
        .iter()
        .map(|p| p.material.as_deref().unwrap())
        .collect();
    assert_eq!(kinds, ["glass", "mirror", "other-reflective"]);
    for p in &run.planes {
        for pose in &run.poses {
            let t = pose.pose.translation.vector;
            let s = p.normal[0] * t.x + p.normal[1] * t.y + p.normal[2] * t.z + p.d;
            assert!(s > 0.0, "plane {} faces away from the sensor", p.id);
        }
        assert!(p.observations > 0 && p.observations <= 5);
        assert_eq!(p.first_frame.as_deref(), Some("1700000000.000000"));
    }
}

#[test]
fn strongest_last_mode_reports_the_strongest_echo_first() {
    let text = LAB
        .replace("NOISE", "0.0")
        .replace("pandar_qt64", "velodyne_hdl32e");
    let scene = Scene::from_toml(&text, Path::new("lab-hdl.toml")).unwrap();
    let sim = Simulator::new(&scene);
    let f = sim.frame(0, 1);
    assert!(f.frame.points.iter().all(|p| p.ring < 32));
    let mut pairs = 0;
    for (i, p) in f.frame.points.iter().enumerate() {
        if p.ret == 2 {
            let q = &f.frame.points[i - 1];
            // Return 2 is the last echo: never nearer than return 1, and at
            // least as weak (intensity is the clamped signal).
            assert!(p.range() > q.range());
            assert!(p.intensity <= q.intensity);
            pairs += 1;
        }
    }
    assert!(pairs > 50);
}

#[test]
fn bad_scene_files_are_clear_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("broken-scene.toml");
    std::fs::write(
        &path,
        LAB.replace("NOISE", "0.0")
            .replace("material = \"board\"", "material = \"bored\""),
    )
    .unwrap();
    let msg = Scene::load(&path).unwrap_err().to_string();
    assert!(msg.contains("broken-scene.toml"), "{msg}");
    assert!(
        msg.contains("walls[1]") && msg.contains("unknown material 'bored'"),
        "{msg}"
    );

    std::fs::write(&path, "[sensor]\nmodel = \"pandar_qt64\"\nnoise = 1\n").unwrap();
    let msg = Scene::load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("broken-scene.toml") && msg.contains("noise"),
        "{msg}"
    );

    // The command line reports it and fails.
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(["simulate", "--scene"])
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("broken-scene.toml"), "{stderr}");
    assert!(!out.join("poses.txt").exists());
}

#[test]
fn the_command_writes_identical_bytes_for_the_same_seed() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, seed: &str| {
        let out = dir.path().join(name);
        let o = Command::new(env!("CARGO_BIN_EXE_specular"))
            .args([
                "simulate", "--scene", "demo", "--frames", "4", "--seed", seed, "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (a, b, c) = (run("a", "5"), run("b", "5"), run("c", "6"));
    let files = |d: &Path| {
        let mut v: Vec<_> = std::fs::read_dir(d.join("frames"))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        v.sort();
        v
    };
    assert_eq!(files(&a).len(), 4);
    assert_eq!(files(&a), files(&b));
    for f in files(&a) {
        let fa = std::fs::read(a.join("frames").join(&f)).unwrap();
        assert_eq!(fa, std::fs::read(b.join("frames").join(&f)).unwrap());
        assert_ne!(fa, std::fs::read(c.join("frames").join(&f)).unwrap());
    }
    for f in ["poses.txt", "planes.json"] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap()
        );
    }
    // The frames read back as 3DRef frames matching their poses.
    let entries = specular::io::list_frames(&a.join("frames")).unwrap();
    let poses = specular::io::read_tum(&a.join("poses.txt")).unwrap();
    specular::io::match_poses(&entries, &poses, 1e-3, &a.join("poses.txt")).unwrap();
    let frame = specular::io::read_frame(&entries[0].path).unwrap();
    assert!(frame.has_labels && frame.points.len() > 30_000);
    // A second run into the same directory with other frames is refused.
    let o = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(["simulate", "--scene", "demo", "--frames", "2", "--out"])
        .arg(&a)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("another run"));
}
