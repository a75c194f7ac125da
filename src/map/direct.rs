//! Whether a beam reached a plane directly, or only after passing another
//! reflective landmark.
//!
//! Past a window or a mirror a beam's returns no longer say where they are:
//! the first may be a reflection (a virtual point, where nothing is) and the
//! second a return transmitted through the glass along the straight line.
//! On the far side of a window the reflected image of the room lies beside
//! the street seen through it, so a reflected wall echo with the street's
//! return behind it looks exactly like a glass echo with something behind it,
//! on whatever plane the reflected wall has: the demo scene's mirror plane
//! gathered such "glass echoes" 2-5 m outside the room, in the window's
//! reflection of the wall beside the mirror, and grew a phantom pane there.
//! Transparency evidence of a plane is therefore taken from beams that meet
//! it before any other reflective landmark
//! ([`EvidenceParams::direct_only`](super::EvidenceParams::direct_only)).

use nalgebra::{Point3, Vector3};

use crate::reflect::BoundedPlane;

/// Whether the beam from the origin along `dir` (unit) crosses one of
/// `others` inside its boundary more than `band` metres before `t`, the
/// range at which it crosses the plane being voted on (all in the same
/// frame, the beam's origin at the frame's origin). Crossings within `band`
/// of `t` do not count: where two panes meet, a beam through the corner
/// meets both at about the same range and is evidence for both.
pub fn passed_another(others: &[BoundedPlane], dir: &Vector3<f64>, t: f64, band: f64) -> bool {
    let origin = Point3::origin();
    others.iter().any(|o| {
        o.plane
            .ray_intersection(&origin, dir)
            .is_some_and(|to| to + band < t && o.bounds(&(origin + dir * to), 0.0))
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;

    /// A window at y = 2, x in [-1, 1], z in [-1, 1].
    fn window() -> BoundedPlane {
        let plane = Plane::new(Vector3::new(0.0, -1.0, 0.0), 2.0).unwrap();
        BoundedPlane::from_points(
            plane,
            [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .iter()
                .map(|&(x, z)| Point3::new(x, 2.0, z)),
        )
    }

    #[test]
    fn only_a_crossing_inside_the_other_and_before_counts() {
        let others = [window()];
        let through = Vector3::new(0.0, 1.0, 0.0);
        // Through the window at 2 m, voting at 5 m: passed it.
        assert!(passed_another(&others, &through, 5.0, 0.1));
        // Voting at 1.95 m (before the window, or at the corner where
        // the planes meet): not passed.
        assert!(!passed_another(&others, &through, 1.95, 0.1));
        assert!(!passed_another(&others, &through, 1.0, 0.1));
        // Beside the window (x = 3 at y = 2): the wall, not the window.
        let beside = Vector3::new(3.0, 2.0, 0.0).normalize();
        assert!(!passed_another(&others, &beside, 10.0, 0.1));
        // Away from it: never crosses.
        let away = Vector3::new(0.0, -1.0, 0.0);
        assert!(!passed_another(&others, &away, 10.0, 0.1));
        assert!(!passed_another(&[], &through, 5.0, 0.1));
    }

    /// One scan (sensor at the origin) of a room corner: a window at
    /// y = 3 (x in [-1.5, 2]) and a wall mirror on the plane x = -1.5
    /// (y in [-1, 1.5]). Beams that hit the mirror return its weak echo and
    /// the mirrored room 2 m behind; beams through the window return the
    /// window's reflection of the room's wall, which lies on the mirror's
    /// plane again, 0.3-1.3 m beyond the window (y in [3.3, 4.3]), with the
    /// street 12 m away, seen through the glass, behind it.
    fn corner_frame(sensor: &crate::sensor::SensorModel) -> crate::cloud::Frame {
        let mut points = Vec::new();
        let mut push = |p: Vector3<f64>, intensity: f32, ring: usize, ret: u8| {
            points.push(crate::cloud::Point {
                xyz: [p.x as f32, p.y as f32, p.z as f32],
                intensity,
                ring: ring as u16,
                ret,
                label: 0,
                time: 0.0,
            })
        };
        for ring in 0..sensor.rings() {
            for column in 0..sensor.columns {
                let d = sensor.beam_direction(ring, column);
                if d.x >= 0.0 || d.z.abs() > 0.4 {
                    continue;
                }
                let on_mirror_plane = d * (-1.5 / d.x);
                let (y, z) = (on_mirror_plane.y, on_mirror_plane.z);
                if (-1.0..=1.5).contains(&y) && (-0.8..=1.2).contains(&z) {
                    push(on_mirror_plane, 10.0, ring, 1);
                    push(d * (on_mirror_plane.norm() + 2.0), 50.0, ring, 2);
                } else if (3.3..=4.3).contains(&y) && (-0.8..=1.2).contains(&z) {
                    push(on_mirror_plane, 30.0, ring, 1);
                    push(d * 12.0, 60.0, ring, 2);
                }
            }
        }
        crate::cloud::Frame {
            name: "corner".into(),
            points,
            ..crate::cloud::Frame::default()
        }
    }

    /// The window's reflection of the wall beside the mirror lies on the
    /// mirror's plane beyond the window, a reflected echo with the street
    /// behind it: with the default configuration it is no evidence (only
    /// the mirror is a pane); counted as direct evidence it grows a phantom
    /// pane outside the room, as in the demo scene (issue 18, finding 6).
    #[test]
    fn no_phantom_pane_beyond_a_window() {
        use crate::geometry::grid::Surface;
        use crate::map::{find_panes, EvidenceFrame, EvidenceGatherer};
        use crate::sensor::{OrganizedScan, SensorModel};
        use nalgebra::Isometry3;
        let sensor = SensorModel::resolve("pandar_qt64").unwrap();
        let frame = corner_frame(&sensor);
        let scan = OrganizedScan::build(&frame, &sensor).unwrap();
        let f = EvidenceFrame::new(&frame, &scan, Isometry3::identity(), &sensor);
        let window = BoundedPlane::from_points(
            Plane::new(Vector3::new(0.0, -1.0, 0.0), 3.0).unwrap(),
            [(-1.5, -1.0), (2.0, -1.0), (2.0, 1.5), (-1.5, 1.5)]
                .iter()
                .map(|&(x, z)| Point3::new(x, 3.0, z)),
        );
        // The mirror landmark's hull holds the reflected candidates too, as
        // the detector found them on its plane.
        let mirror = BoundedPlane::from_points(
            Plane::new(Vector3::new(1.0, 0.0, 0.0), 1.5).unwrap(),
            [(-1.0, -0.8), (4.3, -0.8), (4.3, 1.2), (-1.0, 1.2)]
                .iter()
                .map(|&(y, z)| Point3::new(-1.5, y, z)),
        );
        let config = crate::config::Config::default();
        assert!(config.map.evidence.direct_only);
        let panes = |direct_only: bool| {
            let params = crate::map::EvidenceParams {
                direct_only,
                ..config.map.evidence
            };
            let gatherer = EvidenceGatherer::new(&mirror, &params)
                .unwrap()
                .with_others(std::slice::from_ref(&window));
            let mut total = gatherer.total();
            total.add(gatherer.votes(&f));
            let grid = total.finish();
            let beyond = grid.state(&mirror.chart.to_2d(&Point3::new(-1.5, 3.8, 0.2)));
            let ys: Vec<(f64, f64)> = find_panes(&grid, &config.map.panes)
                .iter()
                .map(|p| {
                    let ys = p
                        .boundary
                        .vertices()
                        .iter()
                        .map(|q| mirror.chart.to_3d(q).y);
                    (
                        ys.clone().fold(f64::INFINITY, f64::min),
                        ys.fold(f64::NEG_INFINITY, f64::max),
                    )
                })
                .collect();
            (beyond, ys)
        };
        let (beyond, direct) = panes(true);
        assert_ne!(beyond, Surface::Transparent);
        assert_eq!(direct.len(), 1, "{direct:?}");
        assert!(
            direct[0].0 < -0.5 && direct[0].1 > 1.0 && direct[0].1 < 3.0,
            "{direct:?}"
        );
        // The same votes counted past the window: a phantom pane out there.
        let (beyond, all) = panes(false);
        assert_eq!(beyond, Surface::Transparent);
        assert!(all.iter().any(|&(lo, _)| lo > 3.0), "{all:?}");
    }
}
