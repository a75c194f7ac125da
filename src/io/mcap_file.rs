//! One MCAP file (a bag's storage file, or a bag of its own): its
//! point-cloud messages (`PointCloud2` or Livox `CustomMsg`, the type from
//! the channel's schema name) gathered into a [`TopicFrames`].
//!
//! Read with the mcap crate's sans-io reader and a record length limit, and
//! every chunk's claimed size checked before it is decompressed: a damaged
//! length field is an error naming the file, never an allocation of
//! exabytes (`mcap::MessageStream` sets no limit; the fuzz test of issue 39
//! found one that aborted the process).

use std::collections::HashMap;
use std::path::Path;

use super::bag_topics::TopicFrames;
use super::ros2_bag::MCAP_MAGIC;
use crate::{Error, Result};

/// Gather the messages of an MCAP file (one file of a bag, or a bag of
/// its own).
pub fn read_mcap(path: &Path, frames: &mut TopicFrames) -> Result<()> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    if !bytes.starts_with(MCAP_MAGIC) {
        return Err(Error::format(path, "not an MCAP file"));
    }
    let largest =
        check_mcap_chunks(&bytes).map_err(|m| Error::format(path, format!("MCAP: {m}")))?;
    let mcap_error = |e: mcap::McapError| Error::format(path, format!("MCAP: {e}"));
    // The records are read with the sans-io reader and a record length
    // limit (no record is longer than the file, or than the largest
    // chunk's contents): `mcap::MessageStream` sets none, and a damaged
    // length inside a chunk made it allocate exabytes (an abort).
    let options = mcap::sans_io::LinearReaderOptions::default()
        .with_record_length_limit(bytes.len().max(largest));
    let mut reader = mcap::sans_io::LinearReader::new_with_options(options);
    let mut rest = &bytes[..];
    let mut schemas: HashMap<u16, String> = HashMap::new();
    // Channel id -> (topic, schema id, message encoding).
    let mut channels: HashMap<u16, (String, u16, String)> = HashMap::new();
    while let Some(event) = reader.next_event() {
        match event.map_err(mcap_error)? {
            mcap::sans_io::LinearReadEvent::ReadRequest(need) => {
                let n = need.min(rest.len());
                reader.insert(n).copy_from_slice(&rest[..n]);
                reader.notify_read(n);
                rest = &rest[n..];
            }
            mcap::sans_io::LinearReadEvent::Record { data, opcode } => {
                match mcap::parse_record(opcode, data).map_err(mcap_error)? {
                    mcap::records::Record::Schema { header, .. } => {
                        schemas.insert(header.id, header.name);
                    }
                    mcap::records::Record::Channel(c) => {
                        channels.insert(c.id, (c.topic, c.schema_id, c.message_encoding));
                    }
                    mcap::records::Record::Message { header, data } => {
                        let Some((topic, schema, encoding)) = channels.get(&header.channel_id)
                        else {
                            return Err(Error::format(
                                path,
                                format!(
                                    "MCAP: a message on channel {}, which no channel record declares",
                                    header.channel_id
                                ),
                            ));
                        };
                        let kind = schemas.get(schema).map_or("schemaless", String::as_str);
                        frames.note(path, topic, kind, encoding, 1)?;
                        if frames.wants(topic) {
                            frames.push(path, topic, header.log_time as i64, &data)?;
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// The most a chunk may expand when decompressed, as a multiple of its
/// compressed size (zstd on point clouds gives a few times; far more is a
/// damaged length field).
const MAX_CHUNK_EXPANSION: u64 = 256;

/// Walk the records of an MCAP file and check every chunk's claimed
/// uncompressed size against its compressed size ([`MAX_CHUNK_EXPANSION`]),
/// before the mcap reader allocates that much: a flipped byte in that
/// field asked it for exabytes (a capacity-overflow panic, or an abort).
/// A record that does not fit the file ends the walk (the reader reports
/// it), after its chunk header, if it is one, is checked against the bytes
/// that are there. Returns the largest uncompressed size a chunk claims.
fn check_mcap_chunks(bytes: &[u8]) -> std::result::Result<usize, String> {
    const CHUNK: u8 = 0x06;
    let u64_at = |at: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(at..at + 8)?.try_into().ok()?))
    };
    let u32_at = |at: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
    };
    let mut pos = MCAP_MAGIC.len();
    let mut largest = 0u64;
    while pos + 9 <= bytes.len() {
        let opcode = bytes[pos];
        let Some(len) = u64_at(pos + 1) else { break };
        let body = pos + 9;
        let end = usize::try_from(len)
            .ok()
            .and_then(|l| body.checked_add(l))
            .filter(|&e| e <= bytes.len());
        let len = match end {
            Some(_) => len,
            None => bytes.len().saturating_sub(body) as u64,
        };
        if opcode == CHUNK {
            // start time, end time, uncompressed size, crc, compression
            // (a string), then the records' length and bytes.
            let uncompressed = u64_at(body + 16).unwrap_or(0);
            let compression = u32_at(body + 28).unwrap_or(0) as usize;
            let records = body
                .checked_add(32)
                .and_then(|p| p.checked_add(compression))
                .and_then(u64_at)
                .unwrap_or(0);
            let compressed = records.min(len);
            if uncompressed > compressed.saturating_mul(MAX_CHUNK_EXPANSION).max(1 << 20) {
                return Err(format!(
                    "a chunk at byte {pos} claims {uncompressed} bytes uncompressed from {compressed}: the file is damaged"
                ));
            }
            largest = largest.max(uncompressed);
        }
        let Some(end) = end else { break };
        pos = end;
    }
    Ok(usize::try_from(largest).unwrap_or(usize::MAX))
}
