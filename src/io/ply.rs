//! 3DRef PLY frames: a fast reader (ascii and binary_little_endian,
//! properties found by name) and a compact binary writer.
//!
//! The reader needs the vertex properties `x y z intensity ring return` and
//! reads `label` when present; every other property (`nx ny nz`, ...) is
//! skipped without being parsed. Properties may have any PLY scalar type.
//! Elements other than `vertex` are skipped; list properties are rejected.
//!
//! The ascii body is parsed from bytes with a hand-rolled number parser (no
//! allocation per point), falling back to the standard library for unusual
//! forms (`nan`, `inf`, more than 19 significant digits, large exponents).
//! Errors name the file and, for ascii bodies, the 1-based line number;
//! vertex numbers in messages are 0-based indices into [`Frame::points`].

use std::io::Write;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::cloud::{Frame, Point};
use crate::io::frames::parse_stamp;
use crate::{Error, Result};

/// PLY body encoding for writing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    /// `format ascii 1.0`, as the real 3DRef files.
    Ascii,
    /// `format binary_little_endian 1.0`, compact and fast.
    #[default]
    BinaryLittleEndian,
}

/// Read one 3DRef frame. The file stem is the timestamp in seconds.
///
/// The file is read into a per-thread buffer that is reused across calls,
/// so parsing a sequence does not fault in fresh pages for every frame.
pub fn read_frame(path: &Path) -> Result<Frame> {
    thread_local! {
        static BUFFER: std::cell::RefCell<Vec<u8>> = const { std::cell::RefCell::new(Vec::new()) };
    }
    BUFFER.with(|cell| {
        let mut buf = cell.borrow_mut();
        buf.clear();
        let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
        std::io::Read::read_to_end(&mut file, &mut buf).map_err(|e| Error::io(path, e))?;
        let frame = parse_frame(&buf, path);
        // Do not keep an unusually large buffer alive.
        if buf.capacity() > 64 << 20 {
            *buf = Vec::new();
        }
        frame
    })
}

/// Read several frames in parallel (rayon), in the order of `paths`.
///
/// All files are read and parsed; when any fails, the error of the first
/// failing path (in `paths` order) is returned.
pub fn read_frames(paths: &[PathBuf]) -> Result<Vec<Frame>> {
    let results: Vec<Result<Frame>> = paths.par_iter().map(|p| read_frame(p)).collect();
    results.into_iter().collect()
}

/// Parse a frame from the bytes of a PLY file (`path` names it in errors and
/// gives the stem/timestamp).
pub fn parse_frame(bytes: &[u8], path: &Path) -> Result<Frame> {
    let (name, stamp) = parse_stamp(path)?;
    let fail = |msg: String| Error::format(path, msg);
    let header = parse_header(bytes).map_err(fail)?;
    let layout = VertexLayout::new(&header).map_err(fail)?;
    let body = &bytes[header.body_start..];
    let points = match header.format {
        Format::Ascii => parse_ascii(body, &header, &layout).map_err(fail)?,
        Format::BinaryLittleEndian => parse_binary(body, &header, &layout).map_err(fail)?,
    };
    Ok(Frame {
        name,
        stamp,
        points,
        has_labels: layout.has_labels,
    })
}

/// Write a frame with properties `x y z intensity ring return label`
/// (`label` only when [`Frame::has_labels`]), atomically.
///
/// Types are `float x y z intensity`, `ushort ring`, `uchar return label`.
/// The ascii encoding writes floats in their shortest round-trip form, so
/// reading the file back gives identical points.
pub fn write_frame(path: &Path, frame: &Frame, encoding: PlyEncoding) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        let format = match encoding {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        };
        write!(
            w,
            "ply\nformat {format} 1.0\ncomment written by specular\nelement vertex {}\n\
             property float x\nproperty float y\nproperty float z\n\
             property float intensity\nproperty ushort ring\nproperty uchar return\n",
            frame.points.len()
        )?;
        if frame.has_labels {
            w.write_all(b"property uchar label\n")?;
        }
        w.write_all(b"end_header\n")?;
        match encoding {
            PlyEncoding::Ascii => {
                for p in &frame.points {
                    write!(
                        w,
                        "{} {} {} {} {} {}",
                        p.xyz[0], p.xyz[1], p.xyz[2], p.intensity, p.ring, p.ret
                    )?;
                    if frame.has_labels {
                        write!(w, " {}", p.label)?;
                    }
                    w.write_all(b"\n")?;
                }
            }
            PlyEncoding::BinaryLittleEndian => {
                let rec = if frame.has_labels { 20 } else { 19 };
                let mut buf = Vec::with_capacity(rec * 4096);
                for chunk in frame.points.chunks(4096) {
                    buf.clear();
                    for p in chunk {
                        for c in p.xyz {
                            buf.extend_from_slice(&c.to_le_bytes());
                        }
                        buf.extend_from_slice(&p.intensity.to_le_bytes());
                        buf.extend_from_slice(&p.ring.to_le_bytes());
                        buf.push(p.ret);
                        if frame.has_labels {
                            buf.push(p.label);
                        }
                    }
                    w.write_all(&buf)?;
                }
            }
        }
        Ok(())
    })
}

// ---------------------------------------------------------------------------
// Header

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Format {
    Ascii,
    BinaryLittleEndian,
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// Read a little-endian value at the start of `b` (which holds at least
    /// `self.size()` bytes).
    #[inline]
    fn read_le(self, b: &[u8]) -> f64 {
        fn arr<const N: usize>(b: &[u8]) -> [u8; N] {
            let mut a = [0u8; N];
            a.copy_from_slice(&b[..N]);
            a
        }
        match self {
            Scalar::I8 => b[0] as i8 as f64,
            Scalar::U8 => b[0] as f64,
            Scalar::I16 => i16::from_le_bytes(arr(b)) as f64,
            Scalar::U16 => u16::from_le_bytes(arr(b)) as f64,
            Scalar::I32 => i32::from_le_bytes(arr(b)) as f64,
            Scalar::U32 => u32::from_le_bytes(arr(b)) as f64,
            Scalar::F32 => f32::from_le_bytes(arr(b)) as f64,
            Scalar::F64 => f64::from_le_bytes(arr(b)),
        }
    }
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<(Scalar, String)>,
}

#[derive(Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Index of the `vertex` element in `elements`.
    vertex: usize,
    /// Byte offset of the body.
    body_start: usize,
    /// Number of lines in the header (ascii body line numbers follow it).
    lines: usize,
}

fn parse_header(bytes: &[u8]) -> std::result::Result<Header, String> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut vertex = None;
    loop {
        if pos >= bytes.len() {
            return Err(if line_no == 0 {
                "empty file (not a PLY file)".to_string()
            } else {
                "header has no end_header line".to_string()
            });
        }
        let end = bytes[pos..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |i| pos + i);
        let raw = &bytes[pos..end];
        pos = (end + 1).min(bytes.len());
        line_no += 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(if line_no == 1 {
                "not a PLY file (first line is not 'ply')".to_string()
            } else {
                format!("header line {line_no} is not valid UTF-8")
            });
        };
        let line = text.trim();
        if line_no == 1 {
            if line != "ply" {
                return Err("not a PLY file (first line is not 'ply')".to_string());
            }
            continue;
        }
        let mut words = line.split_ascii_whitespace();
        let Some(keyword) = words.next() else {
            continue; // blank header line
        };
        let rest: Vec<&str> = words.collect();
        match keyword {
            "comment" | "obj_info" => {}
            "format" => {
                if format.is_some() {
                    return Err(format!("header line {line_no}: second 'format' line"));
                }
                let (f, v) = match rest.as_slice() {
                    [f, v] => (*f, *v),
                    _ => return Err(format!("header line {line_no}: malformed 'format' line")),
                };
                if v != "1.0" {
                    return Err(format!("unsupported PLY version '{v}' (only 1.0)"));
                }
                format = Some(match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittleEndian,
                    "binary_big_endian" => {
                        return Err("format binary_big_endian is unsupported \
                                    (use ascii or binary_little_endian)"
                            .to_string())
                    }
                    other => return Err(format!("unsupported format '{other}'")),
                });
            }
            "element" => {
                let [name, count] = rest.as_slice() else {
                    return Err(format!(
                        "header line {line_no}: malformed element line '{line}'"
                    ));
                };
                let count: usize = count.parse().map_err(|_| {
                    format!("header line {line_no}: element count '{count}' is not a number")
                })?;
                if *name == "vertex" {
                    if vertex.is_some() {
                        return Err("header declares two 'vertex' elements".to_string());
                    }
                    vertex = Some(elements.len());
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            "property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(format!(
                        "header line {line_no}: property before any element"
                    ));
                };
                match rest.as_slice() {
                    ["list", ..] => {
                        return Err(format!(
                            "list properties are not supported (element '{}')",
                            el.name
                        ))
                    }
                    [ty, name] => {
                        let scalar = Scalar::from_name(ty).ok_or_else(|| {
                            format!("header line {line_no}: unknown property type '{ty}'")
                        })?;
                        if el.props.iter().any(|(_, n)| n == name) {
                            return Err(format!(
                                "element '{}' declares property '{name}' twice",
                                el.name
                            ));
                        }
                        el.props.push((scalar, name.to_string()));
                    }
                    _ => {
                        return Err(format!(
                            "header line {line_no}: malformed property line '{line}'"
                        ))
                    }
                }
            }
            "end_header" => break,
            other => {
                return Err(format!(
                    "header line {line_no}: unknown keyword '{other}' \
                     (is the end_header line missing?)"
                ))
            }
        }
    }
    let format = format.ok_or("header has no 'format' line")?;
    let vertex = vertex.ok_or("header has no 'element vertex' line")?;
    Ok(Header {
        format,
        elements,
        vertex,
        body_start: pos,
        lines: line_no,
    })
}

/// What one vertex property feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Slot {
    Skip,
    X,
    Y,
    Z,
    Intensity,
    Ring,
    Return,
    Label,
}

impl Slot {
    fn name(self) -> &'static str {
        match self {
            Slot::Skip => "?",
            Slot::X => "x",
            Slot::Y => "y",
            Slot::Z => "z",
            Slot::Intensity => "intensity",
            Slot::Ring => "ring",
            Slot::Return => "return",
            Slot::Label => "label",
        }
    }
}

/// The vertex properties mapped to point fields.
struct VertexLayout {
    /// One slot per vertex property, in file order.
    slots: Vec<Slot>,
    /// Property names (for messages), in file order.
    names: Vec<String>,
    has_labels: bool,
}

impl VertexLayout {
    fn new(header: &Header) -> std::result::Result<VertexLayout, String> {
        let el = &header.elements[header.vertex];
        let mut slots = Vec::with_capacity(el.props.len());
        for (_, name) in &el.props {
            slots.push(match name.as_str() {
                "x" => Slot::X,
                "y" => Slot::Y,
                "z" => Slot::Z,
                "intensity" => Slot::Intensity,
                "ring" => Slot::Ring,
                "return" => Slot::Return,
                "label" => Slot::Label,
                _ => Slot::Skip,
            });
        }
        for need in [
            Slot::X,
            Slot::Y,
            Slot::Z,
            Slot::Intensity,
            Slot::Ring,
            Slot::Return,
        ] {
            if !slots.contains(&need) {
                return Err(format!(
                    "header has no '{}' property (3DRef frames need x y z intensity ring return)",
                    need.name()
                ));
            }
        }
        Ok(VertexLayout {
            has_labels: slots.contains(&Slot::Label),
            slots,
            names: el.props.iter().map(|(_, n)| n.clone()).collect(),
        })
    }
}

// ---------------------------------------------------------------------------
// Field validation shared by both encodings

/// Where a vertex is, for messages: "line 17, vertex 5" or "vertex 5".
#[derive(Clone, Copy)]
struct Loc {
    line: usize,
    vertex: usize,
}

impl std::fmt::Display for Loc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "line {}, vertex {}", self.line, self.vertex)
        } else {
            write!(f, "vertex {}", self.vertex)
        }
    }
}

/// Store a non-coordinate value into `p`, validating it.
#[inline(always)]
fn store_int(p: &mut Point, slot: Slot, v: f64, loc: Loc) -> std::result::Result<(), String> {
    // Saturating casts: the value is valid iff it survives the round trip
    // (NaN, negative, fractional and too large values do not).
    match slot {
        Slot::Ring => {
            let r = v as u16;
            if r as f64 == v {
                p.ring = r;
                return Ok(());
            }
        }
        Slot::Return => {
            if v == 1.0 || v == 2.0 {
                p.ret = v as u8;
                return Ok(());
            }
        }
        Slot::Label => {
            let l = v as u8;
            if l as f64 == v && l <= 6 {
                p.label = l;
                return Ok(());
            }
        }
        _ => return Ok(()),
    }
    Err(bad_int(slot, v, loc))
}

#[cold]
fn bad_int(slot: Slot, v: f64, loc: Loc) -> String {
    match slot {
        Slot::Ring => format!("{loc}: ring must be an integer in 0..=65535, got {v}"),
        Slot::Return => format!("{loc}: return must be 1 or 2, got {v}"),
        _ => format!("{loc}: label must be an integer in 0..=6, got {v}"),
    }
}

#[inline]
fn check_point(p: &Point, loc: Loc) -> std::result::Result<(), String> {
    if !(p.xyz[0].is_finite() && p.xyz[1].is_finite() && p.xyz[2].is_finite()) {
        let what = if p.xyz.iter().any(|c| c.is_nan()) {
            "NaN"
        } else {
            "infinite"
        };
        return Err(format!("{loc}: coordinates are not finite ({what})"));
    }
    if !p.intensity.is_finite() {
        return Err(format!("{loc}: intensity is not finite ({})", p.intensity));
    }
    Ok(())
}

fn truncated(expected: usize, got: usize) -> String {
    format!("expected {expected} vertices, file ends after {got} (truncated?)")
}

// ---------------------------------------------------------------------------
// Binary body

fn parse_binary(
    body: &[u8],
    header: &Header,
    layout: &VertexLayout,
) -> std::result::Result<Vec<Point>, String> {
    let el_size = |el: &Element| el.props.iter().map(|(t, _)| t.size()).sum::<usize>();
    let overflow = || "element sizes overflow".to_string();
    let mut offset = 0usize;
    for el in &header.elements[..header.vertex] {
        offset = el_size(el)
            .checked_mul(el.count)
            .and_then(|s| s.checked_add(offset))
            .ok_or_else(overflow)?;
    }
    let vel = &header.elements[header.vertex];
    let n = vel.count;
    if n == 0 {
        return Err("frame has no points".to_string());
    }
    if offset > body.len() {
        return Err(format!(
            "file ends inside element '{}' before the vertices (truncated?)",
            header.elements[..header.vertex]
                .iter()
                .rev()
                .find(|e| e.count > 0)
                .map_or("?", |e| e.name.as_str())
        ));
    }
    let stride = el_size(vel);
    if stride == 0 {
        return Err("vertex element has no properties".to_string());
    }
    let vbytes = stride.checked_mul(n).ok_or_else(overflow)?;
    let avail = body.len() - offset;
    if avail < vbytes {
        return Err(truncated(n, avail / stride));
    }
    let mut rest = offset + vbytes;
    for el in &header.elements[header.vertex + 1..] {
        rest = el_size(el)
            .checked_mul(el.count)
            .and_then(|s| s.checked_add(rest))
            .ok_or_else(overflow)?;
    }
    if rest > body.len() {
        return Err("file ends inside the elements after the vertices (truncated?)".to_string());
    }
    if rest < body.len() {
        return Err(format!(
            "{} unexpected bytes after the last element (wrong vertex count?)",
            body.len() - rest
        ));
    }

    // (offset in record, type, slot) of the fields we read.
    let mut fields = Vec::new();
    let mut off = 0;
    for ((ty, _), &slot) in vel.props.iter().zip(&layout.slots) {
        if slot != Slot::Skip {
            fields.push((off, *ty, slot));
        }
        off += ty.size();
    }

    let mut points = Vec::with_capacity(n);
    for (i, rec) in body[offset..offset + vbytes]
        .chunks_exact(stride)
        .enumerate()
    {
        let loc = Loc { line: 0, vertex: i };
        let mut p = Point::default();
        for &(o, ty, slot) in &fields {
            let b = &rec[o..];
            match slot {
                Slot::X | Slot::Y | Slot::Z | Slot::Intensity => {
                    let v = if ty == Scalar::F32 {
                        f32::from_le_bytes([b[0], b[1], b[2], b[3]])
                    } else {
                        ty.read_le(b) as f32
                    };
                    match slot {
                        Slot::X => p.xyz[0] = v,
                        Slot::Y => p.xyz[1] = v,
                        Slot::Z => p.xyz[2] = v,
                        _ => p.intensity = v,
                    }
                }
                _ => store_int(&mut p, slot, ty.read_le(b), loc)?,
            }
        }
        check_point(&p, loc)?;
        points.push(p);
    }
    Ok(points)
}

// ---------------------------------------------------------------------------
// Ascii body

/// Separator bytes: space, \t, \n, \v, \f, \r.
#[inline(always)]
fn is_ws(b: u8) -> bool {
    b == b' ' || b.wrapping_sub(b'\t') < 5
}

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

/// Fast path for an unsigned integer field written as `digits[.0*]`
/// (`36`, `36.0`). `None` for any other form (the caller falls back to the
/// general parser).
#[inline(always)]
fn parse_uint_fast(b: &[u8], mut p: usize) -> Option<(f64, usize)> {
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

/// Skip to the start of the next line (past `\n`), or to the end.
#[inline]
fn next_line(b: &[u8], p: usize) -> usize {
    b[p..]
        .iter()
        .position(|&c| c == b'\n')
        .map_or(b.len(), |i| p + i + 1)
}

/// Exact powers of ten representable in `f64`.
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Fast path for a decimal number `[+-]digits[.digits][(e|E)[+-]digits]`
/// starting at `p`. Returns the correctly rounded `f64` and the end of the
/// token, or `None` when the token has another form or the value is outside
/// the exact fast path (mantissa above 2^53, more than 19 significant digits,
/// decimal exponent outside ±22); the caller then uses the standard parser.
#[inline(always)]
fn parse_fast(b: &[u8], mut p: usize) -> Option<(f64, usize)> {
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
fn f32_halfway(v: f64) -> bool {
    v.to_bits() & 0x1FFF_FFFF == 0x1000_0000
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

fn not_a_number(line: usize, name: &str, tok: &[u8]) -> String {
    format!(
        "line {line}: property '{name}' is not a number: '{}'",
        show_token(tok)
    )
}

/// Slow path: parse the token with the standard library.
#[cold]
fn parse_slow_f64(tok: &[u8]) -> Option<f64> {
    std::str::from_utf8(tok).ok()?.parse::<f64>().ok()
}

#[cold]
fn parse_slow_f32(tok: &[u8]) -> Option<f32> {
    std::str::from_utf8(tok).ok()?.parse::<f32>().ok()
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

fn parse_ascii(
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
        check_point(&p, loc)?;
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
