//! Euclidean clustering of 2-D points (connected components under a link
//! distance), used to drop isolated evidence before hulls are taken.

use std::collections::HashMap;

use nalgebra::Point2;

/// Cluster label of every point: points closer than `link` (directly or
/// through a chain) share a label. Labels are `0..k`, numbered by first
/// appearance, so the result is deterministic for a given input order.
pub fn euclidean_clusters(points: &[Point2<f64>], link: f64) -> Vec<usize> {
    let n = points.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    if !(link > 0.0) {
        return (0..n).collect();
    }
    let key = |p: &Point2<f64>| ((p.x / link).floor() as i64, (p.y / link).floor() as i64);
    let mut grid: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        if p.x.is_finite() && p.y.is_finite() {
            grid.entry(key(p)).or_default().push(i);
        }
    }
    let link2 = link * link;
    for (i, p) in points.iter().enumerate() {
        if !(p.x.is_finite() && p.y.is_finite()) {
            continue;
        }
        let (cx, cy) = key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(cell) = grid.get(&(cx + dx, cy + dy)) else {
                    continue;
                };
                for &j in cell {
                    if j > i && (points[j] - p).norm_squared() <= link2 {
                        let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                        if a != b {
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    let mut ids: HashMap<usize, usize> = HashMap::new();
    (0..n)
        .map(|i| {
            let root = find(&mut parent, i);
            let next = ids.len();
            *ids.entry(root).or_insert(next)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn separates_groups_and_chains_links() {
        let pts = [
            Point2::new(0.0, 0.0),
            Point2::new(0.4, 0.0),
            Point2::new(0.8, 0.0), // chained to the first through the second
            Point2::new(5.0, 5.0),
            Point2::new(5.3, 5.0),
            Point2::new(20.0, 0.0),
        ];
        let l = euclidean_clusters(&pts, 0.5);
        assert_eq!(l, vec![0, 0, 0, 1, 1, 2]);
    }
}
