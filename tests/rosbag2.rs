//! ROS 2 bags as people record them, read through the command line: rosbag2
//! directories with sqlite3 (split in two files) and MCAP storage, bare
//! `.db3` and `.mcap` files. The bags in `tests/fixtures/` were written by
//! the `rosbags` Python library from the bundled sample, not by specular.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{copy_dir, fixtures_dir, predictions, sample_dir, specular};

const TOPIC: &str = "/points";

fn sqlite_bag() -> PathBuf {
    fixtures_dir().join("rosbag2_sqlite3")
}

fn mcap_bag() -> PathBuf {
    fixtures_dir().join("rosbag2_mcap")
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `detect --lean` of `input` (and `extra`) into `out`; must succeed.
fn detect(input: &[&str], out: &Path, extra: &[&str]) {
    let mut args = vec!["detect"];
    args.extend_from_slice(input);
    args.extend_from_slice(&["--out", s(out), "--lean"]);
    args.extend_from_slice(extra);
    let o = specular(&args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

/// `detect` on the bag at `bag` (topic `topic`), which must fail; its error
/// message. Nothing is written for a bag that cannot be read.
fn detect_fails(bag: &Path, topic: &str) -> String {
    let out = tempfile::tempdir().unwrap();
    let out = out.path().join("out");
    let args = [
        "detect",
        "--bag",
        s(bag),
        "--topic",
        topic,
        "--method",
        "single-scan",
        "--out",
        s(&out),
    ];
    let o = specular(&args);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(!out.exists(), "a failed read wrote {}", out.display());
    stderr(&o)
}

#[test]
fn the_fixtures_are_what_their_readme_says() {
    let sqlite = std::fs::read_to_string(sqlite_bag().join("metadata.yaml")).unwrap();
    assert!(sqlite.contains("storage_identifier: sqlite3"));
    assert!(sqlite.contains("- rosbag2_sqlite3_0.db3\n  - rosbag2_sqlite3_1.db3\n"));
    let mcap = std::fs::read_to_string(mcap_bag().join("metadata.yaml")).unwrap();
    assert!(mcap.contains("storage_identifier: mcap"));
    for f in ["rosbag2_sqlite3_0.db3", "rosbag2_sqlite3_1.db3"] {
        let head = std::fs::read(sqlite_bag().join(f)).unwrap();
        assert!(head.starts_with(b"SQLite format 3\0"), "{f}");
    }
    let head = std::fs::read(mcap_bag().join("rosbag2_mcap_0.mcap")).unwrap();
    assert!(head.starts_with(b"\x89MCAP0\r\n"));
}

/// Both rosbag2 directories, the MCAP bag's metadata.yaml and its bare
/// `.mcap` give byte-identical predictions and metrics to the PLY frames
/// (plane-optimized, with the sample's poses matched by header stamp).
#[test]
fn every_bag_form_gives_the_predictions_of_the_ply_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let sample = sample_dir();
    let poses = sample.join("poses.txt");
    let ply = tmp.path().join("ply");
    detect(
        &["--frames", s(&sample.join("frames"))],
        &ply,
        &["--poses", s(&poses)],
    );
    let want = predictions(&ply);
    assert_eq!(want.len(), 3);
    let want_probs = common::confidences(&ply);
    assert_eq!(want_probs.len(), 3);
    let want_metrics = std::fs::read(ply.join("metrics.json")).unwrap();
    let bags = [
        ("sqlite3", sqlite_bag()),
        ("mcap", mcap_bag()),
        ("metadata", mcap_bag().join("metadata.yaml")),
        ("bare-mcap", mcap_bag().join("rosbag2_mcap_0.mcap")),
    ];
    for (name, bag) in bags {
        let out = tmp.path().join(name);
        detect(
            &["--bag", s(&bag), "--topic", TOPIC],
            &out,
            &["--poses", s(&poses)],
        );
        assert_eq!(predictions(&out), want, "{name}: predictions");
        assert_eq!(common::confidences(&out), want_probs, "{name}: confidences");
        assert_eq!(
            std::fs::read(out.join("metrics.json")).unwrap(),
            want_metrics,
            "{name}: metrics.json"
        );
    }
}

/// Each file of the split sqlite3 bag read on its own holds its frames:
/// single-scan predictions equal the PLY frames' for exactly those frames.
#[test]
fn a_bare_db3_file_is_a_bag_of_its_own() {
    let tmp = tempfile::tempdir().unwrap();
    let ply = tmp.path().join("ply");
    let single = ["--method", "single-scan"];
    detect(
        &["--frames", s(&sample_dir().join("frames"))],
        &ply,
        &single,
    );
    let want: Vec<(String, Vec<u8>)> = predictions(&ply).into_iter().collect();
    assert_eq!(want.len(), 3);
    for (file, frames) in [
        ("rosbag2_sqlite3_0.db3", &want[..2]),
        ("rosbag2_sqlite3_1.db3", &want[2..]),
    ] {
        let out = tmp.path().join(file);
        let bag = sqlite_bag().join(file);
        detect(&["--bag", s(&bag), "--topic", TOPIC], &out, &single);
        let got: Vec<(String, Vec<u8>)> = predictions(&out).into_iter().collect();
        assert_eq!(got, frames, "{file}");
    }
}

/// `slam --bag` estimates the same poses (and predictions, and trajectory
/// error against the true poses matched by header stamp) as `slam --frames`
/// on the PLY sample.
#[test]
fn slam_on_a_bag_gives_the_poses_of_slam_on_the_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let sample = sample_dir();
    let gt = sample.join("poses.txt");
    let run = |input: &[&str], out: &Path| {
        let mut args = vec!["slam"];
        args.extend_from_slice(input);
        args.extend_from_slice(&["--gt-poses", s(&gt), "--out", s(out)]);
        let o = specular(&args);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    };
    let ply = tmp.path().join("ply");
    run(&["--frames", s(&sample.join("frames"))], &ply);
    let bag = tmp.path().join("bag");
    run(&["--bag", s(&sqlite_bag()), "--topic", TOPIC], &bag);

    let poses = std::fs::read_to_string(ply.join("poses.txt")).unwrap();
    assert_eq!(poses.lines().count(), 3);
    assert_eq!(
        std::fs::read_to_string(bag.join("poses.txt")).unwrap(),
        poses
    );
    assert_eq!(predictions(&bag), predictions(&ply));
    assert_eq!(
        std::fs::read(bag.join("planes.json")).unwrap(),
        std::fs::read(ply.join("planes.json")).unwrap()
    );
    let metrics = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap()).unwrap()
    };
    let (a, b) = (metrics(&ply), metrics(&bag));
    assert!(a["trajectory"]["ate_rmse"].as_f64().is_some(), "{a}");
    assert_eq!(a["trajectory"], b["trajectory"]);
    assert_eq!(a["classification"], b["classification"]);
}

/// An unknown topic names the bag's file and lists the topics present; a
/// topic of another type says what it is.
#[test]
fn an_unknown_topic_lists_the_topics_present() {
    let meta = sqlite_bag().join("metadata.yaml");
    let err = detect_fails(&sqlite_bag(), "/nope");
    assert!(
        err.contains(&format!("{}: no topic /nope; topics: ", meta.display())),
        "{err}"
    );
    assert!(
        err.contains("/points (sensor_msgs/msg/PointCloud2, 3 messages)"),
        "{err}"
    );
    assert!(
        err.contains("/chatter (std_msgs/msg/String, 3 messages)"),
        "{err}"
    );

    let db3 = sqlite_bag().join("rosbag2_sqlite3_1.db3");
    let err = detect_fails(&db3, "/nope");
    assert!(
        err.contains(&format!("{}: no messages on /nope", db3.display())),
        "{err}"
    );
    assert!(
        err.contains("/points (sensor_msgs/msg/PointCloud2, 1 messages)"),
        "{err}"
    );

    let mcap = mcap_bag().join("rosbag2_mcap_0.mcap");
    let err = detect_fails(&mcap, "/nope");
    assert!(
        err.contains(&format!("{}: no messages on /nope", mcap.display())),
        "{err}"
    );
    assert!(err.contains("/chatter (std_msgs/msg/String"), "{err}");

    let err = detect_fails(&mcap_bag(), "/chatter");
    let want = "topic /chatter is std_msgs/msg/String in cdr, not sensor_msgs/msg/PointCloud2";
    assert!(err.contains(want), "{err}");
    assert!(err.contains("rosbag2_mcap/metadata.yaml"), "{err}");
}

/// A copy of the sqlite3 bag in `tmp/name`, changed by `edit`.
fn broken(tmp: &Path, name: &str, edit: impl FnOnce(&Path)) -> PathBuf {
    let dir = tmp.join(name);
    copy_dir(&sqlite_bag(), &dir);
    edit(&dir);
    dir
}

/// Replace `from` by `to` in the bag's metadata.yaml (which must hold it).
fn edit_metadata(dir: &Path, from: &str, to: &str) {
    let path = dir.join("metadata.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "metadata.yaml lacks {from:?}");
    std::fs::write(&path, text.replace(from, to)).unwrap();
}

#[test]
fn a_broken_bag_names_the_file_and_what_is_wrong() {
    let tmp = tempfile::tempdir().unwrap();
    let tmp = tmp.path();
    let meta = |dir: &Path| dir.join("metadata.yaml").display().to_string();

    let dir = broken(tmp, "storage", |d| {
        edit_metadata(d, "storage_identifier: sqlite3", "storage_identifier: foo")
    });
    let err = detect_fails(&dir, TOPIC);
    let want = format!(
        "{}: storage_identifier 'foo' is not mcap or sqlite3",
        meta(&dir)
    );
    assert!(err.contains(&want), "{err}");

    let dir = broken(tmp, "missing-file", |d| {
        std::fs::remove_file(d.join("rosbag2_sqlite3_1.db3")).unwrap()
    });
    let err = detect_fails(&dir, TOPIC);
    let want = format!(
        "{}: relative_file_paths lists rosbag2_sqlite3_1.db3, which is not a file in",
        meta(&dir)
    );
    assert!(err.contains(&want), "{err}");

    let dir = broken(tmp, "no-file-list", |d| {
        edit_metadata(
            d,
            "  relative_file_paths:\n  - rosbag2_sqlite3_0.db3\n  - rosbag2_sqlite3_1.db3\n",
            "",
        )
    });
    let err = detect_fails(&dir, TOPIC);
    assert!(err.contains(&format!("{}: ", meta(&dir))), "{err}");
    assert!(err.contains("missing field `relative_file_paths`"), "{err}");

    let dir = broken(tmp, "not-sqlite", |d| {
        std::fs::write(d.join("rosbag2_sqlite3_1.db3"), b"not a database").unwrap()
    });
    let err = detect_fails(&dir, TOPIC);
    let file = dir.join("rosbag2_sqlite3_1.db3");
    let want = format!("{}: not an SQLite database", file.display());
    assert!(err.contains(&want), "{err}");
    // The same file given on its own.
    assert!(detect_fails(&file, TOPIC).contains(&want));

    let dir = broken(tmp, "wrong-storage", |d| {
        edit_metadata(d, "storage_identifier: sqlite3", "storage_identifier: mcap")
    });
    let err = detect_fails(&dir, TOPIC);
    let file = dir.join("rosbag2_sqlite3_0.db3");
    assert!(
        err.contains(&format!("{}: not an MCAP file", file.display())),
        "{err}"
    );

    let dir = broken(tmp, "no-metadata", |d| {
        std::fs::remove_file(d.join("metadata.yaml")).unwrap()
    });
    let err = detect_fails(&dir, TOPIC);
    let want = format!("{}: a directory without metadata.yaml", dir.display());
    assert!(err.contains(&want), "{err}");
}

/// `--topic` belongs to `--bag`: with `--frames` it is refused, not ignored.
#[test]
fn a_topic_without_a_bag_is_refused() {
    let out = tempfile::tempdir().unwrap();
    let frames = sample_dir().join("frames");
    for command in ["detect", "slam"] {
        let o = specular(&[
            command,
            "--frames",
            s(&frames),
            "--topic",
            TOPIC,
            "--out",
            s(&out.path().join(command)),
        ]);
        assert!(!o.status.success(), "{command}");
        let err = stderr(&o);
        assert!(err.contains("'--topic <TOPIC>'"), "{command}: {err}");
    }
}
