//! 3DRef PLY frames: a fast reader (ascii and binary_little_endian,
//! properties found by name) and a compact binary writer.
//!
//! The reader needs the vertex properties `x y z intensity ring return` and
//! reads `label` when present; every other property (`nx ny nz`, ...) is
//! skipped without being parsed. Properties may have any PLY scalar type.
//! Elements other than `vertex` are skipped; list properties are rejected.
//!
//! The ascii body is parsed from bytes without allocation per point. Lines
//! of the usual form (single spaces, `[-]digits.digits` floats, `digits.0`
//! integers) take a fast line parser; every other line takes a general
//! parser with a hand-rolled number parser, which falls back to the standard
//! library for unusual forms (`nan`, `inf`, more than 19 significant digits,
//! large exponents). Both give the same (correctly rounded) values.
//! Errors name the file and, for ascii bodies, the 1-based line number;
//! vertex numbers in messages are 0-based indices into the file's vertices.
//!
//! Vertices whose `x`, `y`, `z` or `intensity` is NaN or infinite (`nan`,
//! `inf` in ascii) are not errors: real recordings hold them for beams
//! without a return. They are dropped after parsing and counted in
//! [`Frame::dropped_non_finite`], exactly as the ROS 2 bag reader does
//! (see [`crate::cloud::drop_non_finite`]); the other points keep their
//! order and their labels. A malformed file (bad header, wrong counts,
//! truncated, a field that is not a number, an integer out of range) is
//! still an error naming the file.

use std::io::Write;
use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::cloud::{drop_non_finite, Frame, Point};
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
/// The file is mapped into memory (its pages mapped up front) and parsed in
/// place: for a 3.7 MB frame that costs 0.5 ms, where the kernel's copy into
/// a buffer cost 1.1 ms. Where it cannot be mapped (a pipe, a special file),
/// it is read instead.
pub fn read_frame(path: &Path) -> Result<Frame> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // SAFETY: the map is only read, and only while this function runs. The
    // one hazard of a file mapping, another process truncating the file in
    // that time, ends the process with SIGBUS rather than reading wrong
    // bytes; reading frames that are being rewritten is not supported.
    match unsafe { memmap2::MmapOptions::new().populate().map(&file) } {
        Ok(map) => parse_frame(&map, path),
        Err(_) => {
            let mut bytes = Vec::new();
            let mut file = file;
            std::io::Read::read_to_end(&mut file, &mut bytes).map_err(|e| Error::io(path, e))?;
            parse_frame(&bytes, path)
        }
    }
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
    let mut points = match header.format {
        Format::Ascii => parse_ascii(body, &header, &layout).map_err(fail)?,
        Format::BinaryLittleEndian => parse_binary(body, &header, &layout).map_err(fail)?,
    };
    let dropped_non_finite = drop_non_finite(&mut points);
    Ok(Frame {
        name,
        stamp,
        points,
        has_labels: layout.has_labels,
        dropped_non_finite,
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

// ---------------------------------------------------------------------------
// Fast line parser
//
// Nearly every line of a 3DRef frame has the form
// `x y z nx ny nz intensity ring return label\n` with single spaces, floats
// written `[-]digits.digits` and integer fields written `digits.0`. The fast
// line parser accepts exactly such lines (for any property layout) and
// returns `None` for anything else; the caller then parses that line with the
// general code below, so errors, blank lines, unusual separators and number
// forms behave exactly as without the fast path. Whenever the fast path
// accepts a line its values are the correctly rounded ones, which the general
// path also gives (see `fast_float`).
//
// The fast path reads a fixed window of `WIN` bytes at the line start, so
// every index is checked against a constant; lines that do not end within
// the window and the last few lines of the body use the general path.

/// Bytes of the window the fast line parser reads.
const WIN: usize = 256;
/// Largest window index at which the fast parser starts a token (every token
/// parser reads at most 32 bytes from its start).
const TOKEN_LIMIT: usize = WIN - 32;

/// One step of the fast line parser.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Op {
    /// A float stored as `x`, `y`, `z` (0, 1, 2) or `intensity` (3).
    Float(usize),
    /// An integer field (ring, return or label) written `digits.0`.
    Int(Slot),
    /// This many consecutive tokens that are not parsed.
    Skip(usize),
}

/// The fast-path steps for a vertex layout (consecutive skipped properties
/// merged into one step).
fn fast_plan(slots: &[Slot]) -> Vec<Op> {
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
const PLAN_3DREF: [Op; 8] = [
    Op::Float(0),
    Op::Float(1),
    Op::Float(2),
    Op::Skip(3),
    Op::Float(3),
    Op::Int(Slot::Ring),
    Op::Int(Slot::Return),
    Op::Int(Slot::Label),
];

const ONES: u64 = 0x0101_0101_0101_0101;
const HIGHS: u64 = 0x8080_8080_8080_8080;

/// The eight bytes of `w` at `i` as a little-endian word (byte `i` lowest).
#[inline(always)]
fn word(w: &[u8; WIN], i: usize) -> u64 {
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
fn fast_float<const PLAIN: bool>(w: &[u8; WIN], q: usize) -> Option<(f32, usize)> {
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
fn fast_uint<const PLAIN: bool>(w: &[u8; WIN], q: usize) -> Option<(u32, usize)> {
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
fn skip_tokens<B: BlankScan>(w: &[u8; WIN], mut q: usize, mut n: usize) -> Option<usize> {
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
trait BlankScan {
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
struct SwarBlanks;

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
struct Sse2Blanks;

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
type Blanks = Sse2Blanks;
/// The [`BlankScan`] the fast path uses.
#[cfg(not(all(target_arch = "x86_64", target_feature = "sse2")))]
type Blanks = SwarBlanks;

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
fn fast_lines(
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
fn fast_line_3dref(w: &[u8; WIN]) -> Option<(Point, usize)> {
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
fn fast_line(w: &[u8; WIN], plan: &[Op]) -> Option<(Point, usize)> {
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
mod tests {
    use super::*;

    /// Four points, the third with coordinates `bad` (and an odd label, so
    /// label alignment is checked): as ascii and as binary PLY bytes.
    fn with_bad_point(bad: [f32; 3]) -> (Vec<Point>, [Vec<u8>; 2]) {
        let points: Vec<Point> = (0..4u8)
            .map(|i| Point {
                xyz: if i == 2 {
                    bad
                } else {
                    [1.5 + i as f32, -2.0, 0.25]
                },
                intensity: 10.0 + i as f32,
                ring: 7 + i as u16,
                ret: 1 + i % 2,
                label: i + 1,
            })
            .collect();
        let header = |format: &str| {
            format!(
                "ply\nformat {format} 1.0\nelement vertex 4\nproperty float x\n\
                 property float y\nproperty float z\nproperty float intensity\n\
                 property ushort ring\nproperty uchar return\nproperty uchar label\nend_header\n"
            )
            .into_bytes()
        };
        let mut ascii = header("ascii");
        let mut binary = header("binary_little_endian");
        for p in &points {
            let [x, y, z] = p.xyz;
            // `{}` writes NaN as `NaN` and infinity as `inf`/`-inf`.
            let line = format!(
                "{x} {y} {z} {} {} {} {}\n",
                p.intensity, p.ring, p.ret, p.label
            );
            ascii.extend_from_slice(line.as_bytes());
            for v in [x, y, z, p.intensity] {
                binary.extend_from_slice(&v.to_le_bytes());
            }
            binary.extend_from_slice(&p.ring.to_le_bytes());
            binary.extend_from_slice(&[p.ret, p.label]);
        }
        (points, [ascii, binary])
    }

    /// A NaN or infinite point among finite ones is dropped and counted,
    /// in both encodings; the others keep their order and labels.
    #[test]
    fn non_finite_points_are_dropped_and_counted() {
        let path = Path::new("/data/1689496219.652560.ply");
        for bad in [
            [1.0, f32::NAN, 2.0],
            [f32::NAN; 3],
            [f32::INFINITY, 0.0, 0.0],
            [0.0, 0.0, f32::NEG_INFINITY],
        ] {
            let (points, files) = with_bad_point(bad);
            let mut want = points.clone();
            want.remove(2);
            for bytes in files {
                let frame = parse_frame(&bytes, path).unwrap();
                assert_eq!(frame.dropped_non_finite, 1, "{bad:?}");
                assert_eq!(frame.points, want, "{bad:?}");
                assert!(frame.has_labels);
                assert_eq!(frame.labels(), vec![1, 2, 4]);
            }
        }
        // Nothing dropped from a clean frame.
        let (points, files) = with_bad_point([3.0, 3.0, 3.0]);
        for bytes in files {
            let frame = parse_frame(&bytes, path).unwrap();
            assert_eq!(frame.dropped_non_finite, 0);
            assert_eq!(frame.points, points);
        }
    }

    /// A NaN intensity drops its point the same way; malformed files are
    /// still errors naming the file.
    #[test]
    fn non_finite_intensity_is_dropped_and_malformed_files_still_fail() {
        let path = Path::new("/data/1689496219.652560.ply");
        let (_, [ascii, _]) = with_bad_point([3.0, 3.0, 3.0]);
        let text = String::from_utf8(ascii).unwrap();
        let nan_intensity = text.replacen(" 11 ", " nan ", 1);
        assert_ne!(nan_intensity, text);
        let frame = parse_frame(nan_intensity.as_bytes(), path).unwrap();
        assert_eq!((frame.points.len(), frame.dropped_non_finite), (3, 1));
        for bad in [
            text.replacen("element vertex 4", "element vertex 5", 1),
            text.replacen("element vertex 4", "element vertex 3", 1),
            text.replacen("end_header", "end_hdr", 1),
            text.replacen(" 11 ", " x11 ", 1),
        ] {
            let err = parse_frame(bad.as_bytes(), path).unwrap_err().to_string();
            assert!(err.contains("1689496219.652560.ply"), "{err}");
        }
    }

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

    // --- fast line parser -------------------------------------------------

    /// Parse an ascii PLY file's body with the fast line parser on or off.
    fn parse_both(bytes: &[u8]) -> [std::result::Result<Vec<Point>, String>; 2] {
        let header = parse_header(bytes).expect("header");
        let layout = VertexLayout::new(&header).expect("layout");
        let body = &bytes[header.body_start..];
        [true, false].map(|fast| parse_ascii_with(body, &header, &layout, fast))
    }

    fn bits(points: &[Point]) -> Vec<[u32; 7]> {
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

    /// The window of `body` at `pos` (zero-padded past the end).
    fn window(body: &[u8], pos: usize) -> [u8; WIN] {
        let mut w = [0u8; WIN];
        let n = body.len().saturating_sub(pos).min(WIN);
        w[..n].copy_from_slice(&body[pos..pos + n]);
        w
    }

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
