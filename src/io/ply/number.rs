//! Decimal numbers of the ascii body, parsed by the `fast-float2` crate
//! (Lemire's algorithm, correctly rounded, no allocation).
//!
//! A field's value is exactly what `str::parse` gives for its token:
//! `[+-]digits[.digits][(e|E)[+-]digits]` (also `5.` and `.5`), `nan`,
//! `inf` and `infinity` in any case, correctly rounded to `f32` for
//! coordinates and intensity and to `f64` for the integer fields (which the
//! caller then checks). The tests below hold it to the standard library on
//! the forms of the real files, on odd forms and on arbitrary bytes.
//!
//! ## Why a crate, measured
//!
//! Until commit 53f89e2 the ascii body had its own parser: a SWAR/SSE2 line
//! parser for lines of the usual form and an exact number parser for the
//! rest, about 1,000 lines. Issue 19 set the rule: keep it only if it makes
//! the whole command at least 1.3x faster. It does not, so it was deleted.
//! The whole command, on the ten shared frames (3.8 MB of ascii each):
//!
//! ```text
//! specular detect --frames ../shared/data/3dref-seq1-demo \
//!     --poses ../shared/data/3dref-seq1-demo/hesai_pose.txt \
//!     --out OUT --lean --quiet --force --timings
//! ```
//!
//! on the 2-core development machine, default 2 threads, 41 rounds of
//! back-to-back runs (order alternating, one discarded warm-up run, each
//! round started once the cores were 95% idle; 1-minute load average
//! 0.5-1.7 from the other engineers' jobs), medians:
//!
//! | parser                               | whole command | parse stage    |
//! |--------------------------------------|---------------|----------------|
//! | hand-written (main at 23c1fe2)       | 75.0 ms       | 2.08 ms/frame  |
//! | `fast-float2` (this module)          | 87.0 ms       | 4.68 ms/frame  |
//!
//! The hand-written parser is 1.16x faster on the whole command (median of
//! the paired ratios 1.18, 95% bootstrap interval 1.12-1.20), though 2.9x
//! faster at parsing alone (`cargo bench --bench parse`, one thread: 1.40
//! against 4.03 ms a frame). With a byte loop in place of the ascii body's
//! word-at-a-time token scan, the crate's figure was 94.0 ms (1.25x; 1.23x
//! and 1.28x in two earlier, busier sessions, and 1.37x in 15 runs while
//! other builds were running: parsing is a larger share of the command when
//! the cores are shared). Frames read many times are
//! best converted once to binary PLY (`specular convert`), which parses no
//! numbers at all.
//!
//! Since then, whole numbers of at most four digits (`14.0`: four of the
//! seven fields read per point) skip the general algorithm (the private
//! `small_whole_number`, 25 lines, held to `str::parse` by the tests):
//! paired runs of the whole command as `cargo bench --bench detect` runs it
//! (15 each, one thread), parse 4.56 -> 4.04 ms a frame, the whole command
//! 12.08 -> 11.57 ms a frame.
//!
//! Then short decimals, `[-]digits.digits` with at most 15 digits and no
//! exponent (the coordinates, `-2.6758089`), take Clinger's fast path: the
//! digits as an integer divided by a power of ten, both exact in `f64`, is
//! the correctly rounded `f64`; rounding it to `f32` is correct unless it
//! lies exactly halfway between two `f32` (then the crate decides; the
//! private `short_decimal` and `Field`, held to `str::parse` by the tests,
//! including decimals that round onto such a midpoint). 15 paired runs as
//! above: parse 3.62 -> 3.35 ms a frame, the whole command 10.35 -> 10.04
//! ms a frame (median paired ratio 0.974), outputs identical.

/// Separator bytes: space, \t, \n, \v, \f, \r.
#[inline(always)]
pub(super) fn is_ws(b: u8) -> bool {
    b == b' ' || b.wrapping_sub(b'\t') < 5
}

/// The number at `pos` in `b` when it is the whole token there (the bytes up
/// to the next separator or the end of `b`): its value and the end of the
/// token. `None` when the token is not a number.
#[inline]
pub(super) fn number<F: Field>(b: &[u8], pos: usize) -> Option<(F, usize)> {
    if let Some((v, end)) = small_whole_number(b, pos) {
        return Some((F::from(v), end));
    }
    if let Some((x, end)) = short_decimal(b, pos) {
        if let Some(v) = F::from_short_decimal(x) {
            return Some((v, end));
        }
    }
    let (v, n) = fast_float2::parse_partial::<F, _>(&b[pos..]).ok()?;
    let end = pos + n;
    (end == b.len() || is_ws(b[end])).then_some((v, end))
}

/// The token at `pos` when it is a whole number of at most four digits,
/// written `digits`, `digits.` or `digits.0...0` (no sign, no exponent):
/// its value and the token's end; `None` for every other token.
///
/// These are the intensity, ring, return and label fields of the 3DRef
/// frames (`14.0 36.0 1.0 4.0`), four of the seven fields read per point.
/// Such a value is exact in `f32` and `f64`, so it needs none of the
/// general algorithm's rounding; the tests below hold this path to
/// `str::parse` with the rest.
#[inline(always)]
fn small_whole_number(b: &[u8], pos: usize) -> Option<(u16, usize)> {
    let mut p = pos;
    let mut v = 0u16;
    while p < b.len() && p - pos < 4 && b[p].is_ascii_digit() {
        v = v * 10 + u16::from(b[p] - b'0');
        p += 1;
    }
    if p == pos {
        return None;
    }
    if p < b.len() && b[p] == b'.' {
        p += 1;
        while p < b.len() && b[p] == b'0' {
            p += 1;
        }
    }
    (p == b.len() || is_ws(b[p])).then_some((v, p))
}

/// Exact powers of ten up to the most fraction digits [`short_decimal`]
/// takes.
const POW10: [f64; 16] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
];

/// The token at `pos` when it is a short decimal, `[-]digits.digits` with
/// at most 15 digits in all and no exponent (the coordinates of the 3DRef
/// frames, `-2.6758089`): its value correctly rounded to `f64`, and the
/// token's end; `None` for every other token.
///
/// With at most 15 digits the digits make an integer `m < 10^15` and the
/// value is `m / 10^k` with `k <= 15`: both are exact in `f64`, so one
/// IEEE division gives the correctly rounded `f64` (Clinger's fast path).
#[inline(always)]
fn short_decimal(b: &[u8], pos: usize) -> Option<(f64, usize)> {
    const MAX_DIGITS: usize = 15;
    let negative = b.get(pos) == Some(&b'-');
    let start = pos + usize::from(negative);
    let mut p = start;
    let mut m = 0u64;
    while p < b.len() && b[p].is_ascii_digit() && p - start < MAX_DIGITS {
        m = m * 10 + u64::from(b[p] - b'0');
        p += 1;
    }
    let whole_digits = p - start;
    if whole_digits == 0 || b.get(p) != Some(&b'.') {
        return None;
    }
    p += 1;
    let fraction = p;
    while p < b.len() && b[p].is_ascii_digit() && whole_digits + (p - fraction) < MAX_DIGITS {
        m = m * 10 + u64::from(b[p] - b'0');
        p += 1;
    }
    let k = p - fraction;
    if k == 0 || (p < b.len() && !is_ws(b[p])) {
        return None;
    }
    let x = m as f64 / POW10[k];
    Some((if negative { -x } else { x }, p))
}

/// A field type: parsed by `fast-float2`, made from a small whole number,
/// and from a short decimal's correctly rounded `f64` when that gives its
/// own correctly rounded value.
pub(super) trait Field: fast_float2::FastFloat + From<u16> {
    /// The correctly rounded value of the decimal whose correctly rounded
    /// `f64` is `x`, when `x` determines it.
    fn from_short_decimal(x: f64) -> Option<Self>;
}

impl Field for f64 {
    #[inline(always)]
    fn from_short_decimal(x: f64) -> Option<Self> {
        Some(x)
    }
}

impl Field for f32 {
    /// Rounding `x` again to `f32` gives the decimal's own rounding unless
    /// `x` lies exactly halfway between two `f32` (every such midpoint is
    /// an `f64`, so a decimal on one side of it rounds to an `x` on the
    /// same side or onto it): then `None`, and the general algorithm
    /// decides. Short decimals stay in `f32`'s normal range.
    #[inline(always)]
    fn from_short_decimal(x: f64) -> Option<Self> {
        // The 29 low mantissa bits that `f32` drops are exactly one half.
        let halfway = x.to_bits() & ((1 << 29) - 1) == 1 << 28;
        (!halfway).then_some(x as f32)
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// The standard library's answer for the token at the start of `b`:
    /// the value and the token's length.
    fn std_number<F: std::str::FromStr>(b: &[u8]) -> Option<(F, usize)> {
        let end = b.iter().position(|&c| is_ws(c)).unwrap_or(b.len());
        let v = std::str::from_utf8(&b[..end]).ok()?.parse::<F>().ok()?;
        Some((v, end))
    }

    /// `number` and `std_number` agree on `b`, for `f32` and `f64` (NaNs
    /// of either sign are equal: they are dropped or rejected alike).
    fn agree(b: &[u8]) -> Result<(), String> {
        let same32 = |x: f32, y: f32| x.to_bits() == y.to_bits() || x.is_nan() && y.is_nan();
        let same64 = |x: f64, y: f64| x.to_bits() == y.to_bits() || x.is_nan() && y.is_nan();
        let (a, s) = (number::<f32>(b, 0), std_number::<f32>(b));
        let ok32 = match (a, s) {
            (None, None) => true,
            (Some((x, i)), Some((y, j))) => same32(x, y) && i == j,
            _ => false,
        };
        let (a64, s64) = (number::<f64>(b, 0), std_number::<f64>(b));
        let ok64 = match (a64, s64) {
            (None, None) => true,
            (Some((x, i)), Some((y, j))) => same64(x, y) && i == j,
            _ => false,
        };
        if ok32 && ok64 {
            Ok(())
        } else {
            Err(format!(
                "{:?}: f32 {a:?} vs std {s:?}, f64 {a64:?} vs std {s64:?}",
                String::from_utf8_lossy(b)
            ))
        }
    }

    #[test]
    fn listed_forms_match_std() {
        let forms = [
            "0",
            "-0",
            "-0.0",
            "1",
            "14.0",
            "36.0",
            "2.6758089",
            "-0.48358452",
            "-0.001302886288613081",
            "0.988094687461853",
            "1e5",
            "1.5E-3",
            "1.e5",
            "+3.25",
            ".5",
            "-.5",
            "5.",
            "9007199254740993",
            "1048576.0625",
            "16777217.0",
            // 15 digits whose f64 is an f32 midpoint, though they are not.
            "2.10236132144928",
            "64.2085075378418",
            "59.3325252532959",
            "9.55862283706665",
            "3.83785617351532",
            "0.000000000000000000001",
            "123456789012345678901234567890",
            "1e22",
            "1e-22",
            "1e-50",
            "1e39",
            "1e99999999999999999999",
            "3.4028235e38",
            "3.4028236e38",
            "1.4e-45",
            "nan",
            "NaN",
            "-nan",
            "+nan",
            "inf",
            "-inf",
            "+Inf",
            "infinity",
            "-Infinity",
            "INFINITY",
            "",
            "-",
            "+",
            ".",
            "-.",
            "e5",
            ".e5",
            "1e",
            "1e+",
            "1.5e",
            "1x",
            "1.5.5",
            "--1",
            "+-1",
            "1,5",
            "0x1p3",
            "1.5-",
            "infin",
            "infinityx",
            "nana",
            "nan(1)",
            "1_000",
            "x",
            "\u{e9}",
        ];
        for s in forms {
            for tail in ["", " ", "\t1", "\n", "\r\n", "\x0b", "\x0c"] {
                let b = format!("{s}{tail}");
                agree(b.as_bytes()).unwrap();
            }
            // A number is a whole token: one followed by another byte is not.
            let b = format!("{s}x");
            assert_eq!(number::<f64>(b.as_bytes(), 0), None, "{s}x");
        }
        // At an offset, with the end of the token returned.
        assert_eq!(number::<f32>(b"1 -2.5 3", 2), Some((-2.5, 6)));
        assert_eq!(number::<f64>(b"1 36.0", 2), Some((36.0, 6)));
    }

    proptest! {
        /// Every `f32` reads back as itself from its shortest, exponent and
        /// fixed forms, and agrees with the standard library.
        #[test]
        fn f32_forms_match_std(bits in any::<u32>(), prec in 0usize..20) {
            let x = f32::from_bits(bits);
            for s in [format!("{x}"), format!("{x:e}"), format!("{x:.prec$}")] {
                prop_assert!(agree(format!("{s} ").as_bytes()).is_ok(), "{}", s);
            }
            if x.is_finite() {
                let s = format!("{x}");
                prop_assert_eq!(number::<f32>(s.as_bytes(), 0).map(|(v, _)| v.to_bits()), Some(bits));
            }
        }

        #[test]
        fn f64_forms_match_std(v in proptest::num::f64::ANY, digits in 1usize..25) {
            for s in [format!("{v:.digits$e}"), format!("{v}"), format!("{v:.digits$}")] {
                prop_assert!(agree(s.as_bytes()).is_ok(), "{}", s);
            }
        }

        /// Strings of number characters and decimal forms, most of them
        /// not numbers.
        #[test]
        fn number_like_strings_match_std(
            s in "[-+]?[0-9.eE+-]{0,12}|[-+]?[0-9]{0,25}\\.?[0-9]{0,25}([eE][-+]?[0-9]{0,4})?|[-+]?(?i:nan|inf|infinity)[a-z]?",
            tail in prop::sample::select(vec!["", " ", "\n", "\r", "x"]),
        ) {
            let b = format!("{s}{tail}");
            let r = agree(b.as_bytes());
            prop_assert!(r.is_ok(), "{}", r.unwrap_err());
        }

        /// Whole numbers as the integer fields are written (`14.0`, `7`,
        /// `0036.000`, `5.`), and near misses (five digits, a fraction):
        /// the short path and the general one agree with the standard
        /// library.
        #[test]
        fn whole_number_forms_match_std(
            s in "[0-9]{1,6}(\\.0{0,3}[0-9]?)?",
            tail in prop::sample::select(vec!["", " ", "\n", "\t", "x", "e1"]),
        ) {
            let b = format!("{s}{tail}");
            let r = agree(b.as_bytes());
            prop_assert!(r.is_ok(), "{}", r.unwrap_err());
        }

        /// Decimals as the coordinates are written (`-2.6758089`), up to and
        /// past the short path's 15 digits, and `f32` midpoints (which the
        /// short path hands to the general one): every path agrees with the
        /// standard library.
        #[test]
        fn short_decimal_forms_match_std(
            s in "-?[0-9]{1,9}\\.[0-9]{1,9}",
            tail in prop::sample::select(vec!["", " ", "\n", "x", "e1", "5"]),
        ) {
            let b = format!("{s}{tail}");
            let r = agree(b.as_bytes());
            prop_assert!(r.is_ok(), "{}", r.unwrap_err());
        }

        /// Halfway between two neighbouring `f32`: written exactly, and
        /// as the nearest decimal of 15 digits, which the `f64` division
        /// may round onto the midpoint although it is not (then rounding
        /// that `f64` to `f32` could go the wrong way, and the short path
        /// must hand the token on).
        #[test]
        fn f32_midpoints_match_std(bits in 0x3000_0000u32..0x4C80_0000) {
            let lo = f32::from_bits(bits) as f64;
            let hi = f32::from_bits(bits + 1) as f64;
            let mid = (lo + hi) / 2.0;
            let whole_digits = if mid >= 1.0 { mid.log10().floor() as usize + 1 } else { 1 };
            let k = 15usize.saturating_sub(whole_digits).max(1);
            for s in [format!("{mid}"), format!("{mid:.k$}")] {
                let r = agree(s.as_bytes());
                prop_assert!(r.is_ok(), "{}", r.unwrap_err());
            }
        }

        /// Arbitrary bytes: no panic, and the standard library's answer.
        #[test]
        fn arbitrary_bytes_match_std(b in proptest::collection::vec(any::<u8>(), 0..40)) {
            let r = agree(&b);
            prop_assert!(r.is_ok(), "{}", r.unwrap_err());
        }
    }
}
