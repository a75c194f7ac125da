//! Records the git commit the crate is built from (`SPECULAR_GIT_COMMIT`,
//! "unknown" outside a git checkout), so every run's metrics.json and
//! report.md can say which code produced them.

use std::path::Path;
use std::process::Command;

fn main() {
    let commit = Command::new("git")
        .args(["rev-parse", "--short=12", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "unknown".to_string());
    println!("cargo:rustc-env=SPECULAR_GIT_COMMIT={commit}");
    // Rebuild when HEAD moves (a commit, a checkout); without a .git
    // directory cargo reruns this on any change of the package.
    for path in [".git/HEAD", ".git/refs/heads", ".git/packed-refs"] {
        if Path::new(path).exists() {
            println!("cargo:rerun-if-changed={path}");
        }
    }
}
