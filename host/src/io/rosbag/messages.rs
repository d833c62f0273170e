//! The schema, channel and message records of a bag: which channel is the wanted
//! `sensor_msgs/msg/JointState` topic ([`Channels`]), and each of its messages decoded into a
//! [`JointReading`] (stamp relative to the topic's first message; rad -> deg, m -> mm for
//! prismatic joints) or counted as skipped.

use std::path::Path;

use mcap::records::Record;

use super::{BagError, BagSummary, JointLogSpec, JointReading, JOINT_STATE_TYPE};
use crate::io::cdr::decode_joint_state;

pub(super) struct State<'s, 'a> {
    pub(super) spec: &'s JointLogSpec<'a>,
    /// Stamp of the topic's first decodable message, ns.
    pub(super) first_stamp_ns: Option<i64>,
    /// Every topic seen, for messages.
    pub(super) topics: Vec<String>,
}

/// The schemas and channels of one file.
#[derive(Default)]
pub(super) struct Channels {
    /// Per channel id: whether it is the wanted JointState topic.
    wanted: std::collections::HashMap<u16, bool>,
    schemas: std::collections::HashMap<u16, String>,
}

impl Channels {
    /// A schema, channel or message record (of the file or of a chunk).
    pub(super) fn record<E: From<BagError>>(
        &mut self,
        record: Record,
        file: &Path,
        state: &mut State,
        summary: &mut BagSummary,
        each: &mut impl FnMut(JointReading) -> Result<(), E>,
    ) -> Result<(), E> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                if !state.topics.contains(&c.topic) {
                    state.topics.push(c.topic.clone());
                }
                let wanted = c.topic == state.spec.topic;
                if wanted {
                    let found = self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                    if found != JOINT_STATE_TYPE || c.message_encoding != "cdr" {
                        return Err(BagError::TopicType {
                            path: file.to_path_buf(),
                            topic: c.topic,
                            found,
                            encoding: c.message_encoding,
                        }
                        .into());
                    }
                }
                self.wanted.insert(c.id, wanted);
            }
            Record::Message { header, data } => {
                if self.wanted.get(&header.channel_id) == Some(&true) {
                    summary.topic_messages += 1;
                    message(&data, state, summary, each)?;
                } else {
                    summary.other_messages += 1;
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// One message of the wanted topic.
fn message<E: From<BagError>>(
    data: &[u8],
    state: &mut State,
    summary: &mut BagSummary,
    each: &mut impl FnMut(JointReading) -> Result<(), E>,
) -> Result<(), E> {
    let n = summary.topic_messages;
    let msg = match decode_joint_state(data) {
        Ok(m) => m,
        Err(e) => {
            summary.undecodable += 1;
            if summary.first_undecodable.is_none() {
                summary.first_undecodable = Some((n, e.to_string()));
            }
            return Ok(());
        }
    };
    // t counts from the first message on the topic (FORMATS.md), used or not.
    let stamp = msg.stamp_ns();
    let first = *state.first_stamp_ns.get_or_insert(stamp);
    let spec = state.spec;
    let mut q = Vec::with_capacity(spec.names.len());
    for (k, name) in spec.names.iter().enumerate() {
        let v = msg
            .names
            .iter()
            .position(|m| m == name)
            .and_then(|i| msg.position.get(i))
            .copied()
            .filter(|v| v.is_finite());
        match v {
            Some(v) => q.push(if spec.prismatic.get(k).copied().unwrap_or(false) {
                v * 1e3
            } else {
                v.to_degrees()
            }),
            None => {
                summary.skipped_missing += 1;
                if summary.first_missing.is_none() {
                    summary.first_missing = Some((n, name.clone()));
                }
                return Ok(());
            }
        }
    }
    summary.used += 1;
    each(JointReading {
        message: n,
        t_s: (stamp - first) as f64 / 1e9,
        q,
    })
}
