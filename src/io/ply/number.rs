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

/// Separator bytes: space, \t, \n, \v, \f, \r.
#[inline(always)]
pub(super) fn is_ws(b: u8) -> bool {
    b == b' ' || b.wrapping_sub(b'\t') < 5
}

/// The number at `pos` in `b` when it is the whole token there (the bytes up
/// to the next separator or the end of `b`): its value and the end of the
/// token. `None` when the token is not a number.
#[inline]
pub(super) fn number<F: fast_float2::FastFloat + From<u16>>(
    b: &[u8],
    pos: usize,
) -> Option<(F, usize)> {
    if let Some((v, end)) = small_whole_number(b, pos) {
        return Some((F::from(v), end));
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

        /// Arbitrary bytes: no panic, and the standard library's answer.
        #[test]
        fn arbitrary_bytes_match_std(b in proptest::collection::vec(any::<u8>(), 0..40)) {
            let r = agree(&b);
            prop_assert!(r.is_ok(), "{}", r.unwrap_err());
        }
    }
}
