//! The scene file as written: one serde table per item kind, every table
//! rejecting unknown keys, omitted parameters taking their defaults here.
//! Nothing is checked yet; [`super::build`] validates and builds.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

/// Whether a list or map is empty (not written when serialising).
fn is_empty<T>(v: &T) -> bool
where
    for<'a> &'a T: IntoIterator,
{
    v.into_iter().next().is_none()
}

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

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFile {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) name: Option<String>,
    #[serde(default)]
    pub(crate) description: String,
    #[serde(default)]
    pub(crate) seed: u64,
    pub(crate) sensor: SensorFile,
    pub(crate) trajectory: TrajectoryFile,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) materials: BTreeMap<String, MaterialFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) rooms: Vec<RoomFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) boxes: Vec<BoxFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) walls: Vec<WallFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) polygons: Vec<PolygonFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) floors: Vec<RectFile>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) ceilings: Vec<RectFile>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SensorFile {
    pub(crate) model: String,
    #[serde(default = "default_noise")]
    pub(crate) range_noise: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) max_range: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) crop_range: Option<f64>,
    #[serde(default = "default_bounces")]
    pub(crate) max_bounces: u32,
    #[serde(default = "default_gain")]
    pub(crate) intensity_gain: f64,
    #[serde(default = "default_threshold")]
    pub(crate) detection_threshold: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) blind_sector_deg: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) dropout: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) sweep: Option<bool>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TrajectoryFile {
    pub(crate) waypoints: Vec<[f64; 3]>,
    pub(crate) speed: f64,
    #[serde(rename = "loop", default)]
    pub(crate) closed: bool,
    #[serde(default = "default_smoothing")]
    pub(crate) heading_smoothing: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) frames: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) tilt_deg: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) turn_rate_deg: Option<f64>,
}

/// Material parameters as written in scene files (see
/// [`crate::sim::material`] for their meaning); omitted parameters take
/// physically plausible defaults for the class.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(tag = "type", rename_all = "kebab-case", deny_unknown_fields)]
pub(crate) enum MaterialFile {
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

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RoomFile {
    pub(crate) min: [f64; 3],
    pub(crate) max: [f64; 3],
    #[serde(default)]
    pub(crate) yaw_deg: f64,
    pub(crate) material: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) floor: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) ceiling: Option<String>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) omit: Vec<String>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) sides: BTreeMap<String, String>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct BoxFile {
    pub(crate) min: [f64; 3],
    pub(crate) max: [f64; 3],
    #[serde(default)]
    pub(crate) yaw_deg: f64,
    pub(crate) material: String,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) omit: Vec<String>,
    #[serde(default, skip_serializing_if = "is_empty")]
    pub(crate) sides: BTreeMap<String, String>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct WallFile {
    pub(crate) from: [f64; 2],
    pub(crate) to: [f64; 2],
    #[serde(default)]
    pub(crate) base: f64,
    pub(crate) height: f64,
    pub(crate) material: String,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct PolygonFile {
    pub(crate) vertices: Vec<[f64; 3]>,
    pub(crate) material: String,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RectFile {
    pub(crate) min: [f64; 2],
    pub(crate) max: [f64; 2],
    pub(crate) z: f64,
    pub(crate) material: String,
}
