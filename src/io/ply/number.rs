//! Decimal numbers of the general ascii path: a fast exact parser for the
//! common forms, the standard library for every other form.

/// Separator bytes: space, \t, \n, \v, \f, \r.
#[inline(always)]
pub(super) fn is_ws(b: u8) -> bool {
    b == b' ' || b.wrapping_sub(b'\t') < 5
}

/// Fast path for an unsigned integer field written as `digits[.0*]`
/// (`36`, `36.0`). `None` for any other form (the caller falls back to the
/// general parser).
#[inline(always)]
pub(super) fn parse_uint_fast(b: &[u8], mut p: usize) -> Option<(f64, usize)> {
    let len = b.len();
    let start = p;
    let mut n: u32 = 0;
    while p < len && p - start < 9 {
        let d = b[p].wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        n = n * 10 + d as u32;
        p += 1;
    }
    if p == start {
        return None;
    }
    if p < len && b[p] == b'.' {
        p += 1;
        while p < len && b[p] == b'0' {
            p += 1;
        }
    }
    if p < len && !is_ws(b[p]) {
        return None;
    }
    Some((n as f64, p))
}

/// Exact powers of ten representable in `f64`.
pub(super) const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Fast path for a decimal number `[+-]digits[.digits][(e|E)[+-]digits]`
/// starting at `p`. Returns the correctly rounded `f64` and the end of the
/// token, or `None` when the token has another form or the value is outside
/// the exact fast path (mantissa above 2^53, more than 19 significant digits,
/// decimal exponent outside ±22); the caller then uses the standard parser.
#[inline(always)]
pub(super) fn parse_fast(b: &[u8], mut p: usize) -> Option<(f64, usize)> {
    let len = b.len();
    let neg = p < len && b[p] == b'-';
    if p < len && (b[p] == b'-' || b[p] == b'+') {
        p += 1;
    }
    let mut m: u64 = 0;
    let mut nd = 0u32; // significant digits in m
    let mut exp: i32 = 0;
    let mut any = false;
    while p < len {
        let d = b[p].wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        any = true;
        if m != 0 || d != 0 {
            if nd >= 19 {
                return None;
            }
            m = m * 10 + d as u64;
            nd += 1;
        }
        p += 1;
    }
    if p < len && b[p] == b'.' {
        p += 1;
        while p < len {
            let d = b[p].wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            any = true;
            if m != 0 || d != 0 {
                if nd >= 19 {
                    return None;
                }
                m = m * 10 + d as u64;
                nd += 1;
            }
            exp -= 1;
            p += 1;
        }
    }
    if !any {
        return None;
    }
    if p < len && (b[p] | 0x20) == b'e' {
        p += 1;
        let eneg = p < len && b[p] == b'-';
        if p < len && (b[p] == b'-' || b[p] == b'+') {
            p += 1;
        }
        let mut e: i32 = 0;
        let mut ed = 0;
        while p < len {
            let d = b[p].wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            if ed >= 4 {
                return None;
            }
            e = e * 10 + d as i32;
            ed += 1;
            p += 1;
        }
        if ed == 0 {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if p < len && !is_ws(b[p]) {
        return None;
    }
    let v = if m == 0 {
        0.0
    } else {
        if m > (1u64 << 53) {
            return None;
        }
        // "14.0" -> 14: avoid a division for trailing fractional zeros.
        while exp < 0 && m.is_multiple_of(10) {
            m /= 10;
            exp += 1;
        }
        if (0..=22).contains(&exp) {
            m as f64 * POW10[exp as usize]
        } else if (-22..0).contains(&exp) {
            m as f64 / POW10[(-exp) as usize]
        } else {
            return None;
        }
    };
    Some((if neg { -v } else { v }, p))
}

/// Whether `v` (an `f64` within the normal `f32` range) lies exactly halfway
/// between two `f32` values, where casting could round twice wrongly.
#[inline(always)]
pub(super) fn f32_halfway(v: f64) -> bool {
    v.to_bits() & 0x1FFF_FFFF == 0x1000_0000
}

/// Slow path: parse the token with the standard library.
#[cold]
pub(super) fn parse_slow_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse::<f64>().ok()
}

/// [`parse_slow_f64`] for `f32`.
#[cold]
pub(super) fn parse_slow_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok).ok()?.parse::<f32>().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fast(s: &str) -> Option<f64> {
        parse_fast(s.as_bytes(), 0).map(|(v, end)| {
            assert_eq!(end, s.len());
            v
        })
    }

    #[test]
    fn fast_parser_matches_std() {
        for s in [
            "0",
            "-0",
            "1",
            "14.0",
            "2.6758089",
            "-0.001302886288613081",
            "0.988094687461853",
            "1e5",
            "1.5E-3",
            "+3.25",
            ".5",
            "5.",
            "9007199254740992",
            "1234567890123456",
            "0.000000000000000000001",
            "1e22",
            "1e-22",
        ] {
            let v = fast(s).unwrap_or_else(|| panic!("fast path failed on {s}"));
            assert_eq!(v, s.parse::<f64>().unwrap(), "{s}");
        }
        for s in [
            "", "-", ".", "e5", "1e", "1e+", "nan", "inf", "1x", "1e99999", "1e300",
        ] {
            assert!(fast(s).is_none(), "{s}");
        }
    }

    #[test]
    fn halfway_detection() {
        // 1 + 2^-24 is halfway between 1.0f32 and its successor.
        let mid = 1.0f64 + 2f64.powi(-24);
        assert!(f32_halfway(mid));
        assert!(!f32_halfway(1.0));
        assert!(!f32_halfway(1.5f32 as f64));
    }

    proptest::proptest! {
        #[test]
        fn fast_parser_agrees_with_std(v in proptest::num::f64::NORMAL, digits in 1usize..19) {
            let s = format!("{:.*e}", digits, v);
            if let Some(f) = fast(&s) {
                proptest::prop_assert_eq!(f, s.parse::<f64>().unwrap());
            }
            let s = format!("{v}");
            if let Some(f) = fast(&s) {
                proptest::prop_assert_eq!(f, s.parse::<f64>().unwrap());
            }
        }

        #[test]
        fn f32_values_round_trip(bits in proptest::prelude::any::<u32>()) {
            let x = f32::from_bits(bits);
            if x.is_finite() {
                let s = format!("{x}");
                let parsed = match parse_fast(s.as_bytes(), 0) {
                    Some((v, _)) if !f32_halfway(v) => v as f32,
                    _ => s.parse::<f32>().unwrap(),
                };
                proptest::prop_assert_eq!(parsed.to_bits(), x.to_bits());
            }
        }
    }
}
