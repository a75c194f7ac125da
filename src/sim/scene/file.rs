//! The scene file as written: one serde table per item kind, every table
//! rejecting unknown keys, omitted parameters taking their defaults here.
//! Nothing is checked yet; [`super::build`] validates and builds.

use std::collections::BTreeMap;

use serde::Deserialize;

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
pub(super) struct SceneFile {
    pub(super) name: Option<String>,
    #[serde(default)]
    pub(super) description: String,
    #[serde(default)]
    pub(super) seed: u64,
    pub(super) sensor: SensorFile,
    pub(super) trajectory: TrajectoryFile,
    #[serde(default)]
    pub(super) materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    pub(super) rooms: Vec<RoomFile>,
    #[serde(default)]
    pub(super) boxes: Vec<BoxFile>,
    #[serde(default)]
    pub(super) walls: Vec<WallFile>,
    #[serde(default)]
    pub(super) polygons: Vec<PolygonFile>,
    #[serde(default)]
    pub(super) floors: Vec<RectFile>,
    #[serde(default)]
    pub(super) ceilings: Vec<RectFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct SensorFile {
    pub(super) model: String,
    #[serde(default = "default_noise")]
    pub(super) range_noise: f64,
    pub(super) max_range: Option<f64>,
    pub(super) crop_range: Option<f64>,
    #[serde(default = "default_bounces")]
    pub(super) max_bounces: u32,
    #[serde(default = "default_gain")]
    pub(super) intensity_gain: f64,
    #[serde(default = "default_threshold")]
    pub(super) detection_threshold: f64,
    pub(super) blind_sector_deg: Option<[f64; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct TrajectoryFile {
    pub(super) waypoints: Vec<[f64; 3]>,
    pub(super) speed: f64,
    #[serde(rename = "loop", default)]
    pub(super) closed: bool,
    #[serde(default = "default_smoothing")]
    pub(super) heading_smoothing: f64,
    pub(super) frames: Option<usize>,
}

/// Material parameters as written in scene files (see
/// [`crate::sim::material`] for their meaning); omitted parameters take
/// physically plausible defaults for the class.
#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub(super) enum MaterialFile {
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
pub(super) struct RoomFile {
    pub(super) min: [f64; 3],
    pub(super) max: [f64; 3],
    #[serde(default)]
    pub(super) yaw_deg: f64,
    pub(super) material: String,
    pub(super) floor: Option<String>,
    pub(super) ceiling: Option<String>,
    #[serde(default)]
    pub(super) omit: Vec<String>,
    #[serde(default)]
    pub(super) sides: BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct BoxFile {
    pub(super) min: [f64; 3],
    pub(super) max: [f64; 3],
    #[serde(default)]
    pub(super) yaw_deg: f64,
    pub(super) material: String,
    #[serde(default)]
    pub(super) omit: Vec<String>,
    #[serde(default)]
    pub(super) sides: BTreeMap<String, String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct WallFile {
    pub(super) from: [f64; 2],
    pub(super) to: [f64; 2],
    #[serde(default)]
    pub(super) base: f64,
    pub(super) height: f64,
    pub(super) material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct PolygonFile {
    pub(super) vertices: Vec<[f64; 3]>,
    pub(super) material: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RectFile {
    pub(super) min: [f64; 2],
    pub(super) max: [f64; 2],
    pub(super) z: f64,
    pub(super) material: String,
}
