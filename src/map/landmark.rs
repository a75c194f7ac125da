//! Landmarks and the map that holds them.

use nalgebra::{Isometry3, Point3};

use crate::geometry::{ConvexPolygon, Plane, PlaneChart};
use crate::io::{PlaneKind, PlaneRecord};
use crate::reflect::BoundedPlane;
use crate::sensor::{FieldOfView, SensorModel};

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

impl PlaneObservation {
    /// The observation in the frame `t` maps the world into.
    pub fn transformed(&self, t: &Isometry3<f64>) -> Self {
        Self {
            kind: self.kind,
            plane: self.plane.transformed(t),
            boundary: self.boundary.iter().map(|q| t * q).collect(),
            frame: self.frame,
        }
    }
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

    /// Move the landmark into the frame `t` maps its frame into.
    pub fn transform(&mut self, t: &Isometry3<f64>) {
        self.plane = self.plane.transformed(t);
        for q in &mut self.boundary {
            *q = t * *q;
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

    /// Frames of `poses` (`T_world_sensor`) that had this landmark in view:
    /// the sensor on its front side and within `range` metres of its
    /// boundary. Occlusion is not modelled, so this is an upper bound.
    pub fn frames_in_view(&self, poses: &[Isometry3<f64>], range: f64) -> usize {
        self.frames_in_field(poses, range, None)
    }

    /// [`frames_in_view`](Self::frames_in_view) for a sensor with a
    /// limited `field` of view (a Livox): the landmark must also lie in
    /// the field, i.e. one of its boundary's vertices or edge midpoints,
    /// or the point where the sensor's axis meets it.
    pub fn frames_in_field(
        &self,
        poses: &[Isometry3<f64>],
        range: f64,
        field: Option<FieldOfView>,
    ) -> usize {
        let bounded = self.bounded();
        poses
            .iter()
            .filter(|pose| {
                let o = Point3::from(pose.translation.vector);
                let s = self.plane.signed_distance(&o);
                if !(s > 0.0) || s > range {
                    return false;
                }
                let across = bounded.boundary.signed_distance(&bounded.chart.to_2d(&o));
                if s * s + across.max(0.0).powi(2) > range * range {
                    return false;
                }
                field.is_none_or(|f| self.in_field(pose, &bounded, &f))
            })
            .count()
    }

    /// Whether the landmark lies in the field `f` of a sensor at `pose`.
    fn in_field(&self, pose: &Isometry3<f64>, bounded: &BoundedPlane, f: &FieldOfView) -> bool {
        let inv = pose.inverse();
        let n = self.boundary.len();
        let on_edges = (0..n).any(|i| {
            let (a, b) = (self.boundary[i], self.boundary[(i + 1) % n]);
            f.contains(&(inv * a)) || f.contains(&(inv * Point3::from((a.coords + b.coords) * 0.5)))
        });
        if on_edges {
            return true;
        }
        // The sensor's axis through the plane, inside the boundary.
        let axis = pose.rotation * nalgebra::Vector3::x();
        let o = Point3::from(pose.translation.vector);
        let denom = self.plane.normal.dot(&axis);
        if denom.abs() < 1e-9 {
            return false;
        }
        let t = -self.plane.signed_distance(&o) / denom;
        t > 0.0
            && bounded
                .boundary
                .signed_distance(&bounded.chart.to_2d(&(o + axis * t)))
                <= 0.0
    }

    /// Share of the frames that had the landmark in view
    /// ([`Landmark::frames_in_view`]) in which it was detected: a surface
    /// that is really there is found in a good share of the frames that
    /// see it, a plane fitted to a chance alignment of points (a reflection,
    /// points behind glass) only now and then. ORB-SLAM culls map points by
    /// the same found-over-visible ratio.
    pub fn found_ratio(
        &self,
        poses: &[Isometry3<f64>],
        range: f64,
        field: Option<FieldOfView>,
    ) -> f64 {
        let in_view = self
            .frames_in_field(poses, range, field)
            .max(self.observations);
        if in_view == 0 {
            return 0.0;
        }
        self.observations as f64 / in_view as f64
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
            mirror_probability: b.mirror_probability,
            reflection_share: b.reflection_share,
            decided_share: b.decided_share,
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

/// Which landmarks of a fused map are trusted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LandmarkSelection {
    /// Fewest observations.
    pub min_observations: usize,
    /// Smallest found-over-in-view ratio ([`Landmark::found_ratio`]); 0
    /// disables the test.
    pub min_found_ratio: f64,
    /// A landmark is in view within this distance of its boundary, m.
    pub visibility_range: f64,
    /// The sensor's field of view when it is limited (a Livox;
    /// [`LandmarkSelection::for_sensor`]): a landmark outside it is not in
    /// view. `None`: all round.
    pub field: Option<FieldOfView>,
}

impl LandmarkSelection {
    /// The selection for frames of `sensor`, whose field of view decides
    /// which frames had a landmark in view.
    pub fn for_sensor(mut self, sensor: &SensorModel) -> Self {
        self.field = sensor.field_of_view();
        self
    }
}

impl std::fmt::Display for LandmarkSelection {
    /// "observed at least N times[, found in at least P% of the frames in view]".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "observed at least {} times", self.min_observations)?;
        if self.min_found_ratio > 0.0 {
            write!(
                f,
                ", found in at least {}% of the frames in view",
                self.min_found_ratio * 100.0
            )?;
        }
        Ok(())
    }
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

    /// Indices of the landmarks that pass `selection` for a sequence with
    /// `poses`: observed often enough, and found in a large enough share of
    /// the frames that had them in view.
    pub fn reliable(&self, poses: &[Isometry3<f64>], selection: &LandmarkSelection) -> Vec<usize> {
        self.landmarks
            .iter()
            .enumerate()
            .filter(|(_, l)| l.observations >= selection.min_observations)
            .filter(|(_, l)| {
                selection.min_found_ratio <= 0.0
                    || l.found_ratio(poses, selection.visibility_range, selection.field)
                        >= selection.min_found_ratio
            })
            .map(|(i, _)| i)
            .collect()
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

    /// A landmark detected in 3 of the 100 frames that had it in view is a
    /// chance fit (found ratio 0.03); frames behind it or far away do not
    /// count as having it in view.
    #[test]
    fn landmarks_found_in_too_few_of_the_frames_that_see_them_are_not_used() {
        use nalgebra::{Isometry3, Translation3, UnitQuaternion};
        let plane = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
        let obs = PlaneObservation {
            kind: PlaneKind::Reflective,
            plane,
            boundary: vec![
                Point3::new(5.0, -1.0, 0.0),
                Point3::new(5.0, 1.0, 0.0),
                Point3::new(5.0, 1.0, 2.0),
                Point3::new(5.0, -1.0, 2.0),
            ],
            frame: 0,
        };
        let mut map = PlaneMap::new();
        map.landmarks.push(Landmark::new(0, &obs));
        map.landmarks[0].observations = 3;
        let at = |x: f64, y: f64| {
            Isometry3::from_parts(Translation3::new(x, y, 1.0), UnitQuaternion::identity())
        };
        // 100 poses in front of it, 50 behind it, 50 far away.
        let mut poses: Vec<_> = (0..100).map(|k| at(k as f64 * 0.04, 0.0)).collect();
        poses.extend((0..50).map(|k| at(6.0 + k as f64 * 0.04, 0.0)));
        poses.extend((0..50).map(|_| at(0.0, 40.0)));
        assert_eq!(map.landmarks[0].frames_in_view(&poses, 10.0), 100);
        assert!((map.landmarks[0].found_ratio(&poses, 10.0, None) - 0.03).abs() < 1e-12);
        let selection = |min_found_ratio| LandmarkSelection {
            min_observations: 3,
            min_found_ratio,
            visibility_range: 10.0,
            field: None,
        };
        // A sensor with a limited field (a Livox) sees it only facing it.
        let field = Some(FieldOfView {
            half_h_deg: 35.2,
            half_v_deg: 38.6,
        });
        let turned: Vec<_> = poses
            .iter()
            .map(|p| p * UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::PI))
            .collect();
        let landmark = &map.landmarks[0];
        assert_eq!(landmark.frames_in_field(&poses, 10.0, field), 100);
        assert_eq!(landmark.frames_in_field(&turned, 10.0, field), 0);
        assert_eq!(landmark.frames_in_view(&turned, 10.0), 100);
        assert!(map.reliable(&poses, &selection(0.05)).is_empty());
        assert_eq!(map.reliable(&poses, &selection(0.0)), vec![0]);
        map.landmarks[0].observations = 20;
        assert_eq!(map.reliable(&poses, &selection(0.05)), vec![0]);
    }

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
