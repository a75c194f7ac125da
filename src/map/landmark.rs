//! Landmarks and the map that holds them.

use nalgebra::Point3;

use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::io::{PlaneKind, PlaneRecord};
use crate::reflect::BoundedPlane;

/// A plane seen in one frame, expressed in the world frame.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneObservation {
    /// Kind of plane.
    pub kind: PlaneKind,
    /// The plane in the world frame, facing the sensor that saw it.
    pub plane: Plane,
    /// Boundary vertices (world frame, on the plane).
    pub boundary: Vec<Point3<f64>>,
    /// Index of the frame in the sequence.
    pub frame: usize,
}

/// A plane landmark of the global map (world frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Landmark {
    /// Unique id (index of creation).
    pub id: usize,
    /// Kind of plane.
    pub kind: PlaneKind,
    /// The plane, facing the sensors that observed it.
    pub plane: Plane,
    /// Boundary vertices in 3-D (world frame, on the plane), convex and
    /// ordered; the polygon in the plane's chart is [`Landmark::bounded`].
    pub boundary: Vec<Point3<f64>>,
    /// Observations fused.
    pub observations: usize,
    /// First frame that observed it.
    pub first_frame: usize,
    /// Last frame that observed it.
    pub last_frame: usize,
}

impl Landmark {
    /// A landmark created from its first observation.
    pub fn new(id: usize, obs: &PlaneObservation) -> Self {
        Self {
            id,
            kind: obs.kind,
            plane: obs.plane,
            boundary: obs.boundary.clone(),
            observations: 1,
            first_frame: obs.frame,
            last_frame: obs.frame,
        }
    }

    /// The plane with its boundary as a convex polygon in its chart.
    pub fn bounded(&self) -> BoundedPlane {
        BoundedPlane::from_points(self.plane, self.boundary.iter().copied())
    }

    /// Area of the boundary, m².
    pub fn area(&self) -> f64 {
        self.bounded().boundary.area()
    }

    /// The `planes.json` record, with frame names from `frame_names`; the
    /// boundary and panes are taken from `bounded` (this landmark as used for
    /// classification, e.g. with panes fitted).
    pub fn record(&self, bounded: &BoundedPlane, frame_names: &[String]) -> PlaneRecord {
        let b = bounded;
        let to_3d = |poly: &ConvexPolygon| -> Vec<[f64; 3]> {
            poly.vertices()
                .iter()
                .map(|q| {
                    let p = b.chart.to_3d(q);
                    [p.x, p.y, p.z]
                })
                .collect()
        };
        PlaneRecord {
            id: self.id,
            kind: self.kind,
            material: None,
            normal: self.plane.normal.into(),
            d: self.plane.d,
            hull: to_3d(&b.boundary),
            observations: self.observations,
            first_frame: frame_names.get(self.first_frame).cloned(),
            last_frame: frame_names.get(self.last_frame).cloned(),
            panes: b
                .panes
                .as_ref()
                .map(|ps| ps.iter().map(to_3d).collect())
                .unwrap_or_default(),
        }
    }
}

/// Project `points` onto `plane` and return their convex hull as 3-D points
/// (in the plane's chart order, counter-clockwise seen from the normal side).
pub fn hull_on_plane(
    plane: &Plane,
    points: impl IntoIterator<Item = Point3<f64>>,
) -> Vec<Point3<f64>> {
    let chart = PlaneChart::of(plane);
    let uv: Vec<_> = points.into_iter().map(|p| chart.to_2d(&p)).collect();
    ConvexPolygon::hull(&uv)
        .vertices()
        .iter()
        .map(|q| chart.to_3d(q))
        .collect()
}

/// The global plane map.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlaneMap {
    /// Landmarks in creation order.
    pub landmarks: Vec<Landmark>,
}

impl PlaneMap {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Landmarks observed at least `min_observations` times.
    pub fn selected(&self, min_observations: usize) -> impl Iterator<Item = &Landmark> {
        self.landmarks
            .iter()
            .filter(move |l| l.observations >= min_observations)
    }

    /// An id no landmark of the map has (ids stay unique when landmarks are
    /// pruned).
    pub fn next_id(&self) -> usize {
        self.landmarks.iter().map(|l| l.id + 1).max().unwrap_or(0)
    }

    /// Remove the landmarks that, `after` frames or more after they were
    /// first seen, have fewer than `min_observations` observations
    /// (spurious or dynamic planes); `frame` is the current frame. Returns
    /// how many were removed.
    pub fn prune(&mut self, frame: usize, after: usize, min_observations: usize) -> usize {
        let before = self.landmarks.len();
        self.landmarks.retain(|l| {
            frame.saturating_sub(l.first_frame) < after || l.observations >= min_observations
        });
        before - self.landmarks.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::PlaneKind;
    use nalgebra::Vector3;

    #[test]
    fn pruning_drops_rare_landmarks_once_old_enough_and_ids_stay_unique() {
        let obs = |frame: usize| PlaneObservation {
            kind: PlaneKind::Ordinary,
            plane: Plane::new(Vector3::x(), 1.0).unwrap(),
            boundary: vec![],
            frame,
        };
        let mut map = PlaneMap::new();
        map.landmarks.push(Landmark::new(0, &obs(0)));
        map.landmarks.push(Landmark::new(1, &obs(5)));
        map.landmarks[1].observations = 3;
        map.landmarks.push(Landmark::new(2, &obs(20)));
        assert_eq!(map.prune(29, 30, 3), 0);
        assert_eq!(map.prune(30, 30, 3), 1); // landmark 0: 30 frames, 1 observation
        assert_eq!(
            map.landmarks.iter().map(|l| l.id).collect::<Vec<_>>(),
            vec![1, 2]
        );
        assert_eq!(map.next_id(), 3);
    }
}
