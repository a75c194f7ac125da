//! Reading frames: files read into memory, parsed by the header's
//! encoding, non-finite points dropped and counted.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::ascii::parse_ascii;
use super::binary::parse_binary;
use super::header::{parse_header, Format};
use super::vertex::VertexLayout;
use crate::cloud::{set_aside_non_returns, Frame, SetAside};
use crate::io::frames::parse_stamp;
use crate::{Error, Result};

/// Read one 3DRef frame. The file stem is the timestamp in seconds.
///
/// The file is read into memory and parsed there. It used to be mapped
/// (0.5 ms for a 3.7 MB frame where the copy costs about 1 ms more), but a
/// mapped file that another process truncates ends the reading process
/// with SIGBUS, nothing printed (issue 39: 2 tries in 10); a copy read
/// from a file that shrinks is at worst truncated, which the parser
/// reports as an error naming the file.
pub fn read_frame(path: &Path) -> Result<Frame> {
    read_frame_full(path).map(|(frame, _)| frame)
}

/// [`read_frame`], and where the points it set aside were in the file
/// ([`SetAside`]): to write or score one entry per input point.
pub fn read_frame_full(path: &Path) -> Result<(Frame, SetAside)> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_frame_full(&bytes, path)
}

/// Read several frames in parallel (rayon), in the order of `paths`.
///
/// All files are read and parsed; when any fails, the error of the first
/// failing path (in `paths` order) is returned.
pub fn read_frames(paths: &[PathBuf]) -> Result<Vec<Frame>> {
    let results: Vec<Result<Frame>> = paths.par_iter().map(|p| read_frame(p)).collect();
    results.into_iter().collect()
}

/// The sensor a PLY frame names in its header (`comment sensor NAME`),
/// reading no more than the header; `None` when it names none.
pub fn frame_sensor(path: &Path) -> Result<Option<String>> {
    use std::io::Read;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // A header is a few hundred bytes; 64 KiB holds any sane one.
    let mut bytes = Vec::with_capacity(4096);
    file.take(64 * 1024)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    let header = parse_header(&bytes).map_err(|m| Error::format(path, m))?;
    Ok(header.sensor)
}

/// Parse a frame from the bytes of a PLY file (`path` names it in errors and
/// gives the stem/timestamp).
pub fn parse_frame(bytes: &[u8], path: &Path) -> Result<Frame> {
    parse_frame_full(bytes, path).map(|(frame, _)| frame)
}

/// [`parse_frame`], and where the points it set aside were ([`SetAside`]).
pub fn parse_frame_full(bytes: &[u8], path: &Path) -> Result<(Frame, SetAside)> {
    let (name, stamp) = parse_stamp(path)?;
    let fail = |msg: String| Error::format(path, msg);
    let header = parse_header(bytes).map_err(fail)?;
    let layout = VertexLayout::new(&header).map_err(fail)?;
    let body = &bytes[header.body_start..];
    let mut points = match header.format {
        Format::Ascii => parse_ascii(body, &header, &layout).map_err(fail)?,
        Format::BinaryLittleEndian => parse_binary(body, &header, &layout).map_err(fail)?,
    };
    let aside = set_aside_non_returns(&mut points);
    let frame = Frame {
        name,
        stamp,
        points,
        has_labels: layout.has_labels,
        dropped_non_finite: aside.len(),
        intensity_scale: header.intensity_scale,
    };
    Ok((frame, aside))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Point;

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
                time: 0.0,
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
}
