//! Property tests of the geometry identities: planes, charts and convex
//! polygons (SO(3) and SE(3): `lie_props.rs`).

mod common;

use common::strategies::{isometry, point3, vec3};
use nalgebra::{Point2, Point3, Vector3};
use proptest::prelude::*;
use specular::geometry::{ConvexPolygon, Plane, PlaneChart};

// ---------------------------------------------------------------- strategies

/// Random planes, with exactly and nearly horizontal ones mixed in so the
/// chart's fallback axis is exercised.
fn plane() -> impl Strategy<Value = Plane> {
    let normal = prop_oneof![
        6 => vec3(1.0),
        1 => Just(Vector3::z()),
        1 => Just(-Vector3::z()),
        1 => vec3(1e-7).prop_map(|e| Vector3::z() + e),
    ];
    (normal, -20.0..20.0f64).prop_filter_map("degenerate normal", |(n, d)| {
        (n.norm() > 0.1).then(|| Plane::new(n, d)).flatten()
    })
}

fn points2(n: std::ops::Range<usize>, r: f64) -> impl Strategy<Value = Vec<Point2<f64>>> {
    prop::collection::vec((-r..r, -r..r).prop_map(|(x, y)| Point2::new(x, y)), n)
}

fn polygon() -> impl Strategy<Value = ConvexPolygon> {
    points2(3..16, 10.0)
        .prop_map(|p| ConvexPolygon::hull(&p))
        .prop_filter("degenerate polygon", |p| p.area() > 1e-3)
}

// ------------------------------------------------------------------- helpers

fn scale(p: &Plane, pts: &[&Point3<f64>]) -> f64 {
    1.0 + p.d.abs() + pts.iter().map(|q| q.coords.norm()).sum::<f64>()
}

fn cross2(o: &Point2<f64>, a: &Point2<f64>, b: &Point2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

fn assert_convex_ccw(p: &ConvexPolygon) -> Result<(), TestCaseError> {
    let v = p.vertices();
    let n = v.len();
    for i in 0..n {
        let c = cross2(&v[i], &v[(i + 1) % n], &v[(i + 2) % n]);
        prop_assert!(c > 0.0, "not strictly convex CCW at {i}: {c} in {v:?}");
    }
    Ok(())
}

fn p2(x: f64, y: f64) -> Point2<f64> {
    Point2::new(x, y)
}

// -------------------------------------------------------------------- planes

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn mirror_is_involution(pl in plane(), p in point3(50.0)) {
        let back = pl.mirror(&pl.mirror(&p));
        prop_assert!((back - p).norm() < 1e-12 * scale(&pl, &[&p]));
        let v = p.coords;
        prop_assert!((pl.mirror_vector(&pl.mirror_vector(&v)) - v).norm() < 1e-12 * (1.0 + v.norm()));
    }

    #[test]
    fn mirror_flips_signed_distance(pl in plane(), p in point3(50.0)) {
        let s = pl.signed_distance(&p);
        let m = pl.signed_distance(&pl.mirror(&p));
        prop_assert!((m + s).abs() < 1e-12 * scale(&pl, &[&p]));
    }

    #[test]
    fn mirror_is_isometry(pl in plane(), p in point3(50.0), q in point3(50.0)) {
        let d0 = (p - q).norm();
        let d1 = (pl.mirror(&p) - pl.mirror(&q)).norm();
        prop_assert!((d0 - d1).abs() < 1e-12 * scale(&pl, &[&p, &q]));
    }

    #[test]
    fn transform_agrees_with_points(pl in plane(), t in isometry(), p in point3(50.0)) {
        let pt = pl.transformed(&t);
        prop_assert!((pt.normal.norm() - 1.0).abs() < 1e-12);
        // A point on the plane maps onto the transformed plane.
        let on = pl.project(&p);
        let tol = 1e-12 * (scale(&pl, &[&p]) + t.translation.vector.norm());
        prop_assert!(pt.signed_distance(&(t * on)).abs() < tol);
        // Signed distance is invariant.
        prop_assert!((pt.signed_distance(&(t * p)) - pl.signed_distance(&p)).abs() < tol);
    }

    #[test]
    fn transform_round_trip(pl in plane(), t in isometry()) {
        let back = pl.transformed(&t).transformed(&t.inverse());
        prop_assert!((back.normal - pl.normal).norm() < 1e-12);
        prop_assert!((back.d - pl.d).abs() < 1e-12 * (1.0 + pl.d.abs() + t.translation.vector.norm()));
    }

    #[test]
    fn projection_on_plane_and_idempotent(pl in plane(), p in point3(50.0)) {
        let q = pl.project(&p);
        let tol = 1e-12 * scale(&pl, &[&p]);
        prop_assert!(pl.signed_distance(&q).abs() < tol);
        prop_assert!((pl.project(&q) - q).norm() < tol);
    }

    #[test]
    fn ray_hit_lies_on_plane(pl in plane(), o in point3(50.0), dir in vec3(1.0)) {
        prop_assume!(dir.norm() > 1e-3);
        let toward = pl.signed_distance(&o) * pl.normal.dot(&dir) < 0.0
            && pl.normal.dot(&dir).abs() >= 1e-9 * dir.norm();
        match pl.ray_intersection(&o, &dir) {
            Some(t) => {
                prop_assert!(t > 0.0);
                let hit = o + dir * t;
                prop_assert!(pl.signed_distance(&hit).abs() < 1e-11 * scale(&pl, &[&o, &hit]));
            }
            None => prop_assert!(!toward, "missed a ray pointing at the plane"),
        }
    }

    #[test]
    fn facing_puts_viewpoint_in_front(pl in plane(), vp in point3(50.0)) {
        let f = pl.facing(&vp);
        prop_assert!(f.signed_distance(&vp) >= 0.0);
        prop_assert!(f == pl || f == pl.flipped());
    }

    // ---------------------------------------------------------------- charts

    #[test]
    fn chart_round_trip_is_projection(pl in plane(), p in point3(50.0)) {
        let c = PlaneChart::of(&pl);
        let back = c.to_3d(&c.to_2d(&p));
        prop_assert!((back - pl.project(&p)).norm() < 1e-12 * scale(&pl, &[&p]));
        prop_assert!(pl.signed_distance(&c.origin).abs() < 1e-12 * (1.0 + pl.d.abs()));
    }

    #[test]
    fn chart_axes_orthonormal(pl in plane()) {
        let c = PlaneChart::of(&pl);
        for a in [c.u, c.v, c.normal] {
            prop_assert!((a.norm() - 1.0).abs() < 1e-12);
        }
        prop_assert!(c.u.dot(&c.v).abs() < 1e-12);
        prop_assert!(c.u.dot(&c.normal).abs() < 1e-12);
        prop_assert!(c.v.dot(&c.normal).abs() < 1e-12);
        prop_assert!((c.u.cross(&c.v) - c.normal).norm() < 1e-12);
        prop_assert!((c.normal - pl.normal).norm() < 1e-12);
    }


    // ---------------------------------------------------------- plane sums

    /// The incremental plane fit recovers the plane its points lie on,
    /// whatever the reference point, and equals the batch fit.
    #[test]
    fn plane_sums_recover_the_plane(
        pl in plane(),
        uv in proptest::collection::vec((-5.0..5.0f64, -5.0..5.0f64), 3..60),
        reference in point3(30.0),
    ) {
        let c = PlaneChart::of(&pl);
        let pts: Vec<Point3<f64>> =
            uv.iter().map(|&(u, v)| c.to_3d(&Point2::new(u, v))).collect();
        let mut sums = specular::geometry::fit::PlaneSums::new(reference);
        for p in &pts {
            sums.add(p, 1.0);
        }
        let batch = specular::geometry::fit::fit_plane(pts.iter().copied());
        // Nearly collinear points: the two may round either way.
        let flat = |f: &Option<(Plane, [f64; 3])>| f.is_some_and(|(_, v)| v[1] < 1e-6);
        let fit = sums.fit();
        prop_assume!(!flat(&fit) && !flat(&batch));
        match (fit, batch) {
            (Some((fit, values)), Some((b, _))) => {
                prop_assert!(fit.normal.dot(&pl.normal).abs() > 1.0 - 1e-9);
                prop_assert!(fit.normal.dot(&b.normal).abs() > 1.0 - 1e-9);
                for p in &pts {
                    prop_assert!(fit.signed_distance(p).abs() < 1e-6 * scale(&pl, &[&reference]));
                }
                prop_assert!(values[0] <= values[1] && values[1] <= values[2]);
            }
            // Both call collinear points degenerate, or neither does.
            (None, None) => {}
            (a, b) => prop_assert!(false, "incremental {:?} against batch {:?}", a, b),
        }
    }

    /// Merging the sums of two halves gives the sums of the whole, and a
    /// point of tiny weight barely moves the plane.
    #[test]
    fn plane_sums_merge_and_weigh(
        pl in plane(),
        uv in proptest::collection::vec((-5.0..5.0f64, -5.0..5.0f64), 6..40),
        split in 1usize..5,
        off in 0.5..5.0f64,
    ) {
        let c = PlaneChart::of(&pl);
        let pts: Vec<Point3<f64>> =
            uv.iter().map(|&(u, v)| c.to_3d(&Point2::new(u, v))).collect();
        let reference = c.origin;
        let mut whole = specular::geometry::fit::PlaneSums::new(reference);
        let (mut a, mut b) = (whole.clone(), whole.clone());
        for (k, p) in pts.iter().enumerate() {
            whole.add(p, 1.0);
            if k < split { a.add(p, 1.0) } else { b.add(p, 1.0) }
        }
        a.merge(&b);
        prop_assert_eq!(a.count(), whole.count());
        let (ca, cw) = (a.centroid().unwrap(), whole.centroid().unwrap());
        prop_assert!((ca - cw).norm() < 1e-9 * scale(&pl, &[]));
        // An outlier `off` metres off the plane with a millionth of a
        // point's weight moves the plane by about a millionth of that.
        let Some((before, _)) = whole.fit() else { return Ok(()) };
        whole.add(&(pts[0] + pl.normal * off), 1e-6);
        let (after, _) = whole.fit().unwrap();
        prop_assert!(after.signed_distance(&cw).abs() < 1e-4 * off);
        prop_assert!(after.normal.dot(&before.normal).abs() > 1.0 - 1e-6);
    }
    // -------------------------------------------------------------- polygons

    #[test]
    fn hull_contains_points_and_is_convex_ccw(pts in points2(0..40, 100.0)) {
        let h = ConvexPolygon::hull(&pts);
        if h.is_empty() {
            prop_assert_eq!(h.area(), 0.0);
            return Ok(());
        }
        for p in &pts {
            prop_assert!(h.contains(p), "{p} not in {:?}", h.vertices());
        }
        assert_convex_ccw(&h)?;
        // The hull's vertices are input points.
        for v in h.vertices() {
            prop_assert!(pts.contains(v));
        }
        // Re-hulling is the identity.
        prop_assert_eq!(ConvexPolygon::from_vertices(h.vertices().to_vec()), h.clone());
        // The centroid is inside.
        let c = h.centroid().expect("non-empty");
        prop_assert!(h.contains(&c));
    }

    #[test]
    fn hull_of_collinear_points_is_empty(
        o in (-50.0..50.0f64, -50.0..50.0f64),
        d in (-1.0..1.0f64, -1.0..1.0f64),
        ts in prop::collection::vec(-10i32..10, 0..12),
    ) {
        // Integer steps along an exactly representable direction: collinear
        // up to rounding of the products only.
        let pts: Vec<_> = ts.iter().map(|&t| p2(o.0 + d.0 * f64::from(t), o.1 + d.1 * f64::from(t))).collect();
        prop_assert!(ConvexPolygon::hull(&pts).is_empty());
    }

    #[test]
    fn intersection_bounded_and_symmetric(a in polygon(), b in polygon()) {
        let ab = a.intersection(&b);
        let ba = b.intersection(&a);
        let tol = 1e-9 * (1.0 + a.area().max(b.area()));
        prop_assert!(ab.area() <= a.area().min(b.area()) + tol);
        prop_assert!((ab.area() - ba.area()).abs() < tol);
        if !ab.is_empty() {
            assert_convex_ccw(&ab)?;
            for v in ab.vertices() {
                prop_assert!(a.signed_distance(v) < 1e-9 && b.signed_distance(v) < 1e-9);
            }
        }
    }

    #[test]
    fn self_intersection_keeps_area(a in polygon()) {
        let aa = a.intersection(&a);
        prop_assert!((aa.area() - a.area()).abs() < 1e-9 * (1.0 + a.area()));
    }

    #[test]
    fn union_hull_contains_both(a in polygon(), b in polygon()) {
        let u = a.union_hull(&b);
        for v in a.vertices().iter().chain(b.vertices()) {
            prop_assert!(u.contains(v));
        }
        prop_assert!(u.area() >= a.area().max(b.area()) - 1e-9);
        assert_convex_ccw(&u)?;
    }

    #[test]
    fn contains_agrees_with_signed_distance(a in polygon(), q in (-15.0..15.0f64, -15.0..15.0f64)) {
        let q = p2(q.0, q.1);
        let sd = a.signed_distance(&q);
        prop_assume!(sd.abs() > 1e-6);
        prop_assert_eq!(a.contains(&q), sd < 0.0);
        // Outside, the distance is attained at a boundary point.
        let nearest_vertex = a.vertices().iter().map(|v| (v - q).norm()).fold(f64::INFINITY, f64::min);
        prop_assert!(sd.abs() <= nearest_vertex + 1e-12);
    }

    #[test]
    fn offset_grows_and_shrinks(a in polygon(), m in 0.01..5.0f64) {
        let g = a.offset(m);
        for v in a.vertices() {
            prop_assert!(g.contains(v));
            // Every original vertex is at least m inside the grown polygon.
            prop_assert!(g.signed_distance(v) <= -m + 1e-9);
        }
        prop_assert!(g.area() >= a.area());
        assert_convex_ccw(&g)?;
        let s = a.offset(-m);
        for v in s.vertices() {
            prop_assert!(a.contains(v));
            prop_assert!(a.signed_distance(v) <= -m + 1e-9);
        }
        prop_assert!(s.area() <= a.area());
        if !s.is_empty() {
            assert_convex_ccw(&s)?;
        }
    }

    #[test]
    fn rectangle_area_and_translation(
        x0 in -50.0..50.0f64, y0 in -50.0..50.0f64, w in 0.01..20.0f64, h in 0.01..20.0f64,
    ) {
        let r = ConvexPolygon::rectangle(p2(x0, y0), p2(x0 + w, y0 + h));
        prop_assert!((r.area() - w * h).abs() < 1e-9 * (1.0 + w * h));
        let c = r.centroid().expect("non-empty");
        prop_assert!((c - p2(x0 + w / 2.0, y0 + h / 2.0)).norm() < 1e-9);
        // Overlap with the same rectangle shifted by half its width.
        let s = ConvexPolygon::rectangle(p2(x0 + w / 2.0, y0), p2(x0 + 1.5 * w, y0 + h));
        prop_assert!((r.intersection_area(&s) - w * h / 2.0).abs() < 1e-9 * (1.0 + w * h));
    }
}

// ------------------------------------------------------- known-answer tests

#[test]
fn known_areas() {
    let r = ConvexPolygon::rectangle(p2(-1.0, 2.0), p2(3.0, 4.5));
    assert!((r.area() - 10.0).abs() < 1e-12);
    let t = ConvexPolygon::hull(&[p2(0.0, 0.0), p2(4.0, 0.0), p2(0.0, 3.0)]);
    assert!((t.area() - 6.0).abs() < 1e-12);
    let c = t.centroid().expect("triangle");
    assert!((c - p2(4.0 / 3.0, 1.0)).norm() < 1e-12);
    // Clockwise input is re-ordered CCW.
    let cw = ConvexPolygon::from_vertices(vec![p2(0.0, 0.0), p2(0.0, 3.0), p2(4.0, 0.0)]);
    assert_eq!(cw, t);
}

#[test]
fn unit_square_intersections() {
    let a = ConvexPolygon::rectangle(p2(0.0, 0.0), p2(1.0, 1.0));
    let b = ConvexPolygon::rectangle(p2(0.5, 0.5), p2(1.5, 1.5));
    assert!((a.intersection_area(&b) - 0.25).abs() < 1e-12);
    let i = a.intersection(&b);
    assert_eq!(i.vertices().len(), 4);
    // Touching along an edge: zero area, empty.
    let c = ConvexPolygon::rectangle(p2(1.0, 0.0), p2(2.0, 1.0));
    assert!(a.intersection(&c).is_empty());
    // Disjoint.
    let d = ConvexPolygon::rectangle(p2(3.0, 3.0), p2(4.0, 4.0));
    assert!(a.intersection(&d).is_empty());
    // Nested.
    let e = ConvexPolygon::rectangle(p2(0.25, 0.25), p2(0.75, 0.75));
    assert!((a.intersection_area(&e) - 0.25).abs() < 1e-12);
    // Diamond inside-out: the square rotated 45° about its centre.
    let h = 0.5_f64.sqrt();
    let diamond = ConvexPolygon::hull(&[
        p2(0.5 - h, 0.5),
        p2(0.5, 0.5 - h),
        p2(0.5 + h, 0.5),
        p2(0.5, 0.5 + h),
    ]);
    let oct = a.intersection(&diamond);
    assert_eq!(oct.vertices().len(), 8);
    // Square minus four corner triangles with legs 1 - h... area 2(√2 - 1).
    assert!((oct.area() - 2.0 * (2f64.sqrt() - 1.0)).abs() < 1e-12);
    // Union hull of the two offset squares.
    let u = a.union_hull(&b);
    assert!((u.area() - (2.25 - 2.0 * 0.125)).abs() < 1e-12);
}

#[test]
fn empty_polygon_everywhere() {
    let e = ConvexPolygon::default();
    let a = ConvexPolygon::rectangle(p2(0.0, 0.0), p2(1.0, 1.0));
    assert!(e.intersection(&a).is_empty());
    assert!(a.intersection(&e).is_empty());
    assert_eq!(e.union_hull(&a), a);
    assert!(e.offset(-1.0).is_empty());
    assert!(a.offset(f64::NAN).is_empty());
    assert!(!a.contains(&p2(f64::NAN, 0.5)));
}

fn wild_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => -10.0..10.0f64,
        1 => prop::num::f64::ANY,
        1 => Just(0.0),
        1 => Just(1e-300),
        1 => Just(1e300),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// No polygon operation panics, whatever the input.
    #[test]
    fn polygon_ops_never_panic(
        a in prop::collection::vec((wild_f64(), wild_f64()), 0..8),
        b in prop::collection::vec((wild_f64(), wild_f64()), 0..8),
        q in (wild_f64(), wild_f64()),
        m in wild_f64(),
    ) {
        let pa: Vec<_> = a.iter().map(|&(x, y)| p2(x, y)).collect();
        let pb: Vec<_> = b.iter().map(|&(x, y)| p2(x, y)).collect();
        let (a, b, q) = (ConvexPolygon::hull(&pa), ConvexPolygon::hull(&pb), p2(q.0, q.1));
        for p in [&a, &b] {
            prop_assert!(p.vertices().iter().all(|v| v.x.is_finite() && v.y.is_finite()));
            let _ = (p.area(), p.centroid(), p.contains(&q), p.signed_distance(&q));
            let _ = (p.offset(m).area(), p.offset(-m).area());
        }
        let _ = (a.intersection(&b).area(), a.union_hull(&b).area());
    }
}
