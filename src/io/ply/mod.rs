//! 3DRef PLY frames: a fast reader (ascii and binary_little_endian,
//! properties found by name) and a compact binary writer.
//!
//! The reader needs the vertex properties `x y z intensity ring return` and
//! reads `label` and `time` (per-point time, seconds after the frame's
//! stamp, `float` or `double`; [`crate::cloud::Point::time`]) when
//! present; the writer writes `time` only for frames whose points carry
//! one; every other property (`nx ny nz`, ...) is
//! skipped without being parsed. Properties may have any PLY scalar type.
//! Elements other than `vertex` are skipped; list properties are rejected.
//! A header comment `comment intensity_scale raw-power` (or `reflectivity`)
//! says what the intensities measure ([`crate::cloud::IntensityScale`]);
//! the writer adds it for frames that know (the simulator's). A comment
//! `comment sensor NAME` names the sensor model ([`frame_sensor`]); the
//! simulator writes it for every sensor but the 3DRef QT64.
//!
//! The ascii body is parsed from bytes without allocation per point, one
//! token at a time, the numbers by the `fast-float2` crate, which gives
//! exactly the standard library's (correctly rounded) values. It replaced
//! a hand-written SWAR/SSE2 parser of about 1,000 lines, which made the
//! whole command only 1.16x faster: the measurement is in `number.rs`.
//! Errors name the file and, for ascii bodies, the 1-based line number;
//! vertex numbers in messages are 0-based indices into the file's vertices.
//!
//! Vertices whose `x`, `y`, `z` or `intensity` is NaN or infinite (`nan`,
//! `inf` in ascii) are not errors: real recordings hold them for beams
//! without a return; nor are points exactly at the origin, which drivers
//! write for the same. They are set aside after parsing and counted in
//! [`crate::cloud::Frame::dropped_non_finite`], exactly as the ROS 2 bag
//! reader does (see [`crate::cloud::set_aside_non_returns`]); the other
//! points keep their order and their labels, and [`read_frame_full`] says
//! where the ones set aside were, so outputs keep one entry per input point. A malformed file (bad header, wrong counts,
//! truncated, a field that is not a number, an integer out of range) is
//! still an error naming the file.
//!
//! The rooms: `read` (files to frames), `header` (the PLY header),
//! `vertex` (vertex properties to point fields, the checks both encodings
//! share), `binary` and `ascii` (the two body encodings), `number` (decimal
//! numbers of the ascii body), `write` (the writer).

mod ascii;
mod binary;
mod header;
mod number;
mod read;
mod vertex;
mod write;

pub use read::{
    frame_sensor, parse_frame, parse_frame_full, read_frame, read_frame_full, read_frames,
};
pub use write::{write_frame, write_frame_of, PlyEncoding};
