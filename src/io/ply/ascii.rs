//! The ascii body: the fast line parser for lines of the usual form, a
//! general parser (one token at a time) for every other line.

use super::fast_line::{fast_line, fast_line_3dref, fast_lines, fast_plan, PLAN_3DREF};
use super::header::{Element, Header};
use super::number::{
    f32_halfway, is_ws, parse_fast, parse_slow_f32, parse_slow_f64, parse_uint_fast,
};
use super::vertex::{store_int, truncated, Loc, Slot, VertexLayout};
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
/// `p`, or the end. Scans eight bytes at a time for a byte below `0x21`
/// (every separator is), then checks byte by byte.
#[inline(always)]
fn token_end(b: &[u8], mut p: usize) -> usize {
    const LO: u64 = 0x0101_0101_0101_0101;
    const HI: u64 = 0x8080_8080_8080_8080;
    while let Some(chunk) = b.get(p..p + 8) {
        let mut a = [0u8; 8];
        a.copy_from_slice(chunk);
        let x = u64::from_le_bytes(a);
        // High bit set in the lowest byte below 0x21 (exact for the lowest).
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
                el.name
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
    parse_ascii_with(body, header, layout, true)
}

/// [`parse_ascii`], with the fast line parser or (`fast == false`, for
/// tests) the general parser only.
fn parse_ascii_with(
    body: &[u8],
    header: &Header,
    layout: &VertexLayout,
    fast: bool,
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
    let plan = if fast { fast_plan(slots) } else { Vec::new() };
    let plan_3dref = plan == PLAN_3DREF;
    while points.len() < n {
        if fast {
            let before = points.len();
            pos = if plan_3dref {
                fast_lines(b, pos, &mut points, n, fast_line_3dref)
            } else {
                fast_lines(b, pos, &mut points, n, |w| fast_line(w, &plan))
            };
            line += points.len() - before;
            if points.len() == n {
                break;
            }
        }
        // The general parser: one line (or a blank line) at `pos`.
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
            if slot == Slot::Skip {
                pos = token_end(b, pos);
                continue;
            }
            match slot {
                Slot::X | Slot::Y | Slot::Z | Slot::Intensity => {
                    let v32 = match parse_fast(b, pos) {
                        Some((v, end)) if !f32_halfway(v) => {
                            pos = end;
                            v as f32
                        }
                        _ => {
                            let end = token_end(b, pos);
                            let tok = &b[pos..end];
                            let v = parse_slow_f32(tok)
                                .ok_or_else(|| not_a_number(line, &layout.names[k], tok))?;
                            pos = end;
                            v
                        }
                    };
                    match slot {
                        Slot::X => p.xyz[0] = v32,
                        Slot::Y => p.xyz[1] = v32,
                        Slot::Z => p.xyz[2] = v32,
                        _ => p.intensity = v32,
                    }
                }
                _ => {
                    let v = match parse_uint_fast(b, pos).or_else(|| parse_fast(b, pos)) {
                        Some((v, end)) => {
                            pos = end;
                            v
                        }
                        None => {
                            let end = token_end(b, pos);
                            let tok = &b[pos..end];
                            let v = parse_slow_f64(tok)
                                .ok_or_else(|| not_a_number(line, &layout.names[k], tok))?;
                            pos = end;
                            v
                        }
                    };
                    store_int(&mut p, slot, v, loc)?;
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
pub(super) mod tests {
    use super::*;
    use crate::io::ply::header::parse_header;

    /// Parse an ascii PLY file's body with the fast line parser on or off.
    pub(in crate::io::ply) fn parse_both(
        bytes: &[u8],
    ) -> [std::result::Result<Vec<Point>, String>; 2] {
        let header = parse_header(bytes).expect("header");
        let layout = VertexLayout::new(&header).expect("layout");
        let body = &bytes[header.body_start..];
        [true, false].map(|fast| parse_ascii_with(body, &header, &layout, fast))
    }

    pub(in crate::io::ply) fn bits(points: &[Point]) -> Vec<[u32; 7]> {
        points
            .iter()
            .map(|p| {
                [
                    p.xyz[0].to_bits(),
                    p.xyz[1].to_bits(),
                    p.xyz[2].to_bits(),
                    p.intensity.to_bits(),
                    p.ring as u32,
                    p.ret as u32,
                    p.label as u32,
                ]
            })
            .collect()
    }

    proptest::proptest! {
        #![proptest_config(proptest::test_runner::Config::with_cases(1024))]

        /// Random bodies with mostly well-formed lines and many kinds of
        /// oddities: the fast path never changes a result or an error.
        #[test]
        fn fast_path_never_changes_results(
            layout in 0usize..3,
            rows in rows_strategy(),
            count_delta in -1isize..=1,
            trailer in proptest::prop_oneof![
                4 => proptest::strategy::Just(""),
                1 => proptest::strategy::Just("\n\n"),
                1 => proptest::strategy::Just("1 2 3\n"),
            ],
        ) {
            let props: &[&str] = match layout {
                0 => &["x", "y", "z", "nx", "ny", "nz", "intensity", "ring", "return", "label"],
                1 => &["x", "y", "z", "intensity", "ring", "return"],
                _ => &["ring", "x", "nx", "y", "z", "label", "return", "intensity", "t"],
            };
            let count = (rows.len() as isize + count_delta).max(0);
            let mut s = format!("ply\nformat ascii 1.0\nelement vertex {count}\n");
            for p in props {
                s += &format!("property float {p}\n");
            }
            s += "end_header\n";
            let mut bytes = s.into_bytes();
            for row in &rows {
                bytes.extend_from_slice(&row.render(props));
            }
            bytes.extend_from_slice(trailer.as_bytes());
            let [fast, general] = parse_both(&bytes);
            proptest::prop_assert_eq!(fast.map(|p| bits(&p)), general.map(|p| bits(&p)));
        }
    }

    /// One generated body line: a token per property name, and how the
    /// tokens are joined.
    #[derive(Debug, Clone)]
    struct Row {
        floats: [String; 4],
        ints: [String; 3],
        skip: String,
        /// Separator before token `k` (`seps[0]` is unused).
        seps: [&'static str; 12],
        lead: &'static str,
        end: &'static str,
        extra: &'static str,
        /// Tokens left off at the end.
        cut: usize,
    }

    impl Row {
        fn render(&self, props: &[&str]) -> Vec<u8> {
            let mut out = self.lead.to_string();
            let tokens = props.len().saturating_sub(self.cut);
            for (k, p) in props.iter().take(tokens).enumerate() {
                if k > 0 {
                    out += self.seps[k];
                }
                out += match *p {
                    "x" => &self.floats[0],
                    "y" => &self.floats[1],
                    "z" => &self.floats[2],
                    "intensity" => &self.floats[3],
                    "ring" => &self.ints[0],
                    "return" => &self.ints[1],
                    "label" => &self.ints[2],
                    _ => &self.skip,
                };
            }
            out += self.extra;
            out += self.end;
            out.into_bytes()
        }
    }

    /// The forms of the real files.
    fn clean_float() -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        prop_oneof![
            6 => (-100.0f32..100.0).prop_map(|x| format!("{x}")),
            1 => (-1e6f32..1e6).prop_map(|x| format!("{x}")),
            1 => (0u32..300).prop_map(|v| format!("{v}.0")),
        ]
        .boxed()
    }

    /// Floats of other forms, some not numbers at all.
    fn odd_float() -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        prop_oneof![
            any::<f32>().prop_map(|x| format!("{x}")),
            (any::<f32>(), 0usize..20).prop_map(|(x, p)| format!("{x:.p$}")),
            "-?[0-9]{1,9}\\.[0-9]{1,10}",
            any::<f32>().prop_map(|x| format!("{x:e}")),
            prop::sample::select(vec![
                "-0.0",
                "+1.5",
                ".5",
                "5.",
                "1e5",
                "nan",
                "inf",
                "-inf",
                "1.5.5",
                "--1",
                "1,5",
                "0x1p3",
                "1048576.0625",
                "16777217.0",
                "1e-50",
                "x",
                "\u{e9}",
                "-",
                "1.5-",
            ])
            .prop_map(String::from),
        ]
        .boxed()
    }

    /// Valid values `min..max` written `v.0`.
    fn clean_int(min: u32, max: u32) -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        (min..max).prop_map(|v| format!("{v}.0")).boxed()
    }

    /// Integer fields of other forms or out of range.
    fn odd_int() -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        prop_oneof![
            4 => clean_int(0, 12),
            1 => (0u32..70000).prop_map(|v| format!("{v}.0")),
            1 => (0u32..100).prop_map(|v| format!("{v}")),
            2 => prop::sample::select(vec![
                "1.00", "01.0", "-1.0", "1.5", "2.", "+1.0", "1e0", "nan", "0.0", "65535.0",
                "65536.0", "9999.0", "10000.0", "00001.0", "06.0", "1.0x", "",
            ])
            .prop_map(String::from),
        ]
        .boxed()
    }

    fn clean_skip() -> proptest::strategy::BoxedStrategy<String> {
        use proptest::prelude::*;
        (-1.0f64..1.0).prop_map(|x| format!("{x}")).boxed()
    }

    /// A line of the real files' form.
    fn clean_row() -> impl proptest::strategy::Strategy<Value = Row> {
        use proptest::prelude::*;
        let floats = [clean_float(), clean_float(), clean_float(), clean_float()];
        let ints = [clean_int(0, 64), clean_int(1, 3), clean_int(0, 7)];
        (floats, ints, clean_skip()).prop_map(|(floats, ints, skip)| Row {
            floats,
            ints,
            skip,
            seps: [" "; 12],
            lead: "",
            end: "\n",
            extra: "",
            cut: 0,
        })
    }

    /// A line of the real files' form but for one oddity.
    fn odd_row() -> impl proptest::strategy::Strategy<Value = Row> {
        use proptest::prelude::*;
        let skip = prop_oneof![
            "[!-~]{1,30}",
            "[a\\x01\\x0b\\x0c\\x7f\u{e9}-]{1,4}",
            Just(String::new()),
        ];
        let sep = prop::sample::select(vec!["  ", "\t", " \t", "\n", "\r", "\x0b", "\x0c", ""]);
        let lead = prop::sample::select(vec![" ", "\n", "\t", "\r\n"]);
        let end = prop::sample::select(vec!["\r\n", " \n", "\r\r\n", "\t\n", "\r", "\n\n"]);
        let extra = prop::sample::select(vec![" 9", " ", " x", "\t1.0"]);
        let oddity = (0usize..13, 1usize..12, odd_float(), odd_int(), skip);
        (clean_row(), oddity, (sep, lead, end, extra)).prop_map(
            |(mut row, (kind, at, float, int, skip), (sep, lead, end, extra))| {
                match kind {
                    0..=3 => row.floats[kind] = float,
                    4..=6 => row.ints[kind - 4] = int,
                    7 => row.skip = skip,
                    8 => row.seps[at] = sep,
                    9 => row.lead = lead,
                    10 => row.end = end,
                    11 => row.extra = extra,
                    _ => row.cut = at % 4,
                }
                row
            },
        )
    }

    /// Body lines: all clean, or clean with some odd ones.
    fn rows_strategy() -> impl proptest::strategy::Strategy<Value = Vec<Row>> {
        use proptest::prelude::*;
        let row = prop_oneof![4 => clean_row(), 1 => odd_row()];
        prop_oneof![
            1 => proptest::collection::vec(clean_row(), 0..40),
            3 => proptest::collection::vec(row, 0..40),
        ]
    }
}
