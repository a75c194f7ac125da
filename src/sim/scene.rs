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
//!
//! [trajectory]
//! waypoints = [[1.0, 1.0, 1.2], [8.0, 1.0, 1.2]]
//! speed = 0.5                # m/s; frames at the sensor rate (10 Hz)
//! loop = false
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

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::{DVec2, DVec3};
use serde::Deserialize;

use super::material::{Material, MaterialKind};
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

    /// Parse and validate a scene (`origin` names it in errors and anchors
    /// relative sensor paths).
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let file: SceneFile =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string().trim_end()))?;
        file.build(origin)
            .map_err(|m| Error::format(origin, m.to_string()))
    }

    /// The material of a surface.
    pub fn material_of(&self, surface: &Surface) -> &Material {
        &self.materials[surface.material].material
    }
}

// ---------------------------------------------------------------- file format

fn default_noise() -> f64 {
    0.01
}
fn default_bounces() -> u32 {
    2
}
fn default_gain() -> f64 {
    20_000.0
}
fn default_threshold() -> f64 {
    3.0
}
fn default_smoothing() -> f64 {
    1.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    name: Option<String>,
    #[serde(default)]
    description: String,
    #[serde(default)]
    seed: u64,
    sensor: SensorFile,
    trajectory: TrajectoryFile,
    #[serde(default)]
    materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    rooms: Vec<RoomFile>,
    #[serde(default)]
    boxes: Vec<BoxFile>,
    #[serde(default)]
    walls: Vec<WallFile>,
    #[serde(default)]
    polygons: Vec<PolygonFile>,
    #[serde(default)]
    floors: Vec<RectFile>,
    #[serde(default)]
    ceilings: Vec<RectFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorFile {
    model: String,
    #[serde(default = "default_noise")]
    range_noise: f64,
    max_range: Option<f64>,
    crop_range: Option<f64>,
    #[serde(default = "default_bounces")]
    max_bounces: u32,
    #[serde(default = "default_gain")]
    intensity_gain: f64,
    #[serde(default = "default_threshold")]
    detection_threshold: f64,
    blind_sector_deg: Option<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrajectoryFile {
    waypoints: Vec<[f64; 3]>,
    speed: f64,
    #[serde(rename = "loop", default)]
    closed: bool,
    #[serde(default = "default_smoothing")]
    heading_smoothing: f64,
    frames: Option<usize>,
}

/// Material parameters as written in scene files (see
/// [`super::material`] for their meaning); omitted parameters take
/// physically plausible defaults for the class.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
enum MaterialFile {
    Diffuse {
        reflectivity: f64,
    },
    Glass {
        #[serde(default = "glass_r")]
        reflectance: f64,
        #[serde(default = "glass_t")]
        transmittance: f64,
        #[serde(default = "one")]
        echo_peak: f64,
        #[serde(default = "three")]
        echo_width_deg: f64,
        #[serde(default = "glass_dirt")]
        echo_diffuse: f64,
        #[serde(default = "glass_lobe")]
        echo_lobe: f64,
    },
    Mirror {
        #[serde(default = "mirror_r")]
        reflectance: f64,
        #[serde(default = "half")]
        echo_peak: f64,
        #[serde(default = "two")]
        echo_width_deg: f64,
        #[serde(default = "mirror_dirt")]
        echo_diffuse: f64,
        #[serde(default = "one")]
        echo_lobe: f64,
    },
    OtherReflective {
        #[serde(default = "other_rho")]
        reflectivity: f64,
        #[serde(default = "other_r")]
        reflectance: f64,
        #[serde(default = "one")]
        echo_peak: f64,
        #[serde(default = "five")]
        echo_width_deg: f64,
    },
}

fn glass_r() -> f64 {
    0.08
}
fn glass_t() -> f64 {
    0.85
}
fn glass_dirt() -> f64 {
    0.03
}
fn glass_lobe() -> f64 {
    8.0
}
fn mirror_r() -> f64 {
    0.9
}
fn mirror_dirt() -> f64 {
    0.01
}
fn other_rho() -> f64 {
    0.3
}
fn other_r() -> f64 {
    0.1
}
fn half() -> f64 {
    0.5
}
fn one() -> f64 {
    1.0
}
fn two() -> f64 {
    2.0
}
fn three() -> f64 {
    3.0
}
fn five() -> f64 {
    5.0
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RoomFile {
    min: [f64; 3],
    max: [f64; 3],
    #[serde(default)]
    yaw_deg: f64,
    material: String,
    floor: Option<String>,
    ceiling: Option<String>,
    #[serde(default)]
    omit: Vec<String>,
    #[serde(default)]
    sides: BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BoxFile {
    min: [f64; 3],
    max: [f64; 3],
    #[serde(default)]
    yaw_deg: f64,
    material: String,
    #[serde(default)]
    omit: Vec<String>,
    #[serde(default)]
    sides: BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct WallFile {
    from: [f64; 2],
    to: [f64; 2],
    #[serde(default)]
    base: f64,
    height: f64,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PolygonFile {
    vertices: Vec<[f64; 3]>,
    material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RectFile {
    min: [f64; 2],
    max: [f64; 2],
    z: f64,
    material: String,
}

/// The six sides of a box, in the order they are generated.
const SIDES: [&str; 6] = ["-x", "+x", "-y", "+y", "floor", "ceiling"];

type BuildResult<T> = std::result::Result<T, String>;

impl MaterialFile {
    fn build(&self) -> BuildResult<Material> {
        let unit = |name: &str, v: f64| -> BuildResult<f64> {
            if (0.0..=1.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("{name} must be in 0..1, got {v}"))
            }
        };
        let peak = |v: f64| -> BuildResult<f64> {
            if (0.0..=100.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("echo_peak must be in 0..100, got {v}"))
            }
        };
        let lobe = |v: f64| -> BuildResult<f64> {
            if (1.0..=1000.0).contains(&v) {
                Ok(v)
            } else {
                Err(format!("echo_lobe must be in 1..1000, got {v}"))
            }
        };
        let width = |v: f64| -> BuildResult<f64> {
            if v > 0.0 && v <= 90.0 {
                Ok(v.to_radians())
            } else {
                Err(format!("echo_width_deg must be in (0, 90], got {v}"))
            }
        };
        Ok(match *self {
            MaterialFile::Diffuse { reflectivity } => {
                Material::diffuse(unit("reflectivity", reflectivity)?)
            }
            MaterialFile::Glass {
                reflectance,
                transmittance,
                echo_peak,
                echo_width_deg,
                echo_diffuse,
                echo_lobe,
            } => {
                let r = unit("reflectance", reflectance)?;
                let t = unit("transmittance", transmittance)?;
                if r + t > 1.0 {
                    return Err(format!(
                        "reflectance + transmittance must not exceed 1 (energy), got {r} + {t}"
                    ));
                }
                Material {
                    kind: MaterialKind::Glass,
                    diffuse: unit("echo_diffuse", echo_diffuse)?,
                    lobe: lobe(echo_lobe)?,
                    echo_peak: peak(echo_peak)?,
                    echo_width: width(echo_width_deg)?,
                    reflectance: r,
                    transmittance: t,
                    fresnel: true,
                }
            }
            MaterialFile::Mirror {
                reflectance,
                echo_peak,
                echo_width_deg,
                echo_diffuse,
                echo_lobe,
            } => Material {
                kind: MaterialKind::Mirror,
                diffuse: unit("echo_diffuse", echo_diffuse)?,
                lobe: lobe(echo_lobe)?,
                echo_peak: peak(echo_peak)?,
                echo_width: width(echo_width_deg)?,
                reflectance: unit("reflectance", reflectance)?,
                transmittance: 0.0,
                fresnel: false,
            },
            MaterialFile::OtherReflective {
                reflectivity,
                reflectance,
                echo_peak,
                echo_width_deg,
            } => {
                let rho = unit("reflectivity", reflectivity)?;
                let r = unit("reflectance", reflectance)?;
                if rho + r > 1.0 {
                    return Err(format!(
                        "reflectivity + reflectance must not exceed 1 (energy), got {rho} + {r}"
                    ));
                }
                Material {
                    kind: MaterialKind::OtherReflective,
                    diffuse: rho,
                    lobe: 1.0,
                    echo_peak: peak(echo_peak)?,
                    echo_width: width(echo_width_deg)?,
                    reflectance: r,
                    transmittance: 0.0,
                    fresnel: true,
                }
            }
        })
    }
}

fn finite(what: &str, v: &[f64]) -> BuildResult<()> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what} must be finite numbers"))
    }
}

/// Surfaces are collected with the material names resolved.
struct Builder<'a> {
    names: &'a BTreeMap<String, usize>,
    surfaces: Vec<Surface>,
}

impl Builder<'_> {
    fn material(&self, item: &str, name: &str) -> BuildResult<usize> {
        self.names.get(name).copied().ok_or_else(|| {
            let known: Vec<&str> = self.names.keys().map(String::as_str).collect();
            format!(
                "{item}: unknown material '{name}' (defined: {})",
                if known.is_empty() {
                    "none".to_string()
                } else {
                    known.join(", ")
                }
            )
        })
    }

    fn push(&mut self, item: &str, vertices: Vec<DVec3>, material: usize) -> BuildResult<()> {
        let s = Surface::new(vertices, material, item.to_string())
            .map_err(|m| format!("{item}: {m}"))?;
        s.triangles().map_err(|m| format!("{item}: {m}"))?;
        self.surfaces.push(s);
        Ok(())
    }

    /// The sides of an oriented box; `inward` for rooms.
    #[allow(clippy::too_many_arguments)]
    fn cuboid(
        &mut self,
        item: &str,
        min: [f64; 3],
        max: [f64; 3],
        yaw_deg: f64,
        default_material: usize,
        per_side: &[Option<usize>; 6],
        omit: &[String],
        sides: &BTreeMap<String, String>,
        inward: bool,
    ) -> BuildResult<()> {
        finite(
            &format!("{item}: min/max/yaw_deg"),
            &[min, max, [yaw_deg; 3]].concat(),
        )?;
        if (0..3).any(|i| !(max[i] > min[i])) {
            return Err(format!(
                "{item}: max must exceed min on every axis, got min {min:?} max {max:?}"
            ));
        }
        for name in omit.iter().chain(sides.keys()) {
            if !SIDES.contains(&name.as_str()) {
                return Err(format!(
                    "{item}: unknown side '{name}' (sides: {})",
                    SIDES.join(", ")
                ));
            }
        }
        let lo = DVec3::from_array(min);
        let hi = DVec3::from_array(max);
        let centre = DVec2::new(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y));
        let (s, c) = yaw_deg.to_radians().sin_cos();
        let place = |p: DVec3| -> DVec3 {
            let q = DVec2::new(p.x, p.y) - centre;
            DVec3::new(
                centre.x + c * q.x - s * q.y,
                centre.y + s * q.x + c * q.y,
                p.z,
            )
        };
        let corner = |ix: usize, iy: usize, iz: usize| -> DVec3 {
            place(DVec3::new(
                if ix == 0 { lo.x } else { hi.x },
                if iy == 0 { lo.y } else { hi.y },
                if iz == 0 { lo.z } else { hi.z },
            ))
        };
        for (k, side) in SIDES.iter().enumerate() {
            if omit.iter().any(|o| o == side) {
                continue;
            }
            let axis = k / 2;
            let at = k % 2;
            // The four corners with coordinate `axis` fixed, in cyclic order.
            let cyc = [(0, 0), (1, 0), (1, 1), (0, 1)];
            let mut vertices: Vec<DVec3> = cyc
                .iter()
                .map(|&(a, b)| match axis {
                    0 => corner(at, a, b),
                    1 => corner(a, at, b),
                    _ => corner(a, b, at),
                })
                .collect();
            let mut outward = DVec3::ZERO;
            outward[axis] = if at == 0 { -1.0 } else { 1.0 };
            let outward = place(outward) - place(DVec3::ZERO);
            let want = if inward { -outward } else { outward };
            let material = match sides.get(*side) {
                Some(name) => self.material(&format!("{item}.sides.{side}"), name)?,
                None => per_side[k].unwrap_or(default_material),
            };
            let label = format!("{item}.{side}");
            let probe = Surface::new(vertices.clone(), material, label.clone())
                .map_err(|m| format!("{label}: {m}"))?;
            if probe.normal.dot(want) < 0.0 {
                vertices.reverse();
            }
            self.push(&label, vertices, material)?;
        }
        Ok(())
    }
}

impl SceneFile {
    fn build(self, origin: &Path) -> BuildResult<Scene> {
        // Materials.
        let mut materials = Vec::new();
        let mut names = BTreeMap::new();
        for (name, spec) in &self.materials {
            let m = spec.build().map_err(|e| format!("materials.{name}: {e}"))?;
            names.insert(name.clone(), materials.len());
            materials.push(NamedMaterial {
                name: name.clone(),
                material: m,
            });
        }

        // Sensor.
        let sensor = self.sensor.build(origin)?;

        // Trajectory.
        let t = &self.trajectory;
        let waypoints: Vec<DVec3> = t.waypoints.iter().map(|w| DVec3::from_array(*w)).collect();
        let trajectory = Trajectory::new(waypoints, t.speed, t.closed, t.heading_smoothing)
            .map_err(|m| format!("trajectory: {m}"))?;
        let frames = match t.frames {
            Some(0) => return Err("trajectory: frames must be at least 1".into()),
            Some(n) => n,
            None => trajectory.default_frames(sensor.model.rate_hz),
        };

        // Surfaces.
        let mut b = Builder {
            names: &names,
            surfaces: Vec::new(),
        };
        for (i, r) in self.rooms.iter().enumerate() {
            let item = format!("rooms[{i}]");
            let walls = b.material(&item, &r.material)?;
            let floor = r
                .floor
                .as_deref()
                .map(|n| b.material(&format!("{item}.floor"), n))
                .transpose()?;
            let ceiling = r
                .ceiling
                .as_deref()
                .map(|n| b.material(&format!("{item}.ceiling"), n))
                .transpose()?;
            let per_side = [None, None, None, None, floor, ceiling];
            b.cuboid(
                &item, r.min, r.max, r.yaw_deg, walls, &per_side, &r.omit, &r.sides, true,
            )?;
        }
        for (i, x) in self.boxes.iter().enumerate() {
            let item = format!("boxes[{i}]");
            let m = b.material(&item, &x.material)?;
            b.cuboid(
                &item, x.min, x.max, x.yaw_deg, m, &[None; 6], &x.omit, &x.sides, false,
            )?;
        }
        for (i, w) in self.walls.iter().enumerate() {
            let item = format!("walls[{i}]");
            let m = b.material(&item, &w.material)?;
            finite(
                &format!("{item}: from/to/base/height"),
                &[w.from[0], w.from[1], w.to[0], w.to[1], w.base, w.height],
            )?;
            if !(w.height > 0.0) {
                return Err(format!("{item}: height must be positive, got {}", w.height));
            }
            let top = w.base + w.height;
            let v = vec![
                DVec3::new(w.from[0], w.from[1], w.base),
                DVec3::new(w.to[0], w.to[1], w.base),
                DVec3::new(w.to[0], w.to[1], top),
                DVec3::new(w.from[0], w.from[1], top),
            ];
            b.push(&item, v, m)?;
        }
        for (i, p) in self.polygons.iter().enumerate() {
            let item = format!("polygons[{i}]");
            let m = b.material(&item, &p.material)?;
            let v = p.vertices.iter().map(|v| DVec3::from_array(*v)).collect();
            b.push(&item, v, m)?;
        }
        for (list, what, up) in [
            (&self.floors, "floors", true),
            (&self.ceilings, "ceilings", false),
        ] {
            for (i, r) in list.iter().enumerate() {
                let item = format!("{what}[{i}]");
                let m = b.material(&item, &r.material)?;
                finite(
                    &format!("{item}: min/max/z"),
                    &[r.min[0], r.min[1], r.max[0], r.max[1], r.z],
                )?;
                if !(r.max[0] > r.min[0] && r.max[1] > r.min[1]) {
                    return Err(format!("{item}: max must exceed min on x and y"));
                }
                let mut v = vec![
                    DVec3::new(r.min[0], r.min[1], r.z),
                    DVec3::new(r.max[0], r.min[1], r.z),
                    DVec3::new(r.max[0], r.max[1], r.z),
                    DVec3::new(r.min[0], r.max[1], r.z),
                ];
                if !up {
                    v.reverse();
                }
                b.push(&item, v, m)?;
            }
        }
        let surfaces = b.surfaces;
        if surfaces.is_empty() {
            return Err(
                "the scene has no surfaces (rooms, boxes, walls, polygons, floors or ceilings)"
                    .into(),
            );
        }
        if surfaces.len() > u32::MAX as usize / 4 {
            return Err("too many surfaces".into());
        }
        let name = self.name.unwrap_or_else(|| {
            origin
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into())
        });
        Ok(Scene {
            name,
            description: self.description,
            seed: self.seed,
            sensor,
            trajectory,
            frames,
            materials,
            surfaces,
            origin: origin.to_path_buf(),
        })
    }
}

impl SensorFile {
    fn build(&self, origin: &Path) -> BuildResult<SensorSetup> {
        let model = if SensorModel::builtin_names().contains(&self.model.as_str()) {
            SensorModel::resolve(&self.model)
        } else {
            let base = origin.parent().unwrap_or(Path::new("."));
            SensorModel::resolve(&base.join(&self.model).to_string_lossy())
        }
        .map_err(|e| format!("sensor.model: {e}"))?;
        let bad = |m: String| Err(format!("sensor: {m}"));
        if !(self.range_noise >= 0.0 && self.range_noise < 10.0) {
            return bad(format!(
                "range_noise must be in 0..10 m, got {}",
                self.range_noise
            ));
        }
        let max_range = self.max_range.unwrap_or(model.max_range);
        if !(max_range > model.min_range && max_range.is_finite()) {
            return bad(format!(
                "max_range must exceed the sensor's min_range ({} m), got {max_range}",
                model.min_range
            ));
        }
        let max_range = max_range.min(model.max_range);
        if let Some(c) = self.crop_range {
            if !(c > model.min_range && c.is_finite()) {
                return bad(format!(
                    "crop_range must exceed the sensor's min_range ({} m), got {c}",
                    model.min_range
                ));
            }
        }
        if self.max_bounces > 8 {
            return bad(format!(
                "max_bounces must be at most 8, got {}",
                self.max_bounces
            ));
        }
        if !(self.intensity_gain > 0.0 && self.intensity_gain.is_finite()) {
            return bad(format!(
                "intensity_gain must be positive, got {}",
                self.intensity_gain
            ));
        }
        if !(self.detection_threshold > 0.0 && self.detection_threshold <= 255.0) {
            return bad(format!(
                "detection_threshold must be in (0, 255], got {}",
                self.detection_threshold
            ));
        }
        if let Some(b) = self.blind_sector_deg {
            if !b.iter().all(|x| x.is_finite()) {
                return bad("blind_sector_deg must be two finite angles".into());
            }
        }
        Ok(SensorSetup {
            blind_sector_deg: self.blind_sector_deg,
            model,
            range_noise: self.range_noise,
            max_range,
            crop_range: self.crop_range,
            max_bounces: self.max_bounces,
            intensity_gain: self.intensity_gain,
            detection_threshold: self.detection_threshold,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
