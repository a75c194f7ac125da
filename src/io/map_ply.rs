//! Classified point-cloud maps as PLY (readable by CloudCompare and Open3D):
//! `x y z` (float), `red green blue` (uchar), `class` (uchar, prediction
//! ids), `mirrored` (uchar, 1 for reflections moved back through their
//! plane) and `confidence` (float, the probability that the class is
//! right; NaN where the method gives none).

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
    /// The probability that `class` is right (of the point kept for the
    /// voxel); NaN where the method gives none.
    pub confidence: f32,
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
            "ply\nformat binary_little_endian 1.0\ncomment written by specular: class 1 normal, 2 reflective surface, 5 reflection, 6 obstacle behind glass\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar class\nproperty uchar mirrored\nproperty float confidence\nend_header\n",
            points.len()
        )?;
        // Through a small reused chunk: no buffer the size of the map.
        const RECORD: usize = 21;
        let mut chunk = [0u8; 256 * RECORD];
        for points in points.chunks(256) {
            for (out, p) in chunk.chunks_exact_mut(RECORD).zip(points) {
                for (k, c) in p.xyz.iter().enumerate() {
                    out[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
                }
                out[12..15].copy_from_slice(&class_colour(p.class, p.mirrored));
                out[15] = p.class.id();
                out[16] = p.mirrored as u8;
                out[17..21].copy_from_slice(&p.confidence.to_le_bytes());
            }
            w.write_all(&chunk[..points.len() * RECORD])?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header names every column, and each record holds the point's
    /// position, colour, class, mirroring and confidence at their offsets.
    #[test]
    fn records_carry_the_confidence() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("map.ply");
        let points = [
            MapPoint {
                xyz: [1.0, 2.0, 3.0],
                class: Class::Glass,
                mirrored: false,
                confidence: 0.75,
            },
            MapPoint {
                xyz: [-1.0, 0.5, 0.0],
                class: Class::Reflection,
                mirrored: true,
                confidence: f32::NAN,
            },
        ];
        write_map_ply(&path, &points).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        let header = std::str::from_utf8(&bytes[..end]).unwrap();
        assert!(
            header.contains("property uchar mirrored\nproperty float confidence\nend_header"),
            "{header}"
        );
        let body = &bytes[end..];
        assert_eq!(body.len(), 2 * 21);
        let f = |r: &[u8], at: usize| f32::from_le_bytes(r[at..at + 4].try_into().unwrap());
        let (a, b) = (&body[..21], &body[21..]);
        assert_eq!((f(a, 0), f(a, 4), f(a, 8)), (1.0, 2.0, 3.0));
        assert_eq!(&a[12..15], &class_colour(Class::Glass, false));
        assert_eq!((a[15], a[16]), (2, 0));
        assert_eq!(f(a, 17), 0.75);
        assert_eq!((b[15], b[16]), (5, 1));
        assert!(f(b, 17).is_nan());
    }
}
