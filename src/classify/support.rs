//! Observed surfaces of a whole sequence, for the mirror-support test.
//!
//! The paper's last classification step mirrors undecided behind-plane
//! points back through their plane and looks for Normal points nearby; with
//! the Normal points of *all* frames (not only the current one) a reflection
//! of a surface seen from elsewhere in the sequence is recognised too.
//!
//! The points are thinned to one per small voxel and bucketed in cubes as
//! large as the query radius, so "is there a point within r" inspects the
//! cubes of at most nine columns (one hash lookup per column, cubes wholly
//! beyond r skipped); building it is two linear passes (no tree to balance), which
//! matters because it is rebuilt for every run over all frames. The buckets
//! are ranges of one flat array (a counting sort), not a vector each.
//!
//! A reflected beam ends on the first surface it meets, so an image behind
//! a seen surface is no reflection of it: with the behind test, each kept
//! point remembers where it was seen from, and an image with no kept point
//! within the behind distance is supported only if it does not lie behind
//! the surface at its nearest kept point.

use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

use super::decide::SurfaceSupport;
use crate::geometry::fastmath::floor_i64;
use crate::geometry::voxel::{FxHashMap, VoxelSet};

/// Observed surface points in the world frame, answering radius queries.
pub struct WorldSupport {
    radius: f64,
    /// Bucket key (packed cube of edge `radius`) to bucket number.
    buckets: FxHashMap<u64, u32>,
    /// The cubes of each column of cubes (same x and y), by column key
    /// ([`column_key`]): a range of `column_cubes`.
    columns: FxHashMap<u64, (u32, u32)>,
    /// Every cube's z index and bucket, column by column, z ascending: a
    /// ball query asks the hash for its (at most nine) columns, not for each
    /// of its (up to 27) cubes.
    column_cubes: Vec<(i32, u32)>,
    /// Bucket `b` holds `points[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    points: Vec<[f32; 3]>,
    /// Per point, the unit direction towards the sensor that first saw it,
    /// times 127 (only its side of the surface is used).
    views: Vec<[i8; 3]>,
    /// Images more than this behind the surface at their nearest point are
    /// not supported, m (infinite: no such test).
    behind: f64,
}

impl std::fmt::Debug for WorldSupport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WorldSupport")
            .field("points", &self.points.len())
            .field("radius", &self.radius)
            .finish()
    }
}

/// Kept points within this distance of a surface point give its normal, m
/// (three support voxels at the default 0.05 m).
const NORMAL_REACH: f64 = 0.15;

/// Fewer kept points than this near a surface point give no normal.
const MIN_NORMAL_POINTS: usize = 6;

/// A surface is a plane where its least spread is at most this share of
/// the middle one (a corner is not) and the middle one at least this share
/// of the largest (a thin edge, a line of points, is not).
const MAX_FLATNESS: f64 = 0.1;

/// Squared distance of two points.
#[inline]
fn dist2(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    let (x, y, z) = (a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    x * x + y * y + z * z
}

/// A cube's integer coordinates packed into one key: 21 bits per axis, two's
/// complement, exact within ±2^20 cubes (±330 km at 0.3 m); farther away two
/// cubes may share a bucket, which only costs distance tests, never answers.
#[inline]
fn bucket_key(c: [i64; 3]) -> u64 {
    let m = (1u64 << 21) - 1;
    (c[0] as u64 & m) | ((c[1] as u64 & m) << 21) | ((c[2] as u64 & m) << 42)
}

/// The key of the column of cubes at `x`, `y` (any z): the x and y bits of
/// [`bucket_key`].
#[inline]
fn column_key(x: i64, y: i64) -> u64 {
    bucket_key([x, y, 0])
}

/// The cube index along one axis back from a [`bucket_key`]'s 21 bits
/// (sign-extended).
#[inline]
fn axis_of_key(bits: u64) -> i64 {
    ((bits << 43) as i64) >> 43
}

/// Squared distance from `v` to the interval `[c, c + 1) * size` along one
/// axis: 0 inside it.
#[inline]
fn gap2(v: f64, c: i64, size: f64) -> f64 {
    let lo = c as f64 * size;
    let g = (lo - v).max(v - (lo + size)).max(0.0);
    g * g
}

/// Builds a [`WorldSupport`] from points offered a frame at a time: what it
/// keeps grows with the surface seen (one point per voxel), not with the
/// number of frames.
pub struct SupportBuilder {
    radius: f64,
    inv: f64,
    seen: VoxelSet,
    buckets: FxHashMap<u64, u32>,
    /// The kept points with their bucket numbers and view directions.
    kept: Vec<(u32, [f32; 3], [i8; 3])>,
    /// See [`SupportBuilder::with_behind`] (infinite: no such test).
    behind: f64,
    /// Points per bucket.
    counts: Vec<u32>,
    /// Consecutive points mostly share a bucket: the last one.
    last: Option<(u64, u32)>,
}

impl SupportBuilder {
    /// An empty support thinned to one point per `voxel`, for queries of
    /// radius up to `radius`.
    pub fn new(voxel: f64, radius: f64) -> Self {
        let radius = radius.max(voxel).max(1e-3);
        Self {
            radius,
            inv: 1.0 / radius,
            seen: VoxelSet::new(voxel),
            buckets: FxHashMap::default(),
            kept: Vec::new(),
            counts: Vec::new(),
            last: None,
            behind: f64::INFINITY,
        }
    }

    /// Support no mirror image more than `behind` metres behind the
    /// surface at the kept point nearest to it (see
    /// [`WorldSupport::near_world`]).
    pub fn with_behind(mut self, behind: f64) -> Self {
        self.behind = behind;
        self
    }

    /// Offer world-frame points seen from `origin` (the first of each voxel
    /// is kept).
    pub fn extend(&mut self, origin: Point3<f64>, points: impl IntoIterator<Item = Point3<f64>>) {
        let inv = self.inv;
        for p in points {
            let xyz = [p.x, p.y, p.z];
            if !self.seen.insert(xyz, 0) {
                continue;
            }
            let key = bucket_key([
                floor_i64(p.x * inv),
                floor_i64(p.y * inv),
                floor_i64(p.z * inv),
            ]);
            let b = match self.last {
                Some((k, b)) if k == key => b,
                _ => {
                    let next = self.counts.len() as u32;
                    let b = *self.buckets.entry(key).or_insert(next);
                    if b == next {
                        self.counts.push(0);
                    }
                    self.last = Some((key, b));
                    b
                }
            };
            self.counts[b as usize] += 1;
            let view = (origin - p).try_normalize(0.0).unwrap_or_default();
            let view = [view.x, view.y, view.z].map(|c| (c * 127.0).round() as i8);
            self.kept
                .push((b, [p.x as f32, p.y as f32, p.z as f32], view));
        }
    }

    /// The support: a counting sort of the kept points into one array,
    /// input order kept per bucket.
    pub fn finish(self) -> WorldSupport {
        let mut starts = Vec::with_capacity(self.counts.len() + 1);
        let mut total = 0u32;
        starts.push(0);
        for &c in &self.counts {
            total += c;
            starts.push(total);
        }
        let mut fill: Vec<u32> = starts[..self.counts.len()].to_vec();
        let mut flat = vec![[0f32; 3]; self.kept.len()];
        let mut views = vec![[0i8; 3]; self.kept.len()];
        for (b, q, v) in self.kept {
            let slot = &mut fill[b as usize];
            flat[*slot as usize] = q;
            views[*slot as usize] = v;
            *slot += 1;
        }
        let m = (1u64 << 21) - 1;
        let mut cubes: Vec<(u64, i64, u32)> = self
            .buckets
            .iter()
            .map(|(&key, &b)| (key & ((1u64 << 42) - 1), axis_of_key((key >> 42) & m), b))
            .collect();
        cubes.sort_unstable();
        let mut columns = FxHashMap::default();
        let mut start = 0u32;
        for column in cubes.chunk_by(|a, b| a.0 == b.0) {
            columns.insert(column[0].0, (start, column.len() as u32));
            start += column.len() as u32;
        }
        let column_cubes = cubes.iter().map(|&(_, z, b)| (z as i32, b)).collect();
        WorldSupport {
            radius: self.radius,
            columns,
            column_cubes,
            buckets: self.buckets,
            starts,
            points: flat,
            views,
            behind: self.behind,
        }
    }
}

impl WorldSupport {
    /// Build from world-frame points, keeping the first point of each
    /// `voxel`-sized cube (deterministic for a given input order), for
    /// queries of radius up to `radius`.
    pub fn build(points: impl IntoIterator<Item = Point3<f64>>, voxel: f64, radius: f64) -> Self {
        let mut builder = SupportBuilder::new(voxel, radius);
        builder.extend(Point3::origin(), points);
        builder.finish()
    }

    /// Number of points kept.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether no point was kept.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Whether a kept point lies within `radius` of `p` (world frame) that
    /// supports `p` as a mirror image: with the behind test on
    /// ([`SupportBuilder::with_behind`]), an image more than `behind`
    /// metres behind the surface at its nearest kept point is not
    /// supported. `radius` is clamped to the radius the support was built
    /// for.
    pub fn near_world(&self, p: &Point3<f64>, radius: f64) -> bool {
        // Within `behind` of a kept point an image is on that surface, from
        // whichever side: the common case ends the search there.
        let (on_surface, nearest) = self.nearest_within(p, radius, self.behind);
        on_surface || nearest.is_some_and(|i| !self.behind_surface_at(p, i))
    }

    /// The kept point nearest to `p` within `radius` (clamped to the radius
    /// the support was built for), searched until one lies within `stop`:
    /// whether one did (the nearest is then not sought further), and the
    /// nearest found.
    fn nearest_within(&self, p: &Point3<f64>, radius: f64, stop: f64) -> (bool, Option<usize>) {
        let r = radius.min(self.radius);
        let q = [p.x as f32, p.y as f32, p.z as f32];
        let r2 = (r * r) as f32;
        let stop = stop.min(r);
        let stop2 = (stop * stop) as f32;
        let mut nearest: Option<(f32, usize)> = None;
        let stopped = self.any_in_ball(p, r, |i, point| {
            let d2 = dist2(point, &q);
            if d2 <= r2 && nearest.is_none_or(|(n, _)| d2 < n) {
                nearest = Some((d2, i));
            }
            d2 <= stop2
        });
        (stopped, nearest.map(|(_, i)| i))
    }

    /// Whether `p` lies more than `behind` metres behind the surface at kept
    /// point `i`: along that surface's normal ([`Self::normal_at`]) turned
    /// towards where `i` was seen from. `false` where the points there make
    /// no plane.
    fn behind_surface_at(&self, p: &Point3<f64>, i: usize) -> bool {
        let Some(normal) = self.normal_at(i) else {
            return false;
        };
        let s = Point3::from(Vector3::from(self.points[i].map(f64::from)));
        let view = Vector3::from(self.views[i].map(f64::from));
        let depth = normal.dot(&(p - s)) * normal.dot(&view).signum();
        depth < -self.behind
    }

    /// The unit normal of the surface at kept point `i`: the direction of
    /// least spread of the kept points within [`NORMAL_REACH`], where they
    /// make a plane (at least [`MIN_NORMAL_POINTS`], flatter than
    /// [`MAX_FLATNESS`]); its sign is arbitrary.
    fn normal_at(&self, i: usize) -> Option<Vector3<f64>> {
        let s = Point3::from(Vector3::from(self.points[i].map(f64::from)));
        let reach2 = (NORMAL_REACH * NORMAL_REACH) as f32;
        let centre = self.points[i];
        let (mut n, mut sum, mut outer) = (0usize, Vector3::zeros(), Matrix3::zeros());
        self.any_in_ball(&s, NORMAL_REACH, |_, point| {
            if dist2(point, &centre) <= reach2 {
                let d = Vector3::from(point.map(f64::from)) - s.coords;
                n += 1;
                sum += d;
                outer += d * d.transpose();
            }
            false
        });
        if n < MIN_NORMAL_POINTS {
            return None;
        }
        let mean = sum / n as f64;
        let spread = (outer / n as f64 - mean * mean.transpose()).symmetric_eigen();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| spread.eigenvalues[a].total_cmp(&spread.eigenvalues[b]));
        let [least, middle, most] = order.map(|k| spread.eigenvalues[k]);
        // Flat, and spread in two directions (a line of points, a thin
        // edge, has no normal).
        if least > MAX_FLATNESS * middle || middle < MAX_FLATNESS * most {
            return None;
        }
        Some(spread.eigenvectors.column(order[0]).into_owned())
    }

    /// The unit normal (either sign) of the surface at the kept point
    /// nearest to `p` within `radius` (world frame; clamped to the radius
    /// the support was built for): the direction of least spread of the
    /// kept points around it, where they make a plane.
    pub fn normal_near_world(&self, p: &Point3<f64>, radius: f64) -> Option<Vector3<f64>> {
        // A point at distance 0 is the nearest: stopping there loses nothing.
        let (_, nearest) = self.nearest_within(p, radius, 0.0);
        nearest.and_then(|i| self.normal_at(i))
    }

    /// Call `f` on every kept point (index and position) in the cubes that
    /// the ball of `reach` around `c` overlaps (one or two per axis, `reach`
    /// at most the support's radius), until it returns `true`; whether it
    /// did.
    fn any_in_ball(
        &self,
        c: &Point3<f64>,
        reach: f64,
        mut f: impl FnMut(usize, &[f32; 3]) -> bool,
    ) -> bool {
        let inv = 1.0 / self.radius;
        let xyz = [c.x, c.y, c.z];
        let lo = xyz.map(|v| floor_i64((v - reach) * inv));
        let hi = xyz.map(|v| floor_i64((v + reach) * inv));
        // The cube holding `c` first: the nearest points are most often
        // there, and a search that stops at one stops soonest.
        let home = xyz.map(|v| floor_i64(v * inv));
        let mut visit_bucket = |b: u32| {
            let start = self.starts[b as usize] as usize;
            let end = self.starts[b as usize + 1] as usize;
            (start..end)
                .zip(&self.points[start..end])
                .any(|(i, point)| f(i, point))
        };
        if let Some(&b) = self.buckets.get(&bucket_key(home)) {
            if visit_bucket(b) {
                return true;
            }
        }
        // Then the others in x, y, z order, each column found once and the
        // cubes wholly beyond `reach` skipped (a little margin for the
        // points' f32 rounding).
        let (size, reach2) = (self.radius, (reach + 1e-4) * (reach + 1e-4));
        for cx in lo[0]..=hi[0] {
            let gx = gap2(xyz[0], cx, size);
            for cy in lo[1]..=hi[1] {
                let gxy = gx + gap2(xyz[1], cy, size);
                if gxy > reach2 {
                    continue;
                }
                let Some(&(start, len)) = self.columns.get(&column_key(cx, cy)) else {
                    continue;
                };
                let column = &self.column_cubes[start as usize..(start + len) as usize];
                for &(cz, b) in column {
                    let cz = i64::from(cz);
                    if cz > hi[2] {
                        break;
                    }
                    if cz < lo[2] || [cx, cy, cz] == home || gxy + gap2(xyz[2], cz, size) > reach2 {
                        continue;
                    }
                    if visit_bucket(b) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// A view answering in the sensor frame of a frame with pose `pose`.
    pub fn in_sensor_frame(&self, pose: Isometry3<f64>) -> SensorFrameSupport<'_> {
        SensorFrameSupport { world: self, pose }
    }
}

/// [`WorldSupport`] seen from one sensor pose.
pub struct SensorFrameSupport<'a> {
    world: &'a WorldSupport,
    pose: Isometry3<f64>,
}

impl SurfaceSupport for SensorFrameSupport<'_> {
    fn near(&self, p: &Point3<f64>, radius: f64) -> bool {
        self.world.near_world(&(self.pose * p), radius)
    }

    fn normal_near(&self, p: &Point3<f64>, radius: f64) -> Option<Vector3<f64>> {
        self.world
            .normal_near_world(&(self.pose * p), radius)
            .map(|n| self.pose.rotation.inverse() * n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_queries_match_brute_force() {
        let mut rng = crate::rng::SplitMix64::new(3);
        let pts: Vec<Point3<f64>> = (0..2000)
            .map(|_| Point3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 4.0 - 2.0, rng.unit()))
            .collect();
        let support = WorldSupport::build(pts.iter().copied(), 1e-6, 0.3);
        assert_eq!(support.len(), 2000);
        for _ in 0..500 {
            let q = Point3::new(
                rng.unit() * 5.0 - 2.5,
                rng.unit() * 5.0 - 2.5,
                rng.unit() * 1.5 - 0.25,
            );
            for r in [0.05, 0.2, 0.3] {
                let brute = pts.iter().any(|p| (p - q).norm() <= r - 1e-6);
                let fast = support.near_world(&q, r);
                if brute {
                    assert!(fast, "missed a point within {r} of {q}");
                }
                if fast {
                    assert!(pts.iter().any(|p| (p - q).norm() <= r + 1e-5));
                }
            }
        }
    }

    /// A 2 x 2 m wall at x = 0, one point every 0.04 m.
    fn wall_at_x0() -> Vec<Point3<f64>> {
        (-25..=25)
            .flat_map(|i| {
                (-25..=25).map(move |k| Point3::new(0.0, i as f64 * 0.04, k as f64 * 0.04))
            })
            .collect()
    }

    /// A wall at x = 0 seen from x = 3: a mirror image 0.3 m behind it is
    /// not supported with the behind test, and is without; one 0.1 m behind
    /// it, one in front of it and one beside its edge are supported either
    /// way.
    #[test]
    fn an_image_behind_a_seen_wall_is_not_supported() {
        let wall = wall_at_x0();
        let build = |behind: Option<f64>| {
            let mut b = SupportBuilder::new(0.01, 0.316);
            if let Some(behind) = behind {
                b = b.with_behind(behind);
            }
            b.extend(Point3::new(3.0, 0.5, 0.2), wall.iter().copied());
            b.finish()
        };
        let (on, off) = (build(Some(0.2)), build(None));
        let behind = Point3::new(-0.3, 0.1, 0.0);
        assert!(!on.near_world(&behind, 0.316));
        assert!(off.near_world(&behind, 0.316));
        for supported in [
            Point3::new(-0.1, 0.1, 0.0),
            Point3::new(0.3, 0.1, 0.0),
            Point3::new(0.0, 1.25, 0.0),
            Point3::new(-0.05, 1.2, 0.3),
        ] {
            assert!(on.near_world(&supported, 0.316), "{supported}");
            assert!(off.near_world(&supported, 0.316), "{supported}");
        }
    }

    /// The surface normal near a point: a wall's normal (either sign) where
    /// its points make a plane, turned into a sensor frame with the pose's
    /// rotation; none beyond the radius or at a lone line of points.
    #[test]
    fn the_normal_near_an_image_is_its_surfaces_turned_into_the_sensor_frame() {
        let wall = wall_at_x0();
        let line: Vec<Point3<f64>> = (0..40)
            .map(|i| Point3::new(5.0, i as f64 * 0.04, 0.0))
            .collect();
        let support = WorldSupport::build(wall.into_iter().chain(line), 0.01, 0.316);
        let n = support
            .normal_near_world(&Point3::new(0.1, 0.2, 0.3), 0.316)
            .expect("a plane there");
        assert!(n.x.abs() > 0.999, "{n}");
        assert!(support
            .normal_near_world(&Point3::new(0.5, 0.2, 0.3), 0.316)
            .is_none());
        assert!(support
            .normal_near_world(&Point3::new(5.0, 0.6, 0.0), 0.316)
            .is_none());
        let pose = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.0, 0.0, 0.7));
        let in_sensor = pose.inverse() * Point3::new(0.1, 0.2, 0.3);
        let turned = support
            .in_sensor_frame(pose)
            .normal_near(&in_sensor, 0.316)
            .expect("a plane there");
        let want = pose.rotation.inverse() * Vector3::x();
        assert!(turned.dot(&want).abs() > 0.999, "{turned} against {want}");
    }

    /// With the behind test a supported image still has a kept point within
    /// the radius, and one with a kept point within the behind distance is
    /// supported, on random surfaces seen from random places.
    #[test]
    fn the_behind_test_keeps_the_radius_bounds() {
        let mut rng = crate::rng::SplitMix64::new(5);
        let mut b = SupportBuilder::new(1e-6, 0.3).with_behind(0.1);
        let mut pts = Vec::new();
        for _ in 0..20 {
            let origin = Point3::new(rng.unit() * 6.0 - 3.0, rng.unit() * 6.0 - 3.0, 1.0);
            let batch: Vec<Point3<f64>> = (0..100)
                .map(|_| Point3::new(rng.unit() * 4.0 - 2.0, rng.unit() * 4.0 - 2.0, rng.unit()))
                .collect();
            b.extend(origin, batch.iter().copied());
            pts.extend(batch);
        }
        let support = b.finish();
        for _ in 0..500 {
            let q = Point3::new(rng.unit() * 5.0 - 2.5, rng.unit() * 5.0 - 2.5, rng.unit());
            let nearest = pts
                .iter()
                .map(|p| (p - q).norm())
                .fold(f64::INFINITY, f64::min);
            let near = support.near_world(&q, 0.3);
            if nearest <= 0.1 - 1e-5 {
                assert!(near, "{q}: a point {nearest} away");
            }
            if near {
                assert!(nearest <= 0.3 + 1e-5, "{q}: nearest {nearest}");
            }
        }
    }
}
