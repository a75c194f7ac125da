//! Issue 39, "Nothing silently wrong, nothing lost": output directories.
//! A forced rerun never loses a finished run, two runs never share a
//! directory, interrupted commands clean up and stay marked, and nothing
//! a user wrote is overwritten. Each test's doc says which case it guards;
//! each fails on the code before the fix (172d754).

mod common;

use std::process::{Command, Stdio};

use common::cli::{detect_sample, s, specular, stderr};
use common::faults::*;

/// Case 2: a forced rerun that fails (a truncated frame) leaves the earlier
/// complete run as it was; the old code removed it before reading a frame.
#[test]
fn a_failed_forced_rerun_keeps_the_earlier_run() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    ok(&detect_sample(&out, &["--method", "single-scan", "--lean"]));
    let before = common::predictions(&out);
    let metrics = std::fs::read(out.join("metrics.json")).unwrap();

    let frames = tmp.path().join("frames");
    common::copy_dir(&common::sample_dir().join("frames"), &frames);
    let victim = frames.join("1689496220.052616.ply");
    let bytes = std::fs::read(&victim).unwrap();
    std::fs::write(&victim, &bytes[..bytes.len() / 2]).unwrap();
    let o = specular(&[
        "detect",
        "--frames",
        s(&frames),
        "--out",
        s(&out),
        "--method",
        "single-scan",
        "--lean",
        "--force",
    ]);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("1689496220.052616.ply"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        common::predictions(&out),
        before,
        "the earlier run was lost"
    );
    assert_eq!(std::fs::read(out.join("metrics.json")).unwrap(), metrics);
    assert!(!out.join("INCOMPLETE").exists());
    // Nothing left beside it either.
    let siblings: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".run"))
        .collect();
    assert!(siblings.is_empty(), "{siblings:?}");
}

/// Case 2, `graph solve`: a graph that cannot be solved (no prior, no
/// fixed pose) leaves an earlier solution in `--out` as it was.
#[test]
fn a_failed_forced_solve_keeps_the_earlier_solution() {
    let tmp = tempfile::tempdir().unwrap();
    let graph = tmp.path().join("g.json");
    ok(&specular(&[
        "graph",
        "synth",
        "--poses",
        "20",
        "--out",
        s(&graph),
        "--seed",
        "4",
    ]));
    let out = tmp.path().join("solved");
    ok(&specular(&[
        "graph",
        "solve",
        "--graph",
        s(&graph),
        "--backend",
        "lm",
        "--out",
        s(&out),
    ]));
    let poses = std::fs::read(out.join("poses.txt")).unwrap();
    let mut g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&graph).unwrap()).unwrap();
    g["auto_gauge"] = false.into();
    let free = tmp.path().join("free.json");
    std::fs::write(&free, g.to_string()).unwrap();
    let o = specular(&[
        "graph",
        "solve",
        "--graph",
        s(&free),
        "--backend",
        "lm",
        "--out",
        s(&out),
        "--force",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("gauge"), "{}", stderr(&o));
    assert_eq!(std::fs::read(out.join("poses.txt")).unwrap(), poses);
    assert!(!out.join("INCOMPLETE").exists());
}

/// Case 3: a second run into a directory a first run is writing is refused
/// (a lock), even with `--force`; the first run finishes whole. The old
/// code let the second remove the first's outputs while the first reported
/// success.
#[cfg(unix)]
#[test]
fn a_second_run_cannot_enter_a_directory_in_use() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    many_frames(&frames, 300);
    let out = tmp.path().join("run");
    let mut first = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args([
            "detect",
            "--frames",
            s(&frames),
            "--out",
            s(&out),
            "--method",
            "single-scan",
            "--lean",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&mut first, &out, |n| n == "predictions.partial");
    let second = specular(&[
        "detect",
        "--frames",
        s(&frames),
        "--out",
        s(&out),
        "--method",
        "single-scan",
        "--lean",
        "--force",
    ]);
    assert!(!second.status.success());
    assert!(
        stderr(&second).contains("another run"),
        "{}",
        stderr(&second)
    );
    let o = first.wait_with_output().unwrap();
    ok(&o);
    assert_eq!(common::predictions(&out).len(), 300);
    assert!(!out.join("INCOMPLETE").exists());
}

/// Case 9: `convert` stopped by SIGTERM removes its temporary files, leaves
/// an `INCOMPLETE` marker and exits with 130 (the old code: 143, a stray
/// `.tmp`, no marker); a later `convert` of other frames into it is refused
/// rather than merged.
#[cfg(unix)]
#[test]
fn convert_stopped_by_sigterm_cleans_up_and_is_not_merged_into() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    many_frames(&frames, 300);
    let out = tmp.path().join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args([
            "convert",
            "--frames",
            s(&frames),
            "--out",
            s(&out),
            "--ascii",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&mut child, &out.join("frames"), |n| n.ends_with(".ply"));
    let o = interrupt(child, "TERM");
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(out.join("INCOMPLETE").exists());
    assert!(temporaries(&out.join("frames")).is_empty());
    let sample = common::sample_dir().join("frames");
    let o = specular(&["convert", "--frames", s(&sample), "--out", s(&out)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("another run"), "{}", stderr(&o));
}

/// Case 9: `simulate` stopped by SIGTERM does the same.
#[cfg(unix)]
#[test]
fn simulate_stopped_by_sigterm_cleans_up() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sim");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args([
            "simulate",
            "--scene",
            "office",
            "--frames",
            "2000",
            "--out",
            s(&out),
            "--ascii",
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&mut child, &out.join("frames"), |n| n.ends_with(".ply"));
    let o = interrupt(child, "TERM");
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(out.join("INCOMPLETE").exists());
    assert!(temporaries(&out.join("frames")).is_empty());
    assert!(!out.join("poses.txt").exists());
}

/// Case 10: `demo --out DIR` refuses a DIR whose `report.md` is not an
/// earlier demo's, and leaves it untouched (the old code overwrote it).
#[test]
fn demo_does_not_overwrite_a_users_report() {
    let tmp = tempfile::tempdir().unwrap();
    let mine = tmp.path().join("report.md");
    std::fs::write(&mine, "# my notes\n").unwrap();
    let o = specular(&["demo", "--out", s(tmp.path())]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("report.md"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "# my notes\n");
    assert!(!tmp.path().join("sim").exists());
}
