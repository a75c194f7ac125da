//! The label a simulated point is given: 3DRef's ray-cast rule (the
//! default) or the physical path of its echo.
//!
//! 3DRef labels its real clouds by casting the straight ray from the sensor
//! to each point against a mesh of the building (its `raycast/` folders;
//! `reference/sensors.md` of the project's shared notes). With `d` the
//! range of the first mesh hit minus the point's range:
//!
//! | first hit | point | label |
//! |---|---|---|
//! | not reflective | range ≤ 30 m | 1 normal |
//! | glass / mirror / other reflective | \|d\| < 0.15 m | 2 / 3 / 4 |
//! | mirror or other reflective | more than 0.15 m behind | 5 reflection |
//! | glass | more than 0.15 m behind, within 0.15 m of any mesh surface, or beyond 30 m | 6 obstacle |
//! | glass | more than 0.15 m behind, farther than 0.15 m from the mesh | 5 reflection |
//! | anything else | | 0 unlabeled |
//!
//! The real data is labelled and scored that way, so the simulator's truth
//! follows it whatever echo was stronger: where a floor continues beyond a
//! window, the reflection of the floor in front of the glass lands on the
//! floor behind it and is an Obstacle; where the ground beyond is lower, it
//! is a Reflection. The physical truth (which surface scattered the return,
//! whether the path was reflected) stays in
//! [`PointTruth`](super::PointTruth) and is the label under
//! [`LabelRule::Physical`].

use glam::DVec3;
use serde::{Deserialize, Serialize};

use super::echo::label;
use super::material::MaterialKind;
use super::raycast::{Hit, SceneIndex};

/// How far a point may lie from the first reflective surface on its ray
/// and still be that surface's echo, metres (3DRef's threshold).
pub const SURFACE_TOLERANCE: f64 = 0.15;
/// A point behind glass this close to any surface of the mesh is an
/// obstacle seen through the glass, metres (3DRef's threshold).
pub const MESH_PROXIMITY: f64 = 0.15;
/// Points farther than this are labelled normal only when they lie on a
/// non-reflective surface, and behind glass they are obstacles, metres
/// (3DRef's cut-off).
pub const FAR_RANGE: f64 = 30.0;

/// Which truth a simulated point's `label` carries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LabelRule {
    /// 3DRef's ray-cast rule against the scene's surfaces (the module
    /// doc): how the real data is labelled and scored.
    #[default]
    Raycast3dref,
    /// The path of the echo: 5 for anything reached after a specular
    /// reflection, 6 for a diffuse surface reached through glass, the
    /// material's id for a surface echo, 1 otherwise; a merged echo takes
    /// the label of its stronger part.
    Physical,
}

impl LabelRule {
    /// Name as written on the command line and in `metrics.json`.
    pub fn name(self) -> &'static str {
        match self {
            LabelRule::Raycast3dref => "3dref",
            LabelRule::Physical => "physical",
        }
    }
}

/// 3DRef's rule for one point: `first` is the first surface its straight
/// ray from the sensor meets (with `kinds[surface]` its material class),
/// `range` the point's measured range and `point` its world position;
/// `index` answers the mesh-proximity test.
pub fn raycast_label(
    first: Option<Hit>,
    range: f64,
    point: DVec3,
    kinds: &[MaterialKind],
    index: &SceneIndex,
) -> u8 {
    let Some(hit) = first else {
        return label::UNLABELED;
    };
    let kind = kinds[hit.surface as usize];
    if !kind.is_reflective() {
        return if range <= FAR_RANGE {
            label::NORMAL
        } else {
            label::UNLABELED
        };
    }
    let behind = range - hit.t;
    if behind.abs() < SURFACE_TOLERANCE {
        return kind.label();
    }
    if behind < 0.0 {
        // In front of the first surface on its ray: nothing is there.
        return label::UNLABELED;
    }
    match kind {
        MaterialKind::Glass
            if range > FAR_RANGE || index.distance_within(point, MESH_PROXIMITY).is_some() =>
        {
            label::OBSTACLE_BEHIND_GLASS
        }
        _ => label::REFLECTION,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::surface::Surface;

    fn rect(x: f64, y: [f64; 2], z: [f64; 2], material: usize) -> Surface {
        Surface::new(
            vec![
                DVec3::new(x, y[0], z[0]),
                DVec3::new(x, y[1], z[0]),
                DVec3::new(x, y[1], z[1]),
                DVec3::new(x, y[0], z[1]),
            ],
            material,
            format!("x={x}"),
        )
        .unwrap()
    }

    fn floor(x: [f64; 2], z: f64) -> Surface {
        Surface::new(
            vec![
                DVec3::new(x[0], -10.0, z),
                DVec3::new(x[1], -10.0, z),
                DVec3::new(x[1], 10.0, z),
                DVec3::new(x[0], 10.0, z),
            ],
            0,
            "floor".into(),
        )
        .unwrap()
    }

    /// The label of the point `range` metres along the ray from `origin`
    /// towards `dir`, in a scene of `surfaces` with materials
    /// `kinds` (diffuse, glass, mirror by index).
    fn label_at(surfaces: &[Surface], origin: DVec3, dir: DVec3, range: f64) -> u8 {
        let kinds = [
            MaterialKind::Diffuse,
            MaterialKind::Glass,
            MaterialKind::Mirror,
        ];
        let surface_kinds: Vec<_> = surfaces.iter().map(|s| kinds[s.material]).collect();
        let index = SceneIndex::new(surfaces);
        let dir = dir.normalize();
        let first = index.cast(origin, dir, 100.0, None);
        raycast_label(first, range, origin + dir * range, &surface_kinds, &index)
    }

    /// The ray from a sensor 1 m above the floor at the origin, down through
    /// a window at x = 2 to where the floor's mirror image lies: the point
    /// is at the range of the floor in front of the glass reflected.
    fn floor_image(surfaces: &[Surface]) -> u8 {
        // The beam meets the floor 4 m ahead (z = 0 at x = 4) when it goes
        // straight; its reflection in the window (x = 2) would meet the
        // floor in front of it at x = 0 (range the same): the sensor
        // reports it 4 m along the straight ray, at (4, 0, 0).
        let dir = DVec3::new(4.0, 0.0, -1.0);
        label_at(surfaces, DVec3::new(0.0, 0.0, 1.0), dir, dir.length())
    }

    #[test]
    fn a_floor_continuing_beyond_a_window_at_the_same_level_is_an_obstacle() {
        let scene = [
            floor([-5.0, 2.0], 0.0),
            rect(2.0, [-10.0, 10.0], [0.0, 3.0], 1),
            floor([2.0, 12.0], 0.0),
        ];
        assert_eq!(floor_image(&scene), label::OBSTACLE_BEHIND_GLASS);
    }

    #[test]
    fn a_floor_half_a_metre_lower_beyond_a_window_leaves_a_reflection() {
        let scene = [
            floor([-5.0, 2.0], 0.0),
            rect(2.0, [-10.0, 10.0], [-0.5, 3.0], 1),
            floor([2.0, 12.0], -0.5),
        ];
        assert_eq!(floor_image(&scene), label::REFLECTION);
    }

    #[test]
    fn everything_behind_a_mirror_is_a_reflection() {
        // A mirror at x = 2 with a wall right behind it: even a point on
        // that wall's position is a reflection, and so is one far behind.
        let scene = [
            rect(2.0, [-10.0, 10.0], [-3.0, 3.0], 2),
            rect(2.1, [-10.0, 10.0], [-3.0, 3.0], 0),
        ];
        for range in [2.25, 3.0, 7.0, 40.0] {
            let l = label_at(&scene, DVec3::ZERO, DVec3::X, range);
            assert_eq!(l, label::REFLECTION, "range {range}");
        }
        // On the mirror itself: its surface echo.
        assert_eq!(label_at(&scene, DVec3::ZERO, DVec3::X, 2.1), label::MIRROR);
    }

    #[test]
    fn an_object_behind_glass_is_an_obstacle_and_empty_space_a_reflection() {
        // Glass at x = 2, a box face at x = 5 behind it.
        let scene = [
            rect(2.0, [-10.0, 10.0], [-3.0, 3.0], 1),
            rect(5.0, [-1.0, 1.0], [-1.0, 1.0], 0),
        ];
        let at = |dir: DVec3, range: f64| label_at(&scene, DVec3::ZERO, dir, range);
        // On the box (within noise of it): an obstacle.
        assert_eq!(at(DVec3::X, 5.0), label::OBSTACLE_BEHIND_GLASS);
        assert_eq!(at(DVec3::X, 5.1), label::OBSTACLE_BEHIND_GLASS);
        // Between glass and box, where nothing is: a reflection.
        assert_eq!(at(DVec3::X, 3.5), label::REFLECTION);
        // On the glass: its surface echo.
        assert_eq!(at(DVec3::X, 2.05), label::GLASS);
        // Beside the box, far behind the glass: a reflection; beyond 30 m an
        // obstacle whatever is there.
        let side = DVec3::new(1.0, 0.5, 0.0);
        assert_eq!(at(side, 8.0), label::REFLECTION);
        assert_eq!(at(side, 31.0), label::OBSTACLE_BEHIND_GLASS);
        // In front of the glass, where the ray has met nothing: unlabeled.
        assert_eq!(at(DVec3::X, 1.0), label::UNLABELED);
    }

    #[test]
    fn points_on_opaque_surfaces_are_normal_up_to_30_m() {
        let scene = [rect(2.0, [-10.0, 10.0], [-3.0, 3.0], 0)];
        assert_eq!(label_at(&scene, DVec3::ZERO, DVec3::X, 2.0), label::NORMAL);
        let far = [rect(31.0, [-10.0, 10.0], [-3.0, 3.0], 0)];
        assert_eq!(
            label_at(&far, DVec3::ZERO, DVec3::X, 31.0),
            label::UNLABELED
        );
        assert_eq!(label_at(&[], DVec3::ZERO, DVec3::X, 3.0), label::UNLABELED);
    }
}
