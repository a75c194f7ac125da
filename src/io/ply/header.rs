//! The PLY header: format, elements and their scalar properties, and where
//! the body starts.

use crate::cloud::IntensityScale;
use crate::error::excerpt as ex;

/// The body encoding a header declares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Format {
    Ascii,
    BinaryLittleEndian,
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scalar {
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
    /// The type a header names (`float`, `uchar`, `int32`, ...).
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

    /// Whether the type is a floating-point one (`float`, `double`).
    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The name the writer gives the type (for messages).
    pub(super) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// Bytes of one value.
    pub(super) fn size(self) -> usize {
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
    pub(super) fn read_le(self, b: &[u8]) -> f64 {
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

/// One `element` of the header: its name, count and properties.
#[derive(Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) props: Vec<(Scalar, String)>,
}

/// A parsed header.
#[derive(Debug)]
pub(super) struct Header {
    pub(super) format: Format,
    pub(super) elements: Vec<Element>,
    /// Index of the `vertex` element in `elements`.
    pub(super) vertex: usize,
    /// Byte offset of the body.
    pub(super) body_start: usize,
    /// Number of lines in the header (ascii body line numbers follow it).
    pub(super) lines: usize,
    /// What the intensities measure, from a `comment intensity_scale NAME`
    /// line (specular writes one for its simulated frames).
    pub(super) intensity_scale: Option<IntensityScale>,
    /// The sensor the frame was taken with, from a `comment sensor NAME`
    /// line (specular writes one for simulated frames of a sensor other
    /// than the 3DRef QT64).
    pub(super) sensor: Option<String>,
}

/// Parse the header at the start of a file; the error says what is wrong
/// (the caller names the file).
pub(super) fn parse_header(bytes: &[u8]) -> std::result::Result<Header, String> {
    let mut pos = 0usize;
    let mut line_no = 0usize;
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut vertex = None;
    let mut intensity_scale = None;
    let mut sensor = None;
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
            "comment" if rest.first() == Some(&"intensity_scale") => {
                let name = rest.get(1).copied().unwrap_or("");
                intensity_scale = Some(IntensityScale::from_name(name).ok_or_else(|| {
                    format!(
                        "header line {line_no}: unknown intensity_scale '{}' \
                         (reflectivity or raw-power)",
                        ex(name)
                    )
                })?);
            }
            "comment" if rest.first() == Some(&"sensor") => match rest.get(1) {
                Some(name) if rest.len() == 2 => sensor = Some(name.to_string()),
                _ => {
                    return Err(format!(
                        "header line {line_no}: 'comment sensor' takes one sensor name"
                    ))
                }
            },
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
                    return Err(format!("unsupported PLY version '{}' (only 1.0)", ex(v)));
                }
                format = Some(match f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::BinaryLittleEndian,
                    "binary_big_endian" => {
                        return Err("format binary_big_endian is unsupported \
                                    (use ascii or binary_little_endian)"
                            .to_string())
                    }
                    other => return Err(format!("unsupported format '{}'", ex(other))),
                });
            }
            "element" => {
                let [name, count] = rest.as_slice() else {
                    return Err(format!(
                        "header line {line_no}: malformed element line '{}'",
                        ex(line)
                    ));
                };
                let count: usize = count.parse().map_err(|_| {
                    format!(
                        "header line {line_no}: element count '{}' is not a number",
                        ex(count)
                    )
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
                            ex(&el.name)
                        ))
                    }
                    [ty, name] => {
                        let scalar = Scalar::from_name(ty).ok_or_else(|| {
                            format!("header line {line_no}: unknown property type '{}'", ex(ty))
                        })?;
                        if el.props.iter().any(|(_, n)| n == name) {
                            return Err(format!(
                                "element '{}' declares property '{}' twice",
                                ex(&el.name),
                                ex(name)
                            ));
                        }
                        el.props.push((scalar, name.to_string()));
                    }
                    _ => {
                        return Err(format!(
                            "header line {line_no}: malformed property line '{}'",
                            ex(line)
                        ))
                    }
                }
            }
            "end_header" => break,
            other => {
                return Err(format!(
                    "header line {line_no}: unknown keyword '{}' \
                     (is the end_header line missing?)",
                    ex(other)
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
        intensity_scale,
        sensor,
    })
}
