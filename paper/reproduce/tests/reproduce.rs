//! `specular-reproduce`: a quick run writes every table, JSON and figure,
//! gives the same deterministic files twice, and refuses a bad `--data`.

use std::path::Path;
use std::process::{Command, Output};

use specular::config::Config;
use specular_paper::{slam_backends, with_backend};

fn reproduce(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_specular-reproduce"))
        .args(args)
        .output()
        .expect("run specular-reproduce")
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The README up to its machine-dependent timing section.
fn deterministic_readme(path: &Path) -> String {
    let text = String::from_utf8(read(path)).unwrap();
    let cut = text.find("## Timing").expect("timing section");
    text[..cut].to_string()
}

#[test]
fn quick_run_writes_everything_and_repeats_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("results");
    let out_s = out.to_str().unwrap();
    let o = reproduce(&["--quick", "--out", out_s]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let tables = String::from_utf8(read(&out.join("tables.md"))).unwrap();
    // Published values (Plane Optimized, sequence 1) beside ours.
    assert!(tables.contains("*99.42 / 90.23*"), "{tables}");
    assert!(tables.contains("*93.26*"), "{tables}"); // Reflection SLAM removal
    for name in [
        "3dref-sample",
        "sim:office",
        "sim:lobby",
        "sim:corridor",
        "sim:mirror-room",
    ] {
        assert!(tables.contains(name), "{name} missing:\n{tables}");
    }
    assert!(tables.contains("Reflection SLAM [average]"), "{tables}");
    assert!(tables.contains("not run: pass --with-kiss-icp"), "{tables}");

    let results: serde_json::Value =
        serde_json::from_slice(&read(&out.join("results.json"))).unwrap();
    let datasets = results["datasets"].as_array().unwrap().len();
    assert!(datasets >= 5, "{datasets} datasets");
    assert_eq!(
        results["classification"].as_array().unwrap().len(),
        3 * datasets
    );
    assert_eq!(
        results["slam"].as_array().unwrap().len(),
        slam_backends().len() * datasets
    );
    // Every labelled row carries metrics, and the simulated office is
    // classified far better than chance.
    let office_po = results["classification"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["dataset"] == "sim:office" && r["method"] == "plane-optimized (default)")
        .expect("office row");
    let accuracy = office_po["metrics"]["accuracy"].as_f64().unwrap();
    assert!(accuracy > 80.0, "office accuracy {accuracy}");
    let corner = &results["corner_figure"];
    assert!(
        corner["reflections_mirrored"].as_u64().unwrap() > 0,
        "{corner}"
    );

    let png = read(&out.join("around_corner.png"));
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let timings: serde_json::Value =
        serde_json::from_slice(&read(&out.join("timings.json"))).unwrap();
    assert!(!timings["timing"]["rows"].as_array().unwrap().is_empty());
    let readme = tmp.path().join("README.md");
    let first_readme = deterministic_readme(&readme);
    assert!(first_readme.contains("around_corner.png"), "{first_readme}");
    assert!(
        !first_readme.contains("{{"),
        "unfilled placeholder:\n{first_readme}"
    );

    // Twice: the deterministic files are byte-identical.
    let first: Vec<Vec<u8>> = ["results.json", "tables.md", "around_corner.png"]
        .iter()
        .map(|f| read(&out.join(f)))
        .collect();
    let o = reproduce(&["--quick", "--out", out_s]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (f, bytes) in ["results.json", "tables.md", "around_corner.png"]
        .iter()
        .zip(&first)
    {
        assert!(read(&out.join(f)) == *bytes, "{f} differs between two runs");
    }
    assert_eq!(deterministic_readme(&readme), first_readme);
    // No temporary file is left behind.
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp"), "{name}");
    }
}

#[test]
fn a_bad_data_directory_is_named_and_nothing_is_written() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("results");
    let missing = tmp.path().join("no-such-dataset");
    let o = reproduce(&[
        "--quick",
        "--out",
        out.to_str().unwrap(),
        "--data",
        missing.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("no-such-dataset"), "{stderr}");
    assert!(!out.join("tables.md").exists());

    // A directory without a pose file.
    let empty = tmp.path().join("frames-only");
    std::fs::create_dir_all(&empty).unwrap();
    let o = reproduce(&[
        "--quick",
        "--out",
        out.to_str().unwrap(),
        "--data",
        empty.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("frames-only") && stderr.contains("pose"),
        "{stderr}"
    );
}

#[test]
fn a_readme_without_generated_blocks_is_not_overwritten() {
    let tmp = tempfile::tempdir().unwrap();
    let readme = tmp.path().join("README.md");
    std::fs::write(&readme, "# someone else's README\n").unwrap();
    let o = reproduce(&[
        "--quick",
        "--out",
        tmp.path().join("results").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("not overwriting"), "{stderr}");
    assert_eq!(
        std::fs::read_to_string(&readme).unwrap(),
        "# someone else's README\n"
    );
}

#[test]
fn backends_are_applied_by_name() {
    let config = Config::resolve("default").unwrap();
    for name in slam_backends() {
        assert!(with_backend(&config, &name).is_ok(), "{name}");
    }
    for name in ["average", "gn", "lm"] {
        assert!(slam_backends().iter().any(|b| b == name), "{name}");
        assert_eq!(
            with_backend(&config, name).unwrap().backend.name.as_str(),
            name
        );
    }
    let err = with_backend(&config, "no-such-backend").unwrap_err();
    assert!(err.to_string().contains("no-such-backend"), "{err}");
}

/// Without `--out` a run writes into `runs/reproduce/` of the working
/// directory, never over the tracked `paper/` tables.
#[test]
fn by_default_a_run_writes_a_fresh_directory_not_paper() {
    let tmp = tempfile::tempdir().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_specular-reproduce"))
        .current_dir(tmp.path())
        .arg("--quick")
        .output()
        .expect("run specular-reproduce");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(tmp
        .path()
        .join("runs/reproduce/results/results.json")
        .is_file());
    assert!(tmp.path().join("runs/reproduce/README.md").is_file());
    assert!(!tmp.path().join("paper").exists());
}
