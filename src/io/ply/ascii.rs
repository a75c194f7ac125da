//! The ascii body: one vertex a line, its fields separated by blanks
//! (spaces, tabs, carriage returns), blank lines skipped. Numbers are parsed by [`super::number`]; properties the reader
//! does not use are skipped without being parsed. Errors name the 1-based
//! line (counting the header).

use super::header::{Element, Header};
use super::number::{is_ws, number};
use super::vertex::{store_int, store_time, truncated, Loc, Slot, VertexLayout};
use crate::cloud::Point;

/// Skip spaces, tabs and carriage returns (not newlines).
#[inline(always)]
fn skip_blank(b: &[u8], mut p: usize) -> usize {
    while p < b.len() && (b[p] == b' ' || b[p] == b'\t' || b[p] == b'\r') {
        p += 1;
    }
    p
}

/// End of the token starting at `p`: the first separator byte at or after
/// `p`, or the end.
///
/// Looks at eight bytes at a time for a byte below `0x21` (every separator
/// is one), then finishes byte by byte. The properties the reader skips
/// (`nx ny nz`, about 20 bytes each in the 3DRef files) made a byte loop a
/// fifth of the parse time: this scan takes the whole command on the ten
/// shared frames from 94 to 87 ms (see [`super::number`]).
#[inline(always)]
fn token_end(b: &[u8], mut p: usize) -> usize {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    while let Some(chunk) = b.get(p..p + 8) {
        let x = u64::from_le_bytes(chunk.try_into().expect("eight bytes"));
        // The high bit is set in the lowest byte below 0x21, if there is
        // one (bytes above it may be flagged wrongly: only the lowest is
        // used). Bytes at or above 0x80 are never flagged.
        let m = x.wrapping_sub(0x21 * LO) & !x & HI;
        if m != 0 {
            p += (m.trailing_zeros() / 8) as usize;
            break;
        }
        p += 8;
    }
    while p < b.len() && !is_ws(b[p]) {
        p += 1;
    }
    p
}

/// Skip to the start of the next line (past `\n`), or to the end.
#[inline]
fn next_line(b: &[u8], p: usize) -> usize {
    b[p..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |i| p + i + 1)
}

/// A token for error messages (lossy, shortened).
fn show_token(t: &[u8]) -> String {
    let s = String::from_utf8_lossy(&t[..t.len().min(40)]).into_owned();
    if t.len() > 40 {
        format!("{s}...")
    } else {
        s
    }
}

/// The message for a field that does not parse as a number.
fn not_a_number(line: usize, name: &str, tok: &[u8]) -> String {
    format!(
        "line {line}: property '{name}' is not a number: '{}'",
        show_token(tok)
    )
}

/// Skip `count` non-blank lines of an element that precedes the vertices.
fn skip_ascii_element(
    body: &[u8],
    mut pos: usize,
    mut line: usize,
    el: &Element,
) -> std::result::Result<(usize, usize), String> {
    let mut done = 0;
    while done < el.count {
        if pos >= body.len() {
            return Err(format!(
                "file ends inside element '{}' before the vertices (truncated?)",
                crate::error::excerpt(&el.name)
            ));
        }
        let start = skip_blank(body, pos);
        let blank = start >= body.len() || body[start] == b'\n';
        pos = next_line(body, pos);
        line += 1;
        if !blank {
            done += 1;
        }
    }
    Ok((pos, line))
}

/// Parse the vertices of an ascii body (after skipping the elements
/// before them): errors name the 1-based line.
pub(super) fn parse_ascii(
    body: &[u8],
    header: &Header,
    layout: &VertexLayout,
) -> std::result::Result<Vec<Point>, String> {
    let mut pos = 0usize;
    // Line number of the line starting at `pos` (1-based, counting the header).
    let mut line = header.lines + 1;
    for el in &header.elements[..header.vertex] {
        (pos, line) = skip_ascii_element(body, pos, line, el)?;
    }
    let n = header.elements[header.vertex].count;
    if n == 0 {
        return Err("frame has no points".to_string());
    }
    let slots = layout.slots.as_slice();
    let nprops = slots.len();
    // Every vertex needs at least two bytes per property: never reserve more
    // than the body can hold, whatever the header claims.
    let mut points = Vec::with_capacity(n.min(body.len() / (2 * nprops) + 1));
    let b = body;
    let len = b.len();
    while points.len() < n {
        pos = skip_blank(b, pos);
        if pos >= len {
            return Err(truncated(n, points.len()));
        }
        if b[pos] == b'\n' {
            // Blank line.
            pos += 1;
            line += 1;
            continue;
        }
        let loc = Loc {
            line,
            vertex: points.len(),
        };
        let mut p = Point::default();
        for (k, &slot) in slots.iter().enumerate() {
            if k > 0 {
                pos = skip_blank(b, pos);
            }
            if pos >= len {
                // The file ends inside this vertex.
                return Err(truncated(n, points.len()));
            }
            if b[pos] == b'\n' {
                return Err(format!(
                    "line {line}: too few fields (found {k}, the header declares {nprops})"
                ));
            }
            let bad = |pos: usize| not_a_number(line, &layout.names[k], &b[pos..token_end(b, pos)]);
            match slot {
                Slot::Skip => pos = token_end(b, pos),
                Slot::X | Slot::Y | Slot::Z | Slot::Intensity => {
                    let (v, end) = number::<f32>(b, pos).ok_or_else(|| bad(pos))?;
                    if v.is_infinite() && !b[pos..end].iter().any(|c| matches!(c, b'i' | b'I')) {
                        // A finite number too large for a float (1e300):
                        // out of range, not "inf" in the file.
                        return Err(format!(
                            "line {line}: property '{}' is {}, beyond the range of a float (about 3.4e38)",
                            crate::error::excerpt(&layout.names[k]),
                            show_token(&b[pos..end])
                        ));
                    }
                    pos = end;
                    match slot {
                        Slot::X => p.xyz[0] = v,
                        Slot::Y => p.xyz[1] = v,
                        Slot::Z => p.xyz[2] = v,
                        _ => p.intensity = v,
                    }
                }
                _ => {
                    let (v, end) = number::<f64>(b, pos).ok_or_else(|| bad(pos))?;
                    pos = end;
                    if slot == Slot::Time {
                        store_time(&mut p, v, loc)?;
                    } else {
                        store_int(&mut p, slot, v, loc)?;
                    }
                }
            }
        }
        pos = skip_blank(b, pos);
        if pos < len {
            if b[pos] != b'\n' {
                return Err(format!(
                    "line {line}: too many fields (the header declares {nprops})"
                ));
            }
            pos += 1;
        }
        line += 1;
        points.push(p);
    }
    // Anything after the vertices must belong to later elements.
    if header.vertex + 1 == header.elements.len() {
        let rest = &b[pos.min(len)..];
        if let Some(i) = rest.iter().position(|&c| !is_ws(c)) {
            let extra_line = line + rest[..i].iter().filter(|&&c| c == b'\n').count();
            return Err(format!(
                "line {extra_line}: data after the {n} declared vertices (wrong vertex count?)"
            ));
        }
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;
    use crate::io::ply::header::parse_header;

    proptest::proptest! {
        /// The word-at-a-time scan ends every token where a byte loop does.
        #[test]
        fn token_end_matches_a_byte_loop(
            bytes in proptest::collection::vec(
                proptest::prop_oneof![
                    6 => b'!'..=b'~',
                    2 => proptest::sample::select(vec![b' ', b'\t', b'\n', b'\r', 0x0b, 0x0c]),
                    2 => proptest::prelude::any::<u8>(),
                ],
                0..40,
            ),
            start in 0usize..40,
        ) {
            let p = start.min(bytes.len());
            let want = bytes[p..].iter().position(|&c| is_ws(c)).map_or(bytes.len(), |i| p + i);
            proptest::prop_assert_eq!(token_end(&bytes, p), want);
        }
    }

    /// The shared 3DRef frames: every field is exactly `str::parse` of its
    /// token.
    #[test]
    fn demo_frames_match_std() {
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
            let header = parse_header(&bytes).unwrap();
            let layout = VertexLayout::new(&header).unwrap();
            let body = &bytes[header.body_start..];
            let points = parse_ascii(body, &header, &layout).unwrap();
            let text = std::str::from_utf8(body).unwrap();
            assert_eq!(text.lines().count(), points.len());
            for (line, p) in text.lines().zip(&points) {
                let t: Vec<&str> = line.split_ascii_whitespace().collect();
                let f = |i: usize| t[i].parse::<f32>().unwrap().to_bits();
                let int = |i: usize| t[i].parse::<f64>().unwrap();
                let got = [
                    p.xyz[0].to_bits(),
                    p.xyz[1].to_bits(),
                    p.xyz[2].to_bits(),
                    p.intensity.to_bits(),
                    p.ring as u32,
                    p.ret as u32,
                    p.label as u32,
                ];
                let want = [
                    f(0),
                    f(1),
                    f(2),
                    f(6),
                    int(7) as u32,
                    int(8) as u32,
                    int(9) as u32,
                ];
                assert_eq!(got, want, "{line}");
            }
        }
    }
}
