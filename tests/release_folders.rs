//! The 3DRef release's Ouster and Livox folders (`raw/seqN/raycast/ouster`,
//! `.../livox`): PLY frames read with their own pose files, and `detect`
//! on one. (Split from the driver bag tests.)

mod common;

use std::path::{Path, PathBuf};

// ------------------------------------------------------- 3DRef release

/// `x y z nx ny nz intensity ring return label`, ascii float: the one
/// writer of 3DRef's labelling script, for every sensor.
fn write_release_ply(path: &Path, rows: &[[f32; 4]]) {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float intensity\nproperty float ring\nproperty float return\nproperty float label\nend_header\n",
        rows.len()
    );
    for (i, [x, ring, ret, label]) in rows.iter().enumerate() {
        s += &format!(
            "{x} {} 0.5 0 0 0 {} {ring} {ret} {label}\n",
            i as f32 * 0.1,
            10 * i
        );
    }
    std::fs::write(path, s).unwrap();
}

/// A release sequence with Ouster frames (128 rings) and Livox frames (6
/// lines, up to three returns), each with its pose file.
fn release(dir: &Path) -> PathBuf {
    let seq = dir.join("raw/seq1");
    for (sensor, rows) in [
        (
            "ouster",
            vec![
                [3.0, 127.0, 1.0, 1.0],
                [4.0, 127.0, 2.0, 5.0],
                [5.0, 0.0, 1.0, 2.0],
            ],
        ),
        (
            "livox",
            vec![
                [3.0, 5.0, 1.0, 1.0],
                [4.0, 5.0, 2.0, 5.0],
                [6.0, 5.0, 3.0, 5.0],
            ],
        ),
    ] {
        let frames = seq.join("raycast").join(sensor);
        std::fs::create_dir_all(&frames).unwrap();
        for stamp in ["1689496219.600000", "1689496219.700000"] {
            write_release_ply(&frames.join(format!("{stamp}.ply")), &rows);
        }
        std::fs::write(
            seq.join(format!("{sensor}_pose.txt")),
            "1689496219.600000 0 0 0 0 0 0 1\n1689496219.700000 0.1 0 0 0 0 0 1\n",
        )
        .unwrap();
    }
    seq
}

#[test]
fn the_release_ouster_and_livox_folders_are_read_with_their_poses() {
    use specular::io::{frame_dir, release_poses, Dataset, PlyDir};
    let tmp = tempfile::tempdir().unwrap();
    let seq = release(tmp.path());
    for sensor in ["ouster", "livox"] {
        let folder = seq.join("raycast").join(sensor);
        assert_eq!(frame_dir(&folder), folder);
        assert_eq!(
            release_poses(&folder),
            Some(seq.join(format!("{sensor}_pose.txt")))
        );
        let data = PlyDir::open(&folder).unwrap();
        assert_eq!(data.entries().len(), 2);
        let f = data.frame(0).unwrap();
        let rets: Vec<u8> = f.points.iter().map(|p| p.ret).collect();
        let rings: Vec<u16> = f.points.iter().map(|p| p.ring).collect();
        let labels: Vec<u8> = f.points.iter().map(|p| p.label).collect();
        if sensor == "ouster" {
            assert_eq!(
                (rets, rings, labels),
                (vec![1, 2, 1], vec![127, 127, 0], vec![1, 5, 2])
            );
        } else {
            // The Livox's third echo stays return 3: its sensor model pairs
            // up to three returns by emission.
            assert_eq!(
                (rets, rings, labels),
                (vec![1, 2, 3], vec![5, 5, 5], vec![1, 5, 5])
            );
        }
        assert_eq!(f.points[2].intensity, 20.0);
    }
    // The sequence directory without a Hesai folder: the Ouster one.
    assert_eq!(frame_dir(&seq), seq.join("raycast/ouster"));
    assert_eq!(release_poses(&seq), Some(seq.join("ouster_pose.txt")));
    // detect on the Livox folder finds its pose file.
    let out = tmp.path().join("out");
    let o = common::specular(&[
        "detect",
        "--frames",
        seq.join("raycast/livox").to_str().unwrap(),
        "--method",
        "single-scan",
        "--out",
        out.to_str().unwrap(),
        "--lean",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("livox_pose.txt"), "{stdout}");
    assert_eq!(common::predictions(&out).len(), 2);
}
