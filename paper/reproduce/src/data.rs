//! The datasets of the reproduction: real 3DRef directories and the
//! simulator's scenes, loaded as sequences with their true poses.

use std::path::{Path, PathBuf};

use serde::Serialize;

use nalgebra::Isometry3;
use rayon::prelude::*;
use specular::config::Config;
use specular::pipeline::{Sequence, StageTimings};

use specular::cloud::Frame;
use specular::sim::{self, LabelCounts, Scene, SimFrame, Simulator};
use specular::{Error, Result};

/// Where a dataset comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// A 3DRef-format directory: `*.ply` frames (in `frames/`, in
    /// `raycast/hesai/` as in the 3DRef release's `raw/seqN/`, or directly)
    /// and a TUM pose file (`poses.txt` or `hesai_pose.txt`).
    Real(PathBuf),
    /// A built-in simulator scene, simulated in memory.
    Simulated(String),
}

/// Real or simulated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DataKind {
    /// Recorded 3DRef frames.
    Real,
    /// The built-in simulator.
    Simulated,
}

/// A loaded dataset.
#[derive(Debug, Clone)]
pub struct Dataset {
    /// Name in the tables (directory name or `sim:<scene>`).
    pub name: String,
    /// Real or simulated.
    pub kind: DataKind,
    /// The frames with their true poses.
    pub sequence: Sequence,
    /// The scene name, for simulated data.
    pub scene: Option<String>,
    /// The sensor the frames come from (configuration `sensor` value).
    pub sensor: String,
}

/// What the tables say about a dataset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DatasetInfo {
    /// Name in the tables.
    pub name: String,
    /// Real or simulated.
    pub kind: DataKind,
    /// Frames used.
    pub frames: usize,
    /// Points (both returns) over all frames.
    pub points: u64,
    /// Points per 3DRef label id 0..=6.
    pub by_label: [u64; 7],
    /// Whether every frame carries labels.
    pub labelled: bool,
}

/// The frame directory and pose file of a 3DRef-format directory; an error
/// naming `dir` when it is not one.
pub fn resolve_real(dir: &Path) -> Result<(PathBuf, PathBuf)> {
    if !dir.is_dir() {
        return Err(Error::Input(format!(
            "--data {}: not a directory",
            dir.display()
        )));
    }
    // `frames/` (as `specular simulate` and the bundled sample), the
    // 3DRef release layout `raw/seqN/raycast/hesai/`, or the directory
    // itself (as the shared ten frames).
    let frames = [dir.join("frames"), dir.join("raycast").join("hesai")]
        .into_iter()
        .find(|d| d.is_dir())
        .unwrap_or_else(|| dir.to_path_buf());
    let poses = ["poses.txt", "hesai_pose.txt"]
        .iter()
        .map(|f| dir.join(f))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            Error::Input(format!(
                "--data {}: no pose file (poses.txt or hesai_pose.txt) in it",
                dir.display()
            ))
        })?;
    Ok((frames, poses))
}

/// Load a dataset; simulated sequences are shortened to
/// [`super::QUICK_FRAMES`] frames from the middle of their trajectory with
/// `quick`.
pub fn load(source: &Source, quick: bool) -> Result<Dataset> {
    match source {
        Source::Real(dir) => {
            let (frames, poses) = resolve_real(dir)?;
            let tolerance = Config::default().input.pose_tolerance;
            let sequence = Sequence::load(
                &frames,
                Some(&poses),
                tolerance,
                &mut StageTimings::default(),
            )
            .map_err(|e| Error::Input(format!("--data {}: {e}", dir.display())))?;
            if sequence.is_empty() {
                return Err(Error::Input(format!(
                    "--data {}: no frames (*.ply) found",
                    dir.display()
                )));
            }
            Ok(Dataset {
                name: dir_name(dir),
                kind: DataKind::Real,
                sequence,
                scene: None,
                sensor: Config::default().sensor,
            })
        }
        Source::Simulated(name) => {
            let scene = Scene::resolve(name)?;
            let label = format!("sim:{name}");
            let (frames, poses) = if quick {
                middle_frames(&scene, super::QUICK_FRAMES)
            } else {
                let run = sim::simulate(&scene, None, None)?;
                let poses = run.poses.iter().map(|p| p.pose).collect();
                (run.frames, poses)
            };
            let sequence = Sequence::from_frames(frames, Some(poses), &label)?;
            Ok(Dataset {
                name: label,
                kind: DataKind::Simulated,
                sequence,
                scene: Some(name.clone()),
                sensor: scene.sensor.model.name.clone(),
            })
        }
    }
}

/// `n` consecutive frames from the middle of the scene's trajectory (where
/// the benchmark scenes show their glass and mirrors; their first frames
/// may see none), with their true poses.
fn middle_frames(scene: &Scene, n: usize) -> (Vec<Frame>, Vec<Isometry3<f64>>) {
    let sim = Simulator::new(scene);
    let first = scene.frames.saturating_sub(n) / 2;
    let count = n.min(scene.frames);
    let frames: Vec<SimFrame> = (first..first + count)
        .into_par_iter()
        .map(|k| sim.frame(k, scene.seed))
        .collect();
    frames.into_iter().map(|f| (f.frame, f.pose.pose)).unzip()
}

/// The last component of `dir` (the whole path when it has none).
pub(crate) fn dir_name(dir: &Path) -> String {
    dir.canonicalize()
        .ok()
        .and_then(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| dir.display().to_string())
}

impl Dataset {
    /// A built-in configuration (`default` or `paper`) for this dataset's
    /// sensor.
    pub fn config(&self, name: &str) -> Result<Config> {
        let mut config = Config::resolve(name)?;
        config.sensor = self.sensor.clone();
        Ok(config)
    }

    /// Its size and label counts.
    pub fn info(&self) -> Result<DatasetInfo> {
        let mut counts = LabelCounts::default();
        let mut labelled = true;
        for k in 0..self.sequence.len() {
            let frame = self.sequence.frame(k)?;
            counts = counts.merge(LabelCounts::of(&frame));
            labelled &= frame.has_labels;
        }
        Ok(DatasetInfo {
            name: self.name.clone(),
            kind: self.kind,
            frames: self.sequence.len(),
            points: counts.points,
            by_label: counts.by_label,
            labelled,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_three_directory_layouts_resolve_and_a_missing_pose_file_is_named() {
        let tmp = tempfile::tempdir().unwrap();
        let root = tmp.path();
        // 3DRef release layout: raw/seqN/{hesai_pose.txt, raycast/hesai/}.
        let seq = root.join("seq1");
        std::fs::create_dir_all(seq.join("raycast/hesai")).unwrap();
        std::fs::write(seq.join("hesai_pose.txt"), "").unwrap();
        let (frames, poses) = resolve_real(&seq).unwrap();
        assert_eq!(frames, seq.join("raycast/hesai"));
        assert_eq!(poses, seq.join("hesai_pose.txt"));
        // Simulator / bundled-sample layout: frames/ and poses.txt.
        let sim = root.join("sim");
        std::fs::create_dir_all(sim.join("frames")).unwrap();
        std::fs::write(sim.join("poses.txt"), "").unwrap();
        assert_eq!(resolve_real(&sim).unwrap().0, sim.join("frames"));
        // Frames in the directory itself, but no pose file.
        let flat = root.join("flat");
        std::fs::create_dir_all(&flat).unwrap();
        let err = resolve_real(&flat).unwrap_err().to_string();
        assert!(err.contains("flat") && err.contains("pose"), "{err}");
        let err = resolve_real(&root.join("missing")).unwrap_err().to_string();
        assert!(err.contains("missing"), "{err}");
    }
}
