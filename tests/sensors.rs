//! The Ouster OS0-128 and Livox Avia models in the simulator and the
//! pipelines (issue 40, part 1): each sensor's return semantics, the
//! rosette's field and its pairing by emission, and `simulate --sensor`
//! read back by `detect`.

use std::process::Command;

use specular::sensor::{OrganizedScan, SensorModel};
use specular::sim::{SceneSource, Simulator};

fn frame_of(scene: &str, sensor: &str, k: usize) -> (SensorModel, specular::cloud::Frame) {
    let (scene, toml) = SceneSource::Named(scene.into())
        .resolve_for(Some(sensor))
        .unwrap();
    assert!(toml.unwrap().contains(&scene.sensor.model.name));
    let f = Simulator::new(&scene).frame(k, 3).frame;
    (scene.sensor.model, f)
}

/// Ouster: 128 rings, two returns ordered by strength (the intensity is the
/// received power), so the first is never the weaker.
#[test]
fn ouster_returns_are_strongest_then_second_strongest() {
    let (model, f) = frame_of("demo", "ouster-os0-128", 0);
    assert_eq!(model.rings(), 128);
    assert!(f.points.len() > 80_000, "{}", f.points.len());
    assert!(f.points.iter().all(|p| p.ring < 128 && p.ret <= 2));
    let mut pairs = 0;
    for w in f.points.windows(2) {
        if w[1].ret == 2 {
            assert_eq!(w[0].ret, 1);
            assert!(w[0].intensity >= w[1].intensity, "{:?}", w);
            pairs += 1;
        }
    }
    assert!(pairs > 100, "{pairs}");
    let scan = OrganizedScan::build(&f, &model).unwrap();
    assert!(scan.dual_cells().count() >= pairs * 9 / 10);
}

/// Livox: every point inside the 70.4 x 77.2 degree field, up to three
/// returns, reflectivities; its returns paired by emission on the grid of
/// directions; the pattern differs from one frame to the next. (The
/// corridor: its glass lies ahead, in the field; the demo room's does not.)
#[test]
fn livox_points_stay_in_the_field_and_pair_by_emission() {
    let (model, f) = frame_of("corridor", "livox-avia", 0);
    let r = model.rosette.clone().unwrap();
    assert_eq!(
        f.intensity_scale,
        Some(specular::cloud::IntensityScale::Reflectivity)
    );
    for p in &f.points {
        let q = p.position();
        let az = q.y.atan2(q.x).to_degrees();
        let el = q.z.atan2(q.x.hypot(q.y)).to_degrees();
        assert!(az.abs() <= 0.5 * r.fov_h_deg + 1e-3, "{az}");
        assert!(el.abs() <= 0.5 * r.fov_v_deg + 1e-3, "{el}");
        assert!((1..=3).contains(&p.ret));
        assert!((p.ring as usize) < model.rings());
    }
    let scan = OrganizedScan::build(&f, &model).unwrap();
    let mut paired = 0;
    for (i, p) in f.points.iter().enumerate() {
        if p.ret == 1 {
            continue;
        }
        if let Some(j) = scan.partner(i) {
            // The partner is its emission's return 1: same direction.
            let (a, b) = (p.position().coords, f.points[j].position().coords);
            assert_eq!(f.points[j].ret, 1);
            assert!(a.normalize().dot(&b.normalize()) > 0.9999);
            paired += 1;
        }
    }
    assert!(paired > 50, "{paired}");
    let (_, next) = frame_of("corridor", "livox-avia", 1);
    assert_ne!(f.points[0].xyz, next.points[0].xyz);
}

fn specular(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(args)
        .output()
        .unwrap()
}

/// `simulate --sensor` names the sensor in the frames; `detect` reads them
/// as that sensor's, and refuses a `--sensor` that contradicts them.
#[test]
fn simulated_frames_say_their_sensor_and_detect_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    for (scene, sensor) in [("demo", "ouster-os0-128"), ("corridor", "livox-avia")] {
        let out = dir.path().join(sensor);
        let o = out.to_str().unwrap();
        let r = specular(&[
            "simulate", "--scene", scene, "--frames", "3", "--sensor", sensor, "--out", o,
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let frames = out.join("frames");
        let first = std::fs::read_dir(&frames).unwrap().next().unwrap().unwrap();
        let named = specular::io::frame_sensor(&first.path()).unwrap();
        assert_eq!(named.as_deref(), Some(sensor.replace('-', "_").as_str()));
        let poses = out.join("poses.txt");
        let (f, p) = (frames.to_str().unwrap(), poses.to_str().unwrap());
        let det = dir.path().join(format!("det-{sensor}"));
        let r = specular(&[
            "detect",
            "--frames",
            f,
            "--poses",
            p,
            "--lean",
            "--out",
            det.to_str().unwrap(),
        ]);
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        assert!(String::from_utf8_lossy(&r.stdout).contains("mIoU"));
        let r = specular(&[
            "detect",
            "--frames",
            f,
            "--poses",
            p,
            "--sensor",
            "pandar_qt64",
            "--lean",
            "--out",
            dir.path().join("refused").to_str().unwrap(),
        ]);
        assert!(!r.status.success());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains("--sensor says 'pandar_qt64'"), "{err}");
    }
}

/// The Ouster's 128 rings on the built-in office: where one ring's glass
/// echoes along the window and the table edges lie at one height, the
/// paper's RANSAC fits a "pane" above the floor and hides it behind glass
/// (the SLAM then lost its ground and pitched by 17 degrees, issue 40). The
/// default detector keeps only planes its candidates lie on.
#[test]
fn ouster_panes_in_the_office_face_as_its_glass() {
    use specular::reflect::{CandidateRansacDetector, DetectorParams, ReflectiveDetector};
    let facing_up = |params: DetectorParams| {
        (64..72)
            .step_by(2)
            .filter(|&k| {
                let (model, f) = frame_of("office", "ouster-os0-128", k);
                let scan = OrganizedScan::build(&f, &model).unwrap();
                let detection =
                    CandidateRansacDetector::new(params, model).detect(&f, &scan, k as u64);
                detection
                    .planes
                    .iter()
                    .any(|p| p.bounded.plane.normal.z > 0.9)
            })
            .count()
    };
    let ours = specular::config::Config::default().detector;
    assert_eq!(facing_up(ours), 0);
    let paper = specular::config::Config::resolve("paper").unwrap().detector;
    assert!(
        facing_up(paper) > 0,
        "the paper's detector no longer fits the slice"
    );
}

/// Livox Avia: a forward-looking rosette sees one to five planes a frame,
/// too few to fix the heading, and office/3 starts in a turn at up to
/// 98 deg/s that the motion model cannot foresee from a standstill
/// (tracking kept the heading of frame 0 and ended 20 deg off, issue 40).
/// The frame's points find the turn against the local point map.
#[test]
fn avia_tracks_a_turn_its_planes_cannot_see() {
    use specular::config::Config;
    use specular::pipeline::registry::{self, DatasetSource};
    use specular::pipeline::{run_slam, Sequence};
    use specular::sim::LabelRule;
    let source = DatasetSource::Simulated {
        scene: SceneSource::Family {
            family: "office".into(),
            seed: 3,
        },
        frames: Some(12),
        seed: None,
        labels: LabelRule::Raycast3dref,
        sensor: Some("livox-avia".into()),
    };
    let seq = Sequence::from_dataset(registry::dataset(&source).unwrap());
    let truth = seq.poses.clone().unwrap();
    let turn = truth[0].rotation.angle_to(&truth[11].rotation).to_degrees();
    assert!(turn > 30.0, "the path no longer turns: {turn}");
    let out = run_slam(&seq, &Config::default(), Some(truth[0])).unwrap();
    assert!(out.reports.iter().any(|r| r.points_yaw_deg.is_some()));
    for (k, (tracked, true_pose)) in out.tracked_poses.iter().zip(&truth).enumerate() {
        let off = tracked.rotation.angle_to(&true_pose.rotation).to_degrees();
        assert!(off < 2.0, "frame {k}: {off:.1} deg off");
    }
}
