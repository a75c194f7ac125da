//! The frame writer: `x y z intensity ring return [label] [time]`, ascii
//! or binary little-endian, written atomically.

use std::io::Write;
use std::path::Path;

use crate::cloud::Frame;
use crate::Result;

/// PLY body encoding for writing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlyEncoding {
    /// `format ascii 1.0`, as the real 3DRef files.
    Ascii,
    /// `format binary_little_endian 1.0`, compact and fast.
    #[default]
    BinaryLittleEndian,
}

/// Write a frame with properties `x y z intensity ring return label time`
/// (`label` only when [`Frame::has_labels`], `time` only when some point
/// has a non-zero [`time`](crate::cloud::Point::time): frames without
/// per-point time are written as before), atomically.
///
/// Types are `float x y z intensity time`, `ushort ring`, `uchar return
/// label`.
/// A frame whose intensity scale is known says so in a header comment
/// (`comment intensity_scale raw-power`), which the reader takes back.
/// The ascii encoding writes floats in their shortest round-trip form, so
/// reading the file back gives identical points.
pub fn write_frame(path: &Path, frame: &Frame, encoding: PlyEncoding) -> Result<()> {
    write_frame_of(path, frame, encoding, None)
}

/// [`write_frame`], saying in a header comment which sensor took the frame
/// (`comment sensor ouster_os0_128`) when `sensor` is given, so that a
/// reader picks its model ([`frame_sensor`](super::frame_sensor)).
pub fn write_frame_of(
    path: &Path,
    frame: &Frame,
    encoding: PlyEncoding,
    sensor: Option<&str>,
) -> Result<()> {
    crate::io::write_atomic(path, |w| {
        let format = match encoding {
            PlyEncoding::Ascii => "ascii",
            PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        };
        write!(w, "ply\nformat {format} 1.0\ncomment written by specular\n")?;
        if let Some(scale) = frame.intensity_scale {
            writeln!(w, "comment intensity_scale {}", scale.name())?;
        }
        if let Some(name) = sensor {
            writeln!(w, "comment sensor {name}")?;
        }
        write!(
            w,
            "element vertex {}\n\
             property float x\nproperty float y\nproperty float z\n\
             property float intensity\nproperty ushort ring\nproperty uchar return\n",
            frame.points.len()
        )?;
        if frame.has_labels {
            w.write_all(b"property uchar label\n")?;
        }
        let timed = frame.points.iter().any(|p| p.time != 0.0);
        if timed {
            writeln!(w, "property float {}", super::vertex::TIME_PROPERTY)?;
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
                    if timed {
                        write!(w, " {}", p.time)?;
                    }
                    w.write_all(b"\n")?;
                }
            }
            PlyEncoding::BinaryLittleEndian => {
                let rec = 19 + usize::from(frame.has_labels) + 4 * usize::from(timed);
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
                        if timed {
                            buf.extend_from_slice(&p.time.to_le_bytes());
                        }
                    }
                    w.write_all(&buf)?;
                }
            }
        }
        Ok(())
    })
}
