//! Issue 39, "Nothing silently wrong, nothing lost": one label per input
//! point. Points that cannot be returns (NaN, infinite, the origin, absurdly
//! far) keep their slot with label 0 and are scored; unscored runs say so.
//! Each test's doc says which case it guards; each fails on the code before
//! the fix (172d754).

mod common;

use std::path::Path;

use common::cli::{detect_sample, s, specular, stderr};
use common::faults::*;
use specular::io;

/// Case 1: NaN, infinite and origin points keep their label slot (0) in
/// `detect` with both methods, with `--rules`, and in `slam`; `eval`
/// scores the holed frames against all their points. The old code wrote
/// one label per *kept* point (every later label shifted) and `eval`
/// measured the shortened frame.
#[test]
fn points_that_are_not_returns_keep_their_label_slot() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    let holed = write_holed_sample(&frames);
    let poses = sample_poses();
    for method in ["single-scan", "plane-optimized"] {
        let out = tmp.path().join(method);
        ok(&specular(&[
            "detect",
            "--frames",
            s(&frames),
            "--poses",
            s(&poses),
            "--out",
            s(&out),
            "--method",
            method,
            "--rules",
            "--lean",
        ]));
        assert_one_label_per_input_point(&out, &holed, true);
        // eval against every input point: the holes are scored (as
        // unclassified), the files have the right length.
        ok(&specular(&[
            "eval",
            "--frames",
            s(&frames),
            "--pred",
            s(&out),
        ]));
    }
    let out = tmp.path().join("slam");
    ok(&specular(&[
        "slam",
        "--frames",
        s(&frames),
        "--gt-poses",
        s(&poses),
        "--out",
        s(&out),
    ]));
    assert_one_label_per_input_point(&out, &holed, false);

    // A prediction file with one label per kept point (what the old code
    // wrote) is refused by eval, naming the file.
    let short = tmp.path().join("short");
    std::fs::create_dir_all(&short).unwrap();
    for (name, holes) in &holed {
        let kept = holes.iter().filter(|h| !**h).count();
        io::write_labels(&short.join(format!("{name}.label")), &vec![1u8; kept]).unwrap();
    }
    let o = specular(&["eval", "--frames", s(&frames), "--pred", s(&short)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains(".label"), "{}", stderr(&o));
}

/// Case 1, the scores: `metrics.json` of a run on holed frames counts the
/// holes, whose labels are real classes, as unclassified points; on the old
/// code they were not counted at all.
#[test]
fn holes_are_scored_as_unclassified() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    let holed = write_holed_sample(&frames);
    let clean = tmp.path().join("clean");
    let out = tmp.path().join("holed");
    let sample = common::sample_dir().join("frames");
    for (input, out) in [(&sample, &clean), (&frames, &out)] {
        ok(&specular(&[
            "detect",
            "--frames",
            s(input),
            "--out",
            s(out),
            "--method",
            "single-scan",
            "--lean",
        ]));
    }
    let total = |dir: &Path| -> u64 {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        let rules = v["rules"].to_string();
        assert!(!rules.is_empty());
        v["dropped_non_finite_points"].as_u64().unwrap()
    };
    let holes: usize = holed
        .iter()
        .map(|(_, h)| h.iter().filter(|x| **x).count())
        .sum();
    assert_eq!(total(&out), holes as u64);
    // eval on the holed run and on the clean run differ only by the holes.
    let json = tmp.path().join("m.json");
    ok(&specular(&[
        "eval",
        "--frames",
        s(&frames),
        "--pred",
        s(&out),
        "--json",
        s(&json),
    ]));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let text = m.to_string();
    assert!(text.contains("unclassified"), "{text}");
}

/// Weaker case: a frame whose every point is NaN gets all-0 labels, one
/// per point, in `detect` (both methods) and `slam`; the old code stopped
/// the run with "frame has no points".
#[test]
fn an_all_nan_frame_gets_all_zero_labels() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    let body: String = (0..5).map(|_| "nan nan nan 1 3 1 1\n").collect();
    let name = sample_with(&frames, &(ascii_header(5) + &body));
    let poses = sample_poses();
    let label = |out: &Path| read_u32s(&out.join(format!("predictions/{name}.label")));
    for method in ["single-scan", "plane-optimized"] {
        let out = tmp.path().join(method);
        ok(&specular(&[
            "detect",
            "--frames",
            s(&frames),
            "--poses",
            s(&poses),
            "--out",
            s(&out),
            "--method",
            method,
            "--lean",
        ]));
        assert_eq!(label(&out), vec![0; 5], "{method}");
    }
    let out = tmp.path().join("slam");
    ok(&specular(&[
        "slam",
        "--frames",
        s(&frames),
        "--gt-poses",
        s(&poses),
        "--out",
        s(&out),
    ]));
    assert_eq!(label(&out), vec![0; 5]);
}

/// Weaker cases: a coordinate of 1e300 in an ascii frame (too large for a
/// float) is reported as out of range, naming the file and line, not
/// silently read as infinite; a point at 3e38 (finite) cannot be a return
/// and is set aside with label 0, not called Normal.
#[test]
fn absurd_coordinates_are_out_of_range_or_set_aside() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("1689496220.052700.ply");
    let text = ascii_header(2) + "1e300 0 0 1 3 1 1\n1 2 3 1 3 1 1\n";
    std::fs::write(&path, &text).unwrap();
    let err = io::read_frame(&path).unwrap_err().to_string();
    assert!(
        err.contains("1689496220.052700.ply") && err.contains("line 12") && err.contains("range"),
        "{err}"
    );
    // Written "inf", it is a non-return like NaN.
    std::fs::write(&path, text.replace("1e300", "inf")).unwrap();
    assert_eq!(io::read_frame(&path).unwrap().dropped_non_finite, 1);

    let frames = tmp.path().join("frames");
    let name = sample_with(
        &frames,
        &(ascii_header(2) + "3e38 0 0 1 3 1 1\n1 2 3 1 3 1 1\n"),
    );
    let out = tmp.path().join("out");
    ok(&specular(&[
        "detect",
        "--frames",
        s(&frames),
        "--out",
        s(&out),
        "--method",
        "single-scan",
        "--lean",
    ]));
    let labels = read_u32s(&out.join(format!("predictions/{name}.label")));
    assert_eq!(labels.len(), 2);
    assert_eq!(labels[0], 0, "a point 3e38 m away was classified");
}

/// Weaker case: one frame without a `label` property among labelled ones
/// leaves the run unscored, and the run says so, naming the frame (the old
/// code said nothing).
#[test]
fn one_unlabelled_frame_is_warned_about() {
    let tmp = tempfile::tempdir().unwrap();
    let frames = tmp.path().join("frames");
    let header = ascii_header(3).replace("property uchar label\n", "");
    let body = "1 2 3 1 3 1\n2 2 3 1 4 1\n3 2 3 1 5 1\n";
    let name = sample_with(&frames, &(header + body));
    let o = specular(&[
        "detect",
        "--frames",
        s(&frames),
        "--out",
        s(&tmp.path().join("out")),
        "--method",
        "single-scan",
        "--lean",
    ]);
    ok(&o);
    let err = stderr(&o);
    assert!(err.contains(&name) && err.contains("not scored"), "{err}");
}

/// Weaker case: `eval` rejects a prediction file holding a value that is
/// no class id (> 6), naming the file.
#[test]
fn eval_rejects_values_that_are_no_class() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("run");
    ok(&detect_sample(&out, &["--method", "single-scan", "--lean"]));
    let name = common::predictions(&out).into_keys().next().unwrap();
    let file = out.join("predictions").join(name);
    let mut bytes = std::fs::read(&file).unwrap();
    bytes[..4].copy_from_slice(&7u32.to_le_bytes());
    std::fs::write(&file, bytes).unwrap();
    let frames = common::sample_dir().join("frames");
    let o = specular(&["eval", "--frames", s(&frames), "--pred", s(&out)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains(&file.file_name().unwrap().to_string_lossy().into_owned()),
        "{err}"
    );
}
