//! The non-repetitive rosette of a Risley-prism LiDAR (Livox Avia), and the
//! spherical grid of beam directions that stands in for its missing rings.
//!
//! The beam direction at time `t` is the sum of two counter-rotating
//! phasors, `p(t) = ½ (e^{i ω₁ t} + e^{−i ω₂ t})`, a point of the unit disc
//! that sweeps petals through the centre; its real part scaled to half the
//! horizontal field is the azimuth, its imaginary part scaled to half the
//! vertical field the elevation. With incommensurate `ω₁`, `ω₂` the
//! pattern never repeats: each frame covers the field anew and the
//! coverage grows with integration time, as the Avia's does. This is a
//! model of the pattern, not the vendor's exact prism geometry (which is
//! not published).
//!
//! The points of such a sensor have no ring: the [`SensorModel`] gives it a
//! grid of `grid_deg` cells in azimuth (over the full circle, so the
//! column arithmetic of spinning sensors applies unchanged) and in
//! elevation (rows over the vertical field, row 0 at the bottom). A point
//! falls into the cell of its direction ([`SensorModel::ring_of`],
//! [`SensorModel::column_of`]); the returns of one emission share a
//! direction and so a cell, and the organized scan pairs them by emission
//! ([`OrganizedScan`](super::OrganizedScan)).

use serde::{Deserialize, Serialize};

use super::SensorModel;

/// Parameters of a rosette pattern (the `[rosette]` table of a sensor file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rosette {
    /// Horizontal field of view, degrees (centred on the x axis).
    pub fov_h_deg: f64,
    /// Vertical field of view, degrees (centred on the horizon).
    pub fov_v_deg: f64,
    /// Emissions (laser pulses) per second; each gives up to the return
    /// mode's number of returns.
    pub pulses_per_second: f64,
    /// Rotation frequency of the first phasor, Hz.
    pub freq1_hz: f64,
    /// Rotation frequency of the second (counter-rotating) phasor, Hz.
    pub freq2_hz: f64,
    /// Cell size of the spherical grid of beam directions, degrees.
    pub grid_deg: f64,
}

impl Rosette {
    /// Check the parameters; the message names the bad key.
    pub fn validate(&self) -> Result<(), String> {
        let positive = [
            ("fov_h_deg", self.fov_h_deg),
            ("fov_v_deg", self.fov_v_deg),
            ("pulses_per_second", self.pulses_per_second),
            ("freq1_hz", self.freq1_hz),
            ("freq2_hz", self.freq2_hz),
            ("grid_deg", self.grid_deg),
        ];
        for (key, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                return Err(format!("rosette.{key} must be positive, got {v}"));
            }
        }
        if self.fov_h_deg >= 180.0 || self.fov_v_deg >= 180.0 {
            return Err("rosette fields of view must be below 180 degrees".into());
        }
        if self.grid_deg > 10.0 {
            return Err(format!(
                "rosette.grid_deg must be at most 10, got {}",
                self.grid_deg
            ));
        }
        Ok(())
    }

    /// Rows of the grid: cells of `grid_deg` over the vertical field.
    pub fn grid_rows(&self) -> usize {
        (self.fov_v_deg / self.grid_deg).ceil().max(1.0) as usize
    }

    /// Columns of the grid over the full circle.
    pub fn grid_columns(&self) -> usize {
        (360.0 / self.grid_deg).round().max(4.0) as usize
    }

    /// Elevations of the grid rows' centres, degrees, bottom first.
    pub fn grid_elevations_deg(&self) -> Vec<f64> {
        let rows = self.grid_rows();
        let step = self.fov_v_deg / rows as f64;
        (0..rows)
            .map(|r| -0.5 * self.fov_v_deg + (r as f64 + 0.5) * step)
            .collect()
    }

    /// (azimuth, elevation) in degrees of the beam at time `t` seconds.
    #[inline]
    pub fn angles_deg(&self, t: f64) -> (f64, f64) {
        let (a1, a2) = (
            std::f64::consts::TAU * self.freq1_hz * t,
            std::f64::consts::TAU * self.freq2_hz * t,
        );
        let re = 0.5 * (a1.cos() + a2.cos());
        let im = 0.5 * (a1.sin() - a2.sin());
        (0.5 * self.fov_h_deg * re, 0.5 * self.fov_v_deg * im)
    }
}

/// A limited field of view about the sensor's x axis: half angles in
/// azimuth and elevation, degrees (a rosette sensor's; a spinning sensor
/// sees all round).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldOfView {
    /// Half the horizontal field, degrees.
    pub half_h_deg: f64,
    /// Half the vertical field, degrees.
    pub half_v_deg: f64,
}

impl FieldOfView {
    /// Whether the direction of a sensor-frame point lies in the field.
    #[inline]
    pub fn contains(&self, p: &nalgebra::Point3<f64>) -> bool {
        let az = p.y.atan2(p.x).to_degrees();
        let el = p.z.atan2(p.x.hypot(p.y)).to_degrees();
        az.abs() <= self.half_h_deg && el.abs() <= self.half_v_deg
    }
}

/// Unit direction (sensor frame) of an (azimuth, elevation) in degrees.
#[inline]
pub fn direction(azimuth_deg: f64, elevation_deg: f64) -> [f64; 3] {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    [el.cos() * az.cos(), el.cos() * az.sin(), el.sin()]
}

/// Fill a rosette model's grid (its `elevations_deg` and `columns`).
pub(super) fn fill_grid(model: &mut SensorModel) {
    if let Some(r) = &model.rosette {
        model.elevations_deg = r.grid_elevations_deg();
        model.columns = r.grid_columns();
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;
    use proptest::prelude::*;

    use super::*;

    fn avia() -> SensorModel {
        SensorModel::resolve("livox-avia").unwrap()
    }

    #[test]
    fn the_pattern_stays_in_the_field_and_covers_it() {
        let m = avia();
        let r = m.rosette.as_ref().unwrap();
        let n = (r.pulses_per_second / m.rate_hz) as usize;
        let mut cells = std::collections::HashSet::new();
        for i in 0..n {
            let (az, el) = r.angles_deg(i as f64 / r.pulses_per_second);
            assert!(az.abs() <= 0.5 * r.fov_h_deg + 1e-9);
            assert!(el.abs() <= 0.5 * r.fov_v_deg + 1e-9);
            let d = direction(az, el);
            let p = Point3::new(d[0], d[1], d[2]);
            let ring = m.ring_of(&p).unwrap();
            cells.insert((ring, m.column_of(d[0], d[1])));
        }
        // One frame's pulses reach a good share of the field's cells.
        let field = (r.fov_h_deg / r.grid_deg) * (r.fov_v_deg / r.grid_deg);
        let share = cells.len() as f64 / field;
        assert!(share > 0.4, "{share}");
    }

    proptest! {
        /// A direction in the field falls in the grid cell whose centre is
        /// within half a cell of it in azimuth and elevation, and a cell's
        /// centre direction falls in that cell (the binning round trip).
        #[test]
        fn direction_and_grid_cell_round_trip(
            u in -1.0f64..1.0, v in -1.0f64..1.0, range in 0.5f64..60.0,
        ) {
            let m = avia();
            let r = m.rosette.clone().unwrap();
            let (az, el) = (0.5 * r.fov_h_deg * u, 0.5 * r.fov_v_deg * v);
            let d = direction(az, el);
            let p = Point3::new(d[0] * range, d[1] * range, d[2] * range);
            let ring = m.ring_of(&p).unwrap();
            let col = m.column_of(p.x, p.y);
            let half = 0.5 * r.grid_deg + 1e-6;
            prop_assert!((m.elevations_deg[ring] - el).abs() <= half);
            let daz = (m.column_azimuth_deg(col) - az + 540.0).rem_euclid(360.0) - 180.0;
            prop_assert!(daz.abs() <= half + 0.05);
            let c = m.beam_direction(ring, col) * range;
            prop_assert_eq!(m.ring_of(&Point3::from(c)), Some(ring));
            prop_assert_eq!(m.column_of(c.x, c.y), col);
        }
    }
}
