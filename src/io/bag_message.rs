//! The message types a bag's point-cloud topic may hold, and how a message
//! of each becomes a frame: `sensor_msgs/msg/PointCloud2` in any driver's
//! layout ([`super::pointcloud2`]) and the Livox drivers' `CustomMsg`
//! ([`super::livox_custom`]), both in CDR.

use std::path::Path;

use super::livox_custom::{decode_custom_msg, is_custom_msg, CUSTOM_MSG_TYPES};
use super::pointcloud2::{decode, Decoded, Driver, POINTCLOUD2};
use crate::{Error, Result};

/// The types a point-cloud topic may have, for messages.
pub fn supported_types() -> String {
    format!(
        "{POINTCLOUD2}, {} or {}",
        CUSTOM_MSG_TYPES[0], CUSTOM_MSG_TYPES[1]
    )
}

/// A point-cloud topic's message type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MessageKind {
    /// `sensor_msgs/msg/PointCloud2`, read with a driver's field layout.
    PointCloud2,
    /// A Livox `CustomMsg` (either package's), always the Livox layout.
    LivoxCustom,
}

impl MessageKind {
    /// The kind of a topic of type `kind` serialized as `encoding`; `None`
    /// for any other type or encoding than CDR.
    pub fn of(kind: &str, encoding: &str) -> Option<MessageKind> {
        if encoding != "cdr" {
            return None;
        }
        if kind == POINTCLOUD2 {
            Some(MessageKind::PointCloud2)
        } else if is_custom_msg(kind) {
            Some(MessageKind::LivoxCustom)
        } else {
            None
        }
    }

    /// Decode one message with `driver`'s layout (for a `PointCloud2`,
    /// detected when `None`; `ret` the return of a layout without one). A
    /// `CustomMsg` is always read as [`Driver::Livox`]: another named
    /// driver is an error.
    pub fn decode(self, data: &[u8], driver: Option<Driver>, ret: u8) -> Result<Decoded, String> {
        match self {
            MessageKind::PointCloud2 => decode(data, driver, ret),
            MessageKind::LivoxCustom => {
                check_custom_driver(driver)?;
                decode_custom_msg(data)
            }
        }
    }
}

/// A `CustomMsg` is read with the Livox layout: an error naming another.
pub fn check_custom_driver(driver: Option<Driver>) -> Result<(), String> {
    match driver {
        None | Some(Driver::Livox) => Ok(()),
        Some(d) => Err(format!(
            "a Livox CustomMsg is read with the livox layout, not {d} (give --driver livox, or no --driver)"
        )),
    }
}

/// The topic read must be a CDR point cloud of a supported type
/// ([`MessageKind::of`]): else an error naming `path`, the topic, its type
/// and the supported types.
pub(crate) fn check_type(
    path: &Path,
    topic: &str,
    kind: &str,
    encoding: &str,
) -> Result<MessageKind> {
    MessageKind::of(kind, encoding).ok_or_else(|| {
        Error::format(
            path,
            format!(
                "topic {topic} is {kind} in {encoding}, not {} in cdr (the types specular reads)",
                supported_types()
            ),
        )
    })
}
