//! KISS-ICP (Vizzo et al., RA-L 2023), the external LiDAR odometry peer of
//! the trajectory comparison: its pip package runs in a private venv on the
//! first returns of each sequence, and its poses are scored with our own
//! [`trajectory_error`](specular::eval::trajectory_error), as the SLAM poses
//! are.
//!
//! The work happens in `<out>/.kiss-icp/` (ignored by git): the venv, the
//! exported scans (removed after each run) and KISS-ICP's logs. The shell
//! script `paper/kiss_icp.sh` is embedded in the binary.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use std::io::Write;

use rayon::prelude::*;

use specular::io::write_atomic;
use specular::pipeline::Sequence;
use specular::{Error, Result};

/// The KISS-ICP version installed (pinned for reproducibility).
pub const VERSION: &str = "1.3.0";
/// The script that installs and runs it.
pub const SCRIPT: &str = include_str!("../../kiss_icp.sh");
/// KISS-ICP's configuration: the 3DRef crop as maximum range (its voxel
/// size follows as 1/100 of it), no deskewing (the simulated sweeps have
/// no motion distortion) and one thread, so its result is repeatable.
pub const CONFIG: &str = "data:\n  max_range: 25.0\n  min_range: 0.0\n  deskew: false\nregistration:\n  max_num_threads: 1\n";

/// A KISS-ICP installation in a work directory.
#[derive(Debug, Clone, PartialEq)]
pub struct KissIcp {
    /// The work directory (venv, exported scans, logs).
    pub work: PathBuf,
}

impl KissIcp {
    /// KISS-ICP working in `work`.
    pub fn new(work: PathBuf) -> Self {
        Self { work }
    }

    fn venv(&self) -> PathBuf {
        self.work.join("venv")
    }

    fn script(&self) -> PathBuf {
        self.work.join("kiss_icp.sh")
    }

    /// Write the script, its configuration and a `.gitignore`, then create
    /// the venv and install KISS-ICP unless it is there already.
    pub fn prepare(&self) -> Result<()> {
        write_atomic(&self.work.join(".gitignore"), |w| w.write_all(b"*\n"))?;
        write_atomic(&self.script(), |w| w.write_all(SCRIPT.as_bytes()))?;
        write_atomic(&self.work.join("config.yaml"), |w| {
            w.write_all(CONFIG.as_bytes())
        })?;
        let venv = self.venv();
        self.sh(&["install", &venv.to_string_lossy()])
    }

    /// Run `sh kiss_icp.sh ARGS` to completion, an error with the tail of
    /// its output on failure.
    fn sh(&self, args: &[&str]) -> Result<()> {
        let out = Command::new("sh")
            .arg(self.script())
            .args(args)
            .output()
            .map_err(|e| Error::io(self.script(), e))?;
        if out.status.success() {
            return Ok(());
        }
        let text = format!(
            "{}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        Err(self.failure(args.first().unwrap_or(&""), out.status, &text))
    }

    /// The error of a failed script run: its status and the last lines of
    /// its output (KISS-ICP reports some errors on stdout).
    fn failure(&self, what: &str, status: ExitStatus, output: &str) -> Error {
        let tail: Vec<&str> = output
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .rev()
            .take(3)
            .collect();
        Error::Input(format!(
            "{} {what} failed ({status}): {}",
            self.script().display(),
            tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        ))
    }

    /// Start odometry over `sequence` (first returns only) in the
    /// background; [`KissRun::finish`] waits for its poses. The scans are
    /// exported first, so the sequence may be dropped meanwhile.
    pub fn start(&self, name: &str, sequence: &Sequence) -> Result<KissRun> {
        let safe: String = name
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '-' })
            .collect();
        let dir = self.work.join(&safe);
        let scans = dir.join("scans");
        let logs = dir.join("logs");
        export_scans(&scans, sequence)?;
        std::fs::create_dir_all(&logs).map_err(|e| Error::io(&logs, e))?;
        let output = dir.join("output.txt");
        let file = std::fs::File::create(&output).map_err(|e| Error::io(&output, e))?;
        let file2 = file.try_clone().map_err(|e| Error::io(&output, e))?;
        let child = Command::new("sh")
            .arg(self.script())
            .arg("run")
            .arg(self.venv())
            .arg(self.work.join("config.yaml"))
            .arg(&scans)
            .arg(&logs)
            .stdout(Stdio::from(file))
            .stderr(Stdio::from(file2))
            .spawn()
            .map_err(|e| Error::io(self.script(), e))?;
        Ok(KissRun {
            kiss: self.clone(),
            child: Some(child),
            scans,
            logs,
            output,
            frames: sequence.len(),
        })
    }
}

/// A KISS-ICP run in the background.
#[derive(Debug)]
pub struct KissRun {
    kiss: KissIcp,
    /// `None` once waited for.
    child: Option<Child>,
    scans: PathBuf,
    logs: PathBuf,
    output: PathBuf,
    frames: usize,
}

impl KissRun {
    /// Wait for the run and read its poses (one per frame, the first at
    /// the identity); the exported scans are removed.
    pub fn finish(mut self) -> Result<Vec<Isometry3<f64>>> {
        let status = match self.child.take() {
            Some(mut child) => child.wait().map_err(|e| Error::io(self.kiss.script(), e)),
            None => Err(Error::Input("KISS-ICP run already finished".into())),
        };
        let _ = std::fs::remove_dir_all(&self.scans);
        let status = status?;
        if !status.success() {
            let text = std::fs::read_to_string(&self.output).unwrap_or_default();
            return Err(self.kiss.failure("run", status, &text));
        }
        let poses = read_kitti_poses(&find_poses(&self.logs.join("latest"))?)?;
        if poses.len() != self.frames {
            return Err(Error::Input(format!(
                "KISS-ICP returned {} poses for {} frames",
                poses.len(),
                self.frames
            )));
        }
        Ok(poses)
    }
}

impl Drop for KissRun {
    /// A run abandoned (an error elsewhere) is stopped, not left running.
    fn drop(&mut self) {
        if let Some(mut child) = self.child.take() {
            let _ = child.kill();
            let _ = child.wait();
            let _ = std::fs::remove_dir_all(&self.scans);
        }
    }
}

/// Write every frame's first returns as a KITTI `.bin` scan (float32
/// x y z intensity), named `000000.bin`, ... in sequence order.
pub fn export_scans(dir: &Path, sequence: &Sequence) -> Result<()> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    (0..sequence.len()).into_par_iter().try_for_each(|k| {
        let frame = sequence.frame(k)?;
        write_atomic(&dir.join(format!("{k:06}.bin")), |w| {
            for p in frame.points.iter().filter(|p| p.ret == 1) {
                for v in [p.xyz[0], p.xyz[1], p.xyz[2], p.intensity] {
                    w.write_all(&v.to_le_bytes())?;
                }
            }
            Ok(())
        })
    })
}

/// The `*_poses_kitti.txt` file KISS-ICP wrote into `dir`.
fn find_poses(dir: &Path) -> Result<PathBuf> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    entries
        .flatten()
        .map(|e| e.path())
        .find(|p| p.to_string_lossy().ends_with("_poses_kitti.txt"))
        .ok_or_else(|| Error::Input(format!("{}: no *_poses_kitti.txt", dir.display())))
}

/// Parse KITTI poses: one row-major 3×4 matrix `[R | t]` per line.
pub fn read_kitti_poses(path: &Path) -> Result<Vec<Isometry3<f64>>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    parse_kitti_poses(&text).map_err(|m| Error::format(path, m))
}

/// Parse the text of a KITTI pose file (see [`read_kitti_poses`]); the
/// message names the bad line.
pub fn parse_kitti_poses(text: &str) -> std::result::Result<Vec<Isometry3<f64>>, String> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, line)| {
            let v: Vec<f64> = line
                .split_whitespace()
                .map(str::parse)
                .collect::<std::result::Result<_, _>>()
                .map_err(|e| format!("line {}: {e}", i + 1))?;
            if v.len() != 12 || v.iter().any(|x| !x.is_finite()) {
                return Err(format!("line {}: expected 12 finite numbers", i + 1));
            }
            let r = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
            let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
            let t = Translation3::from(Vector3::new(v[3], v[7], v[11]));
            Ok(Isometry3::from_parts(t, rotation))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kitti_poses_parse_and_bad_lines_are_named() {
        let text = "1 0 0 1.5 0 1 0 -2 0 0 1 0.25\n0 -1 0 0 1 0 0 0 0 0 1 0\n";
        let poses = parse_kitti_poses(text).unwrap();
        assert_eq!(poses.len(), 2);
        assert!((poses[0].translation.vector - Vector3::new(1.5, -2.0, 0.25)).norm() < 1e-12);
        assert!((poses[1].rotation.angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
        let err = parse_kitti_poses("1 0 0\n").unwrap_err();
        assert!(err.contains("line 1"), "{err}");
        assert!(parse_kitti_poses("1 0 0 x 0 1 0 0 0 0 1 0").is_err());
    }
}
