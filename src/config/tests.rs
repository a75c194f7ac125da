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
    let e = Config::from_toml("sensorr = 1", Path::new("c.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("c.toml") && e.contains("sensorr"), "{e}");
    let e = Config::from_toml("[detector]\ndual_gap = -1.0", Path::new("c.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("detector.dual_gap must be positive"), "{e}");
}

/// Dotted paths of every value in a table.
fn paths(table: &toml::Table) -> Vec<String> {
    let mut out = Vec::new();
    leaf_paths(table, "", &mut out);
    out.sort();
    out
}

#[test]
fn default_is_the_default_file() {
    let parsed: Config = toml::from_str(include_str!("../../configs/default.toml"))
        .expect("configs/default.toml parses");
    assert_eq!(Config::default(), parsed);
    assert_eq!(Config::default(), Config::resolve("default").unwrap());
    assert_eq!(Config::default().method, Method::PlaneOptimized);
}

/// Every built-in states every key the configuration has, so none is
/// filled from a section's `Default` impl.
#[test]
fn builtins_are_complete() {
    let Ok(toml::Value::Table(serialised)) = toml::Value::try_from(Config::default()) else {
        panic!("the configuration serialises to a table");
    };
    let all = paths(&serialised);
    for name in Config::builtin_names() {
        assert_eq!(paths(&builtin_table(name)), all, "configs/{name}.toml");
    }
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
    let text = "seed = 7\n[plane_map.decision]\nspace_margin = 0.3\n[map.panes.fit]\nsolver = \"joint-lp\"";
    let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
    let mut want = Config {
        seed: 7,
        ..Config::default()
    };
    want.plane_map.decision.space_margin = 0.3;
    want.map.panes.fit.solver = crate::map::boundary_fit::BoundarySolver::JointLp;
    assert_eq!(c, want);
    assert_eq!(
        layering.keys,
        [
            "map.panes.fit.solver",
            "plane_map.decision.space_margin",
            "seed"
        ]
    );
    assert!(
        layering.comment().contains("\"default\""),
        "{}",
        layering.comment()
    );

    let text = "extends = \"paper\"\n[plane_map.decision]\nspace_margin = 0.3";
    let (c, layering) = Config::from_toml_layered(text, Path::new("c.toml")).unwrap();
    let mut want = Config::resolve("paper").unwrap();
    want.plane_map.decision.space_margin = 0.3;
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
        "[plane_map.decision]\nspace_tset = true",
        Path::new("my.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("my.toml: "), "{e}");
    assert!(e.contains("`plane_map.decision.space_tset`"), "{e}");
    assert!(
        e.contains("did you mean `plane_map.decision.space_test`?"),
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
        e.contains(
            "valid keys here: frame_cache_mb, max_pose_translation, max_speed, pose_interpolation_gap, pose_tolerance"
        ),
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
