//! Scenes embedded in the binary, so `specular simulate --scene office`
//! works from any directory. The files live in `datasets/scenes/`.

/// (name, TOML text) of every built-in scene.
const SCENES: &[(&str, &str)] = &[
    ("demo", include_str!("../../datasets/scenes/demo.toml")),
    ("office", include_str!("../../datasets/scenes/office.toml")),
    (
        "corridor",
        include_str!("../../datasets/scenes/corridor.toml"),
    ),
    (
        "mirror-room",
        include_str!("../../datasets/scenes/mirror-room.toml"),
    ),
    ("lobby", include_str!("../../datasets/scenes/lobby.toml")),
    (
        "glass-loop",
        include_str!("../../datasets/scenes/glass-loop.toml"),
    ),
    (
        "two-panes",
        include_str!("../../datasets/scenes/two-panes.toml"),
    ),
];

/// Names of the built-in scenes.
pub fn names() -> Vec<&'static str> {
    SCENES.iter().map(|(n, _)| *n).collect()
}

/// The TOML text of a built-in scene.
pub fn text(name: &str) -> Option<&'static str> {
    SCENES.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}
