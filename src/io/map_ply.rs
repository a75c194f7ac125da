//! Classified point-cloud maps as PLY (readable by CloudCompare and Open3D):
//! `x y z` (float), `red green blue` (uchar), `class` (uchar, prediction
//! ids) and `mirrored` (uchar, 1 for reflections moved back through their
//! plane).

use std::io::Write;
use std::path::Path;

use super::write_atomic;
use crate::classify::Class;
use crate::Result;

/// One point of a classified map (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapPoint {
    /// Position, world frame.
    pub xyz: [f32; 3],
    /// Predicted class.
    pub class: Class,
    /// Whether the point is a reflection mirrored back to its true place.
    pub mirrored: bool,
}

/// Display colour of a map point: Normal grey, reflective surface green,
/// Obstacle blue, mirrored Reflection red (the paper's figure colours),
/// unmirrored Reflection orange.
pub fn class_colour(class: Class, mirrored: bool) -> [u8; 3] {
    match (class, mirrored) {
        (Class::Normal, _) => [110, 110, 110],
        (Class::Glass, _) => [0, 200, 0],
        (Class::Obstacle, _) => [0, 60, 255],
        (Class::Reflection, true) => [230, 0, 0],
        (Class::Reflection, false) => [255, 150, 0],
        (Class::Unclassified, _) => [200, 200, 200],
    }
}

/// Write a classified map as binary little-endian PLY (atomically).
pub fn write_map_ply(path: &Path, points: &[MapPoint]) -> Result<()> {
    write_atomic(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment written by specular: class 1 normal, 2 reflective surface, 5 reflection, 6 obstacle behind glass\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar class\nproperty uchar mirrored\nend_header\n",
            points.len()
        )?;
        // Through a small reused chunk: no buffer the size of the map.
        const RECORD: usize = 17;
        let mut chunk = [0u8; 256 * RECORD];
        for points in points.chunks(256) {
            for (out, p) in chunk.chunks_exact_mut(RECORD).zip(points) {
                for (k, c) in p.xyz.iter().enumerate() {
                    out[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
                }
                out[12..15].copy_from_slice(&class_colour(p.class, p.mirrored));
                out[15] = p.class.id();
                out[16] = p.mirrored as u8;
            }
            w.write_all(&chunk[..points.len() * RECORD])?;
        }
        Ok(())
    })
}
