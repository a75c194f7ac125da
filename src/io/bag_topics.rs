//! The point-cloud topics of a bag gathered over its storage files: the
//! topic read (a `PointCloud2` or a Livox `CustomMsg`, [`MessageKind`])
//! and, for the Ouster driver, its second-return topic, paired into frames
//! by header stamp.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::bag_message::{check_custom_driver, check_type, MessageKind};
use super::pointcloud2::{decode, Decoded, Driver};
use crate::cloud::{Frame, SetAside};
use crate::{Error, Result};

/// How a bag's point clouds are read: the driver whose layout they have
/// and, for the Ouster driver, the topic of the second return.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BagOptions {
    /// The layout; `None` detects it from the first message's fields
    /// ([`Driver::detect`]). A message without the fields the named layout
    /// needs is an error naming the file, the topic and the fields.
    pub driver: Option<Driver>,
    /// The Ouster driver's second-return topic; `None` is the driver's own
    /// convention, the first topic with `2` appended (`/ouster/points` and
    /// `/ouster/points2`). Only the Ouster layout reads it.
    pub second_topic: Option<String>,
}

/// A second-topic message kept undecoded until the first topic's layout
/// is known: the file it came from, its bag time and its bytes.
type RawMessage = (PathBuf, i64, Vec<u8>);

/// The frames of one topic gathered over a bag's storage files, with every
/// topic seen on the way (for the error that lists them).
pub struct TopicFrames {
    topic: String,
    options: BagOptions,
    /// The second-return topic (given, or the Ouster convention).
    second: String,
    /// Whether the second topic, when not named, is a CDR `PointCloud2`.
    second_usable: bool,
    /// The layout, named or detected from the first message (always
    /// Livox for a `CustomMsg` topic).
    driver: Option<Driver>,
    /// The type of the topic read (`PointCloud2` until noted otherwise).
    kind: MessageKind,
    frames: Vec<Decoded>,
    seconds: Vec<RawMessage>,
    /// Topic name -> (type, messages).
    seen: BTreeMap<String, (String, usize)>,
}

impl TopicFrames {
    /// Gather the point clouds of `topic`, their layout detected.
    pub fn new(topic: &str) -> Self {
        Self::with_options(topic, BagOptions::default())
    }

    /// Gather the point clouds of `topic` read as `options` say.
    pub fn with_options(topic: &str, options: BagOptions) -> Self {
        let second = options
            .second_topic
            .clone()
            .unwrap_or_else(|| format!("{topic}2"));
        Self {
            topic: topic.to_string(),
            driver: options.driver,
            kind: MessageKind::PointCloud2,
            second_usable: true,
            second,
            options,
            frames: Vec::new(),
            seconds: Vec::new(),
            seen: BTreeMap::new(),
        }
    }

    /// The topic gathered.
    pub fn topic(&self) -> &str {
        &self.topic
    }

    /// Whether messages of topic `name` are gathered: the topic read, or
    /// the second-return topic (kept until the layout says whether it is
    /// read).
    pub fn wants(&self, name: &str) -> bool {
        name == self.topic || (name == self.second && self.second_usable && self.may_pair())
    }

    /// Whether the layout may be Ouster's (named, or not yet known).
    fn may_pair(&self) -> bool {
        matches!(self.driver, None | Some(Driver::Ouster))
    }

    /// Note `messages` messages of topic `name` of type `kind` serialized
    /// as `encoding` in the storage file `path`; the topic gathered must be
    /// a CDR point cloud of a supported type ([`MessageKind::of`]; a
    /// `CustomMsg` is read with the Livox layout, and another named driver
    /// is an error), a second topic named in the options a CDR
    /// `PointCloud2`; else the error names `path` and what it is.
    pub fn note(
        &mut self,
        path: &Path,
        name: &str,
        kind: &str,
        encoding: &str,
        messages: usize,
    ) -> Result<()> {
        let point_cloud2 = MessageKind::of(kind, encoding) == Some(MessageKind::PointCloud2);
        if name == self.topic {
            self.kind = check_type(path, name, kind, encoding)?;
            if self.kind == MessageKind::LivoxCustom {
                check_custom_driver(self.driver)
                    .map_err(|m| Error::format(path, format!("topic {name} is {kind}: {m}")))?;
                self.driver = Some(Driver::Livox);
            }
        } else if name == self.second && self.options.second_topic.is_some() {
            check_type(path, name, kind, encoding)?;
        } else if name == self.second && !point_cloud2 {
            self.second_usable = false;
        }
        let entry = self.seen.entry(name.to_string());
        entry.or_insert_with(|| (kind.to_string(), 0)).1 += messages;
        Ok(())
    }

    /// Decode one message of topic `name` (the topic gathered, or its
    /// second-return topic), found in `path` at `time_ns` (the bag's
    /// receive time, for the error message).
    pub fn push(&mut self, path: &Path, name: &str, time_ns: i64, data: &[u8]) -> Result<()> {
        if name != self.topic {
            if self.wants(name) {
                self.seconds
                    .push((path.to_path_buf(), time_ns, data.to_vec()));
            }
            return Ok(());
        }
        let decoded = self
            .kind
            .decode(data, self.driver, 1)
            .map_err(|m| Error::format(path, format!("{name} message at {time_ns} ns: {m}")))?;
        self.driver = Some(decoded.driver);
        self.frames.push(decoded);
        Ok(())
    }

    /// The topics seen, as `name (type, N messages)`, comma-separated.
    pub fn topic_list(&self) -> String {
        if self.seen.is_empty() {
            return "the bag has none".into();
        }
        let list: Vec<String> = self
            .seen
            .iter()
            .map(|(name, (kind, n))| format!("{name} ({kind}, {n} messages)"))
            .collect();
        list.join(", ")
    }

    /// The frames in timestamp order; an error naming `path` when the topic
    /// had no message (listing the topics present) or two messages share a
    /// header stamp (their frames would have the same name).
    pub fn finish(self, path: &Path) -> Result<Vec<Frame>> {
        Ok(self
            .finish_full(path)?
            .into_iter()
            .map(|(frame, _)| frame)
            .collect())
    }

    /// [`finish`](Self::finish), each frame with where its points set
    /// aside were. For the Ouster layout each frame holds the first topic's
    /// points (return 1) then those of the second topic's message with the
    /// same header stamp (return 2); a frame whose second message is
    /// missing keeps its first returns, a second message without a first
    /// is left out.
    pub fn finish_full(mut self, path: &Path) -> Result<Vec<(Frame, SetAside)>> {
        if self.frames.is_empty() {
            return Err(Error::format(
                path,
                format!(
                    "no messages on {}; topics: {}",
                    self.topic,
                    self.topic_list()
                ),
            ));
        }
        let driver = self.driver.unwrap_or(Driver::Generic);
        if driver == Driver::Ouster {
            self.pair_second_returns(path)?;
        } else if let Some(second) = &self.options.second_topic {
            return Err(Error::format(
                path,
                format!(
                    "a second-return topic ({second}) is read only for the ouster layout, but {} has the {driver} layout",
                    self.topic
                ),
            ));
        }
        let mut frames: Vec<(Frame, SetAside)> = self
            .frames
            .into_iter()
            .map(|d| (d.frame, d.aside))
            .collect();
        frames.sort_by(|a, b| a.0.stamp.total_cmp(&b.0.stamp));
        if let Some(w) = frames.windows(2).find(|w| w[0].0.name == w[1].0.name) {
            return Err(Error::format(
                path,
                format!(
                    "two messages on {} have the same header stamp {}",
                    self.topic, w[0].0.name
                ),
            ));
        }
        Ok(frames)
    }

    /// Decode the second-return messages (return 2, the Ouster layout) and
    /// append each to the frame of the same header stamp.
    fn pair_second_returns(&mut self, path: &Path) -> Result<()> {
        if self.seconds.is_empty() {
            return Err(Error::format(
                path,
                format!(
                    "{} has the ouster layout but there are no messages on its second-return topic {} (the driver publishes return 2 there); topics: {}. Name the topic with --second-topic, or read the first returns alone with --driver generic",
                    self.topic,
                    self.second,
                    self.topic_list()
                ),
            ));
        }
        let by_stamp: BTreeMap<(i32, u32), usize> = self
            .frames
            .iter()
            .enumerate()
            .map(|(i, d)| (d.stamp, i))
            .collect();
        for (file, time_ns, data) in std::mem::take(&mut self.seconds) {
            let second = decode(&data, Some(Driver::Ouster), 2).map_err(|m| {
                Error::format(
                    &file,
                    format!("{} message at {time_ns} ns: {m}", self.second),
                )
            })?;
            let Some(&i) = by_stamp.get(&second.stamp) else {
                continue;
            };
            let first = &mut self.frames[i];
            // Organized clouds pair a beam's returns by place; unorganized
            // ones (ouster-ros `organized: false`) drop invalid points, so
            // their lengths differ and each return is known by its topic.
            if first.shape.0 > 1 && first.shape != second.shape {
                return Err(Error::format(
                    &file,
                    format!(
                        "{} message at {time_ns} ns is {}x{} but its first-return message on {} is {}x{}: the two returns of a beam are paired by their place in the organized cloud",
                        self.second,
                        second.shape.0,
                        second.shape.1,
                        self.topic,
                        first.shape.0,
                        first.shape.1
                    ),
                ));
            }
            append(first, second);
        }
        Ok(())
    }
}

/// `second`'s points after `first`'s: the frame, the points set aside (at
/// their input positions after all of `first`'s) and the count.
fn append(first: &mut Decoded, second: Decoded) {
    let inputs = (first.frame.points.len() + first.aside.len()) as u32;
    let f = &mut first.frame;
    f.points.extend(second.frame.points);
    f.has_labels |= second.frame.has_labels;
    f.dropped_non_finite += second.frame.dropped_non_finite;
    let aside = &mut first.aside;
    aside
        .positions
        .extend(second.aside.positions.iter().map(|p| p + inputs));
    aside.labels.extend(second.aside.labels);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::pointcloud2::RawCloud;

    /// An unorganized Ouster cloud (x y z intensity t reflectivity ring, 24
    /// bytes) of `n` points on row 3.
    fn ouster(n: u32) -> Vec<u8> {
        let fields = [
            ("x", 0, 7),
            ("y", 4, 7),
            ("z", 8, 7),
            ("intensity", 12, 7),
            ("t", 16, 6),
            ("reflectivity", 20, 4),
            ("ring", 22, 4),
        ];
        let mut data = Vec::new();
        for i in 0..n {
            for v in [1.0 + i as f32, 0.5, 0.25, 9.0] {
                data.extend_from_slice(&v.to_le_bytes());
            }
            data.extend_from_slice(&[0, 0, 0, 0, 0, 0, 3, 0]);
        }
        let cloud = RawCloud {
            sec: 5,
            nanosec: 0,
            frame_id: "os_lidar",
            height: 1,
            width: n,
            fields: &fields,
            point_step: 24,
            data: &data,
            is_dense: true,
        };
        cloud.encode()
    }

    #[test]
    fn unorganized_ouster_returns_are_paired_by_stamp_alone() {
        let path = Path::new("bag.mcap");
        let mut frames = TopicFrames::new("/ouster/points");
        frames.push(path, "/ouster/points", 0, &ouster(3)).unwrap();
        frames.push(path, "/ouster/points2", 0, &ouster(2)).unwrap();
        let out = frames.finish(path).unwrap();
        let rets: Vec<u8> = out[0].points.iter().map(|p| p.ret).collect();
        assert_eq!(rets, [1, 1, 1, 2, 2]);
        // Row 3 of at least 16 rows, counted from the bottom.
        assert!(out[0].points.iter().all(|p| p.ring == 12));
    }
}
