//! Intensity-peak candidates (the paper's Algorithm 1), for scans without a
//! usable second return.
//!
//! A reflective surface returns a sharp intensity peak where a beam meets it
//! at normal incidence: along the horizontal ring the intensity rises from a
//! low level to a maximum and falls again within a few degrees, and the rings
//! just above and below show the same rise and fall at that azimuth.

use serde::{Deserialize, Serialize};

use crate::cloud::Frame;
use crate::sensor::{OrganizedScan, SensorModel};

/// Thresholds of the intensity-peak search: constants of a sensor's
/// intensity scale and ring layout, the `[intensity_peak]` table of its
/// model (`configs/sensors/*.toml`). Angles are in degrees so one parameter
/// set serves sensors of different column resolution (the built-in sensors
/// carry the original HDL-32E values: 10, 15 and 20 columns of 0.16
/// degrees; intensities are on the sensor's 0-255 scale).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntensityPeakParams {
    /// Elevation of the ring searched for peaks (the ring nearest to it is
    /// used), degrees.
    pub ring_elevation_deg: f64,
    /// Minimum intensity at the peak (the sensor's intensity scale).
    pub peak_min: f32,
    /// Maximum intensity `near_deg` away from the peak on both sides.
    pub near_max: f32,
    /// Azimuth offset of the near flank test, degrees.
    pub near_deg: f64,
    /// Maximum intensity `far_deg` away from the peak on both sides.
    pub far_max: f32,
    /// Azimuth offset of the far flank test, degrees.
    pub far_deg: f64,
    /// Rings above and below that must show the same rise and fall.
    pub verify_rings: usize,
    /// Half width (azimuth) of the region marked around a verified peak,
    /// degrees.
    pub region_deg: f64,
    /// Only points within this horizontal range are marked (peaks need
    /// near-normal incidence, which happens close to the surface), m.
    pub max_range: f64,
    /// Minimum inliers for a plane fitted to peak candidates.
    pub min_inliers: usize,
}

/// Indices (ascending) of the return-1 points in verified intensity peaks.
pub fn intensity_peak_candidates(
    frame: &Frame,
    scan: &OrganizedScan,
    sensor: &SensorModel,
    params: &IntensityPeakParams,
) -> Vec<u32> {
    let rings = scan.rings();
    let cols = scan.columns() as isize;
    let step = sensor.column_step_deg();
    let to_cols = |deg: f64| ((deg / step).round() as isize).max(1);
    let (near, far, region) = (
        to_cols(params.near_deg),
        to_cols(params.far_deg),
        to_cols(params.region_deg),
    );
    let ring = sensor
        .elevations_deg
        .iter()
        .enumerate()
        .min_by(|a, b| {
            (a.1 - params.ring_elevation_deg)
                .abs()
                .total_cmp(&(b.1 - params.ring_elevation_deg).abs())
        })
        .map(|(r, _)| r)
        .unwrap_or(0);
    let v = params.verify_rings;
    if ring < v || ring + v >= rings {
        return Vec::new();
    }
    let intensity = |r: usize, c: isize| -> f32 {
        scan.first(scan.cell(r, c))
            .map(|i| frame.points[i].intensity)
            .unwrap_or(0.0)
    };
    let mut marked = Vec::new();
    let mut c: isize = 0;
    while c < cols {
        let i0 = intensity(ring, c);
        let is_peak = i0 > params.peak_min
            && (-far..=far).all(|o| intensity(ring, c + o) <= i0)
            && intensity(ring, c - near) < params.near_max
            && intensity(ring, c + near) < params.near_max
            && intensity(ring, c - far) < params.far_max
            && intensity(ring, c + far) < params.far_max;
        if !is_peak {
            c += 1;
            continue;
        }
        // Vertical check: intensity rises towards the searched ring and falls
        // away from it at the peak's azimuth.
        let below_rises = (1..=v).all(|k| intensity(ring - k, c) <= intensity(ring - k + 1, c));
        let above_falls = (1..=v).all(|k| intensity(ring + k, c) <= intensity(ring + k - 1, c));
        if below_rises && above_falls {
            for r in ring - v..=ring + v {
                for o in -region..=region {
                    if let Some(i) = scan.first(scan.cell(r, c + o)) {
                        let p = &frame.points[i];
                        let horizontal = (p.xyz[0].powi(2) + p.xyz[1].powi(2)).sqrt() as f64;
                        if horizontal < params.max_range {
                            marked.push(i as u32);
                        }
                    }
                }
            }
        }
        c += far; // skip past this peak
    }
    marked.sort_unstable();
    marked.dedup();
    marked
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Point;

    /// A wall 2 m ahead (along +x) with an intensity peak at azimuth 0.
    fn wall_with_peak(sensor: &SensorModel, peak: bool) -> Frame {
        let mut points = Vec::new();
        for ring in 20..44usize {
            for col in 240..360usize {
                let dir = sensor.beam_direction(ring, col);
                if dir.x <= 0.2 {
                    continue;
                }
                let p = dir * (2.0 / dir.x);
                let dist_deg = (sensor.column_azimuth_deg(col) - 0.0).abs()
                    + (sensor.elevations_deg[ring] - 0.42).abs();
                let intensity = if peak {
                    (200.0 - 100.0 * dist_deg).max(10.0)
                } else {
                    10.0
                };
                points.push(Point {
                    xyz: [p.x as f32, p.y as f32, p.z as f32],
                    intensity: intensity as f32,
                    ring: ring as u16,
                    ret: 1,
                    label: 2,
                    time: 0.0,
                });
            }
        }
        Frame {
            name: "peak".into(),
            points,
            ..Default::default()
        }
    }

    #[test]
    fn finds_a_peak_and_only_near_it() {
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = wall_with_peak(&sensor, true);
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let params = sensor
            .intensity_peak
            .expect("the QT64 has intensity-peak thresholds");
        let found = intensity_peak_candidates(&frame, &scan, &sensor, &params);
        assert!(found.len() >= 5, "found {}", found.len());
        for &i in &found {
            let p = frame.points[i as usize].xyz;
            assert!(p[1].abs() < 0.3, "marked point far from the peak: {p:?}");
        }
        let flat = wall_with_peak(&sensor, false);
        let scan = OrganizedScan::build(&flat, &sensor).unwrap();
        assert!(intensity_peak_candidates(&flat, &scan, &sensor, &params).is_empty());
    }
}
