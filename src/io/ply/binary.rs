//! The `binary_little_endian` body: fixed-size records, read in place.

use super::header::{Element, Header, Scalar};
use super::vertex::{store_int, store_time, truncated, Loc, Slot, VertexLayout};
use crate::cloud::Point;

/// Parse the vertices of a `binary_little_endian` body, after checking that
/// the body has exactly the bytes the header declares.
pub(super) fn parse_binary(
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
                .map_or("?".into(), |e| crate::error::excerpt(&e.name))
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

    let records = &body[offset..offset + vbytes];
    if is_compact(&vel.props, &layout.slots) {
        if let Some(points) = parse_compact(records) {
            return Ok(points);
        }
        // A field out of range: the general loop names it.
    }
    parse_records(records, &vel.props, &layout.slots)
}

/// The points of fixed-size records of the properties `props`, each read
/// into its slot (`slots`, in the same order); errors name the vertex.
fn parse_records(
    records: &[u8],
    props: &[(Scalar, String)],
    slots: &[Slot],
) -> std::result::Result<Vec<Point>, String> {
    // (offset in record, type, slot) of the fields we read.
    let mut fields = Vec::new();
    let mut stride = 0;
    for ((ty, _), &slot) in props.iter().zip(slots) {
        if slot != Slot::Skip {
            fields.push((stride, *ty, slot));
        }
        stride += ty.size();
    }
    let mut points = Vec::with_capacity(records.len() / stride);
    for (i, rec) in records.chunks_exact(stride).enumerate() {
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
                Slot::Time => store_time(&mut p, ty.read_le(b), loc)?,
                _ => store_int(&mut p, slot, ty.read_le(b), loc)?,
            }
        }
        points.push(p);
    }
    Ok(points)
}

/// The record `specular convert` writes (`x y z intensity` as `float`,
/// `ring` as `ushort`, `return` and `label` as `uchar`: 20 bytes), in this
/// order.
const COMPACT: [(Scalar, Slot); 7] = [
    (Scalar::F32, Slot::X),
    (Scalar::F32, Slot::Y),
    (Scalar::F32, Slot::Z),
    (Scalar::F32, Slot::Intensity),
    (Scalar::U16, Slot::Ring),
    (Scalar::U8, Slot::Return),
    (Scalar::U8, Slot::Label),
];

/// Whether the vertex properties are exactly the [`COMPACT`] record.
fn is_compact(props: &[(Scalar, String)], slots: &[Slot]) -> bool {
    props.len() == COMPACT.len()
        && props
            .iter()
            .zip(slots)
            .zip(&COMPACT)
            .all(|(((ty, _), slot), (want_ty, want_slot))| ty == want_ty && slot == want_slot)
}

/// The points of [`COMPACT`] records, decoded without the general loop's
/// per-field dispatch (a tenth of its time on the converted 3DRef frames,
/// `cargo bench --bench parse`); `None` when a return or a label is out of
/// range, for the general loop to report.
fn parse_compact(records: &[u8]) -> Option<Vec<Point>> {
    let f = |b: &[u8], o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    let mut valid = true;
    let points: Vec<Point> = records
        .chunks_exact(20)
        .map(|r| {
            let (ret, label) = (r[18], r[19]);
            valid &= (1..=3).contains(&ret) && label <= 6;
            Point {
                xyz: [f(r, 0), f(r, 4), f(r, 8)],
                intensity: f(r, 12),
                ring: u16::from_le_bytes([r[16], r[17]]),
                ret,
                label,
                time: 0.0,
            }
        })
        .collect();
    valid.then_some(points)
}

#[cfg(test)]
mod tests {
    use super::*;

    proptest::proptest! {
        /// The compact records decode exactly as the general loop decodes
        /// them, and out-of-range returns and labels are left to it.
        #[test]
        fn compact_records_decode_as_the_general_loop(
            records in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..400),
            valid in proptest::prelude::any::<bool>(),
        ) {
            let mut records = records;
            records.truncate(records.len() / 20 * 20);
            if valid {
                for r in records.chunks_exact_mut(20) {
                    r[18] = 1 + r[18] % 2;
                    r[19] %= 7;
                }
            }
            let props: Vec<(Scalar, String)> =
                COMPACT.iter().map(|(ty, _)| (*ty, String::new())).collect();
            let slots: Vec<Slot> = COMPACT.iter().map(|(_, slot)| *slot).collect();
            let general = parse_records(&records, &props, &slots);
            match parse_compact(&records) {
                Some(points) => {
                    let general = general.expect("the general loop accepts them too");
                    proptest::prop_assert_eq!(points.len(), general.len());
                    for (a, b) in points.iter().zip(&general) {
                        // Bitwise: NaN payloads included.
                        proptest::prop_assert_eq!(a.xyz.map(f32::to_bits), b.xyz.map(f32::to_bits));
                        proptest::prop_assert_eq!(a.intensity.to_bits(), b.intensity.to_bits());
                        proptest::prop_assert_eq!((a.ring, a.ret, a.label), (b.ring, b.ret, b.label));
                    }
                }
                None => proptest::prop_assert!(general.is_err()),
            }
            if valid {
                proptest::prop_assert!(parse_compact(&records).is_some());
            }
        }
    }
}
