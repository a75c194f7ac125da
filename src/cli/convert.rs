//! `specular convert`: rewrite 3DRef frames as compact binary (or ascii) PLY,
//! optionally with the matching poses, e.g. to bundle a sample.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use specular::io::{self, PlyEncoding, StampedPose};

/// Arguments of `convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// Directory of 3DRef frames (`<timestamp>.ply`).
    #[arg(long)]
    pub frames: PathBuf,
    /// Output directory: frames go to OUT/frames/, poses to OUT/poses.txt.
    #[arg(long)]
    pub out: PathBuf,
    /// TUM pose file; the poses of the converted frames are written too.
    #[arg(long)]
    pub poses: Option<PathBuf>,
    /// Pose matching tolerance, seconds.
    #[arg(long, default_value_t = 0.01)]
    pub pose_tolerance: f64,
    /// Convert only these frame stems (default: all).
    #[arg(long, num_args = 1..)]
    pub only: Vec<String>,
    /// Write ascii PLY (as the real 3DRef files) instead of binary.
    #[arg(long)]
    pub ascii: bool,
}

/// Run `convert`.
pub fn run(args: ConvertArgs) -> Result<()> {
    let mut entries = io::list_frames(&args.frames)?;
    if !args.only.is_empty() {
        for stem in &args.only {
            anyhow::ensure!(
                entries.iter().any(|e| &e.name == stem),
                "{}: no frame named {stem}.ply",
                args.frames.display()
            );
        }
        entries.retain(|e| args.only.contains(&e.name));
    }
    let poses = match &args.poses {
        Some(p) => Some(io::match_poses(
            &entries,
            &io::read_tum(p)?,
            args.pose_tolerance,
            p,
        )?),
        None => None,
    };
    let frames_dir = args.out.join("frames");
    let names: Vec<String> = entries.iter().map(|e| e.name.clone()).collect();
    super::run_dir::refuse_other_frames(&frames_dir, &names)?;
    std::fs::create_dir_all(&frames_dir)
        .with_context(|| format!("creating {}", frames_dir.display()))?;
    // Marked incomplete until written; Ctrl-C / SIGTERM cleans up (exit 130).
    let guard = super::run_dir::OutputGuard::new(&args.out, std::slice::from_ref(&frames_dir))?;
    let encoding = if args.ascii {
        PlyEncoding::Ascii
    } else {
        PlyEncoding::BinaryLittleEndian
    };
    for e in &entries {
        if super::run_dir::interrupted() {
            anyhow::bail!("interrupted");
        }
        let frame = io::read_frame(&e.path)?;
        io::write_frame(
            &args.out.join("frames").join(format!("{}.ply", e.name)),
            &frame,
            encoding,
        )?;
    }
    if let Some(poses) = poses {
        let stamped: Vec<StampedPose> = entries
            .iter()
            .zip(poses)
            .map(|(e, pose)| StampedPose {
                stamp: e.stamp,
                pose,
            })
            .collect();
        io::write_tum(&args.out.join("poses.txt"), &stamped)?;
    }
    guard.finish()?;
    println!(
        "{} frames written to {}",
        entries.len(),
        args.out.join("frames").display()
    );
    Ok(())
}
