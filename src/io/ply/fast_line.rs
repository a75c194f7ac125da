//! The fast ascii line parser.
//!
//! Nearly every line of a 3DRef frame has the form
//! `x y z nx ny nz intensity ring return label\n` with single spaces, floats
//! written `[-]digits.digits` and integer fields written `digits.0`. The fast
//! line parser accepts exactly such lines (for any property layout) and
//! returns `None` for anything else; the caller then parses that line with the
//! general parser (in `ascii`), so errors, blank lines, unusual separators and number
//! forms behave exactly as without the fast path. Whenever the fast path
//! accepts a line its values are the correctly rounded ones, which the general
//! path also gives (see `fast_float`).
//!
//! The fast path reads a fixed window of `WIN` bytes at the line start, so
//! every index is checked against a constant; lines that do not end within
//! the window and the last few lines of the body use the general path.

use super::swar::{fast_float, fast_uint, skip_tokens, word, Blanks, TOKEN_LIMIT, WIN};
use super::vertex::Slot;
use crate::cloud::Point;

/// One step of the fast line parser.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Op {
    /// A float stored as `x`, `y`, `z` (0, 1, 2) or `intensity` (3).
    Float(usize),
    /// An integer field (ring, return or label) written `digits.0`.
    Int(Slot),
    /// This many consecutive tokens that are not parsed.
    Skip(usize),
}

/// The fast-path steps for a vertex layout (consecutive skipped properties
/// merged into one step).
pub(super) fn fast_plan(slots: &[Slot]) -> Vec<Op> {
    let mut plan: Vec<Op> = Vec::with_capacity(slots.len());
    for &slot in slots {
        let op = match slot {
            Slot::X => Op::Float(0),
            Slot::Y => Op::Float(1),
            Slot::Z => Op::Float(2),
            Slot::Intensity => Op::Float(3),
            Slot::Ring | Slot::Return | Slot::Label => Op::Int(slot),
            Slot::Skip => {
                if let Some(Op::Skip(n)) = plan.last_mut() {
                    *n += 1;
                    continue;
                }
                Op::Skip(1)
            }
        };
        plan.push(op);
    }
    plan
}

/// The plan of the real 3DRef files
/// (`x y z nx ny nz intensity ring return label`); the fast path is
/// compiled separately for it, with the steps known at compile time.
pub(super) const PLAN_3DREF: [Op; 8] = [
    Op::Float(0),
    Op::Float(1),
    Op::Float(2),
    Op::Skip(3),
    Op::Float(3),
    Op::Int(Slot::Ring),
    Op::Int(Slot::Return),
    Op::Int(Slot::Label),
];

/// The end of a token at `end` when it is a single space followed by the
/// next token: the start of that token, at most [`TOKEN_LIMIT`].
#[inline(always)]
fn after_space(w: &[u8; WIN], end: usize) -> Option<usize> {
    (end < TOKEN_LIMIT && w[end] == b' ').then_some(end + 1)
}

/// The end of the last token of a line at `end`: the length of the line
/// when the token ends with `\n` or `\r\n`.
#[inline(always)]
fn line_end(w: &[u8; WIN], end: usize) -> Option<usize> {
    match *w.get(end)? {
        b'\n' => Some(end + 1),
        b'\r' if w.get(end + 1) == Some(&b'\n') => Some(end + 2),
        _ => None,
    }
}

/// Parse lines from `pos` with `parse_line` (the fast line parser for some
/// plan) while they have the common form and fewer than `n` points have been
/// read, appending to `points`. Returns the position after the parsed lines,
/// whose number is the number of points added.
///
/// Not inlined: on its own, the loop gets all registers for the parse.
#[inline(never)]
pub(super) fn fast_lines(
    b: &[u8],
    mut pos: usize,
    points: &mut Vec<Point>,
    n: usize,
    parse_line: impl Fn(&[u8; WIN]) -> Option<(Point, usize)>,
) -> usize {
    while points.len() < n {
        let Some(w) = b.get(pos..pos + WIN) else {
            break;
        };
        let Some((p, used)) = parse_line(w.try_into().expect("window length")) else {
            break;
        };
        points.push(p);
        pos += used;
    }
    pos
}

/// [`fast_line`] for [`PLAN_3DREF`], written out.
#[inline(always)]
pub(super) fn fast_line_3dref(w: &[u8; WIN]) -> Option<(Point, usize)> {
    let (x, end) = fast_float::<false>(w, 0)?;
    let (y, end) = fast_float::<false>(w, after_space(w, end)?)?;
    let (z, end) = fast_float::<false>(w, after_space(w, end)?)?;
    let end = skip_tokens::<Blanks>(w, after_space(w, end)?, 3)?;
    // The intensity is nearly always a small integer (`14.0`).
    let q = after_space(w, end)?;
    let (intensity, end) = match fast_uint::<false>(w, q) {
        Some((v, end)) => (v as f32, end),
        None => fast_float::<false>(w, q)?,
    };
    let (ring, end) = fast_uint::<false>(w, after_space(w, end)?)?;
    // Return and label are nearly always `R.0 L.0\n`: check all eight bytes
    // at once.
    let q = after_space(w, end)?;
    const MASK: u64 = 0xFFFF_FF00_FFFF_FF00;
    const TAIL: u64 = u64::from_le_bytes([0, b'.', b'0', b' ', 0, b'.', b'0', b'\n']);
    let t = word(w, q);
    let (ret, label, used) = if t & MASK == TAIL {
        let ret = (t as u8).wrapping_sub(b'0') as u32;
        let label = ((t >> 32) as u8).wrapping_sub(b'0') as u32;
        (ret, label, q + 8)
    } else {
        let (ret, end) = fast_uint::<false>(w, q)?;
        let (label, end) = fast_uint::<false>(w, after_space(w, end)?)?;
        (ret, label, line_end(w, end)?)
    };
    let ring = u16::try_from(ring).ok()?;
    if !(ret == 1 || ret == 2) || label > 6 {
        return None;
    }
    let p = Point {
        xyz: [x, y, z],
        intensity,
        ring,
        ret: ret as u8,
        label: label as u8,
    };
    Some((p, used))
}

/// Parse the line at the start of `w` following `plan` when it has the
/// common form (see above): the point and the length of the line including
/// its `\n` (or `\r\n`). `None` when the line has any other form or its
/// integer fields are out of range; the general parser then handles it.
#[inline(always)]
pub(super) fn fast_line(w: &[u8; WIN], plan: &[Op]) -> Option<(Point, usize)> {
    let mut p = Point::default();
    let mut q = 0usize;
    let last = plan.len().checked_sub(1)?;
    for (i, &op) in plan.iter().enumerate() {
        let end = match op {
            Op::Float(k) => {
                let (v, end) = fast_float::<true>(w, q)?;
                match k {
                    0 => p.xyz[0] = v,
                    1 => p.xyz[1] = v,
                    2 => p.xyz[2] = v,
                    _ => p.intensity = v,
                }
                end
            }
            Op::Int(slot) => {
                let (v, end) = fast_uint::<true>(w, q)?;
                match slot {
                    Slot::Ring => p.ring = u16::try_from(v).ok()?,
                    Slot::Return if v == 1 || v == 2 => p.ret = v as u8,
                    Slot::Label if v <= 6 => p.label = v as u8,
                    _ => return None,
                }
                end
            }
            Op::Skip(n) => skip_tokens::<Blanks>(w, q, n)?,
        };
        if i == last {
            return Some((p, line_end(w, end)?));
        }
        q = after_space(w, end)?;
    }
    None
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::io::ply::ascii::tests::{bits, parse_both};
    use crate::io::ply::header::parse_header;
    use crate::io::ply::swar::tests::window;
    use crate::io::ply::vertex::VertexLayout;

    /// The shared 3DRef frames: the fast and general paths give bit-identical
    /// points, every field equals `str::parse` of its token, and the fast
    /// path takes nearly every line.
    #[test]
    fn demo_frames_fast_path_matches_general_path_and_std() {
        let dir = std::env::var_os("SPECULAR_DATA")
            .map(PathBuf::from)
            .unwrap_or_else(|| {
                PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data/3dref-seq1-demo")
            });
        let Ok(frames) = crate::io::list_frames(&dir) else {
            assert!(
                std::env::var_os("SPECULAR_REQUIRE_SHARED").is_none_or(|v| v != "1"),
                "{} not found, and SPECULAR_REQUIRE_SHARED=1",
                dir.display()
            );
            eprintln!("note: {} absent, skipping this test", dir.display());
            return;
        };
        assert!(!frames.is_empty());
        for entry in &frames {
            let bytes = std::fs::read(&entry.path).unwrap();
            let [fast, general] = parse_both(&bytes);
            let (fast, general) = (fast.unwrap(), general.unwrap());
            assert_eq!(bits(&fast), bits(&general), "{}", entry.path.display());

            let header = parse_header(&bytes).unwrap();
            assert_eq!(
                fast_plan(&VertexLayout::new(&header).unwrap().slots),
                PLAN_3DREF
            );
            let body = &bytes[header.body_start..];
            let text = std::str::from_utf8(body).unwrap();
            let (mut pos, mut fast_lines) = (0, 0);
            for (line, p) in text.lines().zip(&fast) {
                let t: Vec<&str> = line.split_ascii_whitespace().collect();
                let f = |i: usize| t[i].parse::<f32>().unwrap().to_bits();
                let int = |i: usize| t[i].parse::<f64>().unwrap();
                assert_eq!(
                    bits(std::slice::from_ref(p))[0],
                    [
                        f(0),
                        f(1),
                        f(2),
                        f(6),
                        int(7) as u32,
                        int(8) as u32,
                        int(9) as u32
                    ],
                    "{line}"
                );
                if let Some((q, used)) = fast_line_3dref(&window(body, pos)) {
                    assert_eq!(bits(&[q]), bits(std::slice::from_ref(p)), "{line}");
                    assert_eq!(used, line.len() + 1);
                    fast_lines += 1;
                }
                pos += line.len() + 1;
            }
            // Only lines with exponents and the last couple of lines (less
            // than a window from the end) take the general path.
            assert!(
                fast_lines * 1000 >= fast.len() * 995,
                "{fast_lines} of {}",
                fast.len()
            );
        }
    }

    #[test]
    fn fast_path_handles_crlf_and_other_layouts() {
        let rows = "2.6758089 11.371753 -1.3117709 0.98 0.04 -0.14 14.0 36.0 1.0 4.0";
        let mut props = vec![
            "x",
            "y",
            "z",
            "nx",
            "ny",
            "nz",
            "intensity",
            "ring",
            "return",
            "label",
        ];
        for crlf in [false, true] {
            let nl = if crlf { "\r\n" } else { "\n" };
            let mut s = format!("ply{nl}format ascii 1.0{nl}element vertex 20{nl}");
            for p in &props {
                s += &format!("property float {p}{nl}");
            }
            s += &format!("end_header{nl}");
            let header_len = s.len();
            for _ in 0..20 {
                s += rows;
                s += nl;
            }
            let bytes = s.as_bytes();
            let [fast, general] = parse_both(bytes);
            let fast = fast.unwrap();
            assert_eq!(bits(&fast), bits(&general.unwrap()));
            let want = ["2.6758089", "11.371753", "-1.3117709"].map(|s| s.parse::<f32>().unwrap());
            assert_eq!(fast[0].xyz, want);
            assert_eq!(
                (fast[0].intensity, fast[0].ring, fast[0].ret, fast[0].label),
                (14.0, 36, 1, 4)
            );
            let (p, used) = fast_line_3dref(&window(bytes, header_len)).unwrap();
            assert_eq!(used, rows.len() + nl.len());
            assert_eq!(bits(&[p]), bits(&fast[..1]));
        }
        // A layout of its own: the generic plan.
        props = vec![
            "label",
            "intensity",
            "a",
            "x",
            "b",
            "c",
            "y",
            "z",
            "return",
            "ring",
        ];
        let slots: Vec<Slot> = props
            .iter()
            .map(|n| match *n {
                "x" => Slot::X,
                "y" => Slot::Y,
                "z" => Slot::Z,
                "intensity" => Slot::Intensity,
                "ring" => Slot::Ring,
                "return" => Slot::Return,
                "label" => Slot::Label,
                _ => Slot::Skip,
            })
            .collect();
        let plan = fast_plan(&slots);
        assert_eq!(plan.len(), 9);
        let want = bits(&[Point {
            xyz: [-1.5, 0.001, -0.0],
            intensity: 255.0,
            ring: 63,
            ret: 2,
            label: 6,
        }]);
        // Integral values may also come without `.0` (as `write_frame`
        // writes them) in other layouts.
        for line in [
            &b"6.0 255.0 x -1.5 \xc3\xa9 yy 0.001 -0.0 2.0 63.0\n"[..],
            b"6 255 x -1.5 \xc3\xa9 yy 0.001 -0 2 63\r\n",
        ] {
            let (p, used) = fast_line(&window(line, 0), &plan).unwrap();
            assert_eq!(used, line.len());
            assert_eq!(bits(&[p]), want);
        }
        let written = b"2.6758089 -11.371753 1.3117709 14 36 1 4\n";
        let slots = [
            Slot::X,
            Slot::Y,
            Slot::Z,
            Slot::Intensity,
            Slot::Ring,
            Slot::Return,
            Slot::Label,
        ];
        let (p, used) = fast_line(&window(written, 0), &fast_plan(&slots)).unwrap();
        assert_eq!(used, written.len());
        assert_eq!(
            (p.xyz[1], p.intensity, p.ring, p.ret, p.label),
            (-11.371753, 14.0, 36, 1, 4)
        );
    }
}
