//! Returns paired by the order a driver writes them, for layouts without a
//! return index ([`super::drivers::HesaiLayout`]).

use crate::cloud::Point;

/// No open point in a ring.
const NONE: u32 = u32::MAX;

/// Mark the returns of `points` (message order) where two consecutive
/// points of a ring (the later not yet paired) lie within `tolerance_deg`
/// of azimuth: one firing's two echoes. The nearer becomes return 1 and
/// the farther return 2; a second echo at exactly the first's position is
/// the same echo written twice and is made a non-return (NaN), so the
/// reader sets it aside. Every other point is return 1. Points that are
/// not returns ([`Point::is_return`]) are skipped.
pub(super) fn pair_by_order(points: &mut [Point], tolerance_deg: f64) {
    let rings = points
        .iter()
        .map(|p| p.ring as usize + 1)
        .max()
        .unwrap_or(0);
    let mut open = vec![NONE; rings];
    for i in 0..points.len() {
        let p = points[i];
        if !p.is_return() {
            continue;
        }
        let ring = p.ring as usize;
        let j = open[ring];
        if j != NONE && azimuth_gap_deg(&points[j as usize], &p) <= tolerance_deg {
            open[ring] = NONE;
            let j = j as usize;
            if points[j].xyz == p.xyz {
                points[i].xyz = [f32::NAN; 3];
            } else if p.range() < points[j].range() {
                points[j].ret = 2;
                points[i].ret = 1;
            } else {
                points[i].ret = 2;
            }
            continue;
        }
        points[i].ret = 1;
        open[ring] = i as u32;
    }
}

/// The azimuth difference of two points, degrees in [0, 180].
fn azimuth_gap_deg(a: &Point, b: &Point) -> f64 {
    let az = |p: &Point| (p.xyz[1] as f64).atan2(p.xyz[0] as f64).to_degrees();
    let d = (az(a) - az(b)).rem_euclid(360.0);
    d.min(360.0 - d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::test_point as point;

    #[test]
    fn consecutive_echoes_of_a_ring_at_one_azimuth_are_paired() {
        let mut points = vec![
            point(5.0, 0.0, 0.0, 3, 0),   // ring 3, first echo
            point(2.0, 0.0, 0.0, 4, 0),   // ring 4, alone at this azimuth
            point(9.0, 0.0, 0.0, 3, 0),   // ring 3, farther: return 2
            point(4.0, 0.1, 0.0, 3, 0),   // ring 3, next column (1.4 deg)
            point(3.0, 0.075, 0.0, 3, 0), // nearer than its partner: return 1
            point(2.0, 0.0, 0.0, 4, 0),   // same echo twice: set aside
        ];
        pair_by_order(&mut points, 0.3);
        let rets: Vec<u8> = points.iter().map(|p| p.ret).collect();
        assert_eq!(&rets[..5], &[1, 1, 2, 2, 1]);
        assert!(points[5].xyz[0].is_nan());
    }
}
