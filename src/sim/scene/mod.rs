//! Scene files: TOML descriptions of a world of planar surfaces with
//! materials, a sensor and a trajectory.
//!
//! ```toml
//! name = "demo"
//! seed = 1
//!
//! [sensor]
//! model = "pandar_qt64"      # built-in name, or a sensor TOML path relative to the scene
//! range_noise = 0.01         # Gaussian range noise sigma, metres
//! crop_range = 25.0          # drop returns farther than this (3DRef: 25 m); optional
//! blind_sector_deg = [157.5, 202.5]  # azimuths hidden by the operator; optional
//! dropout = 0.01             # share of beams that return nothing; optional
//! sweep = true               # beams fired over the sensor's period while it moves; optional
//!
//! [trajectory]
//! waypoints = [[1.0, 1.0, 1.2], [8.0, 1.0, 1.2]]
//! speed = 0.5                # m/s; frames at the sensor rate (10 Hz)
//! loop = false
//! tilt_deg = [1.0, -2.0]     # fixed mounting roll and pitch; optional
//! turn_rate_deg = 45.0       # the sensor also turns about its vertical axis, deg/s; optional
//!
//! [materials]
//! plaster = { type = "diffuse", reflectivity = 0.7 }
//! window = { type = "glass", reflectance = 0.3, transmittance = 0.5 }
//!
//! [[rooms]]                  # a box seen from inside: 4 walls, floor, ceiling
//! min = [0.0, 0.0, 0.0]
//! max = [10.0, 8.0, 3.0]
//! material = "plaster"
//! omit = ["+y"]              # sides: +x -x +y -y floor ceiling
//!
//! [[walls]]                  # a vertical rectangle from two floor corners
//! from = [0.0, 8.0]
//! to = [10.0, 8.0]
//! height = 3.0
//! material = "window"
//! ```
//!
//! Other items: `[[boxes]]` (solid boxes seen from outside: furniture,
//! buildings, cars), `[[polygons]]` (any planar polygon, `vertices =
//! [[x, y, z], ...]`), `[[floors]]` and `[[ceilings]]` (horizontal
//! rectangles). Rooms and boxes take `yaw_deg` (rotation about their vertical
//! centre axis), `omit` and per-side material overrides `sides = { "+x" =
//! "window" }`. Every table rejects unknown keys, and every error names the
//! file and the item.
//!
//! The room has three parts: this module holds the validated [`Scene`] and
//! how it is loaded; `file` the TOML tables exactly as written, with their
//! defaults; `build` checks them and turns rooms, boxes, walls and the rest
//! into surfaces with resolved materials.

mod build;
pub(crate) mod file;

use std::path::{Path, PathBuf};

use super::material::Material;
use super::surface::Surface;
use super::trajectory::Trajectory;
use crate::sensor::SensorModel;
use crate::{Error, Result};

/// The sensor as the simulator uses it: the model plus the noise and
/// detection parameters of the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorSetup {
    /// Rings, columns, return mode, range resolution and limits.
    pub model: SensorModel,
    /// Standard deviation of the Gaussian range noise, metres.
    pub range_noise: f64,
    /// Longest path a beam is followed for (one way), metres.
    pub max_range: f64,
    /// Returns farther than this are dropped (3DRef crops at 25 m).
    pub crop_range: Option<f64>,
    /// Specular bounces followed per beam (at least 2 is realistic).
    pub max_bounces: u32,
    /// Intensity of an echo of signal `σ·A/r²` is `gain · σ·A/r²`, clamped
    /// to 255.
    pub intensity_gain: f64,
    /// Echoes weaker than this intensity are not detected.
    pub detection_threshold: f64,
    /// Azimuth sector `[from, to]` (degrees in the sensor frame,
    /// counter-clockwise from `from` to `to`) hidden by the platform or the
    /// operator: beams there return nothing, as in 3DRef where the person
    /// pushing the trolley was removed.
    pub blind_sector_deg: Option<[f64; 2]>,
    /// Probability that a beam returns nothing at all (dust, absorbing or
    /// wet spots, electronics), drawn per beam from the frame's seed.
    pub dropout: f64,
    /// Whether a frame's beams are fired over the sensor's period while it
    /// moves (each from the pose at its own firing time, its point in the
    /// sensor frame of that time, [`Point::time`](crate::cloud::Point::time)
    /// set): motion distortion, as real sensors have. Off (the default),
    /// the whole frame is taken at one pose. See
    /// [`Simulator`](crate::sim::Simulator).
    pub sweep: bool,
}

impl SensorSetup {
    /// Whether a sensor-frame azimuth (degrees) lies in the blind sector.
    pub fn is_blind(&self, azimuth_deg: f64) -> bool {
        match self.blind_sector_deg {
            Some([from, to]) => {
                let width = (to - from).rem_euclid(360.0);
                (azimuth_deg - from).rem_euclid(360.0) <= width
            }
            None => false,
        }
    }
}

/// Changes to a scene as `specular simulate` makes them: another sensor,
/// motion distortion, another speed, a turn rate. The default changes
/// nothing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneChanges {
    /// Another sensor model (a built-in name or a sensor file).
    pub sensor: Option<String>,
    /// Fire the beams over the sensor's period while it moves
    /// ([`SensorSetup::sweep`]).
    pub sweep: bool,
    /// Another speed along the path, m/s.
    pub speed: Option<f64>,
    /// Turn about the vertical axis at this rate on top of the path's
    /// heading, deg/s (the trajectory's `turn_rate_deg`).
    pub turn_rate_deg: Option<f64>,
}

impl SceneChanges {
    /// Whether the changes change nothing.
    pub fn is_empty(&self) -> bool {
        *self == Self::default()
    }
}

/// A material with the name the scene gave it.
#[derive(Debug, Clone, PartialEq)]
pub struct NamedMaterial {
    /// Name in the scene file.
    pub name: String,
    /// Optical parameters.
    pub material: Material,
}

/// A validated scene: surfaces, materials, sensor and trajectory.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// Free-text description.
    pub description: String,
    /// Default seed of the range noise (overridable per run).
    pub seed: u64,
    /// The sensor.
    pub sensor: SensorSetup,
    /// The sensor's path.
    pub trajectory: Trajectory,
    /// Number of frames when the run does not say (default: drive the path
    /// once).
    pub frames: usize,
    /// Materials, referenced by index from the surfaces.
    pub materials: Vec<NamedMaterial>,
    /// Every planar surface of the world.
    pub surfaces: Vec<Surface>,
    /// Where the scene came from (file path or `builtin:<name>`).
    pub origin: PathBuf,
}

impl Scene {
    /// Read and validate a scene file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_toml(&text, path)
    }

    /// A built-in scene by name ([`super::builtin::names`]) or a scene file
    /// by path.
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        if let Some(text) = super::builtin::text(name_or_path) {
            return Self::from_toml(text, Path::new(&format!("builtin:{name_or_path}")));
        }
        let path = Path::new(name_or_path);
        if path.exists() {
            return Self::load(path);
        }
        Err(Error::Config(format!(
            "unknown scene '{name_or_path}': not a built-in ({}) nor a file",
            super::builtin::names().join(", ")
        )))
    }

    /// The text of a built-in scene or a scene file, and the origin it is
    /// parsed with.
    pub fn text_of(name_or_path: &str) -> Result<(String, PathBuf)> {
        if let Some(text) = super::builtin::text(name_or_path) {
            return Ok((
                text.to_string(),
                PathBuf::from(format!("builtin:{name_or_path}")),
            ));
        }
        let path = Path::new(name_or_path);
        if path.exists() {
            let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            return Ok((text, path.to_path_buf()));
        }
        Self::resolve(name_or_path).map(|_| (String::new(), PathBuf::new()))
    }

    /// The scene of the file `text` with its sensor model replaced by
    /// `sensor` (a built-in name or a sensor file), and the scene file as
    /// changed; the rest of `[sensor]` (noise, range cap, crop, blind
    /// sector) stays the scene's.
    pub fn with_sensor(text: &str, origin: &Path, sensor: &str) -> Result<(Self, String)> {
        let changes = SceneChanges {
            sensor: Some(sensor.to_string()),
            ..Default::default()
        };
        Self::with_changes(text, origin, &changes)
    }

    /// The scene of the file `text` with `changes` made to it, and the
    /// scene file as changed (so that it can be written beside the frames
    /// and simulated again).
    pub fn with_changes(
        text: &str,
        origin: &Path,
        changes: &SceneChanges,
    ) -> Result<(Self, String)> {
        let mut file: file::SceneFile =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string().trim_end()))?;
        if let Some(sensor) = &changes.sensor {
            file.sensor.model = match SensorModel::is_builtin(sensor) {
                true => SensorModel::resolve(sensor)?.name,
                false => sensor.to_string(),
            };
        }
        if changes.sweep {
            file.sensor.sweep = Some(true);
        }
        if let Some(speed) = changes.speed {
            file.trajectory.speed = speed;
        }
        if let Some(rate) = changes.turn_rate_deg {
            file.trajectory.turn_rate_deg = Some(rate);
        }
        let toml = toml::to_string(&file).map_err(|e| Error::format(origin, e.to_string()))?;
        Ok((Self::from_file(file, origin)?, toml))
    }

    /// Parse and validate a scene (`origin` names it in errors and anchors
    /// relative sensor paths).
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let file: file::SceneFile =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string().trim_end()))?;
        Self::from_file(file, origin)
    }

    /// Validate and build a scene from its file tables (a generated scene:
    /// [`super::family`]).
    pub(crate) fn from_file(file: file::SceneFile, origin: &Path) -> Result<Self> {
        file.build(origin)
            .map_err(|m| Error::format(origin, m.to_string()))
    }

    /// The material of a surface.
    pub fn material_of(&self, surface: &Surface) -> &Material {
        &self.materials[surface.material].material
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::sim::material::MaterialKind;

    const MINIMAL: &str = r#"
        [sensor]
        model = "pandar_qt64"
        [trajectory]
        waypoints = [[1.0, 1.0, 1.0], [3.0, 1.0, 1.0]]
        speed = 1.0
        [materials]
        wall = { type = "diffuse", reflectivity = 0.5 }
        win = { type = "glass" }
        [[rooms]]
        min = [0.0, 0.0, 0.0]
        max = [4.0, 3.0, 2.5]
        material = "wall"
        omit = ["+y"]
        sides = { "-x" = "win" }
    "#;

    #[test]
    fn a_minimal_scene_builds_with_inward_room_normals() {
        let s = Scene::from_toml(MINIMAL, Path::new("min.toml")).unwrap();
        assert_eq!(s.name, "min");
        assert_eq!(s.surfaces.len(), 5);
        let centre = DVec3::new(2.0, 1.5, 1.25);
        for surf in &s.surfaces {
            assert!(surf.normal.dot(centre) + surf.d > 0.0, "{}", surf.origin);
        }
        let west = s
            .surfaces
            .iter()
            .find(|x| x.origin == "rooms[0].-x")
            .unwrap();
        assert_eq!(s.material_of(west).kind, MaterialKind::Glass);
        assert_eq!(s.frames, 21);
    }

    #[test]
    fn blind_sector_wraps_around_the_seam() {
        let text = MINIMAL.replace(
            "model = \"pandar_qt64\"",
            "model = \"pandar_qt64\"\nblind_sector_deg = [160.0, -160.0]",
        );
        let s = Scene::from_toml(&text, Path::new("min.toml")).unwrap();
        assert!(s.sensor.is_blind(180.0) && s.sensor.is_blind(-180.0));
        assert!(s.sensor.is_blind(165.0) && s.sensor.is_blind(-165.0));
        assert!(!s.sensor.is_blind(0.0) && !s.sensor.is_blind(150.0));
        let open = Scene::from_toml(MINIMAL, Path::new("min.toml")).unwrap();
        assert!(!open.sensor.is_blind(180.0));
    }

    #[test]
    fn errors_name_the_file_and_the_item() {
        let e = |text: &str| {
            Scene::from_toml(text, Path::new("scenes/bad.toml"))
                .unwrap_err()
                .to_string()
        };
        let typo = MINIMAL.replace("material = \"wall\"", "material = \"wal\"");
        let msg = e(&typo);
        assert!(
            msg.contains("scenes/bad.toml") && msg.contains("rooms[0]"),
            "{msg}"
        );
        assert!(msg.contains("unknown material 'wal'"), "{msg}");
        let unknown_key = MINIMAL.replace("speed = 1.0", "speed = 1.0\nspeeed = 2.0");
        let msg = e(&unknown_key);
        assert!(msg.contains("bad.toml") && msg.contains("speeed"), "{msg}");
        let bad_glass = MINIMAL.replace(
            "type = \"glass\"",
            "type = \"glass\", reflectance = 0.5, transmittance = 0.7",
        );
        assert!(e(&bad_glass).contains("materials.win"));
        let bad_kind = MINIMAL.replace("type = \"glass\"", "type = \"glas\"");
        assert!(e(&bad_kind).contains("glas"));
        let bad_side = MINIMAL.replace("omit = [\"+y\"]", "omit = [\"north\"]");
        assert!(e(&bad_side).contains("unknown side 'north'"));
        let unknown_material_key =
            MINIMAL.replace("type = \"glass\"", "type = \"glass\", colour = 1");
        assert!(e(&unknown_material_key).contains("colour"));
    }
}
