//! The space seen directly, queried from one sensor pose: sensor-frame
//! points in, the world map's answers out.

use nalgebra::{Matrix3, Point3, Vector3};

use super::{Occupancy, SpaceMap};

/// A point within this height of a floor or ceiling seen directly lies on
/// it, for its echo's incidence, m (the level-surface test's default
/// tolerance; 3DRef gives a surface 0.15 m).
pub const HORIZONTAL_TOLERANCE: f64 = 0.1;

/// [`SpaceMap`] seen from one sensor pose: queries take sensor-frame points.
pub struct SensorFrameSpace<'a> {
    pub(super) map: &'a SpaceMap,
    pub(super) rotation: Matrix3<f64>,
    pub(super) translation: Vector3<f64>,
}

impl SensorFrameSpace<'_> {
    #[inline]
    fn world(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.rotation * p.coords + self.translation)
    }

    /// [`SpaceMap::occupancy`] of a sensor-frame point.
    pub fn occupancy(&self, p: &Point3<f64>) -> Occupancy {
        self.map.occupancy(&self.world(p))
    }

    /// [`SpaceMap::occupancy_clear_of`] of a sensor-frame point.
    pub fn occupancy_clear_of(&self, p: &Point3<f64>, clearance: f64) -> Occupancy {
        self.map.occupancy_clear_of(&self.world(p), clearance)
    }

    /// Whether a surface was seen through glass ([`SpaceMap::through`]) in
    /// the voxel of a sensor-frame point; `None` where the map keeps none.
    pub fn through_surface_at(&self, p: &Point3<f64>) -> Option<bool> {
        Some(self.map.through()?.surface_at(&self.world(p)))
    }

    /// [`SpaceMap::occupancy_clear_of`] of a sensor-frame point in the
    /// space seen through glass ([`SpaceMap::through`]); `None` where the
    /// map keeps none.
    pub fn through_occupancy_clear_of(&self, p: &Point3<f64>, clearance: f64) -> Option<Occupancy> {
        let through = self.map.through()?;
        Some(through.occupancy_clear_of(&self.world(p), clearance))
    }

    /// The index of the floor or ceiling seen directly
    /// ([`Levels`](crate::classify::levels::Levels)) within `tolerance` of a
    /// sensor-frame point's height, if any.
    pub fn level_of(&self, p: &Point3<f64>, tolerance: f64) -> Option<usize> {
        self.map.levels.index_near(self.world(p).z, tolerance)
    }

    /// The cosine of the incidence at which the beam to a sensor-frame
    /// point met the floor or ceiling seen directly at its height
    /// ([`HORIZONTAL_TOLERANCE`]); `None` at no level's height. A floor far
    /// off is met at grazing incidence, its next ring metres away, so its
    /// neighbours in the scan span no surface; the level says it is
    /// horizontal.
    pub fn level_incidence_cos(&self, p: &Point3<f64>) -> Option<f64> {
        let range = p.coords.norm();
        (range > 0.0 && self.level_of(p, HORIZONTAL_TOLERANCE).is_some())
            .then(|| (self.rotation * p.coords).z.abs() / range)
    }

    /// The world height of a sensor-frame point, m.
    pub fn height(&self, p: &Point3<f64>) -> f64 {
        self.world(p).z
    }

    /// [`SpaceMap::blocked`] for a sensor-frame segment.
    pub fn blocked(&self, a: &Point3<f64>, b: &Point3<f64>, margin: f64) -> bool {
        self.map.blocked(&self.world(a), &self.world(b), margin)
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;

    /// A point at the height of the floor seen directly is met at the
    /// incidence of a horizontal surface whatever the sensor's attitude; a
    /// point at no level's height has none.
    #[test]
    fn a_point_on_a_level_is_met_as_on_a_horizontal_surface() {
        let mut map = SpaceMap::new(0.1, 2, 1);
        let origin = Point3::new(0.0, 0.0, 1.0);
        for i in 1..=40 {
            for j in -20..=20 {
                let end = Point3::new(i as f64 * 0.2, j as f64 * 0.2, 0.0);
                map.add_beam(&origin, &end, 0.2, true);
            }
        }
        assert_eq!(
            map.levels().heights().len(),
            1,
            "{:?}",
            map.levels().heights()
        );
        // A sensor 1 m up, yawed and rolled.
        let pose = Isometry3::new(Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.2, 0.0, 0.7));
        let space = map.in_sensor_frame(pose);
        let to_sensor = |w: Point3<f64>| pose.inverse() * w;
        let on_floor = to_sensor(Point3::new(6.0, 2.0, 0.05));
        // The beam falls 0.95 m over its range.
        let expected = 0.95 / on_floor.coords.norm();
        let cos = space.level_incidence_cos(&on_floor).expect("on the floor");
        assert!((cos - expected).abs() < 1e-9, "{cos} vs {expected}");
        assert_eq!(
            space.level_incidence_cos(&to_sensor(Point3::new(6.0, 2.0, 0.6))),
            None
        );
    }
}
