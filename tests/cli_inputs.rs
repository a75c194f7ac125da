//! The command line's inputs: pose files (missing poses, nanosecond stamps,
//! KITTI, interpolation, tolerance) and simulated scenes.

mod common;

use std::path::Path;

use common::cli::{s, specular, stderr};

/// `detect` on the sample with a pose file holding `poses`: the failed
/// run's error message.
fn detect_sample_failing_with_poses(poses: &str) -> String {
    let sample = common::sample_dir();
    let file = tempfile::NamedTempFile::new().unwrap();
    std::fs::write(file.path(), poses).unwrap();
    let out = tempfile::tempdir().unwrap();
    let o = specular(&[
        "detect",
        "--frames",
        s(&sample.join("frames")),
        "--poses",
        s(file.path()),
        "--out",
        s(out.path()),
    ]);
    assert!(!o.status.success());
    stderr(&o)
}

#[test]
fn a_frame_without_a_pose_is_named() {
    let err = detect_sample_failing_with_poses("1689496219.652560 0 0 0 0 0 0 1\n");
    assert!(
        err.contains("no pose within") && err.contains("1689496220.052616"),
        "{err}"
    );
}

/// Poses stamped in nanoseconds (as ROS writes them) against frames named
/// in seconds: the error says which side looks like nanoseconds.
#[test]
fn nanosecond_timestamps_are_diagnosed() {
    let err = detect_sample_failing_with_poses(
        "1689496219652560000 0 0 0 0 0 0 1\n1689496220652560000 0 0 0 0 0 0 1\n",
    );
    assert!(
        err.contains("pose timestamps look like nanoseconds"),
        "{err}"
    );
}

#[test]
fn plane_optimized_without_poses_is_a_clear_error() {
    let sample = common::sample_dir();
    let out = tempfile::tempdir().unwrap();
    let o = specular(&[
        "detect",
        "--frames",
        s(&sample.join("frames")),
        "--out",
        s(out.path()),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("needs poses"), "{}", stderr(&o));
}

/// The sample's poses as a KITTI file (one `[R | t]` a line, in frame
/// order) give the same predictions as the TUM file; with the stamps moved
/// 50 ms off every frame, poses are interpolated between neighbours up to
/// `input.pose_interpolation_gap`, and `--pose-tolerance` widens the
/// nearest-pose match.
#[test]
fn kitti_poses_interpolation_and_pose_tolerance() {
    let sample = common::sample_dir();
    let tum = specular::io::read_tum(&sample.join("poses.txt")).unwrap();
    let frames = sample.join("frames");
    let run = |poses: &Path, extra: &[&str]| {
        let out = tempfile::tempdir().unwrap();
        let mut args = vec![
            "detect",
            "--frames",
            s(&frames),
            "--poses",
            s(poses),
            "--out",
            s(out.path()),
            "--lean",
        ];
        args.extend_from_slice(extra);
        let o = specular(&args);
        let labels = o.status.success().then(|| {
            let mut all = Vec::new();
            for e in specular::io::list_frames(&frames).unwrap() {
                all.extend(
                    specular::io::read_labels(
                        &out.path().join(format!("predictions/{}.label", e.name)),
                    )
                    .unwrap(),
                );
            }
            all
        });
        (labels, stderr(&o))
    };
    let (reference, err) = run(&sample.join("poses.txt"), &[]);
    let reference = reference.unwrap_or_else(|| panic!("{err}"));

    let dir = tempfile::tempdir().unwrap();
    let kitti = dir.path().join("poses.kitti");
    let mut text = String::new();
    for p in &tum {
        let m = p.pose.to_homogeneous();
        for r in 0..3 {
            for c in 0..4 {
                text.push_str(&format!("{:.12} ", m[(r, c)]));
            }
        }
        text.push('\n');
    }
    std::fs::write(&kitti, &text).unwrap();
    let (labels, err) = run(&kitti, &[]);
    assert_eq!(labels.as_ref(), Some(&reference), "{err}");
    // One pose short: the counts must agree.
    let short: String = text.lines().skip(1).map(|l| format!("{l}\n")).collect();
    std::fs::write(&kitti, short).unwrap();
    let (labels, err) = run(&kitti, &[]);
    assert!(labels.is_none() && err.contains("one per frame"), "{err}");

    // Each pose twice, 50 ms before and after its frame: interpolated
    // halfway, the frame gets (nearly) its own pose back.
    let shifted = dir.path().join("shifted.txt");
    let mut lines = String::new();
    for p in &tum {
        for dt in [-0.05, 0.05] {
            let (t, q) = (p.pose.translation.vector, p.pose.rotation.coords);
            lines.push_str(&format!(
                "{:.6} {} {} {} {} {} {} {}\n",
                p.stamp + dt,
                t.x,
                t.y,
                t.z,
                q.x,
                q.y,
                q.z,
                q.w
            ));
        }
    }
    std::fs::write(&shifted, lines).unwrap();
    let (labels, err) = run(&shifted, &[]);
    assert_eq!(labels.as_ref(), Some(&reference), "{err}");
    let strict = dir.path().join("strict.toml");
    std::fs::write(&strict, "[input]\npose_interpolation_gap = 0.0\n").unwrap();
    let (labels, err) = run(&shifted, &["--config", s(&strict)]);
    assert!(
        labels.is_none() && err.contains("no pose within 0.01 s"),
        "{err}"
    );
    let (labels, err) = run(
        &shifted,
        &["--config", s(&strict), "--pose-tolerance", "0.06"],
    );
    assert!(labels.is_some(), "{err}");
}

/// `--scene` runs a simulated scene in memory with its true poses: `detect`
/// needs no pose file and scores against the scene's labels, `slam` scores
/// its trajectory against the scene's poses; a pose file beside it, or an
/// unknown scene, is a clear error.
#[test]
fn a_simulated_scene_is_an_input_of_detect_and_slam() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("detect");
    let o = specular(&[
        "detect",
        "--scene",
        "two-panes",
        "--scene-frames",
        "6",
        "--out",
        s(&out),
        "--lean",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let metrics = std::fs::read_to_string(out.join("metrics.json")).unwrap();
    assert!(metrics.contains("\"miou\""), "{metrics}");
    // One label file and one confidence file per frame.
    assert_eq!(common::predictions(&out).len(), 6);
    assert_eq!(common::confidences(&out).len(), 6);

    let slam = tmp.path().join("slam");
    let o = specular(&[
        "slam",
        "--scene",
        "office",
        "--scene-frames",
        "8",
        "--out",
        s(&slam),
        "--no-classify",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let metrics = std::fs::read_to_string(slam.join("metrics.json")).unwrap();
    assert!(metrics.contains("\"trajectory\""), "{metrics}");

    let poses = common::sample_dir().join("poses.txt");
    let o = specular(&[
        "detect",
        "--scene",
        "two-panes",
        "--poses",
        s(&poses),
        "--out",
        s(&tmp.path().join("x")),
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--scene brings its true poses"),
        "{}",
        stderr(&o)
    );
    let o = specular(&[
        "detect",
        "--scene",
        "no-such-scene",
        "--out",
        s(&tmp.path().join("y")),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no-such-scene"), "{}", stderr(&o));
}
