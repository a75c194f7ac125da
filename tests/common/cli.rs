//! Running the `specular` binary in tests.

use std::path::Path;
use std::process::{Command, Output};

use super::sample_dir;

/// Run `specular` with `args`.
pub fn specular(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(args)
        .output()
        .expect("run specular")
}

/// A command's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `specular detect` on the bundled sample with its poses, writing to `out`.
pub fn detect_sample(out: &Path, extra: &[&str]) -> Output {
    let sample = sample_dir();
    let frames = sample.join("frames");
    let poses = sample.join("poses.txt");
    let mut args = vec![
        "detect",
        "--frames",
        s(&frames),
        "--poses",
        s(&poses),
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    specular(&args)
}
