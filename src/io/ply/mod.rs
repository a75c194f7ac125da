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
//!
//! The rooms: [`read`] (files to frames), [`header`] (the PLY header),
//! [`vertex`] (vertex properties to point fields, shared checks),
//! [`binary`] and [`ascii`] (the two body encodings), [`number`] (decimal
//! numbers of the general ascii path), [`fast_line`] and [`swar`] (the fast
//! ascii line parser and its word-at-a-time helpers), [`write`] (the writer).

mod ascii;
mod binary;
mod fast_line;
mod header;
mod number;
mod read;
mod swar;
mod vertex;
mod write;

pub use read::{parse_frame, read_frame, read_frames};
pub use write::{write_frame, PlyEncoding};
