//! The mirror image lands on a surface seen directly, and only there.

use std::cell::OnceCell;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::seen_space::{CLEARANCE_RATIO, SUPPORT_RADIUS};
use super::{rate_weight, BehindPoint, EvidenceTest, SeenSpace};
use crate::classify::decide::SurfaceSupport;
use crate::classify::rule::Rule;
use crate::classify::space::{Occupancy, SensorFrameSpace};
use crate::geometry::Plane;
use crate::map::glass_or_mirror::IMAGE_NULL_SHIFTS;

/// Mirrored through the landmark, a reflection lands on the surface it
/// came from; a real point's image lands on one only by chance. A wall
/// that runs along the normal holds the image of anything beside it, so
/// only a landing that the image leaves when moved 1 m along the normal,
/// either way ([`IMAGE_NULL_SHIFTS`]), counts: the landing is specific to
/// the mirror position. Landing anywhere, the image of a real point did so
/// on the development split as often as a reflection's did in symmetric
/// rooms and corridors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImageSupport {
    /// Probability that a reflection's mirror image lands specifically on a
    /// surface seen directly (the others' images lie out of view, at a
    /// floor's height, or on a wall along the normal).
    pub reflection_rate: f64,
    /// Probability that a real point's mirror image lands specifically on
    /// a surface seen directly by chance.
    pub chance_rate: f64,
}

/// The values of `configs/default.toml`.
impl Default for ImageSupport {
    fn default() -> Self {
        crate::config::default_section("plane_map.weighing.image_support")
    }
}

impl ImageSupport {
    /// The test with the settings it shares with the seen space (when a
    /// path is refuted) and the level surfaces (a floor's or ceiling's
    /// height, m), so that it decides landings as the landmark's
    /// chance-landing count does.
    pub fn test(self, seen_space: SeenSpace, level_tolerance: f64) -> ImageSupportTest {
        ImageSupportTest {
            weight: rate_weight(self.reflection_rate, self.chance_rate),
            seen_space,
            level_tolerance,
        }
    }
}

/// [`ImageSupport`] ready to weigh.
#[derive(Debug, Clone, Copy)]
pub struct ImageSupportTest {
    /// The log-likelihood ratio of a specific landing.
    weight: f64,
    seen_space: SeenSpace,
    level_tolerance: f64,
}

impl EvidenceTest for ImageSupportTest {
    fn name(&self) -> &str {
        "image-support"
    }

    fn rule(&self) -> Rule {
        Rule::Support
    }

    fn tells_the_path(&self) -> bool {
        true
    }

    fn is_likelihood_ratio(&self) -> bool {
        true
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        let space = point
            .space
            .filter(|_| point.single_pane && !point.past_extent)?;
        let landing = ImageLanding::new(
            space,
            point.support,
            &point.landmark.plane,
            point.position,
            point.crossing_point(),
            &self.seen_space,
            self.level_tolerance,
        );
        let specific = landing.lands(&point.mirrored)
            && IMAGE_NULL_SHIFTS
                .iter()
                .all(|&s| !landing.lands(&moved_off(landing.plane, &point.mirrored, s)));
        specific.then_some(self.weight)
    }
}

/// Where the images of one point behind a landmark land among what the
/// sequence saw directly (sensor frame): the test above and the landmark's
/// echo counts ([`count_seen`](crate::classify::landmark_echoes)) decide
/// landings alike.
pub(crate) struct ImageLanding<'a> {
    /// The space seen directly, from the frame's pose.
    pub space: &'a SensorFrameSpace<'a>,
    /// The surfaces seen directly, when gathered.
    pub seen: Option<&'a dyn SurfaceSupport>,
    /// Where the point was measured.
    pub position: Point3<f64>,
    /// Whether a surface was seen there (within [`SUPPORT_RADIUS`]): then
    /// no image lands, the point's own surface being as likely where it
    /// is. Asked once, and only of a point with an image on a surface.
    pub seen_at_position: OnceCell<bool>,
    /// When a hypothesis's path is refuted.
    pub seen_space: &'a SeenSpace,
    /// Within this of a floor's or ceiling's height an image says nothing,
    /// m: a vertical pane mirrors the floor behind it onto the floor in
    /// front, real or not.
    pub level_tolerance: f64,
    /// The landmark (facing the sensor).
    pub plane: &'a Plane,
    /// Where its beam crossed the landmark.
    pub crossing: Point3<f64>,
    /// Its range, m.
    pub range: f64,
}

impl<'a> ImageLanding<'a> {
    /// The landings of the point measured at `position` behind `plane`,
    /// its beam crossing the plane at `crossing`.
    pub fn new(
        space: &'a SensorFrameSpace<'a>,
        seen: Option<&'a dyn SurfaceSupport>,
        plane: &'a Plane,
        position: Point3<f64>,
        crossing: Point3<f64>,
        seen_space: &'a SeenSpace,
        level_tolerance: f64,
    ) -> Self {
        Self {
            space,
            seen,
            position,
            seen_at_position: OnceCell::new(),
            seen_space,
            level_tolerance,
            plane,
            crossing,
            range: position.coords.norm(),
        }
    }

    /// Whether the seen space refutes "the echo came from `end`".
    pub fn refuted(&self, end: &Point3<f64>) -> bool {
        self.seen_space.refuted(
            self.space,
            self.seen,
            &self.plane.normal,
            &self.crossing,
            end,
            self.range,
        )
    }

    /// Whether `image` lies on a surface seen directly where none was seen
    /// at the measured position, not at a floor's or ceiling's height.
    pub fn on_seen_surface(&self, image: &Point3<f64>) -> bool {
        let Some(seen) = self.seen else {
            return false;
        };
        self.space.level_of(image, self.level_tolerance).is_none()
            && seen.near(image, SUPPORT_RADIUS)
            && !*self
                .seen_at_position
                .get_or_init(|| seen.near(&self.position, SUPPORT_RADIUS))
    }

    /// Whether `image` lands on a seen surface by a path the seen space
    /// does not refute. A path towards a seen surface is refuted only by
    /// its end in space seen free (`leg_refuted`), the cheapest of the
    /// checks, which goes first: most images land in the room, seen free.
    pub fn lands(&self, image: &Point3<f64>) -> bool {
        let clearance = CLEARANCE_RATIO * self.range;
        self.space.occupancy_clear_of(image, clearance) != Occupancy::Free
            && self.on_seen_surface(image)
    }
}

/// The mirror image `image` (sensor frame) moved `shift` metres along
/// `plane`'s normal, away from the pane into the sensor's side where
/// `shift` is positive, towards the pane (and past it) where negative.
pub(crate) fn moved_off(plane: &Plane, image: &Point3<f64>, shift: f64) -> Point3<f64> {
    image + plane.facing(&Point3::origin()).normal * shift
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use proptest::prelude::*;

    proptest! {
        /// A point behind the pane mirrored and moved by `shift` lies on the
        /// sensor's side `shift` farther from the pane (nearer where
        /// negative), and moved back by `-shift` it is the image again.
        #[test]
        fn a_moved_image_moves_along_the_normal_from_the_pane(
            n in prop::array::uniform3(-1.0f64..1.0),
            d in 0.5f64..10.0,
            flip in any::<bool>(),
            depth in 0.1f64..8.0,
            along in prop::array::uniform3(-5.0f64..5.0),
            shift in -3.0f64..3.0,
        ) {
            let normal = Vector3::from(n);
            prop_assume!(normal.norm() > 0.1);
            let normal = normal.normalize();
            let sign = if flip { -1.0 } else { 1.0 };
            let plane = Plane { normal: normal * sign, d: d * sign };
            // The pane's foot nearest the sensor, a point on it, one behind.
            let foot = Point3::from(-normal * d);
            let on = foot + (Vector3::from(along) - normal * normal.dot(&Vector3::from(along)));
            let behind = on - normal * depth;
            prop_assert!(plane.signed_distance(&behind) * plane.d < 0.0);
            let image = plane.mirror(&behind);
            let moved = moved_off(&plane, &image, shift);
            let from_pane = |p: &Point3<f64>| plane.facing(&Point3::origin()).signed_distance(p);
            prop_assert!((from_pane(&moved) - (depth + shift)).abs() < 1e-9);
            prop_assert!((moved_off(&plane, &moved, -shift) - image).norm() < 1e-9);
        }
    }
}
