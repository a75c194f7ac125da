//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod bags;
pub mod cli;
pub mod faults;
pub mod strategies;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use specular::pipeline::Sequence;
use specular::sim::{Scene, Simulator};

/// The bundled real sample (always present).
pub fn sample_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("datasets/3dref-sample")
}

/// The ten shared real frames (`../shared/data/3dref-seq1-demo` beside the
/// crate, or `SPECULAR_DATA`), when present. A fresh clone without them
/// skips the real-data tests with a note; with `SPECULAR_REQUIRE_SHARED=1`
/// (set by CI) their absence fails the test instead of passing it silently.
pub fn shared_frames() -> Option<PathBuf> {
    let dir = std::env::var_os("SPECULAR_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/3dref-seq1-demo")
        });
    if dir.join("hesai_pose.txt").is_file() {
        Some(dir)
    } else if std::env::var_os("SPECULAR_REQUIRE_SHARED").is_some_and(|v| v == "1") {
        panic!(
            "{} not found, and SPECULAR_REQUIRE_SHARED=1: the real-data tests cannot run",
            dir.display()
        );
    } else {
        eprintln!("note: {} not found; test skipped", dir.display());
        None
    }
}

/// A run's predictions (`OUT/predictions/*.label`), by file name, as bytes.
pub fn predictions(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    prediction_files(dir, "label")
}

/// A run's confidences (`OUT/predictions/*.prob`), by file name, as bytes.
pub fn confidences(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    prediction_files(dir, "prob")
}

/// The files `OUT/predictions/*.{extension}`, by file name, as bytes.
fn prediction_files(dir: &Path, extension: &str) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir.join("predictions"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == extension))
        .map(|p| {
            (
                p.file_name().unwrap().to_str().unwrap().to_string(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect()
}

/// The rosbag2 bags of the bundled sample written by the `rosbags` Python
/// library (`tests/fixtures/`, see its README).
pub fn fixtures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

/// Run the `specular` binary with `args`.
pub fn specular(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(args)
        .output()
        .expect("run specular")
}

/// Copy the files of directory `from` into a new directory `to`.
pub fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// The frames `frames` (indices of the scene's 10 Hz sequence, with their
/// timestamps) of a built-in scene, with their true poses: a subset of
/// them is what a sensor that dropped frames delivers.
pub fn simulated_subset(scene: &str, frames: impl Iterator<Item = usize>) -> Sequence {
    let scene = Scene::resolve(scene).unwrap();
    let sim = Simulator::new(&scene);
    let (frames, poses) = frames
        .map(|k| {
            let f = sim.frame(k, scene.seed);
            (f.frame, f.pose.pose)
        })
        .unzip();
    Sequence::from_frames(frames, Some(poses), "simulated").unwrap()
}
