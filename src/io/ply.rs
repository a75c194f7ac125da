//! 3DRef PLY frames: a fast reader (ascii and binary_little_endian,
//! properties found by name) and a compact binary writer.

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

/// Read one 3DRef frame. The file stem is the timestamp in seconds.
pub fn read_frame(path: &Path) -> Result<Frame> {
    todo!("{}", path.display())
}

/// Parse a frame from the bytes of a PLY file (`path` names it in errors and
/// gives the stem/timestamp).
pub fn parse_frame(bytes: &[u8], path: &Path) -> Result<Frame> {
    todo!("{} {}", bytes.len(), path.display())
}

/// Write a frame with properties `x y z intensity ring return label`.
pub fn write_frame(path: &Path, frame: &Frame, encoding: PlyEncoding) -> Result<()> {
    todo!("{} {} {:?}", path.display(), frame.points.len(), encoding)
}
