//! Scene families and the held-out benchmark: every family draws sound,
//! reproducible scenes whose label shares look like a building with glass,
//! and the benchmark command runs end to end.

mod common;

use std::path::Path;

use common::cli::{s, stderr};
use common::specular;
use glam::DVec3;
use specular::sim::family::{self, Split, HELD_OUT_START};
use specular::sim::{label, LabelCounts, Simulator};

/// The boxes of a generated scene file: (min, max).
fn boxes(toml_text: &str) -> Vec<(DVec3, DVec3)> {
    let v: toml::Value = toml::from_str(toml_text).unwrap();
    let corner = |b: &toml::Value, key: &str| {
        let a: Vec<f64> = b[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_float().unwrap())
            .collect();
        DVec3::new(a[0], a[1], a[2])
    };
    v.get("boxes")
        .and_then(|b| b.as_array())
        .map(|list| {
            list.iter()
                .map(|b| (corner(b, "min"), corner(b, "max")))
                .collect()
        })
        .unwrap_or_default()
}

/// Every family, on development and held-out seeds: the scene builds, the
/// path keeps clear of every surface, no two solids overlap, and the path
/// never runs through a solid.
#[test]
fn every_family_draws_sound_scenes() {
    for f in family::FAMILIES {
        for seed in [0, 1, 7, HELD_OUT_START, HELD_OUT_START + 3] {
            let g = family::generate(f.name(), seed).unwrap();
            family::validate(&g.scene).unwrap_or_else(|e| panic!("{}/{seed}: {e}", f.name()));
            let solids = boxes(&g.toml);
            for (i, a) in solids.iter().enumerate() {
                for b in &solids[i + 1..] {
                    assert!(
                        !family::boxes_overlap(*a, *b),
                        "{}/{seed}: boxes {a:?} and {b:?} overlap",
                        f.name()
                    );
                }
            }
            let t = &g.scene.trajectory;
            for k in 0..=200 {
                let p = t.position(t.length() * k as f64 / 200.0);
                for (lo, hi) in &solids {
                    let inside = (0..3).all(|i| p[i] > lo[i] && p[i] < hi[i]);
                    assert!(
                        !inside,
                        "{}/{seed}: the path runs through a box at {p}",
                        f.name()
                    );
                }
            }
            assert!(
                (0.3..=1.5).contains(&t.speed()),
                "{}/{seed}: speed {}",
                f.name(),
                t.speed()
            );
        }
    }
}

/// A (family, seed) is one scene: the same file and the same frames every
/// time; another seed is another scene.
#[test]
fn the_same_seed_draws_the_same_scene() {
    for f in family::FAMILIES {
        let a = family::generate(f.name(), 5).unwrap();
        let b = family::generate(f.name(), 5).unwrap();
        assert_eq!(a.toml, b.toml, "{}", f.name());
        let c = family::generate(f.name(), 6).unwrap();
        assert_ne!(a.toml, c.toml, "{}", f.name());
        let fa = Simulator::new(&a.scene).frame(3, a.scene.seed);
        let fb = Simulator::new(&b.scene).frame(3, b.scene.seed);
        assert_eq!(fa.frame.points, fb.frame.points, "{}", f.name());
    }
    assert!(family::generate("no-such-family", 0).is_err());
    assert_eq!(Split::of(999), Some(Split::Development));
    assert_eq!(Split::of(1000), None);
    assert_eq!(Split::of(HELD_OUT_START), Some(Split::HeldOut));
}

/// Each family, over a few development seeds, has every class the
/// benchmark scores: glass, reflections and obstacles behind glass, with
/// most points on ordinary surfaces.
#[test]
fn every_family_has_glass_reflections_and_obstacles() {
    for f in family::FAMILIES {
        let mut counts = LabelCounts::default();
        for seed in 0..4 {
            let g = family::generate(f.name(), seed).unwrap();
            let sim = Simulator::new(&g.scene);
            for k in (0..200).step_by(20) {
                counts.add(&sim.frame(k, g.scene.seed).frame);
            }
        }
        let share = |l: &[u8]| {
            l.iter().map(|&i| counts.by_label[i as usize]).sum::<u64>() as f64
                / counts.points as f64
        };
        let (n, g, r, o) = (
            share(&[label::NORMAL]),
            share(&[label::GLASS, label::MIRROR]),
            share(&[label::REFLECTION]),
            share(&[label::OBSTACLE_BEHIND_GLASS]),
        );
        let shares = format!(
            "{}: normal {n:.4}, glass {g:.4}, reflection {r:.4}, obstacle {o:.4}",
            f.name()
        );
        assert!((0.35..0.99).contains(&n), "{shares}");
        assert!((0.005..0.35).contains(&g), "{shares}");
        assert!((0.0005..0.3).contains(&r), "{shares}");
        assert!((0.001..0.4).contains(&o), "{shares}");
    }
}

/// `simulate --list-families` names every family; `simulate --family`
/// writes the scene file, and that file makes the same frames.
#[test]
fn a_family_scene_file_rebuilds_its_frames() {
    let o = specular(&["simulate", "--list-families"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let listed: Vec<String> = String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(listed, family::names());

    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    let o = specular(&[
        "simulate",
        "--family",
        "mirror-hall",
        "--seed",
        "12",
        "--frames",
        "3",
        "--out",
        s(&a),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let scene = a.join("scene.toml");
    assert!(scene.is_file());
    let o = specular(&[
        "simulate",
        "--scene",
        s(&scene),
        "--frames",
        "3",
        "--out",
        s(&b),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for name in ["poses.txt", "planes.json"] {
        assert_eq!(read(&a.join(name)), read(&b.join(name)), "{name}");
    }
    let frames = |d: &Path| -> Vec<Vec<u8>> {
        let mut v: Vec<_> = std::fs::read_dir(d.join("frames"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        v.sort();
        v.iter().map(|p| read(p)).collect()
    };
    assert_eq!(frames(&a), frames(&b));
    assert_eq!(frames(&a).len(), 3);
}

/// The benchmark's quick mode runs both pipelines on one seed of every
/// family and writes its table, scores, plot and the reliability diagram
/// of the confidences; a second run into the
/// same directory is refused without `--force`.
#[test]
fn the_quick_benchmark_runs_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let args = [
        "bench",
        "families",
        "--quick",
        "--split",
        "development",
        "--out",
        s(&out),
    ];
    let o = specular(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&read(&out.join("bench.json"))).unwrap();
    let seeds = json["seeds"].as_array().unwrap();
    assert_eq!(seeds.len(), family::FAMILIES.len());
    for r in seeds {
        assert_eq!(r["seed"], 0);
        assert_eq!(r["frames"], 20);
        let miou = r["miou"].as_f64().unwrap();
        assert!((0.0..=100.0).contains(&miou), "{r}");
        assert!(r["ate"].as_f64().unwrap() < 0.5, "{r}");
    }
    let table = String::from_utf8(read(&out.join("bench.md"))).unwrap();
    assert!(
        table.contains("| office | 1 |") && table.contains("**all**"),
        "{table}"
    );
    assert!(out.join("bench.png").is_file());
    // The calibration of the confidences over every seed: ten bins whose
    // counts add up to the points binned, and there are points.
    let rel = &json["reliability"];
    let bins = rel["bins"].as_array().unwrap();
    assert_eq!(bins.len(), 10, "{rel}");
    let binned: u64 = bins.iter().map(|b| b["points"].as_u64().unwrap()).sum();
    assert!(binned > 1000, "{rel}");
    assert_eq!(binned, rel["points"].as_u64().unwrap());
    for b in bins.iter().filter(|b| b["points"].as_u64().unwrap() > 0) {
        let acc = b["accuracy"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&acc), "{b}");
    }
    let ece = rel["ece"].as_f64().unwrap();
    assert!((0.0..=1.0).contains(&ece), "{rel}");
    assert!(
        table.contains("| confidence | points | predicted (mean) | measured accuracy |")
            && table.contains("Confidence >= 0.9:"),
        "{table}"
    );
    let png = read(&out.join("reliability.png"));
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"));
    let again = specular(&args);
    assert!(!again.status.success());
    assert!(stderr(&again).contains("--force"), "{}", stderr(&again));
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}
