//! `specular graph solve --out` (issue 18, finding 8): the solution is
//! written (poses as TUM, the solved graph in the graph format) and reads
//! back as exactly what the solver found.

use std::path::Path;
use std::process::{Command, Output};

use specular::backend::{backend, BackendName, BackendParams, FactorGraph};
use specular::io::read_tum;

fn specular(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specular"))
        .args(args)
        .output()
        .expect("run specular")
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout.clone()).unwrap()
}

/// A synthetic graph exported by `graph synth` (drifted odometry as the
/// initial values).
fn exported_graph(dir: &Path) -> std::path::PathBuf {
    let graph = dir.join("graph.json");
    let g = graph.to_str().unwrap();
    ok(&specular(&[
        "graph", "synth", "--poses", "25", "--out", g, "--seed", "3",
    ]));
    graph
}

#[test]
fn graph_solve_writes_the_solution_it_reports() {
    let tmp = tempfile::tempdir().unwrap();
    let graph = exported_graph(tmp.path());
    let out = tmp.path().join("solved");
    let stdout = ok(&specular(&[
        "graph",
        "solve",
        "--graph",
        graph.to_str().unwrap(),
        "--backend",
        "lm",
        "--out",
        out.to_str().unwrap(),
    ]));
    let summary: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap();
    let initial = summary["initial_error"].as_f64().unwrap();
    let reported = summary["final_error"].as_f64().unwrap();
    assert!(reported < initial, "{summary}");
    assert!(!out.join("INCOMPLETE").exists());

    // The solved graph reads back; its cost is the reported final cost and
    // below the exported graph's.
    let exported = FactorGraph::read(&graph).unwrap();
    let solved = FactorGraph::read(&out.join("graph.json")).unwrap();
    assert_eq!(solved.factors.len(), exported.factors.len());
    assert_eq!(solved.fixed, exported.fixed);
    let cost = solved.cost(&solved.values).unwrap();
    assert!(
        (cost - reported).abs() <= 1e-9 * reported.max(1e-12),
        "cost {cost} of the written solution, reported {reported}"
    );
    assert!(cost < exported.cost(&exported.values).unwrap());

    // It is exactly what the same back-end finds through the library
    // (with graph solve's initial damping, 1e-8).
    let mut params = BackendParams::default();
    params.solver.initial_lambda = 1e-8;
    params.solver.max_iterations = 100;
    params.solver.relative_tolerance = 1e-5;
    params.solver.absolute_tolerance = 1e-5;
    let (values, _) = backend(BackendName::Lm, &params)
        .unwrap()
        .optimize(&exported, &exported.values)
        .unwrap();
    assert_eq!(solved.values, values);

    // poses.txt: the same poses in id order, stamped by id.
    let tum = read_tum(&out.join("poses.txt")).unwrap();
    assert_eq!(tum.len(), values.poses.len());
    for (p, (&id, pose)) in tum.iter().zip(&values.poses) {
        assert_eq!(p.stamp, f64::from(id));
        let dt = (p.pose.translation.vector - pose.translation.vector).norm();
        assert!(dt < 1e-8, "x{id}: {dt} m");
        assert!(p.pose.rotation.angle_to(&pose.rotation) < 1e-8, "x{id}");
    }
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("solve.json")).unwrap()).unwrap();
    assert_eq!(written, summary);

    // The out directory is claimed like detect's: refused when it holds a
    // run, replaced with --force.
    let again = [
        "graph",
        "solve",
        "--graph",
        graph.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    let refused = specular(&again);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("not empty"));
    ok(&specular(&[&again[..], &["--force"]].concat()));
}

#[test]
fn graph_solve_stamps_the_poses_from_a_tum_file() {
    let tmp = tempfile::tempdir().unwrap();
    let graph = exported_graph(tmp.path());
    let poses = FactorGraph::read(&graph).unwrap().values.poses.len();
    let stamps = tmp.path().join("stamps.txt");
    let line = |k: usize| format!("{:.6} 0 0 0 0 0 0 1\n", 1_700_000_000.0 + 0.1 * k as f64);
    std::fs::write(&stamps, (0..poses).map(line).collect::<String>()).unwrap();
    let out = tmp.path().join("solved");
    let solve = |stamps: &Path, out: &Path| {
        specular(&[
            "graph",
            "solve",
            "--graph",
            graph.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--stamps",
            stamps.to_str().unwrap(),
        ])
    };
    ok(&solve(&stamps, &out));
    let tum = read_tum(&out.join("poses.txt")).unwrap();
    assert_eq!(tum.len(), poses);
    for (k, p) in tum.iter().enumerate() {
        assert!((p.stamp - (1_700_000_000.0 + 0.1 * k as f64)).abs() < 1e-6);
    }
    // One stamp short: an error naming the file, and nothing written.
    std::fs::write(&stamps, (1..poses).map(line).collect::<String>()).unwrap();
    let short = tmp.path().join("short");
    let o = solve(&stamps, &short);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("stamps.txt") && err.contains("timestamps"),
        "{err}"
    );
    assert!(!short.exists());
}
