//! Where the sensor's own path crosses a landmark's plane: there it is
//! open, whatever the echoes say, and a plane the sensor passed through
//! inside its boundary is no mirror.

use nalgebra::Point3;

use crate::reflect::BoundedPlane;

/// Mark as an opening the cells of `landmark`'s decided evidence where the
/// sensor path `path` (positions, world frame, in order) crosses its plane:
/// within `radius` horizontally of a crossing and below `radius` above it.
/// The sensor passed through there, so whatever the votes say, it is no
/// glass (a glass door's open leaf, which the closed leaf's echoes would
/// otherwise keep inside the pane). Returns the number of crossings used.
pub fn open_where_crossed(landmark: &mut BoundedPlane, path: &[Point3<f64>], radius: f64) -> usize {
    if radius <= 0.0 {
        return 0;
    }
    let Some(grid) = landmark.evidence.as_deref() else {
        return 0;
    };
    let crossings: Vec<Point3<f64>> = path_crossings(landmark, path)
        .filter(|x| grid.index(&landmark.chart.to_2d(x)).is_some())
        .collect();
    if crossings.is_empty() {
        return 0;
    }
    let mut grid = grid.clone();
    for k in 0..grid.len() {
        let c = landmark.chart.to_3d(&grid.centre(k));
        let open = crossings.iter().any(|x| {
            let (dx, dy) = (c.x - x.x, c.y - x.y);
            dx * dx + dy * dy <= radius * radius && c.z <= x.z + radius
        });
        if open {
            grid.set_open(k);
        }
    }
    landmark.evidence = Some(std::sync::Arc::new(grid));
    crossings.len()
}

/// Where the sensor path `path` (positions, world frame, in order) crosses
/// `landmark`'s plane.
pub fn path_crossings<'a>(
    landmark: &'a BoundedPlane,
    path: &'a [Point3<f64>],
) -> impl Iterator<Item = Point3<f64>> + 'a {
    let plane = landmark.plane;
    path.windows(2).filter_map(move |w| {
        let (a, b) = (plane.signed_distance(&w[0]), plane.signed_distance(&w[1]));
        (a * b < 0.0).then(|| w[0] + (w[1] - w[0]) * (a / (a - b)))
    })
}

/// Whether the sensor path passed through `landmark` inside its convex
/// boundary: then it has an opening, and it is no mirror.
pub fn passed_through(landmark: &BoundedPlane, path: &[Point3<f64>]) -> bool {
    path_crossings(landmark, path)
        .any(|x| landmark.boundary.signed_distance(&landmark.chart.to_2d(&x)) <= 0.0)
}
