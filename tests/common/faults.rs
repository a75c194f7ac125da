//! Helpers of the fault tests of issue 39 (`tests/faults_*.rs`): frames
//! with points that cannot be returns, long inputs to catch a command
//! while it writes, and the checks they share.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use specular::cloud::{Frame, Point};
use specular::io::{self, PlyEncoding};

use super::cli::stderr;

/// The bundled sample's frames.
pub fn sample_frames() -> Vec<Frame> {
    let entries = io::list_frames(&super::sample_dir().join("frames")).unwrap();
    entries
        .iter()
        .map(|e| io::read_frame(&e.path).unwrap())
        .collect()
}

/// The bundled sample's pose file.
pub fn sample_poses() -> PathBuf {
    super::sample_dir().join("poses.txt")
}

/// `frame` with a point that cannot be a return spliced in before every
/// 500th point: NaN, infinite, exactly at the origin, in turn. Returns the
/// frame and, per input point, whether it is such a point.
pub fn with_holes(frame: &Frame) -> (Frame, Vec<bool>) {
    let mut points = Vec::new();
    let mut hole = Vec::new();
    for (i, p) in frame.points.iter().enumerate() {
        if i % 500 == 0 {
            let xyz = match (i / 500) % 3 {
                0 => [f32::NAN, p.xyz[1], p.xyz[2]],
                1 => [p.xyz[0], f32::INFINITY, p.xyz[2]],
                _ => [0.0; 3],
            };
            points.push(Point { xyz, ..*p });
            hole.push(true);
        }
        points.push(*p);
        hole.push(false);
    }
    (
        Frame {
            points,
            ..frame.clone()
        },
        hole,
    )
}

/// The sample's frames with holes, written as binary PLY into `dir`
/// (the first as ascii); per frame name, which input points are holes.
pub fn write_holed_sample(dir: &Path) -> Vec<(String, Vec<bool>)> {
    std::fs::create_dir_all(dir).unwrap();
    sample_frames()
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let (h, holes) = with_holes(f);
            let encoding = if k == 0 {
                PlyEncoding::Ascii
            } else {
                PlyEncoding::BinaryLittleEndian
            };
            io::write_frame(&dir.join(format!("{}.ply", f.name)), &h, encoding).unwrap();
            (f.name.clone(), holes)
        })
        .collect()
}

/// The u32 values of a `.label` (or `.rule`) file.
pub fn read_u32s(path: &Path) -> Vec<u32> {
    io::read_labels(path).unwrap()
}

/// Every label file in `out/predictions` (and rule file, when `rules`, and
/// confidence file) has one entry per input point, 0 at every hole.
pub fn assert_one_label_per_input_point(out: &Path, holed: &[(String, Vec<bool>)], rules: bool) {
    for (name, holes) in holed {
        let mut files = vec![out.join(format!("predictions/{name}.label"))];
        if rules {
            files.push(out.join(format!("predictions/{name}.rule")));
        }
        for file in files {
            let v = read_u32s(&file);
            assert_eq!(v.len(), holes.len(), "{}", file.display());
            for (i, (&l, &h)) in v.iter().zip(holes).enumerate() {
                if h {
                    assert_eq!(l, 0, "{} point {i}", file.display());
                }
            }
            assert!(
                v.iter().zip(holes).any(|(&l, &h)| !h && l != 0),
                "{}: nothing classified",
                file.display()
            );
        }
        // The confidences: one per input point too, 0 at every hole.
        let file = out.join(format!("predictions/{name}.prob"));
        let probs = io::read_probs_for(&file, holes.len()).unwrap();
        for (i, (&p, &h)) in probs.iter().zip(holes).enumerate() {
            if h {
                assert_eq!(p, 0.0, "{} point {i}", file.display());
            }
        }
        assert!(
            probs.iter().zip(holes).any(|(&p, &h)| !h && p > 0.0),
            "{}: no confidence",
            file.display()
        );
    }
}

pub fn ok(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

/// Many copies of the first sample frame (`n`, 0.1 s apart), for runs long
/// enough to be caught while writing.
pub fn many_frames(dir: &Path, n: usize) {
    std::fs::create_dir_all(dir).unwrap();
    let bytes = std::fs::read(super::sample_dir().join("frames/1689496219.652560.ply")).unwrap();
    for k in 0..n {
        let name = format!("{:.6}.ply", 1_689_496_219.0 + 0.1 * k as f64);
        std::fs::write(dir.join(name), &bytes).unwrap();
    }
}

/// Wait (at most a minute) until `dir` holds an entry for which `seen` is
/// true, while `child` runs.
pub fn wait_for(child: &mut std::process::Child, dir: &Path, seen: impl Fn(&str) -> bool) {
    let started = std::time::Instant::now();
    loop {
        let found = std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .any(|e| seen(&e.file_name().to_string_lossy()));
        if found {
            return;
        }
        assert!(
            started.elapsed() < std::time::Duration::from_secs(60),
            "nothing appeared in {}",
            dir.display()
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "the command ended early"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Interrupt `child` with `signal` (`TERM`, `INT`) and wait for it.
#[cfg(unix)]
pub fn interrupt(child: std::process::Child, signal: &str) -> Output {
    let killed = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait_with_output().unwrap()
}

/// The names in `dir` that are temporary files.
pub fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect()
}

/// The sample's frames plus one more, `extra`, named between two of them
/// (its pose interpolated), written into `dir`; returns the extra's stem.
pub fn sample_with(dir: &Path, extra: &str) -> String {
    super::copy_dir(&super::sample_dir().join("frames"), dir);
    let name = "1689496220.052700";
    std::fs::write(dir.join(format!("{name}.ply")), extra).unwrap();
    name.into()
}

/// An ascii frame header for `n` vertices (3DRef properties).
pub fn ascii_header(n: usize) -> String {
    format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\n\
         property float z\nproperty float intensity\nproperty ushort ring\n\
         property uchar return\nproperty uchar label\nend_header\n"
    )
}
