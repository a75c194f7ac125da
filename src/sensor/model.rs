//! LiDAR sensor descriptions: spinning sensors with rings, and rosette
//! scanners whose points are binned into a spherical grid of directions.

use std::path::Path;

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use super::rosette::Rosette;
pub use crate::cloud::IntensityScale;
use crate::{Error, Result};

/// Which two returns a dual-return sensor reports per beam.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReturnMode {
    /// First and last return (Hesai QT64).
    FirstLast,
    /// Strongest and last return (Velodyne HDL-32E).
    StrongestLast,
    /// The strongest and the second-strongest return, in that order
    /// (Ouster OS0-128, default `return_order` STRONGEST_TO_WEAKEST): the
    /// order is by echo strength, not range, so return 2 may lie in front
    /// of return 1.
    StrongestSecond,
    /// Up to three returns per pulse (Livox Avia triple mode): the three
    /// strongest echoes, numbered 1, 2, 3 by range, nearest first (which
    /// echoes the Avia keeps is not documented; this is the assumption).
    Triple,
    /// A single return per beam (no dual-return information).
    Single,
}

/// How a sensor's beams sweep its field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ScanPattern {
    /// A spinning head: rings at fixed elevations, columns of equal
    /// azimuth steps (Hesai, Velodyne, Ouster).
    #[default]
    Rings,
    /// A non-repetitive rosette over a limited field (Livox Avia), no
    /// rings: the `[rosette]` table gives it, and its points are binned
    /// into a spherical grid of directions that plays the rings' part.
    Rosette,
}

/// A LiDAR: ring elevations (ring 0 at the bottom), columns per
/// revolution, range limits and return mode. For a [`ScanPattern::Rosette`]
/// sensor the rings and columns are its grid of directions, derived from
/// the `[rosette]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorModel {
    /// Identifier, e.g. `pandar_qt64`.
    pub name: String,
    /// Human-readable description.
    #[serde(default)]
    pub description: String,
    /// How the beams sweep the field (default: rings).
    #[serde(default)]
    pub pattern: ScanPattern,
    /// Columns (azimuth steps) per revolution (derived for a rosette).
    #[serde(default)]
    pub columns: usize,
    /// Column counts the sensor can be run with (`name:COLUMNS` picks
    /// one); empty: only `columns`.
    #[serde(default)]
    pub column_modes: Vec<usize>,
    /// Revolutions per second.
    pub rate_hz: f64,
    /// Minimum range, metres.
    pub min_range: f64,
    /// Maximum range, metres.
    pub max_range: f64,
    /// Return mode.
    pub return_mode: ReturnMode,
    /// Two echoes closer than this along a beam cannot be separated, metres.
    pub range_resolution: f64,
    /// Elevation of each ring in degrees, ring 0 (bottom) first (derived
    /// for a rosette: its grid rows).
    #[serde(default)]
    pub elevations_deg: Vec<f64>,
    /// What the intensities it reports measure (default: a reflectivity).
    /// Frames that say otherwise (a PLY comment, the simulator) win.
    #[serde(default)]
    pub intensity: IntensityScale,
    /// Thresholds of the intensity-peak candidate search (the detector's
    /// `intensity-peak` sources), on this sensor's intensity scale and ring
    /// layout; a sensor without them gives no intensity-peak candidates.
    #[serde(default)]
    pub intensity_peak: Option<crate::reflect::IntensityPeakParams>,
    /// The rosette of a [`ScanPattern::Rosette`] sensor.
    #[serde(default)]
    pub rosette: Option<Rosette>,
    /// What the simulator writes as this sensor's intensity: the echo's
    /// received power (default, as for the QT64 so far) or a
    /// range-compensated reflectivity (Livox: 0-150 diffuse).
    #[serde(default = "raw_power")]
    pub simulated_intensity: IntensityScale,
}

fn raw_power() -> IntensityScale {
    IntensityScale::RawPower
}

/// Built-in sensor descriptions, embedded so a fresh clone needs no files.
const BUILTIN: &[(&str, &str)] = &[
    (
        "pandar_qt64",
        include_str!("../../configs/sensors/pandar_qt64.toml"),
    ),
    (
        "velodyne_hdl32e",
        include_str!("../../configs/sensors/velodyne_hdl32e.toml"),
    ),
    (
        "ouster_os0_128",
        include_str!("../../configs/sensors/ouster_os0_128.toml"),
    ),
    (
        "livox_avia",
        include_str!("../../configs/sensors/livox_avia.toml"),
    ),
];

impl SensorModel {
    /// Names of the built-in sensors.
    pub fn builtin_names() -> Vec<&'static str> {
        BUILTIN.iter().map(|(n, _)| *n).collect()
    }

    /// Whether `name` names a built-in sensor, in any of the forms
    /// [`resolve`](Self::resolve) takes (`ouster-os0-128`,
    /// `ouster_os0_128:2048`).
    pub fn is_builtin(name: &str) -> bool {
        let base = match name.rsplit_once(':') {
            Some((b, c)) if c.parse::<usize>().is_ok() => b,
            _ => name,
        };
        let snake = base.replace('-', "_");
        BUILTIN.iter().any(|(n, _)| *n == snake)
    }

    /// A built-in sensor by name (`ouster_os0_128` or `ouster-os0-128`,
    /// optionally `:COLUMNS` for one of its `column_modes`), or a sensor
    /// TOML file by path.
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        let (base, columns) = match name_or_path.rsplit_once(':') {
            Some((b, c)) if c.parse::<usize>().is_ok() => (b, c.parse::<usize>().ok()),
            _ => (name_or_path, None),
        };
        let snake = base.replace('-', "_");
        if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == snake) {
            let model = Self::from_toml(text, Path::new(&snake))?;
            return match columns {
                Some(c) if c != model.columns => model.with_columns(c),
                _ => Ok(model),
            };
        }
        let path = Path::new(name_or_path);
        if path.exists() {
            let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
            return Self::from_toml(&text, path);
        }
        Err(Error::Config(format!(
            "unknown sensor '{name_or_path}': not a built-in ({}) nor a file",
            Self::builtin_names().join(", ")
        )))
    }

    /// Parse and validate a sensor description (`origin` names it in errors).
    pub fn from_toml(text: &str, origin: &Path) -> Result<Self> {
        let mut model: Self =
            toml::from_str(text).map_err(|e| Error::format(origin, e.to_string()))?;
        model.check_pattern(origin)?;
        super::rosette::fill_grid(&mut model);
        model.validate(origin)?;
        Ok(model)
    }

    /// The same sensor run with `columns` columns, one of its
    /// `column_modes` (e.g. the OS0-128's 512, 1024 or 2048).
    pub fn with_columns(mut self, columns: usize) -> Result<Self> {
        if columns != self.columns && !self.column_modes.contains(&columns) {
            return Err(Error::Config(format!(
                "sensor '{}' has no mode with {columns} columns (modes: {:?})",
                self.name, self.column_modes
            )));
        }
        self.columns = columns;
        // The name says the mode, so that it resolves to this model again.
        self.name = format!("{}:{columns}", self.name);
        Ok(self)
    }

    /// A rosette sensor has its `[rosette]` table and no rings of its own;
    /// a ring sensor has no `[rosette]` table.
    fn check_pattern(&self, origin: &Path) -> Result<()> {
        let bad = |m: String| Err(Error::format(origin, m));
        match (self.pattern, &self.rosette) {
            (ScanPattern::Rings, None) => Ok(()),
            (ScanPattern::Rings, Some(_)) => {
                bad("a [rosette] table needs pattern = \"rosette\"".into())
            }
            (ScanPattern::Rosette, None) => {
                bad("pattern = \"rosette\" needs a [rosette] table".into())
            }
            (ScanPattern::Rosette, Some(r)) => {
                if !self.elevations_deg.is_empty() || self.columns != 0 {
                    return bad(
                        "a rosette sensor has no elevations_deg or columns: its grid comes from [rosette] grid_deg".into(),
                    );
                }
                r.validate().or_else(bad)
            }
        }
    }

    /// Whether the sensor scans a rosette (its rings are a grid of
    /// directions, its returns paired by emission).
    pub fn is_rosette(&self) -> bool {
        self.pattern == ScanPattern::Rosette
    }

    /// The field of view of a rosette sensor; `None` for a spinning one
    /// (it sees all round).
    pub fn field_of_view(&self) -> Option<super::rosette::FieldOfView> {
        let r = self.rosette.as_ref().filter(|_| self.is_rosette())?;
        Some(super::rosette::FieldOfView {
            half_h_deg: 0.5 * r.fov_h_deg,
            half_v_deg: 0.5 * r.fov_v_deg,
        })
    }

    /// Returns per beam or pulse at most (1 to 3).
    pub fn max_returns(&self) -> u8 {
        match self.return_mode {
            ReturnMode::Single => 1,
            ReturnMode::Triple => 3,
            _ => 2,
        }
    }

    fn validate(&self, origin: &Path) -> Result<()> {
        let bad = |m: String| Err(Error::format(origin, m));
        if self.elevations_deg.is_empty() || self.elevations_deg.len() > u16::MAX as usize {
            return bad("elevations_deg must list 1..65535 rings".into());
        }
        if self.elevations_deg.windows(2).any(|w| !(w[1] > w[0])) {
            return bad("elevations_deg must increase from ring 0 (bottom) upwards".into());
        }
        if self.columns < 4 {
            return bad(format!("columns must be at least 4, got {}", self.columns));
        }
        if !(self.min_range >= 0.0 && self.max_range > self.min_range) {
            return bad("need 0 <= min_range < max_range".into());
        }
        if !(self.rate_hz > 0.0) || !(self.range_resolution >= 0.0) {
            return bad("rate_hz must be positive and range_resolution non-negative".into());
        }
        if let Some(c) = self.column_modes.iter().find(|&&c| c < 4) {
            return bad(format!("column_modes must be at least 4, got {c}"));
        }
        Ok(())
    }

    /// Number of rings.
    pub fn rings(&self) -> usize {
        self.elevations_deg.len()
    }

    /// Azimuth step per column, degrees.
    pub fn column_step_deg(&self) -> f64 {
        360.0 / self.columns as f64
    }

    /// Column of a sensor-frame direction: `round((180 + atan2(y, x)) / step)`
    /// wrapped to `0..columns` (the seam is one column, never two).
    #[inline]
    pub fn column_of(&self, x: f64, y: f64) -> usize {
        let deg = 180.0 + crate::geometry::fastmath::fast_atan2(y, x).to_degrees();
        let c = crate::geometry::fastmath::round_i64(deg / self.column_step_deg());
        let n = self.columns as i64;
        // `deg` lies in [0, 360], so `c` in [0, n] but for rounding: wrap
        // without an integer division where it can.
        match c {
            c if (0..n).contains(&c) => c as usize,
            c if c == n => 0,
            c => c.rem_euclid(n) as usize,
        }
    }

    /// Azimuth (degrees, atan2 convention) of the centre of a column.
    pub fn column_azimuth_deg(&self, column: usize) -> f64 {
        column as f64 * self.column_step_deg() - 180.0
    }

    /// The ring whose elevation is nearest to the direction of `p`, or `None`
    /// when `p` lies outside the vertical field of view by more than half a
    /// ring spacing.
    pub fn ring_of(&self, p: &Point3<f64>) -> Option<usize> {
        let horizontal = (p.x * p.x + p.y * p.y).sqrt();
        let elev = p.z.atan2(horizontal).to_degrees();
        let e = &self.elevations_deg;
        let i = e.partition_point(|&x| x < elev);
        let candidates = [i.checked_sub(1), (i < e.len()).then_some(i)];
        let best = candidates
            .into_iter()
            .flatten()
            .min_by(|&a, &b| (e[a] - elev).abs().total_cmp(&(e[b] - elev).abs()))?;
        let spacing = if e.len() > 1 {
            let lo = best.saturating_sub(1);
            let hi = (best + 1).min(e.len() - 1);
            (e[hi] - e[lo]) / (hi - lo) as f64
        } else {
            1.0
        };
        ((e[best] - elev).abs() <= 0.5 * spacing.abs()).then_some(best)
    }

    /// Unit beam direction of a (ring, column) cell in the sensor frame.
    pub fn beam_direction(&self, ring: usize, column: usize) -> Vector3<f64> {
        let el = self.elevations_deg[ring].to_radians();
        let az = self.column_azimuth_deg(column).to_radians();
        Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse_and_have_the_documented_shape() {
        let qt = SensorModel::resolve("pandar_qt64").unwrap();
        assert_eq!(qt.rings(), 64);
        assert_eq!(qt.columns, 600);
        assert!((qt.elevations_deg[0] + 52.79).abs() < 1e-9);
        let hdl = SensorModel::resolve("velodyne_hdl32e").unwrap();
        assert_eq!(hdl.rings(), 32);
        assert_eq!(hdl.return_mode, ReturnMode::StrongestLast);
        assert_eq!(hdl.intensity, IntensityScale::Reflectivity);
        assert_eq!(
            SensorModel::resolve("pandar_qt64").unwrap().intensity,
            IntensityScale::Reflectivity
        );
    }

    #[test]
    fn seam_is_one_column() {
        let qt = SensorModel::resolve("pandar_qt64").unwrap();
        // atan2 = +180 and -180 deg are the same physical column.
        assert_eq!(qt.column_of(-1.0, 1e-12), qt.column_of(-1.0, -1e-12));
        assert_eq!(qt.column_of(-1.0, 0.0), 0);
        assert!((0..3600).all(|k| {
            let a = (k as f64 * 0.1).to_radians();
            qt.column_of(a.cos(), a.sin()) < 600
        }));
    }

    #[test]
    fn ring_lookup_inverts_beam_direction() {
        let qt = SensorModel::resolve("pandar_qt64").unwrap();
        for ring in 0..qt.rings() {
            for col in [0, 1, 299, 599] {
                let d = qt.beam_direction(ring, col) * 7.0;
                assert_eq!(qt.ring_of(&Point3::from(d)), Some(ring));
                assert_eq!(qt.column_of(d.x, d.y), col);
            }
        }
        assert_eq!(qt.ring_of(&Point3::new(0.0, 0.0, 5.0)), None);
    }

    #[test]
    fn ouster_and_livox_have_their_documented_shape() {
        let os = SensorModel::resolve("ouster-os0-128").unwrap();
        assert_eq!(os.name, "ouster_os0_128");
        assert_eq!((os.rings(), os.columns), (128, 1024));
        assert_eq!(os.return_mode, ReturnMode::StrongestSecond);
        assert_eq!(os.intensity, IntensityScale::RawPower);
        let span = os.elevations_deg[127] - os.elevations_deg[0];
        assert!((span - 90.46).abs() < 1e-9, "{span}");
        assert_eq!(
            SensorModel::resolve("ouster_os0_128:2048").unwrap().columns,
            2048
        );
        let e = SensorModel::resolve("ouster-os0-128:1000")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no mode with 1000 columns"), "{e}");
        let avia = SensorModel::resolve("livox-avia").unwrap();
        assert!(avia.is_rosette() && !os.is_rosette());
        assert_eq!(avia.max_returns(), 3);
        let r = avia.rosette.as_ref().unwrap();
        assert_eq!(avia.rings(), r.grid_rows());
        assert_eq!(avia.columns, r.grid_columns());
        assert_eq!(avia.simulated_intensity, IntensityScale::Reflectivity);
    }

    #[test]
    fn a_rosette_without_its_table_is_a_clear_error() {
        let text = "name = \"x\"\nrate_hz = 10.0\nmin_range = 0.1\nmax_range = 9.0\nreturn_mode = \"triple\"\nrange_resolution = 0.1\npattern = \"rosette\"\n";
        let e = SensorModel::from_toml(text, Path::new("x.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("x.toml") && e.contains("[rosette]"), "{e}");
    }

    #[test]
    fn unknown_sensor_is_a_clear_error() {
        let e = SensorModel::resolve("nope").unwrap_err().to_string();
        assert!(e.contains("unknown sensor 'nope'"), "{e}");
    }
}
