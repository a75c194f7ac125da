//! The `--out` directory of a run: new or empty, or (with `--force`) holding
//! only an earlier run's outputs, which are replaced; marked incomplete
//! until the run has written everything.
//!
//! Outputs that look finished but are not mislead: an earlier run's stale
//! labels and plots beside fresh metrics, or a killed run's files with no
//! sign that it stopped. So a run writes into a directory that holds
//! nothing else, and an `INCOMPLETE` file says so until it succeeds; a run
//! killed outright (no chance to clean up) leaves the marker behind, and
//! one interrupted (Ctrl-C, SIGTERM) removes its temporary files first.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, Once};

use anyhow::{bail, Context, Result};

/// The marker left in an output directory while its run is unfinished.
pub(crate) const INCOMPLETE: &str = "INCOMPLETE";

/// What `detect`, `slam`, `demo` and `graph solve` write into `--out`
/// (names or extensions): `--force` removes these and nothing else.
const RUN_OUTPUTS: [&str; 17] = [
    "predictions",
    "predictions.partial",
    "metrics.json",
    "config.toml",
    "planes.json",
    "around_corner.ply",
    "map.ply",
    "run.mcap",
    "run.mcap.tmp",
    "report.md",
    "poses.txt",
    "frames.csv",
    "graph.json",
    "solve.json",
    INCOMPLETE,
    ".png",
    ".tmp",
];

/// The output directories of the runs still in progress, cleaned of their
/// temporary files when the process is interrupted.
static IN_PROGRESS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Set on Ctrl-C or SIGTERM: the run's writers stop.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Whether the process was interrupted (writers check it before writing).
pub(crate) fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// Whether `name` is a temporary file or directory of a run (renamed into
/// place when the run finishes).
fn is_temporary(name: &str) -> bool {
    name == "predictions.partial"
        || name.ends_with(".tmp")
        || (name.starts_with('.') && name.contains(".tmp"))
}

/// On Ctrl-C or SIGTERM: remove the temporary files of every run in
/// progress, note the interruption in its marker, and exit with 130.
fn on_interrupt() {
    INTERRUPTED.store(true, Ordering::SeqCst);
    let dirs = IN_PROGRESS.lock().map(|d| d.clone()).unwrap_or_default();
    for dir in dirs {
        // A write already under way when the flag was set may still land:
        // sweep, wait for it, sweep again.
        for _ in 0..5 {
            std::thread::sleep(std::time::Duration::from_millis(20));
            let mut found = false;
            for entry in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
                if is_temporary(&entry.file_name().to_string_lossy()) {
                    found = true;
                    let p = entry.path();
                    let _ = if p.is_dir() {
                        std::fs::remove_dir_all(&p)
                    } else {
                        std::fs::remove_file(&p)
                    };
                }
            }
            if !found {
                break;
            }
        }
        let _ = std::fs::write(
            dir.join(INCOMPLETE),
            format!(
                "specular {} (commit {}): this run was interrupted; its outputs are incomplete.\n",
                specular::VERSION,
                specular::GIT_COMMIT
            ),
        );
        eprintln!(
            "interrupted: the outputs in {} are incomplete (see its {INCOMPLETE} file)",
            dir.display()
        );
    }
    std::process::exit(130);
}

/// Install the interrupt handler once per process (a failure to install
/// it only costs the clean-up, so it is not an error).
fn install_interrupt_handler() {
    static INSTALL: Once = Once::new();
    INSTALL.call_once(|| {
        if let Err(e) = ctrlc::set_handler(on_interrupt) {
            tracing::warn!(
                "no interrupt handler ({e}): an interrupted run keeps its temporary files"
            );
        }
    });
}

/// Whether `name` is something a run writes (or its temporary file).
fn is_run_output(name: &str) -> bool {
    RUN_OUTPUTS
        .iter()
        .any(|k| name == *k || (k.starts_with('.') && name.ends_with(k)))
        || is_temporary(name)
}

/// An output directory claimed by a run.
#[derive(Debug)]
pub(crate) struct RunDir {
    path: PathBuf,
    created: bool,
    finished: bool,
}

impl RunDir {
    /// Claim `path` for a run: create it when missing; refuse it when it
    /// holds anything, unless `force`, which removes an earlier run's
    /// outputs (and refuses a directory holding anything else). Marks the
    /// directory incomplete.
    pub(crate) fn claim(path: &Path, force: bool) -> Result<Self> {
        let created = !path.exists();
        if !created {
            if !path.is_dir() {
                bail!("--out {}: exists and is not a directory", path.display());
            }
            let entries: Vec<_> = std::fs::read_dir(path)
                .with_context(|| format!("reading {}", path.display()))?
                .collect::<std::io::Result<_>>()
                .with_context(|| format!("reading {}", path.display()))?;
            if !entries.is_empty() {
                if !force {
                    bail!(
                        "--out {} is not empty (an earlier run?): give a new directory, or --force to replace that run's outputs",
                        path.display()
                    );
                }
                let mut names: Vec<String> = entries
                    .iter()
                    .map(|e| e.file_name().to_string_lossy().into_owned())
                    .collect();
                names.sort();
                if let Some(other) = names.iter().find(|n| !is_run_output(n)) {
                    bail!(
                        "--out {} holds {other}, which no run writes: --force replaces only an earlier run's outputs; give a new directory",
                        path.display()
                    );
                }
                for e in entries {
                    let p = e.path();
                    let removed = if p.is_dir() {
                        std::fs::remove_dir_all(&p)
                    } else {
                        std::fs::remove_file(&p)
                    };
                    removed.with_context(|| format!("removing the earlier {}", p.display()))?;
                }
            }
        }
        std::fs::create_dir_all(path).with_context(|| format!("creating {}", path.display()))?;
        let marker = path.join(INCOMPLETE);
        std::fs::write(
            &marker,
            format!(
                "specular {} (commit {}): this run has not finished (it is running, failed or was killed); its outputs are incomplete.\n",
                specular::VERSION,
                specular::GIT_COMMIT
            ),
        )
        .with_context(|| format!("writing {}", marker.display()))?;
        install_interrupt_handler();
        if let Ok(mut dirs) = IN_PROGRESS.lock() {
            dirs.push(path.to_path_buf());
        }
        Ok(Self {
            path: path.to_path_buf(),
            created,
            finished: false,
        })
    }

    /// The run succeeded: remove the marker.
    pub(crate) fn finish(mut self) -> Result<()> {
        let marker = self.path.join(INCOMPLETE);
        std::fs::remove_file(&marker).with_context(|| format!("removing {}", marker.display()))?;
        self.finished = true;
        Ok(())
    }
}

impl Drop for RunDir {
    /// A failed run keeps its marker beside whatever it wrote; one that
    /// left nothing else removes the marker too (and the directory, if it
    /// created it).
    fn drop(&mut self) {
        if let Ok(mut dirs) = IN_PROGRESS.lock() {
            dirs.retain(|d| d != &self.path);
        }
        // An interrupted run stays marked, whatever it left.
        if self.finished || interrupted() {
            return;
        }
        let only_marker = std::fs::read_dir(&self.path).is_ok_and(|entries| {
            entries
                .filter_map(|e| e.ok())
                .all(|e| e.file_name() == INCOMPLETE)
        });
        if only_marker {
            let _ = std::fs::remove_file(self.path.join(INCOMPLETE));
            if self.created {
                let _ = std::fs::remove_dir(&self.path);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_outputs_are_recognised_and_nothing_else() {
        for name in [
            "predictions",
            "metrics.json",
            "topdown.png",
            "run.mcap.tmp",
            ".metrics.json.tmp123",
            "INCOMPLETE",
        ] {
            assert!(is_run_output(name), "{name}");
        }
        for name in ["frames", "notes.txt", "data.ply", "poses.tum"] {
            assert!(!is_run_output(name), "{name}");
        }
    }
}
