//! Word-at-a-time helpers of the fast line parser: digits, floats and
//! integers of the common forms, and separators, read from a fixed window.

use super::number::{f32_halfway, POW10};

/// Bytes of the window the fast line parser reads.
pub(super) const WIN: usize = 256;
/// Largest window index at which the fast parser starts a token (every token
/// parser reads at most 32 bytes from its start).
pub(super) const TOKEN_LIMIT: usize = WIN - 32;

/// `0x01` in every byte.
const ONES: u64 = 0x0101_0101_0101_0101;
/// `0x80` in every byte.
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// The eight bytes of `w` at `i` as a little-endian word (byte `i` lowest).
#[inline(always)]
pub(super) fn word(w: &[u8; WIN], i: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&w[i..i + 8]);
    u64::from_le_bytes(a)
}

/// For `x` = eight bytes xor `b'0'`: the high bit of every byte that was not
/// an ascii digit, exact for the lowest such byte (higher ones may be wrong,
/// only the lowest is used). Digits become 0..=9 under the xor; a byte is
/// flagged when its value is 10 or more.
#[inline(always)]
fn non_digits(x: u64) -> u64 {
    (x.wrapping_add(0x76 * ONES) | x) & HIGHS
}

/// Number of leading ascii digits in the word `x` (bytes xor `b'0'`), 0..=8.
#[inline(always)]
fn digit_run(x: u64) -> usize {
    (non_digits(x).trailing_zeros() / 8) as usize
}

/// Value of eight decimal digits, one per byte (0..=9, most significant in
/// the lowest byte), by combining pairs, quads and halves with multiplies.
#[inline(always)]
fn eight_digits(v: u64) -> u64 {
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let lo = (v & 0x0000_00FF_0000_00FF).wrapping_mul(100 + (1_000_000 << 32));
    let hi = ((v >> 16) & 0x0000_00FF_0000_00FF).wrapping_mul(1 + (10_000 << 32));
    lo.wrapping_add(hi) >> 32
}

/// Value of the first `n` (1..=8) digits of `x` (bytes xor `b'0'`); the
/// bytes after them are shifted out and zeros (leading zeros) shifted in.
#[inline(always)]
fn leading_digits(x: u64, n: usize) -> u64 {
    debug_assert!((1..=8).contains(&n));
    eight_digits(x << (64 - 8 * n))
}

/// A float written `[-]digits.digits` (or `[-]digits` when `PLAIN`) at `q`
/// (at most [`TOKEN_LIMIT`]): the correctly rounded `f32` and the index of
/// the byte after the number, which is not a digit (the caller checks that it ends the
/// token, so `1.5e3` is rejected there). `None` for any other form (no digit
/// before the dot or none after it), more than 7 integer digits or 15 digits
/// in all, or a value whose `f64` lies halfway between two `f32`s (where
/// casting could round twice).
///
/// The value is `m / 10^k` for the digits `m` and the fraction length `k`,
/// both exact in an `f64`, divided with one rounding and cast to `f32`. The
/// general path ([`parse_fast`], or the standard parser) also gives the
/// correctly rounded value of the same decimal, so both paths agree.
#[inline(always)]
pub(super) fn fast_float<const PLAIN: bool>(w: &[u8; WIN], q: usize) -> Option<(f32, usize)> {
    debug_assert!(q <= TOKEN_LIMIT);
    let neg = (w[q] == b'-') as usize;
    let q = q + neg;
    const ZEROS: u64 = 0x30 * ONES;
    // Integer digits: `d` of them, then the dot.
    let a = word(w, q) ^ ZEROS;
    let d = digit_run(a);
    if d == 0 || d == 8 {
        return None;
    }
    if (a >> (8 * d)) as u8 != b'.' ^ b'0' {
        if !PLAIN {
            return None;
        }
        // An integer: below 10^7, exact in an `f32`.
        let v = leading_digits(a, d) as f32;
        return Some((f32::from_bits(v.to_bits() | (neg as u32) << 31), q + d));
    }
    // The integer digits followed by the digits after the dot, dot removed:
    // bytes 0..d from `a`, bytes d..8 from the word one byte further on.
    let low = (1u64 << (8 * d)) - 1;
    let c = (a & low) | ((word(w, q + 1) ^ ZEROS) & !low);
    let n = digit_run(c);
    if n == d {
        return None; // nothing after the dot
    }
    let (m, frac, end) = if n < 8 {
        (leading_digits(c, n), n - d, q + 1 + n)
    } else {
        // Eight digits so far; up to seven more follow.
        let e = word(w, q + 9) ^ ZEROS;
        let k = digit_run(e);
        if k == 8 {
            return None;
        }
        let mut m = eight_digits(c);
        if k > 0 {
            m = m * POW10_U64[k] + leading_digits(e, k);
        }
        (m, 8 - d + k, q + 9 + k)
    };
    // At most 15 digits: `m` and `10^frac` are exact in an `f64`, and the
    // division rounds once. The guard cannot fire; the code measured faster
    // with it than with a `debug_assert` (block layout).
    if m > 1 << 53 {
        return None;
    }
    let v = m as f64 / POW10[frac];
    if f32_halfway(v) {
        return None;
    }
    // The sign bit, without a branch.
    let v = f32::from_bits((v as f32).to_bits() | (neg as u32) << 31);
    Some((v, end))
}

/// Powers of ten as integers, for joining digit groups.
const POW10_U64: [u64; 8] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000];

/// An unsigned integer written `digits.0` (or `digits` when `PLAIN`), 1 to 4
/// digits, at `q` (at most [`TOKEN_LIMIT`]): its value and the index of the
/// byte after the number, which is not a digit (the caller checks that it
/// ends the token, so `1.5` is rejected there).
#[inline(always)]
pub(super) fn fast_uint<const PLAIN: bool>(w: &[u8; WIN], q: usize) -> Option<(u32, usize)> {
    debug_assert!(q <= TOKEN_LIMIT);
    let a = word(w, q) ^ (0x30 * ONES);
    let d = digit_run(a);
    if d == 0 || d > 4 {
        return None;
    }
    let value = four_digits((a as u32) << (32 - 8 * d));
    // After the digits: `.0` (xor `00`: 0x1e then 0x00, the low half of a
    // little-endian u16), or when `PLAIN` whatever ends the token.
    let after = (a >> (8 * d)) as u16;
    if after == (b'.' ^ b'0') as u16 {
        Some((value, q + d + 2))
    } else if PLAIN {
        Some((value, q + d))
    } else {
        None
    }
}

/// Value of four decimal digits, one per byte (0..=9, most significant in
/// the lowest byte): [`eight_digits`] on 32 bits.
#[inline(always)]
fn four_digits(v: u32) -> u32 {
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    (v & 0x00FF_00FF).wrapping_mul(1 + (100 << 16)) >> 16
}

/// `n` (at least 1) consecutive tokens of any non-blank bytes, separated by
/// single spaces, starting at `q`: the index of the byte that ends the last
/// one (some byte below 0x21, left to the caller to check). `None` when a
/// token is empty, a separator is not a space or the tokens run past the
/// window. `B` finds the separators.
#[inline(always)]
pub(super) fn skip_tokens<B: BlankScan>(
    w: &[u8; WIN],
    mut q: usize,
    mut n: usize,
) -> Option<usize> {
    debug_assert!(n >= 1);
    let mut start = q;
    loop {
        if q > WIN - B::CHUNK {
            return None;
        }
        let mut m = B::mask(w, q);
        while m != 0 {
            let sep = q + (m.trailing_zeros() >> B::SHIFT) as usize;
            if sep == start {
                return None; // empty token
            }
            n -= 1;
            if n == 0 {
                return Some(sep);
            }
            if w[sep] != b' ' {
                return None;
            }
            start = sep + 1;
            m &= m - 1;
        }
        q += B::CHUNK;
    }
}

/// Finds the bytes below 0x21 (separators and control bytes) in a chunk of
/// the window.
pub(super) trait BlankScan {
    /// Bytes per chunk.
    const CHUNK: usize;
    /// Byte `k` of the chunk is bit `k << SHIFT` of a mask (or the lowest
    /// set bit at or above it).
    const SHIFT: u32;
    /// The mask of the bytes of `w[i..i + CHUNK]` below 0x21.
    fn mask(w: &[u8; WIN], i: usize) -> u64;
}

/// [`BlankScan`] eight bytes at a time in a `u64` (portable).
#[cfg_attr(
    all(target_arch = "x86_64", target_feature = "sse2", not(test)),
    allow(dead_code)
)]
pub(super) struct SwarBlanks;

impl BlankScan for SwarBlanks {
    const CHUNK: usize = 8;
    const SHIFT: u32 = 3;

    /// The high bit of each byte below 0x21.
    #[inline(always)]
    fn mask(w: &[u8; WIN], i: usize) -> u64 {
        let x = word(w, i);
        // Exact for every byte: no carries between bytes.
        !(((x & !HIGHS) + 0x5F * ONES) | x) & HIGHS
    }
}

/// [`BlankScan`] sixteen bytes at a time with SSE2.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
pub(super) struct Sse2Blanks;

#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
impl BlankScan for Sse2Blanks {
    const CHUNK: usize = 16;
    const SHIFT: u32 = 0;

    /// Bit `k` set for each byte `k` below 0x21.
    #[inline(always)]
    fn mask(w: &[u8; WIN], i: usize) -> u64 {
        use std::arch::x86_64::{
            _mm_cmpeq_epi8, _mm_movemask_epi8, _mm_set1_epi8, _mm_set_epi64x, _mm_setzero_si128,
            _mm_subs_epu8,
        };
        let (lo, hi) = (word(w, i) as i64, word(w, i + 8) as i64);
        // SAFETY: these intrinsics only need SSE2, which this build enables
        // (see the cfg above); they compute on register values only.
        let bits = unsafe {
            let v = _mm_set_epi64x(hi, lo);
            // Saturating `byte - 0x20` is zero exactly for bytes <= 0x20.
            let zero = _mm_subs_epu8(v, _mm_set1_epi8(0x20));
            _mm_movemask_epi8(_mm_cmpeq_epi8(zero, _mm_setzero_si128()))
        };
        bits as u16 as u64
    }
}

/// The [`BlankScan`] the fast path uses.
#[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
pub(super) type Blanks = Sse2Blanks;
/// The [`BlankScan`] the fast path uses.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
pub(super) type Blanks = SwarBlanks;

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// The window of `body` at `pos` (zero-padded past the end).
    pub(in crate::io::ply) fn window(body: &[u8], pos: usize) -> [u8; WIN] {
        let mut w = [0u8; WIN];
        let n = body.len().saturating_sub(pos).min(WIN);
        w[..n].copy_from_slice(&body[pos..pos + n]);
        w
    }

    #[test]
    fn fast_tokens() {
        // Accepted when the number is the whole token (the caller checks
        // the byte after it, which is not a digit).
        fn f<const PLAIN: bool>(s: &str) -> Option<u32> {
            let b = format!("{s} ");
            fast_float::<PLAIN>(&window(b.as_bytes(), 0), 0)
                .and_then(|(v, end)| (end == s.len()).then_some(v.to_bits()))
        }
        fn u<const PLAIN: bool>(s: &str) -> Option<u32> {
            let b = format!("{s}\n");
            fast_uint::<PLAIN>(&window(b.as_bytes(), 0), 0)
                .and_then(|(v, end)| (end == s.len()).then_some(v))
        }
        let std = |s: &str| Some(s.parse::<f32>().unwrap().to_bits());
        for s in [
            "0.0",
            "-0.0",
            "1.5",
            "14.0",
            "2.6758089",
            "-0.48358452",
            "1234567.1",
            "0.00000000000001",
            "1234567.12345678",
            "9007199.25474099",
            "0.1000000000000",
            "3.4028235",
        ] {
            assert_eq!(f::<false>(s), std(s), "{s}");
            assert_eq!(f::<true>(s), std(s), "{s}");
        }
        for s in ["1", "-1", "-0", "0014", "9999999"] {
            assert_eq!(f::<false>(s), None, "{s}");
            assert_eq!(f::<true>(s), std(s), "{s}");
        }
        for s in [
            ".5",
            "5.",
            "-.5",
            "+1.5",
            "1e5",
            "1.5e3",
            "12345678",
            "12345678.5",
            "1.234567890123456",
            "123456789012345.0",
            "9007199.254740992",
            "1.5x",
            "--1.0",
            "1..5",
            "nan",
            "",
        ] {
            assert_eq!(f::<false>(s), None, "{s}");
            assert_eq!(f::<true>(s), None, "{s}");
        }
        // Exactly halfway between two f32s: left to the standard parser.
        assert_eq!(f::<true>("1048576.0625"), None);
        assert_eq!("1048576.0625".parse::<f32>(), Ok(1048576.0));

        for (s, v) in [
            ("0.0", 0),
            ("1.0", 1),
            ("36.0", 36),
            ("255.0", 255),
            ("9999.0", 9999),
            ("007.0", 7),
        ] {
            assert_eq!(u::<false>(s), Some(v), "{s}");
            assert_eq!(u::<true>(s), Some(v), "{s}");
        }
        for (s, v) in [("0", 0), ("1", 1), ("36", 36), ("9999", 9999)] {
            assert_eq!(u::<false>(s), None, "{s}");
            assert_eq!(u::<true>(s), Some(v), "{s}");
        }
        for s in [
            "1.00", "1.5", "10000.0", "10000", "-1.0", ".0", "1.", "x.0", "1e0",
        ] {
            assert_eq!(u::<false>(s), None, "{s}");
            assert_eq!(u::<true>(s), None, "{s}");
        }
    }

    /// Naive reference for [`skip_tokens`] with `B`: the same answer when
    /// the tokens end before the bytes that `B` scans do.
    fn skip_tokens_naive<B: BlankScan>(w: &[u8; WIN], q: usize, n: usize) -> Option<usize> {
        let chunks = if q <= WIN - B::CHUNK {
            (WIN - B::CHUNK - q) / B::CHUNK + 1
        } else {
            0
        };
        let mut start = q;
        let mut left = n;
        for (i, &c) in w.iter().enumerate().take(q + chunks * B::CHUNK).skip(q) {
            if c > 0x20 {
                continue;
            }
            if i == start {
                return None;
            }
            left -= 1;
            if left == 0 {
                return Some(i);
            }
            if c != b' ' {
                return None;
            }
            start = i + 1;
        }
        None
    }

    proptest::proptest! {
        #[test]
        fn digit_helpers(digits in proptest::collection::vec(0u8..10, 8), n in 1usize..=8) {
            let word = u64::from_le_bytes(digits.clone().try_into().unwrap());
            let value = digits.iter().fold(0u64, |v, &d| v * 10 + d as u64);
            proptest::prop_assert_eq!(eight_digits(word), value);
            let lead = digits[..n].iter().fold(0u64, |v, &d| v * 10 + d as u64);
            proptest::prop_assert_eq!(leading_digits(word, n), lead);
            let four = digits[..4].iter().fold(0u32, |v, &d| v * 10 + d as u32);
            proptest::prop_assert_eq!(four_digits(word as u32), four);
            let ascii = word ^ (0x30 * ONES);
            let mut bytes = digits.iter().map(|d| d + b'0').collect::<Vec<u8>>();
            proptest::prop_assert_eq!(digit_run(ascii ^ (0x30 * ONES)), 8);
            bytes[n - 1] = b'.';
            let x = u64::from_le_bytes(bytes.try_into().unwrap()) ^ (0x30 * ONES);
            proptest::prop_assert_eq!(digit_run(x), n - 1);
        }

        #[test]
        fn digit_run_finds_the_first_non_digit(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 8)) {
            let x = u64::from_le_bytes(bytes.clone().try_into().unwrap()) ^ (0x30 * ONES);
            let want = bytes.iter().position(|b| !b.is_ascii_digit()).unwrap_or(8);
            proptest::prop_assert_eq!(digit_run(x), want);
        }

        #[test]
        fn blank_scans_and_skip_tokens(
            bytes in proptest::collection::vec(
                proptest::prop_oneof![
                    8 => b'!'..=b'~',
                    3 => proptest::strategy::Just(b' '),
                    1 => proptest::prelude::any::<u8>(),
                ],
                WIN,
            ),
            q in 0usize..WIN,
            n in 1usize..5,
        ) {
            let w: [u8; WIN] = bytes.try_into().unwrap();
            let naive = |i: usize, chunk: usize| -> Vec<usize> {
                (0..chunk).filter(|&k| w[i + k] <= 0x20).collect()
            };
            let positions = |mut m: u64, shift: u32| -> Vec<usize> {
                let mut v = Vec::new();
                while m != 0 {
                    v.push((m.trailing_zeros() >> shift) as usize);
                    m &= m - 1;
                }
                v
            };
            let i = q.min(WIN - 16);
            proptest::prop_assert_eq!(positions(SwarBlanks::mask(&w, i), SwarBlanks::SHIFT), naive(i, 8));
            let want = skip_tokens_naive::<SwarBlanks>(&w, q, n);
            proptest::prop_assert_eq!(skip_tokens::<SwarBlanks>(&w, q, n), want);
            #[cfg(all(target_arch = "x86_64", target_feature = "sse2"))]
            {
                proptest::prop_assert_eq!(positions(Sse2Blanks::mask(&w, i), Sse2Blanks::SHIFT), naive(i, 16));
                let sse2 = skip_tokens::<Sse2Blanks>(&w, q, n);
                proptest::prop_assert_eq!(sse2, skip_tokens_naive::<Sse2Blanks>(&w, q, n));
                if want.is_some_and(|i| i < WIN - 16) || sse2.is_some_and(|i| i < WIN - 16) {
                    proptest::prop_assert_eq!(sse2, want);
                }
            }
        }

        /// Fast floats are exactly `str::parse::<f32>` for the forms they
        /// accept, which include every f32's shortest form without exponent.
        #[test]
        fn fast_float_agrees_with_std(
            x in proptest::prelude::any::<f32>(),
            prec in 0usize..12,
            digits in "-?[0-9]{1,8}\\.[0-9]{1,9}",
        ) {
            for s in [format!("{x}"), format!("{x:.prec$}"), digits] {
                let b = format!("{s} ");
                let w = window(b.as_bytes(), 0);
                for got in [fast_float::<false>(&w, 0), fast_float::<true>(&w, 0)] {
                    if let Some((v, end)) = got.filter(|&(_, end)| end == s.len()) {
                        let want = s.parse::<f32>().unwrap();
                        proptest::prop_assert_eq!(v.to_bits(), want.to_bits(), "{} {}", s, end);
                    }
                }
            }
            // The shortest forms of moderate magnitudes all take the fast
            // path, but for values whose f64 is halfway between two f32s.
            let s = format!("{x}");
            if (1e-4..1e6).contains(&x.abs())
                && s.contains('.')
                && !f32_halfway(s.parse::<f64>().unwrap())
            {
                let b = format!("{s} ");
                let got = fast_float::<false>(&window(b.as_bytes(), 0), 0);
                proptest::prop_assert!(got.is_some_and(|(_, end)| end == s.len()), "{}", s);
            }
        }
    }
}
