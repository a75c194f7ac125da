//! The ground plane, fitted first and stored separately.
//!
//! The paper fits "a plane for all points with z-values less than 0" before
//! region growing. Two guards are ours: RANSAC samples only the
//! below-sensor cells whose normal is within `max_tilt_deg` of vertical
//! (a wall's lower half is also below the sensor; sampling the flat cells
//! makes the floor the dominant model in a few iterations), and the fitted
//! plane must itself be that close to horizontal. Inliers are then taken
//! from every below-sensor cell.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::filter::CellCloud;
use super::normals::OrganizedNormals;
use crate::geometry::fit::{fit_plane, ransac_plane, RansacParams};
use crate::geometry::Plane;
use crate::rng::SplitMix64;

/// Ground-plane settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundParams {
    /// Fit a ground plane at all: yes in every configuration (no key).
    #[serde(skip, default = "enabled")]
    pub enabled: bool,
    /// Largest angle between the ground normal (and the sampled cells'
    /// normals) and the sensor's z axis, degrees.
    pub max_tilt_deg: f64,
    /// RANSAC of the ground fit: the inlier distance (`[extractor.ground.ransac]
    /// distance`, m) is the only key, the rest [`RANSAC`]'s.
    #[serde(
        serialize_with = "crate::geometry::fit::serialize_distance",
        deserialize_with = "deserialize_ransac"
    )]
    pub ransac: RansacParams,
}

/// The ground fit's RANSAC but for the inlier distance (a key): at most 200
/// iterations, stopping once an outlier-free sample was drawn with
/// probability 0.99, and a least-squares refit.
pub const RANSAC: RansacParams = RansacParams {
    distance: 0.05,
    max_iterations: 200,
    probability: 0.99,
    refit: true,
};

fn deserialize_ransac<'de, D: serde::Deserializer<'de>>(d: D) -> Result<RansacParams, D::Error> {
    crate::geometry::fit::deserialize_distance(d, RANSAC)
}

fn enabled() -> bool {
    true
}

impl Default for GroundParams {
    /// `[extractor.ground]` of `configs/default.toml`.
    fn default() -> Self {
        crate::config::default_section("extractor.ground")
    }
}

/// The ground plane (facing up, towards the sensor) and the cells of its
/// inliers, or `None` when no near-horizontal plane is found below the
/// sensor. `min_points` is the fewest inliers accepted.
pub fn fit_ground(
    cells: &CellCloud,
    normals: &OrganizedNormals,
    params: &GroundParams,
    min_points: usize,
    rng: &mut SplitMix64,
) -> Option<(Plane, Vec<usize>)> {
    if !params.enabled {
        return None;
    }
    let cos_tilt = params.max_tilt_deg.to_radians().cos();
    let below: Vec<usize> = (0..cells.cells())
        .filter(|&c| cells.point(c).is_some() && cells.xyz(c)[2] < 0.0)
        .collect();
    let flat: Vec<Point3<f64>> = below
        .iter()
        .filter(|&&c| normals.is_valid(c) && (normals.normals[c][2] as f64).abs() >= cos_tilt)
        .map(|&c| cells.position(c))
        .collect();
    if flat.len() < min_points.max(3) {
        return None;
    }
    let fit = ransac_plane(&flat, &params.ransac, rng)?;
    let plane = fit.plane.facing(&Point3::origin());
    if plane.normal.z < cos_tilt {
        return None;
    }
    let inliers = |plane: &Plane| -> Vec<usize> {
        below
            .iter()
            .copied()
            .filter(|&c| plane.signed_distance(&cells.position(c)).abs() <= params.ransac.distance)
            .collect()
    };
    let mut members = inliers(&plane);
    // Refit on every below-sensor inlier, then reselect.
    let mut plane = plane;
    if params.ransac.refit {
        if let Some((refined, _)) = fit_plane(members.iter().map(|&c| cells.position(c))) {
            let refined = refined.facing(&Point3::origin());
            if refined.normal.z >= cos_tilt {
                plane = refined;
                members = inliers(&plane);
            }
        }
    }
    (members.len() >= min_points).then_some((plane, members))
}
