//! libm-free `floor`, `round` and `atan2` for the per-point hot loops.
//!
//! On the baseline x86-64 target `f64::floor`, `f64::round` and `f64::atan2`
//! are function calls; in voxel hashing and column binning of every point
//! they dominated the run time.

/// `floor(x)` as an integer without a libm call (on the baseline x86-64
/// target `f64::floor` is a function call, which dominated voxel hashing).
/// Saturates like `as` for values outside the `i64` range; NaN gives 0.
#[inline(always)]
pub fn floor_i64(x: f64) -> i64 {
    // With SSE4.1 (x86-64-v2, see .cargo/config.toml) `floor` is one
    // instruction.
    #[cfg(all(target_arch = "x86_64", target_feature = "sse4.1"))]
    {
        x.floor() as i64
    }
    #[cfg(not(all(target_arch = "x86_64", target_feature = "sse4.1")))]
    {
        let i = x as i64;
        if (i as f64) > x {
            i.saturating_sub(1)
        } else {
            i
        }
    }
}

/// `round(x)` (half away from zero) as an integer without a libm call.
#[inline(always)]
pub fn round_i64(x: f64) -> i64 {
    if x >= 0.0 {
        floor_i64(x + 0.5)
    } else {
        -floor_i64(-x + 0.5)
    }
}

/// `atan2(y, x)` in radians without a libm call, accurate to 2e-8 rad
/// (Abramowitz & Stegun 4.4.49 on the octant-reduced argument). The column
/// binning of every point uses it; libm's `atan2` dominated scan pairing.
#[inline]
pub fn fast_atan2(y: f64, x: f64) -> f64 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ay > ax { (ax, ay) } else { (ay, ax) };
    if !(hi > 0.0) {
        // Both zero (or NaN): match atan2's sign conventions for zeros.
        return y.atan2(x);
    }
    let t = lo / hi;
    let t2 = t * t;
    let poly = 1.0
        + t2 * (-0.333_331_452_8
            + t2 * (0.199_935_508_5
                + t2 * (-0.142_088_994_4
                    + t2 * (0.106_562_639_3
                        + t2 * (-0.075_289_640_0
                            + t2 * (0.042_909_613_8
                                + t2 * (-0.016_165_736_7 + t2 * 0.002_866_225_7)))))));
    let mut a = t * poly;
    if ay > ax {
        a = std::f64::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f64::consts::PI - a;
    }
    if y < 0.0 || (y == 0.0 && y.is_sign_negative()) {
        -a
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_atan2_matches_std() {
        let mut rng = crate::rng::SplitMix64::new(9);
        for _ in 0..100_000 {
            let (x, y) = (rng.unit() * 2.0 - 1.0, rng.unit() * 2.0 - 1.0);
            assert!((fast_atan2(y, x) - y.atan2(x)).abs() < 3e-8, "{x} {y}");
        }
        for (y, x) in [
            (0.0, 1.0),
            (0.0, -1.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (1e-300, -1.0),
            (-1e-300, -1.0),
            (0.0, 0.0),
        ] {
            assert!(
                (fast_atan2(y, x) - f64::atan2(y, x)).abs() < 3e-8,
                "{y} {x}"
            );
        }
    }

    #[test]
    fn integer_floor_and_round_match_std() {
        for x in [
            -2.5, -2.0, -1.5, -0.5, -0.0, 0.0, 0.49999, 0.5, 1.5, 2.0, 2.5, 1e15, -1e15, 7.3, -7.3,
        ] {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x}");
            assert_eq!(round_i64(x), x.round() as i64, "round {x}");
        }
    }
}
