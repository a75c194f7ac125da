//! The configuration's tests: built-ins complete and valid, layering, unknown keys.

use super::*;

#[test]
fn builtins_parse() {
    for name in Config::builtin_names() {
        Config::resolve(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}

#[test]
fn round_trips_through_toml() {
    let c = Config::resolve("default").unwrap();
    let again = Config::from_toml(&c.to_toml(), Path::new("x")).unwrap();
    assert_eq!(c, again);
}

#[test]
fn unknown_keys_and_bad_values_are_errors() {
    let error = |toml: &str| {
        Config::from_toml(toml, Path::new("c.toml"))
            .unwrap_err()
            .to_string()
    };
    let e = error("sensorr = 1");
    assert!(e.contains("c.toml") && e.contains("sensorr"), "{e}");
    let e = error("[detector]\ndual_gap = -1.0");
    assert!(e.contains("detector.dual_gap must be positive"), "{e}");
    let e = error("[detector]\nsurface_tolerance_deg = 90.0");
    assert!(
        e.contains("detector.surface_tolerance_deg must be in (0, 90)"),
        "{e}"
    );
}

/// Dotted paths of every value in a table.
fn paths(table: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    leaf_paths(table, "", &mut out);
    out.sort();
    out
}

/// Issue 38: a configuration a reader can hold in mind, every key with a
/// meaning; a new key has to displace one.
#[test]
fn the_default_file_has_at_most_120_keys() {
    let file: toml::Table = toml::from_str(include_str!("../../configs/default.toml")).unwrap();
    let keys = paths(&file);
    assert!(
        keys.len() <= 120,
        "{} keys in configs/default.toml",
        keys.len()
    );
}

#[test]
fn default_is_the_default_file() {
    let parsed: Config = toml::from_str(include_str!("../../configs/default.toml"))
        .expect("configs/default.toml parses");
    assert_eq!(Config::default(), parsed);
    assert_eq!(Config::default(), Config::resolve("default").unwrap());
    assert_eq!(Config::default().method, Method::PlaneOptimized);
}

/// Every built-in states every key its configuration has (an optional
/// quantity left out is off), so none is filled from a section's `Default`
/// impl, and states no key the default file does not know.
#[test]
fn builtins_are_complete() {
    let known = paths(&known_keys());
    for name in Config::builtin_names() {
        let Ok(toml::Value::Table(serialised)) =
            toml::Value::try_from(Config::resolve(name).unwrap())
        else {
            panic!("the configuration serialises to a table");
        };
        let stated = paths(&builtin_table(name));
        assert_eq!(stated, paths(&serialised), "configs/{name}.toml");
        for key in &stated {
            assert!(known.contains(key), "configs/{name}.toml: {key}");
        }
    }
}

/// Sections whose struct's `Default` may still differ from
/// `configs/default.toml` (none left).
const DEFAULTS_MAY_DIFFER: &[&str] = &[];

/// A section's struct's `Default` as TOML, the default file's table at the
/// same path, and both compared key by key: the first key that differs.
fn first_difference(path: &str, ours: toml::Value, file: &toml::Table) -> Option<String> {
    let mut section = file;
    for key in path.split('.') {
        match section.get(key) {
            Some(toml::Value::Table(t)) => section = t,
            _ => return Some(format!("configs/default.toml has no [{path}]")),
        }
    }
    let toml::Value::Table(ours) = ours else {
        return Some(format!("{path}: Default does not serialise to a table"));
    };
    let mut keys: Vec<&String> = ours.keys().chain(section.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter().find_map(|key| {
        let (a, b) = (ours.get(key), section.get(key));
        match (a, b) {
            (Some(toml::Value::Table(_)), Some(toml::Value::Table(_))) => None, // its own section
            _ if a == b => None,
            _ => Some(format!(
                "{path}.{key}: Default {} against configs/default.toml {}",
                a.map_or("(absent)".into(), |v| v.to_string()),
                b.map_or("(absent)".into(), |v| v.to_string())
            )),
        }
    })
}

/// Every section's Rust `Default` is its table of `configs/default.toml`:
/// one source of defaults.
#[test]
fn section_defaults_are_the_default_file() {
    fn value<T: serde::Serialize>(t: T) -> toml::Value {
        toml::Value::try_from(t).expect("a section serialises")
    }
    let file = builtin_table(DEFAULT_BASE);
    let sections: Vec<(&str, toml::Value)> = vec![
        ("input", value(InputParams::default())),
        ("detector", value(DetectorParams::default())),
        ("single_scan", value(SingleScanParams::default())),
        ("map", value(MapParams::default())),
        ("map.merge", value(crate::map::MergeParams::default())),
        ("map.evidence", value(crate::map::EvidenceParams::default())),
        ("map.panes", value(crate::map::PaneParams::default())),
        ("map.ghosts", value(crate::map::GhostParams::default())),
        ("plane_map", value(PlaneMapParams::default())),
        (
            "plane_map.echo_split",
            value(crate::reflect::EchoSplitParams::default()),
        ),
        ("extractor", value(ExtractorParams::default())),
        (
            "extractor.normals",
            value(crate::frontend::NormalParams::default()),
        ),
        (
            "extractor.region",
            value(crate::frontend::RegionParams::default()),
        ),
        (
            "extractor.ground",
            value(crate::frontend::ground::GroundParams::default()),
        ),
        ("slam", value(SlamParams::default())),
        (
            "slam.motion",
            value(crate::slam::motion::MotionParams::default()),
        ),
        (
            "slam.rejector",
            value(crate::registration::RejectorParams::default()),
        ),
        (
            "slam.gauss_newton",
            value(crate::registration::GaussNewtonParams::default()),
        ),
        (
            "slam.recovery",
            value(crate::slam::recovery::RecoveryParams::default()),
        ),
        (
            "slam.points",
            value(crate::slam::point_map::PointParams::default()),
        ),
        (
            "slam.loop_closure",
            value(crate::slam::loop_closure::LoopClosureParams::default()),
        ),
        ("backend", value(BackendParams::default())),
        (
            "backend.solver",
            value(crate::backend::SolverParams::default()),
        ),
        ("output", value(OutputParams::default())),
        (
            "plane_map.mirror",
            value(crate::map::MirrorParams::default()),
        ),
        (
            "plane_map.weighing",
            value(crate::classify::evidence::WeighingParams::default()),
        ),
    ];
    // Every section of the file is covered (the top level is Config::default).
    let mut covered: Vec<&str> = sections.iter().map(|(p, _)| *p).collect();
    covered.extend([
        "detector.ransac",
        "extractor.ransac",
        "extractor.ground.ransac",
    ]);
    covered.extend(["backend.robust", "plane_map.decision"]);
    // The evidence tests' tables are compared as part of their weighing's.
    covered.extend([
        "plane_map.weighing.seen_space",
        "plane_map.weighing.seen_surface",
        "plane_map.weighing.image_support",
        "plane_map.weighing.frame_free_space",
        "plane_map.weighing.depth",
        "plane_map.weighing.echo_strength",
        "plane_map.weighing.echo_order",
        "plane_map.weighing.level_surface",
        "plane_map.weighing.seen_through",
    ]);
    fn tables(t: &toml::Table, prefix: &str, out: &mut Vec<String>) {
        for (k, v) in t {
            if let toml::Value::Table(sub) = v {
                let path = key_path_of(prefix, k);
                tables(sub, &path, out);
                out.push(path);
            }
        }
    }
    fn key_path_of(prefix: &str, key: &str) -> String {
        if prefix.is_empty() {
            key.to_string()
        } else {
            format!("{prefix}.{key}")
        }
    }
    let mut all = Vec::new();
    tables(&file, "", &mut all);
    for path in &all {
        assert!(
            covered.contains(&path.as_str()),
            "[{path}] has no Default compared here"
        );
    }
    let mut differ = Vec::new();
    for (path, ours) in sections {
        if let Some(d) = first_difference(path, ours, &file) {
            if DEFAULTS_MAY_DIFFER.contains(&path) {
                continue;
            }
            differ.push(d);
        }
    }
    assert!(differ.is_empty(), "{}", differ.join("\n"));
}

#[test]
fn an_empty_file_is_the_default() {
    let c = Config::from_toml("", Path::new("empty.toml")).unwrap();
    assert_eq!(c, Config::default());
    let (_, layering) = Config::from_toml_layered("", Path::new("empty.toml")).unwrap();
    assert_eq!(layering.extends, "default");
    assert!(layering.keys.is_empty());
    let c = Config::from_toml("extends = \"paper\"", Path::new("p.toml")).unwrap();
    assert_eq!(c, Config::resolve("paper").unwrap());
}

#[test]
fn a_file_changes_only_its_keys() {
    let text = "seed = 7\n[plane_map.decision]\nbehind_distance = 0.3\n[map.panes]\ncontext = 2.0";
    let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
    let mut want = Config {
        seed: 7,
        ..Config::default()
    };
    want.plane_map.decision.behind_distance = 0.3;
    want.map.panes.context = 2.0;
    assert_eq!(c, want);
    assert_eq!(
        layering.keys,
        [
            "map.panes.context",
            "plane_map.decision.behind_distance",
            "seed"
        ]
    );
    assert!(
        layering.comment().contains("\"default\""),
        "{}",
        layering.comment()
    );

    let text = "extends = \"paper\"\n[plane_map.ladder]\nspace_margin = 0.3";
    let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
    let mut want = Config::resolve("paper").unwrap();
    want.plane_map.decision.space_margin = 0.3;
    if let Some(ladder) = want.plane_map.ladder.as_mut() {
        ladder.space_margin = 0.3;
    }
    assert_eq!(c, want);
    assert_eq!(layering.extends, "paper");
}

#[test]
fn changing_a_tagged_table_variant_replaces_it() {
    let c = Config::from_toml("[backend.robust]\nkind = \"none\"", Path::new("c.toml")).unwrap();
    assert_eq!(c.backend.robust, crate::backend::RobustKernel::None);
    let c = Config::from_toml(
        "[backend.robust]\nkind = \"cauchy\"\nk = 2.0",
        Path::new("c.toml"),
    )
    .unwrap();
    assert_eq!(
        c.backend.robust,
        crate::backend::RobustKernel::Cauchy { k: 2.0 }
    );
    let c = Config::from_toml("[backend.robust]\nk = 2.0", Path::new("c.toml")).unwrap();
    assert_eq!(
        c.backend.robust,
        crate::backend::RobustKernel::Huber { k: 2.0 }
    );
}

#[test]
fn misspelt_keys_suggest_the_closest() {
    let e = Config::from_toml(
        "extends = \"paper\"\n[plane_map.ladder]\nspace_tset = true",
        Path::new("my.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("my.toml: "), "{e}");
    assert!(e.contains("`plane_map.ladder.space_tset`"), "{e}");
    assert!(
        e.contains("did you mean `plane_map.ladder.space_test`?"),
        "{e}"
    );
    let e = Config::from_toml("[plane_mapp]\nhull_margin = 1.0", Path::new("my.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean `plane_map`?"), "{e}");
    let e = Config::from_toml("[input]\nzzz = 1", Path::new("my.toml"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("valid keys here: frame_cache_mb, pose_interpolation_gap, pose_tolerance"),
        "{e}"
    );
    let e = Config::from_toml("extend = \"paper\"", Path::new("my.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean `extends`?"), "{e}");
    let e = Config::from_toml("extends = \"papr\"", Path::new("my.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("my.toml") && e.contains("default, paper"), "{e}");
}

#[test]
fn edit_distances() {
    assert_eq!(edit_distance("space_tset", "space_test"), 1);
    assert_eq!(edit_distance("sensorr", "sensor"), 1);
    assert_eq!(edit_distance("", "abc"), 3);
    assert_eq!(edit_distance("kitten", "sitting"), 3);
}

/// The optional keys the default file leaves out are valid in a file, and
/// each is an optional quantity of the configuration (absent: off).
#[test]
fn optional_keys_are_valid_and_off_when_absent() {
    let Ok(toml::Value::Table(serialised)) = toml::Value::try_from(Config::default()) else {
        panic!("the configuration serialises to a table");
    };
    let stated = paths(&serialised);
    for (path, _) in OPTIONAL_KEYS {
        assert!(
            !stated.contains(&path.to_string()),
            "{path} is in the default"
        );
    }
    let known = known_keys();
    let c = Config::from_toml(&toml::to_string(&known).unwrap(), Path::new("all.toml")).unwrap();
    assert_eq!(c.slam.window, Some(20));
    assert_eq!(c.slam.keyframe_move, Some(0.2));
    assert_eq!(c.backend.odometry_free_rotation_sigma, Some(0.1));
    let e = Config::from_toml("[slam]\nwindw = 20", Path::new("w.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("did you mean `slam.window`?"), "{e}");
}

/// A removed key is an unknown key, named with the file.
#[test]
fn removed_keys_are_unknown() {
    for (text, key) in [
        ("[input]\nmax_speed = 100.0", "input.max_speed"),
        (
            "[slam.points]\nkernel_scale = 0.05",
            "slam.points.kernel_scale",
        ),
        (
            "[backend.solver]\ninitial_lambda = 1e-5",
            "backend.solver.initial_lambda",
        ),
        (
            "[detector.intensity_peak]\npeak_min = 35.0",
            "detector.intensity_peak",
        ),
        (
            "[single_scan.decision]\ndepth_test = true",
            "single_scan.decision",
        ),
        (
            "[single_scan]\nwindow_min_deg = 48.6",
            "single_scan.window_min_deg",
        ),
        (
            "[plane_map]\nspace_min_passes = 2",
            "plane_map.space_min_passes",
        ),
        (
            "[plane_map]\nsupport_keyframe_move = 0.0",
            "plane_map.support_keyframe_move",
        ),
        (
            "[plane_map.decision]\nwall_echo_test = true",
            "plane_map.decision.wall_echo_test",
        ),
        (
            "[plane_map.echo_split]\nenabled = true",
            "plane_map.echo_split.enabled",
        ),
        (
            "[plane_map.echo_split]\nmirror_blocked_paths = true",
            "plane_map.echo_split.mirror_blocked_paths",
        ),
        (
            "[map.evidence]\necho_reach = 1.0",
            "map.evidence.echo_reach",
        ),
        ("[map.ghosts]\nradius = 0.3", "map.ghosts.radius"),
    ] {
        let e = Config::from_toml(text, Path::new("old.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("old.toml: ") && e.contains(&format!("unknown key `{key}`")),
            "{e}"
        );
    }
}

/// The rule ladder needs its thresholds: over the default (which has none)
/// choosing it is an error saying where they are; over the paper it runs
/// with the paper's, and the weighed model ignores them.
#[test]
fn the_ladder_needs_its_table() {
    let e = Config::from_toml(
        "[plane_map]\ndecision_model = \"ladder\"",
        Path::new("l.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("l.toml: ") && e.contains("[plane_map.ladder]"),
        "{e}"
    );
    let paper = Config::resolve("paper").unwrap();
    assert_eq!(Some(paper.plane_map.decision), paper.plane_map.ladder);
    let weighed = Config::from_toml(
        "extends = \"paper\"\n[plane_map]\ndecision_model = \"weighed\"",
        Path::new("w.toml"),
    )
    .unwrap();
    assert_eq!(
        weighed.plane_map.decision,
        crate::classify::decide::DecisionParams::WEIGHED
    );
    assert!(Config::default().plane_map.ladder.is_none());
    assert_eq!(
        Config::default().plane_map.decision,
        crate::classify::decide::DecisionParams::WEIGHED
    );
    assert_eq!(
        Config::default().single_scan.decision,
        crate::classify::decide::DecisionParams {
            free_space_neighbourhood: 1,
            ..crate::classify::decide::DecisionParams::ZHAO2020
        }
    );
    assert_eq!(
        paper.single_scan.decision,
        crate::classify::decide::DecisionParams::ZHAO2020
    );
}
