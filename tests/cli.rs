//! The command-line tool: exit codes, messages, and no half-written outputs.

mod common;

use std::path::Path;
use std::process::Command;

use common::cli::{detect_sample, s, specular, stderr};

use specular::classify::rule::RULES;
use specular::classify::Class;

#[test]
fn detect_then_eval_on_the_sample() {
    let sample = common::sample_dir();
    let out = tempfile::tempdir().unwrap();
    let o = detect_sample(
        out.path(),
        &["--method", "single-scan", "--timings", "--rules"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("accuracy") && stdout.contains("classify"),
        "{stdout}"
    );
    let mut rule_tally = std::collections::BTreeMap::new();
    // The calibration recomputed from the files a run leaves.
    let mut reliability = specular::eval::Reliability::default();
    for entry in specular::io::list_frames(&sample.join("frames")).unwrap() {
        let frame = specular::io::read_frame(&entry.path).unwrap();
        let labels = specular::io::read_labels(
            &out.path().join(format!("predictions/{}.label", entry.name)),
        )
        .unwrap();
        assert_eq!(labels.len(), frame.points.len());
        assert!(labels.iter().all(|l| [0, 1, 2, 5, 6].contains(l)));
        // The confidence of every point's class, beside its label.
        let probs = specular::io::read_probs_for(
            &out.path().join(format!("predictions/{}.prob", entry.name)),
            frame.points.len(),
        )
        .unwrap();
        let classes: Vec<Class> = labels.iter().map(|&l| Class::from_id(l)).collect();
        reliability.add(&frame.labels(), &classes, &probs);
        // --rules: the deciding rule of every point, beside its label.
        let rules =
            specular::io::read_labels(&out.path().join(format!("predictions/{}.rule", entry.name)))
                .unwrap();
        assert_eq!(rules.len(), frame.points.len());
        for (rule, label) in rules.iter().zip(&labels) {
            *rule_tally
                .entry(format!(
                    "{}/{}",
                    RULES[*rule as usize].name(),
                    Class::from_id(*label).name()
                ))
                .or_insert(0u64) += 1;
        }
    }
    assert!(out.path().join("config.toml").exists());
    // metrics.json: the whole confusion matrix by label id, and which rule
    // decided how many points, both adding up to every point.
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("metrics.json")).unwrap())
            .unwrap();
    // The sum of every count in a nested JSON value.
    fn total(v: &serde_json::Value) -> u64 {
        match v {
            serde_json::Value::Number(n) => n.as_u64().unwrap(),
            serde_json::Value::Array(a) => a.iter().map(total).sum(),
            serde_json::Value::Object(o) => o.values().map(total).sum(),
            _ => 0,
        }
    }
    let points = metrics["points"].as_u64().unwrap() + metrics["ignored"].as_u64().unwrap();
    assert_eq!(total(&metrics["confusion"]["by_label"]), points);
    assert_eq!(total(&metrics["rules"]), points);
    // The rule files tally exactly as metrics.json does.
    for (key, n) in &rule_tally {
        assert_eq!(total(&metrics["rules"][key]), *n, "{key}");
    }
    assert!(
        metrics["rules"].get("no-pane/normal").is_some(),
        "{}",
        metrics["rules"]
    );
    // metrics.json's reliability is that of the .prob files.
    let want = reliability.report();
    assert!(want.points > 10_000, "{}", want.points);
    let rel = &metrics["reliability"];
    assert_eq!(rel["points"], want.points, "{rel}");
    for (b, w) in rel["bins"].as_array().unwrap().iter().zip(&want.bins) {
        assert_eq!(b["points"], w.points, "{rel}");
        assert_eq!(b["correct"], w.correct, "{rel}");
    }
    assert!(
        (rel["ece"].as_f64().unwrap() - want.ece).abs() < 1e-9,
        "{rel}"
    );
    let json = out.path().join("eval.json");
    let e = specular(&[
        "eval",
        "--frames",
        s(&sample.join("frames")),
        "--pred",
        s(out.path()),
        "--json",
        s(&json),
    ]);
    assert!(e.status.success(), "{}", stderr(&e));
    // eval reads the .prob files too, to the same calibration.
    let evaluated: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(evaluated["reliability"]["bins"], rel["bins"]);
    assert!(
        String::from_utf8_lossy(&e.stdout).contains("Confidence >= 0.9:"),
        "{}",
        String::from_utf8_lossy(&e.stdout)
    );
    // eval recomputes exactly what detect reported.
    let line = |text: &str| {
        text.lines()
            .find(|l| l.starts_with("accuracy"))
            .map(str::to_owned)
    };
    assert_eq!(line(&stdout), line(&String::from_utf8_lossy(&e.stdout)));
}

#[test]
fn a_truncated_frame_fails_cleanly_and_writes_nothing() {
    let sample = common::sample_dir();
    let frames = tempfile::tempdir().unwrap();
    let out = tempfile::tempdir().unwrap();
    let src = sample.join("frames/1689496219.652560.ply");
    let bytes = std::fs::read(&src).unwrap();
    std::fs::write(
        frames.path().join("1689496219.652560.ply"),
        &bytes[..bytes.len() / 2],
    )
    .unwrap();
    let o = specular(&[
        "detect",
        "--frames",
        s(frames.path()),
        "--out",
        s(out.path()),
        "--method",
        "single-scan",
    ]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("1689496219.652560.ply") && err.contains("truncated"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read_dir(out.path()).unwrap().count(),
        0,
        "outputs written after an error"
    );
}

/// Ctrl-C during a run: the run stops with a non-zero status, removes its
/// temporary files (the recording and the partial predictions) and leaves
/// its `INCOMPLETE` marker.
#[cfg(unix)]
#[test]
fn an_interrupted_run_removes_its_temporary_files_and_stays_marked() {
    let sample = common::sample_dir().join("frames");
    let frames = tempfile::tempdir().unwrap();
    let bytes = std::fs::read(sample.join("1689496219.652560.ply")).unwrap();
    // Long enough that the run is still going when it is interrupted.
    for k in 0..400 {
        let name = format!("{:.6}.ply", 1_689_496_219.0 + 0.1 * k as f64);
        std::fs::write(frames.path().join(name), &bytes).unwrap();
    }
    let out = tempfile::tempdir().unwrap();
    let run = out.path().join("run");
    let mut child = Command::new(env!("CARGO_BIN_EXE_specular"))
        .args([
            "detect",
            "--frames",
            s(frames.path()),
            "--out",
            s(&run),
            "--method",
            "single-scan",
        ])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run specular");
    // Wait until the run has written a temporary file, then interrupt it.
    let started = std::time::Instant::now();
    let temporary = |dir: &Path| -> Vec<String> {
        std::fs::read_dir(dir)
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".tmp") || n.ends_with(".partial"))
            .collect()
    };
    while temporary(&run).is_empty() {
        assert!(
            started.elapsed() < std::time::Duration::from_secs(60),
            "the run wrote no temporary file"
        );
        assert!(child.try_wait().unwrap().is_none(), "the run ended early");
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("interrupted"), "{}", stderr(&o));
    assert!(run.join("INCOMPLETE").exists());
    assert!(
        temporary(&run).is_empty(),
        "left behind: {:?}",
        temporary(&run)
    );
}

#[test]
fn eval_rejects_predictions_of_the_wrong_length() {
    let sample = common::sample_dir();
    let pred = tempfile::tempdir().unwrap();
    for stem in [
        "1689496219.652560",
        "1689496220.052616",
        "1689496220.552407",
    ] {
        std::fs::write(pred.path().join(format!("{stem}.label")), [1u8, 0, 0, 0]).unwrap();
    }
    let o = specular(&[
        "eval",
        "--frames",
        s(&sample.join("frames")),
        "--pred",
        s(pred.path()),
    ]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("1 predictions for 33718 points"), "{err}");
}

/// A `.prob` file beside a good label file is checked: one probability
/// per point, each in [0, 1]; the error names the file.
#[test]
fn eval_rejects_bad_confidence_files() {
    let sample = common::sample_dir();
    let entries = specular::io::list_frames(&sample.join("frames")).unwrap();
    let pred = tempfile::tempdir().unwrap();
    let mut first_points = 0;
    for (k, e) in entries.iter().enumerate() {
        let n = specular::io::read_frame(&e.path).unwrap().points.len();
        specular::io::write_labels(&pred.path().join(format!("{}.label", e.name)), &vec![1; n])
            .unwrap();
        if k == 0 {
            first_points = n;
        }
    }
    let prob = pred.path().join(format!("{}.prob", entries[0].name));
    let eval = || {
        specular(&[
            "eval",
            "--frames",
            s(&sample.join("frames")),
            "--pred",
            s(pred.path()),
        ])
    };
    // A good file: scored, and the calibration printed.
    specular::io::write_probs(&prob, &vec![0.95; first_points]).unwrap();
    let o = eval();
    assert!(o.status.success(), "{}", stderr(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("1 frames with .prob files"), "{out}");
    assert!(stderr(&o).contains("only 1 of 3 frames"), "{}", stderr(&o));
    // One value too few.
    specular::io::write_probs(&prob, &vec![0.5; first_points - 1]).unwrap();
    let o = eval();
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains(s(&prob)) && err.contains("one per input point"),
        "{err}"
    );
    // A value that is not a probability.
    let mut probs = vec![0.5f32; first_points];
    probs[7] = 1.25;
    specular::io::write_probs(&prob, &probs).unwrap();
    let o = eval();
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains(s(&prob)) && err.contains("point 7 has confidence 1.25"),
        "{err}"
    );
}

#[test]
fn an_unknown_config_is_a_clear_error() {
    let o = specular(&["config", "--config", "/nonexistent/x.toml"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("/nonexistent/x.toml"), "{}", stderr(&o));
}

#[test]
fn config_prints_a_file_layered_over_its_built_in() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mine.toml");
    std::fs::write(&path, "extends = \"paper\"\n[map]\nmin_observations = 3\n").unwrap();
    let o = specular(&["config", "--config", s(&path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let first = stdout.lines().next().unwrap();
    assert!(
        first.starts_with('#')
            && first.contains("\"paper\"")
            && first.contains("map.min_observations"),
        "{first}"
    );
    let mut want = specular::config::Config::resolve("paper").unwrap();
    want.map.min_observations = 3;
    assert!(stdout.ends_with(&want.to_toml()), "{stdout}");

    std::fs::write(&path, "[map]\nmin_observatons = 3\n").unwrap();
    let o = specular(&["config", "--config", s(&path)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains(s(&path)) && err.contains("did you mean `map.min_observations`?"),
        "{err}"
    );
}

#[test]
fn plane_optimized_writes_the_map_files() {
    let out = tempfile::tempdir().unwrap();
    let o = detect_sample(out.path(), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let planes = specular::io::read_planes(&out.path().join("planes.json")).unwrap();
    assert_eq!(planes.len(), 1);
    assert_eq!(planes[0].observations, 3);
    assert!(planes[0].hull.len() >= 3);
    let ply = std::fs::read(out.path().join("around_corner.ply")).unwrap();
    let header_end = ply.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8_lossy(&ply[..header_end]);
    let count: usize = header
        .lines()
        .find_map(|l| l.strip_prefix("element vertex "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(count > 10_000, "{count} points");
    assert!(
        header.contains("property uchar class")
            && header.contains("property uchar mirrored")
            && header.contains("property float confidence")
    );
    const RECORD: usize = 21;
    assert_eq!(ply.len() - header_end, count * RECORD);
    // Mirrored reflections are in the map, each with the confidence of
    // its class.
    let body = &ply[header_end..];
    let mirrored = (0..count)
        .filter(|i| body[i * RECORD + 16] == 1)
        .collect::<Vec<_>>();
    assert!(mirrored.len() > 100, "{} mirrored points", mirrored.len());
    for i in mirrored {
        let at = i * RECORD + 17;
        let p = f32::from_le_bytes(body[at..at + 4].try_into().unwrap());
        assert!((0.0..=1.0).contains(&p), "point {i}: confidence {p}");
    }
}

/// An OS error is said once, not once by the library's error and again by
/// its source.
#[test]
fn an_os_error_is_printed_once() {
    let out = tempfile::tempdir().unwrap();
    let missing = out.path().join("no-such-frames");
    let o = specular(&[
        "detect",
        "--frames",
        s(&missing),
        "--method",
        "single-scan",
        "--out",
        s(&out.path().join("run")),
    ]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.contains("no-such-frames"), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

/// A misspelt built-in configuration name lists the built-ins and suggests
/// the closest.
#[test]
fn a_misspelt_builtin_config_is_suggested() {
    let out = tempfile::tempdir().unwrap();
    let o = detect_sample(&out.path().join("run"), &["--config", "defualt"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("default, paper") && err.contains("did you mean `default`"),
        "{err}"
    );
}

/// metrics.json and report.md say which version and commit made them.
#[test]
fn outputs_name_the_version_that_made_them() {
    let out = tempfile::tempdir().unwrap();
    let run = out.path().join("run");
    let o = detect_sample(&run, &["--method", "single-scan"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(run.join("metrics.json")).unwrap()).unwrap();
    assert_eq!(metrics["specular"]["version"], env!("CARGO_PKG_VERSION"));
    let commit = metrics["specular"]["commit"].as_str().unwrap();
    assert!(!commit.is_empty(), "{metrics}");
    let report = std::fs::read_to_string(run.join("report.md")).unwrap();
    assert!(
        report.contains(&format!(
            "specular {} (commit {commit})",
            env!("CARGO_PKG_VERSION")
        )),
        "{report}"
    );
}

/// `--out` must be new or empty: an earlier run's directory is refused
/// unless `--force`, which replaces that run's outputs (stale files
/// included) and never anything a run does not write; a finished run
/// leaves no `INCOMPLETE` marker.
#[test]
fn out_must_be_empty_unless_forced_and_force_removes_only_run_outputs() {
    let out = tempfile::tempdir().unwrap();
    let first = detect_sample(out.path(), &["--method", "single-scan", "--lean"]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert!(!out.path().join("INCOMPLETE").exists());
    let again = detect_sample(out.path(), &["--method", "single-scan", "--lean"]);
    assert!(!again.status.success());
    let err = stderr(&again);
    assert!(
        err.contains("not empty") && err.contains("--force"),
        "{err}"
    );
    // A stale label of an earlier run goes with --force.
    let stale = out.path().join("predictions/0000000000.000000.label");
    std::fs::write(&stale, [0u8; 4]).unwrap();
    let forced = detect_sample(
        out.path(),
        &["--method", "single-scan", "--lean", "--force"],
    );
    assert!(forced.status.success(), "{}", stderr(&forced));
    assert!(!stale.exists(), "a stale prediction survived --force");
    assert!(out.path().join("metrics.json").exists());
    assert!(!out.path().join("INCOMPLETE").exists());
    // Something no run writes is never removed.
    let notes = out.path().join("notes.txt");
    std::fs::write(&notes, "mine").unwrap();
    let refused = detect_sample(
        out.path(),
        &["--method", "single-scan", "--lean", "--force"],
    );
    assert!(!refused.status.success());
    assert!(
        stderr(&refused).contains("notes.txt"),
        "{}",
        stderr(&refused)
    );
    assert_eq!(std::fs::read_to_string(&notes).unwrap(), "mine");
}

/// Unlabelled frames: `detect` prints how many points it predicted per
/// class, and `metrics.json` holds those counts and the rule tally.
#[test]
fn an_unlabelled_run_reports_its_predicted_classes() {
    let sample = common::sample_dir();
    let frames = tempfile::tempdir().unwrap();
    let mut total = 0u64;
    for e in specular::io::list_frames(&sample.join("frames")).unwrap() {
        let mut frame = specular::io::read_frame(&e.path).unwrap();
        frame.has_labels = false;
        total += frame.points.len() as u64;
        specular::io::write_frame(
            &frames.path().join(format!("{}.ply", e.name)),
            &frame,
            specular::io::PlyEncoding::BinaryLittleEndian,
        )
        .unwrap();
    }
    let out = tempfile::tempdir().unwrap();
    let o = specular(&[
        "detect",
        "--frames",
        s(frames.path()),
        "--out",
        s(out.path()),
        "--method",
        "single-scan",
        "--lean",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("points predicted (no labels to score): normal "),
        "{stdout}"
    );
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("metrics.json")).unwrap())
            .unwrap();
    assert_eq!(metrics["labelled"], false);
    let predicted = metrics["predicted"].as_object().unwrap();
    let sum: u64 = predicted.values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(sum, total);
    assert!(predicted["normal"].as_u64().unwrap() > 0);
}
