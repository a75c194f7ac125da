//! Reflective planes as SLAM landmarks.
//!
//! The detector fits its planes to candidate points of the whole scan, so a
//! plane's inliers may join separate surfaces that happen to lie on one
//! plane: a mirror-clad column and the far end of a glass railing, a pane
//! and a reflection patch. For classification that only widens the hull;
//! for registration it tilts the plane (a few far inliers on a lever arm of
//! metres) and makes its hull, centroid and area jump from frame to frame.
//! A reflective plane therefore enters the frame's planes as the largest
//! patch of its inliers — connected in the plane's chart: inliers fall into
//! square cells of `reflective_link` metres, and touching occupied cells
//! (8-neighbourhood) form a patch (glass candidates are sparse: only beams
//! with a second return count, so sensor-grid neighbours are often missing)
//! — refitted by least squares; patches under `min_area` are dropped. A link of 0
//! takes the detector's planes as they are (the paper).

use super::extractor::ExtractorParams;
use super::{inlier_moments, FramePlane};
use crate::cloud::Frame;
use crate::geometry::fit::fit_plane;
use crate::io::PlaneKind;
use crate::reflect::{Detection, ReflectivePlane};
use nalgebra::Point2;

/// The detector's planes as frame planes of kind `Reflective` (see the
/// module documentation); `params` gives the link distance of a patch and
/// the smallest area kept.
pub fn reflective_planes(
    frame: &Frame,
    detection: &Detection,
    params: &ExtractorParams,
) -> Vec<FramePlane> {
    let mut out = Vec::new();
    for rp in &detection.planes {
        let Some(link) = params.reflective_link else {
            // The detector's plane as it is (the paper).
            if let Some(fp) = as_detected(frame, rp) {
                out.push(fp);
            }
            continue;
        };
        let chart = &rp.bounded.chart;
        let uv: Vec<_> = rp
            .inliers
            .iter()
            .map(|&i| chart.to_2d(&frame.points[i as usize].position()))
            .collect();
        let labels = grid_components(&uv, link);
        let mut sizes = vec![0usize; labels.iter().max().map_or(0, |m| m + 1)];
        for &l in &labels {
            sizes[l] += 1;
        }
        // The largest patch (the first found on ties).
        let Some(best) = (0..sizes.len()).max_by(|&a, &b| sizes[a].cmp(&sizes[b]).then(b.cmp(&a)))
        else {
            continue;
        };
        let patch: Vec<u32> = rp
            .inliers
            .iter()
            .zip(&labels)
            .filter(|(_, &l)| l == best)
            .map(|(&i, _)| i)
            .collect();
        let points = || patch.iter().map(|&i| frame.points[i as usize].position());
        let Some((plane, _)) = fit_plane(points()) else {
            continue;
        };
        if let Some(fp) = FramePlane::from_inliers(PlaneKind::Reflective, plane, frame, patch) {
            if fp.area >= params.min_area {
                out.push(fp);
            }
        }
    }
    out
}

/// Patch label of every point: points in touching occupied square cells of
/// side `cell` share a label. Labels are numbered by first appearance in
/// the input order (deterministic); `O(n log n)`, no hashing.
fn grid_components(points: &[Point2<f64>], cell: f64) -> Vec<usize> {
    let key = |p: &Point2<f64>| ((p.x / cell).floor() as i64, (p.y / cell).floor() as i64);
    let keys: Vec<(i64, i64)> = points.iter().map(key).collect();
    let mut cells = keys.clone();
    cells.sort_unstable();
    cells.dedup();
    // Component of every occupied cell, by flood fill over the sorted keys.
    let mut comp = vec![usize::MAX; cells.len()];
    let mut stack = Vec::new();
    let mut next = 0;
    for start in 0..cells.len() {
        if comp[start] != usize::MAX {
            continue;
        }
        comp[start] = next;
        stack.push(start);
        while let Some(c) = stack.pop() {
            let (x, y) = cells[c];
            for dx in -1..=1 {
                for dy in -1..=1 {
                    if let Ok(n) = cells.binary_search(&(x + dx, y + dy)) {
                        if comp[n] == usize::MAX {
                            comp[n] = next;
                            stack.push(n);
                        }
                    }
                }
            }
        }
        next += 1;
    }
    // Renumber by first appearance in the input.
    let mut renumber = vec![usize::MAX; next];
    let mut count = 0;
    keys.iter()
        .map(|k| {
            let c = comp[cells.binary_search(k).unwrap_or(0)];
            if renumber[c] == usize::MAX {
                renumber[c] = count;
                count += 1;
            }
            renumber[c]
        })
        .collect()
}

/// The detector's plane, hull and inliers unchanged.
fn as_detected(frame: &Frame, rp: &ReflectivePlane) -> Option<FramePlane> {
    if rp.bounded.boundary.is_empty() || rp.inliers.is_empty() {
        return None;
    }
    let (centroid, scatter) = inlier_moments(frame, &rp.inliers);
    Some(FramePlane {
        kind: PlaneKind::Reflective,
        plane: rp.bounded.plane,
        chart: rp.bounded.chart,
        hull: rp.bounded.boundary.clone(),
        centroid,
        area: rp.bounded.boundary.area(),
        inliers: rp.inliers.clone(),
        scatter,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frontend::testing::{cast, Rect};
    use crate::geometry::Plane;
    use crate::reflect::{BoundedPlane, ReflectivePlane};
    use nalgebra::{Point3, Vector3};

    #[test]
    fn touching_cells_form_one_patch() {
        let p = |x: f64, y: f64| Point2::new(x, y);
        let pts = [
            p(0.1, 0.1),
            p(5.0, 5.0),
            p(0.6, 0.1),
            p(1.4, 0.9),
            p(5.2, 5.1),
            p(-3.0, 0.0),
        ];
        assert_eq!(grid_components(&pts, 0.5), vec![0, 1, 0, 0, 1, 2]);
    }

    #[test]
    fn a_far_strip_on_the_same_plane_does_not_tilt_the_landmark() {
        // A mirror x = 3 (y in [-1, 1]) and, 4 m away on nearly the same
        // plane, a strip of other points at x = 3.1: one RANSAC plane for the
        // detector, two patches for us.
        let frame = cast(
            &[
                Rect::between(Point3::new(3.0, -1.0, -1.0), Point3::new(3.0, 1.0, 1.5)),
                Rect::between(Point3::new(3.1, 4.5, -1.0), Point3::new(3.1, 5.0, 1.5)),
            ],
            0.0,
        );
        let inliers: Vec<u32> = (0..frame.points.len() as u32).collect();
        let tilted = fit_plane(frame.points.iter().map(|p| p.position()))
            .unwrap()
            .0;
        let detection = Detection {
            candidates: inliers.clone(),
            planes: vec![ReflectivePlane {
                bounded: BoundedPlane::from_points(
                    tilted.facing(&Point3::origin()),
                    frame.points.iter().map(|p| p.position()),
                ),
                inliers,
            }],
        };
        let planes = reflective_planes(&frame, &detection, &ExtractorParams::default());
        assert_eq!(planes.len(), 1);
        let p = &planes[0];
        let truth = Plane::new(Vector3::new(-1.0, 0.0, 0.0), 3.0).unwrap();
        assert!(
            p.plane.normal.dot(&truth.normal) > 1.0 - 1e-9,
            "{:?}",
            p.plane
        );
        assert!((p.plane.d - 3.0).abs() < 1e-6);
        assert!(
            p.centroid.y.abs() < 0.2 && p.area < 5.1,
            "{} {}",
            p.centroid,
            p.area
        );
        assert!(tilted.normal.dot(&truth.normal).abs() < 1.0 - 1e-4);
    }
}
