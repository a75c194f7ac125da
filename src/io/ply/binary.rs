//! The `binary_little_endian` body: fixed-size records, read in place.

use super::header::{Element, Header, Scalar};
use super::vertex::{store_int, truncated, Loc, Slot, VertexLayout};
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
