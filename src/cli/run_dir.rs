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

/// A directory written by a command in progress, and what an interruption
/// does to it.
#[derive(Debug, Clone)]
struct InProgress {
    dir: PathBuf,
    kind: Kind,
}

/// What an interruption does to a directory in progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// Remove its temporary files and mark it `INCOMPLETE`.
    Marked,
    /// The scratch directory of a forced rerun: remove it whole (the
    /// earlier run stays).
    Scratch,
    /// Remove its temporary files only (a subdirectory of a marked one).
    Swept,
}

/// Mark a directory that a command other than a run (`simulate`,
/// `convert`) writes into: its `INCOMPLETE` marker stays until
/// [`OutputGuard::finish`], and on Ctrl-C or SIGTERM its temporary files
/// (and those of `also`, e.g. its `frames/`) are removed, the marker says
/// it was interrupted and the process exits with 130, as for a run.
#[derive(Debug)]
pub(crate) struct OutputGuard {
    dirs: Vec<PathBuf>,
    marker: PathBuf,
    finished: bool,
}

impl OutputGuard {
    /// Guard `dir` (created when missing) and the directories `also`.
    pub(crate) fn new(dir: &Path, also: &[PathBuf]) -> Result<Self> {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let marker = dir.join(INCOMPLETE);
        std::fs::write(
            &marker,
            format!(
                "specular {} (commit {}): this output has not been completely written (it is being written, failed or was killed).\n",
                specular::VERSION,
                specular::GIT_COMMIT
            ),
        )
        .with_context(|| format!("writing {}", marker.display()))?;
        install_interrupt_handler();
        let mut dirs = vec![dir.to_path_buf()];
        dirs.extend(also.iter().cloned());
        if let Ok(mut list) = IN_PROGRESS.lock() {
            for (k, d) in dirs.iter().enumerate() {
                list.push(InProgress {
                    dir: d.clone(),
                    kind: if k == 0 { Kind::Marked } else { Kind::Swept },
                });
            }
        }
        Ok(Self {
            dirs,
            marker,
            finished: false,
        })
    }

    /// Everything was written: remove the marker.
    pub(crate) fn finish(mut self) -> Result<()> {
        std::fs::remove_file(&self.marker)
            .with_context(|| format!("removing {}", self.marker.display()))?;
        self.finished = true;
        Ok(())
    }
}

impl Drop for OutputGuard {
    /// Stop guarding; a command that failed keeps the marker.
    fn drop(&mut self) {
        if let Ok(mut list) = IN_PROGRESS.lock() {
            list.retain(|d| !self.dirs.contains(&d.dir));
        }
        if !self.finished {
            tracing::debug!("{} stays marked incomplete", self.marker.display());
        }
    }
}

/// Refuse to mix runs: `.ply` frames in `dir` that a command writing the
/// frames `names` would not overwrite would be read as part of its
/// sequence later (a directory left by another `convert` or `simulate`).
pub(crate) fn refuse_other_frames(dir: &Path, names: &[String]) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(()); // no directory yet
    };
    let wanted: std::collections::HashSet<&str> = names.iter().map(String::as_str).collect();
    for entry in entries.flatten() {
        let path = entry.path();
        let is_ply = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        if is_ply && !wanted.contains(stem) {
            bail!(
                "{} already holds frames of another run (e.g. {}); use an empty --out directory",
                dir.display(),
                path.display()
            );
        }
    }
    Ok(())
}

/// The output directories of the runs still in progress, cleaned of their
/// temporary files when the process is interrupted.
static IN_PROGRESS: Mutex<Vec<InProgress>> = Mutex::new(Vec::new());

/// The lock files this process holds ([`DirLock`]), removed when it is
/// interrupted.
static LOCK_FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

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
    for InProgress { dir, kind } in dirs {
        if kind == Kind::Scratch {
            // A forced rerun: the earlier run it was to replace stays.
            for _ in 0..3 {
                std::thread::sleep(std::time::Duration::from_millis(20));
                let _ = std::fs::remove_dir_all(&dir);
            }
            eprintln!("interrupted: the earlier run was left as it was");
            continue;
        }
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
        if kind == Kind::Swept {
            continue;
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
    // The locks go with the process; their files are removed here.
    for lock in LOCK_FILES.lock().map(|l| l.clone()).unwrap_or_default() {
        let _ = std::fs::remove_file(lock);
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

/// The exclusive claim of one output directory: `.<name>.lock` beside it,
/// created if need be and locked (`flock`, released by the kernel when the
/// process ends, however it ends), holding the pid of its run. A second run
/// into the same directory fails to lock it and stops with an error before
/// touching anything.
#[derive(Debug)]
struct DirLock {
    path: PathBuf,
    file: std::fs::File,
}

impl DirLock {
    /// Lock the output directory `out`; an error naming it (and the pid
    /// of the run holding it) when another run has it.
    fn take(out: &Path) -> Result<Self> {
        let path = sibling(out, "lock");
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)
                .with_context(|| format!("creating {}", parent.display()))?;
        }
        loop {
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .create(true)
                .truncate(false)
                .open(&path)
                .with_context(|| format!("opening the lock file {}", path.display()))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => {
                    let holder = std::fs::read_to_string(&path).unwrap_or_default();
                    let holder = holder.trim();
                    bail!(
                        "--out {}: another run (pid {}) is writing into it (lock file {}); wait for it to finish or give another directory",
                        out.display(),
                        if holder.is_empty() { "unknown" } else { holder },
                        path.display()
                    );
                }
                Err(std::fs::TryLockError::Error(e)) => {
                    return Err(e).with_context(|| format!("locking {}", path.display()));
                }
            }
            // The file locked must still be the one at `path` (a run that
            // finished removes it; a run that opened it just before then
            // would otherwise hold a lock on a file nobody else sees).
            use std::os::unix::fs::MetadataExt;
            let held = file.metadata().map(|m| (m.dev(), m.ino()));
            let named = std::fs::metadata(&path).map(|m| (m.dev(), m.ino()));
            match (held, named) {
                (Ok(a), Ok(b)) if a == b => {}
                _ => continue,
            }
            let _ = file.set_len(0);
            let _ = std::io::Write::write_all(
                &mut &file,
                format!("{}\n", std::process::id()).as_bytes(),
            );
            if let Ok(mut locks) = LOCK_FILES.lock() {
                locks.push(path.clone());
            }
            return Ok(Self { path, file });
        }
    }
}

impl Drop for DirLock {
    /// Remove the lock file while still holding it (then the lock goes with
    /// the descriptor).
    fn drop(&mut self) {
        if let Ok(mut locks) = LOCK_FILES.lock() {
            locks.retain(|l| l != &self.path);
        }
        let _ = std::fs::remove_file(&self.path);
        let _ = self.file.unlock();
    }
}

/// `.<name>.<what>` beside the directory `out` (the same file system, so a
/// rename moves it into place).
fn sibling(out: &Path, what: &str) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    parent.join(format!(".{name}.{what}"))
}

/// An output directory claimed by a run.
#[derive(Debug)]
pub(crate) struct RunDir {
    /// The directory the user named.
    out: PathBuf,
    /// Where the run writes: `out`, or for a forced rerun over an earlier
    /// run a scratch directory beside it, swapped in when the run
    /// finishes (the earlier run stays whole until then).
    path: PathBuf,
    created: bool,
    finished: bool,
    _lock: DirLock,
}

impl RunDir {
    /// Claim `path` for a run: lock it against other runs; create it when
    /// missing; refuse it when it holds anything, unless `force`, which
    /// replaces an earlier run's outputs (and refuses a directory holding
    /// anything else). A forced rerun writes into a scratch directory beside
    /// `path` ([`RunDir::path`]) and replaces the earlier run only when it
    /// [finishes](RunDir::finish): a rerun that fails or is killed leaves
    /// the earlier run as it was. Marks the directory it writes incomplete.
    pub(crate) fn claim(path: &Path, force: bool) -> Result<Self> {
        if path.exists() && !path.is_dir() {
            bail!("--out {}: exists and is not a directory", path.display());
        }
        let lock = DirLock::take(path)?;
        let mut created = !path.exists();
        let mut write_to = path.to_path_buf();
        // A scratch directory left by a forced rerun that was killed.
        let scratch = sibling(path, "rerun");
        if scratch.exists() {
            std::fs::remove_dir_all(&scratch)
                .with_context(|| format!("removing the stale {}", scratch.display()))?;
        }
        if !created {
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
                // The earlier run stays until this one has finished.
                write_to = scratch;
                created = true;
            }
        }
        std::fs::create_dir_all(&write_to)
            .with_context(|| format!("creating {}", write_to.display()))?;
        let marker = write_to.join(INCOMPLETE);
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
            dirs.push(InProgress {
                dir: write_to.clone(),
                kind: if write_to != path {
                    Kind::Scratch
                } else {
                    Kind::Marked
                },
            });
        }
        Ok(Self {
            out: path.to_path_buf(),
            path: write_to,
            created,
            finished: false,
            _lock: lock,
        })
    }

    /// The directory the run writes into: the one named, or the scratch
    /// directory of a forced rerun (moved to the named one by
    /// [`finish`](Self::finish)).
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// The run succeeded: remove the marker and, for a forced rerun, put
    /// its outputs in place of the earlier run's.
    pub(crate) fn finish(mut self) -> Result<()> {
        if self.path != self.out {
            // Mark the earlier run as being replaced, move it aside, move
            // this one in, then remove the earlier one.
            let old = sibling(&self.out, &format!("replaced-{}", std::process::id()));
            std::fs::rename(&self.out, &old)
                .with_context(|| format!("moving the earlier run {} aside", self.out.display()))?;
            if let Err(e) = std::fs::rename(&self.path, &self.out) {
                let _ = std::fs::rename(&old, &self.out);
                return Err(e).with_context(|| {
                    format!("moving {} into {}", self.path.display(), self.out.display())
                });
            }
            let _ = std::fs::remove_dir_all(&old);
            if let Ok(mut dirs) = IN_PROGRESS.lock() {
                dirs.retain(|d| d.dir != self.path);
            }
            self.path = self.out.clone();
        }
        let marker = self.path.join(INCOMPLETE);
        std::fs::remove_file(&marker).with_context(|| format!("removing {}", marker.display()))?;
        self.finished = true;
        Ok(())
    }
}

impl Drop for RunDir {
    /// A failed run keeps its marker beside whatever it wrote; one that
    /// left nothing else removes the marker too (and the directory, if it
    /// created it). A forced rerun that failed removes its scratch
    /// directory: the earlier run is untouched.
    fn drop(&mut self) {
        if let Ok(mut dirs) = IN_PROGRESS.lock() {
            dirs.retain(|d| d.dir != self.path);
        }
        if self.finished {
            return;
        }
        if self.path != self.out {
            let _ = std::fs::remove_dir_all(&self.path);
            return;
        }
        // An interrupted run stays marked, whatever it left.
        if interrupted() {
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
