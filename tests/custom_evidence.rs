//! A researcher's own evidence test, added from outside the crate: it is
//! weighed with the built-in ones by the plane-map classifier, can overrule
//! them when it weighs more, and is reported as the deciding rule.

use nalgebra::{Isometry3, Point3, Vector3};
use specular::classify::evidence::{BehindPoint, EvidenceTest, Weighing, WeighingParams};
use specular::classify::{Class, Classifier, FrameInput, PlaneMapClassifier, PlaneMapParams, Rule};
use specular::cloud::{Frame, Point};
use specular::geometry::Plane;
use specular::reflect::{BoundedPlane, Detection};
use specular::sensor::{OrganizedScan, SensorModel};

/// Calls a point a reflection when its echo is weaker than a threshold,
/// with a fixed weight (a stand-in for a learned intensity model).
#[derive(Debug)]
struct WeakEchoIsReflection {
    below: f32,
    weight: f64,
}

impl EvidenceTest for WeakEchoIsReflection {
    fn name(&self) -> &str {
        "weak-echo"
    }

    fn weigh(&self, point: &BehindPoint<'_>) -> Option<f64> {
        (point.intensity() < self.below).then_some(self.weight)
    }
}

/// A pane at x = 5 facing the sensor at the origin, 4 m wide, 3 m high.
fn pane() -> BoundedPlane {
    let plane = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 5.0).unwrap();
    let corners = [(-2.0, -1.0), (2.0, -1.0), (2.0, 2.0), (-2.0, 2.0)];
    BoundedPlane::from_points(plane, corners.iter().map(|&(y, z)| Point3::new(5.0, y, z)))
}

/// The classes of single-return points behind the pane, 3 m deep (deeper
/// than the empty room, so the depth test calls them real).
fn classify(weighing: Weighing, intensities: &[f32]) -> (Vec<Class>, Vec<Rule>, Vec<f32>) {
    let sensor = SensorModel::resolve("pandar_qt64").unwrap();
    let frame = Frame {
        name: "synthetic".into(),
        points: intensities
            .iter()
            .enumerate()
            .map(|(k, &intensity)| {
                let xyz = [8.0f32, -1.0 + 0.5 * k as f32, 0.3];
                let p = Point3::new(xyz[0] as f64, xyz[1] as f64, xyz[2] as f64);
                Point {
                    xyz,
                    intensity,
                    ring: sensor.ring_of(&p).unwrap_or(0) as u16,
                    ret: 1,
                    label: 0,
                    time: 0.0,
                }
            })
            .collect(),
        ..Frame::default()
    };
    let scan = OrganizedScan::build(&frame, &sensor).unwrap();
    let detection = Detection {
        candidates: Vec::new(),
        planes: Vec::new(),
    };
    let planes = [pane()];
    let classifier = PlaneMapClassifier::new(PlaneMapParams::default())
        .unwrap()
        .with_weighing(weighing);
    let d = classifier.classify(&FrameInput {
        frame: &frame,
        scan: &scan,
        sensor: &sensor,
        detection: &detection,
        pose: Isometry3::identity(),
        map_planes: &planes,
        support: None,
        space: None,
        beam_hits: None,
    });
    (d.classes, d.rules, d.confidence)
}

#[test]
fn a_custom_test_is_weighed_with_the_built_in_ones() {
    let depth_only = || {
        Weighing::from_params(&WeighingParams {
            tests: vec!["depth".into()],
            ..WeighingParams::default()
        })
        .unwrap()
    };
    // The depth test alone: both points real, seen through glass.
    let (classes, rules, confidence) = classify(depth_only(), &[1.0, 100.0]);
    assert_eq!(classes, [Class::Obstacle, Class::Obstacle]);
    assert_eq!(rules, [Rule::Depth, Rule::Depth]);
    assert!(confidence.iter().all(|&c| c > 0.9), "{confidence:?}");
    // A weak custom test does not overrule the depth test ...
    let weak = depth_only().with_test(Box::new(WeakEchoIsReflection {
        below: 10.0,
        weight: 1.0,
    }));
    assert_eq!(weak.test_names(), ["depth", "weak-echo"]);
    let (classes, _, _) = classify(weak, &[1.0, 100.0]);
    assert_eq!(classes, [Class::Obstacle, Class::Obstacle]);
    // ... a strong one does, on the weak echo only, and says so.
    let strong = depth_only().with_test(Box::new(WeakEchoIsReflection {
        below: 10.0,
        weight: 12.0,
    }));
    let (classes, rules, confidence) = classify(strong, &[1.0, 100.0]);
    assert_eq!(classes, [Class::Reflection, Class::Obstacle]);
    assert_eq!(rules, [Rule::Weighed, Rule::Depth]);
    assert!(confidence[0] > 0.9 && confidence[0] < 1.0, "{confidence:?}");
}
