//! The Foxglove WebSocket protocol (`foxglove.websocket.v1`, the spec of
//! github.com/foxglove/ws-protocol), the parts a server that only
//! publishes needs: its server info, its channels' advertisement, the
//! client's subscribe and unsubscribe, and message data frames. Pure
//! functions over text and bytes: the socket is the caller's
//! (`locus-serve`'s axum server).

use alloc::collections::BTreeMap;

use serde::Deserialize;
use serde_json::json;

use crate::encode::Message;
use crate::topic::{MESSAGE_ENCODING, SCHEMA_ENCODING, Topic};

/// The subprotocol a client asks for and the server selects.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";
/// Opcode of a binary Message Data frame.
const MESSAGE_DATA: u8 = 0x01;
/// The most subscriptions one client may hold (one per channel is all a
/// well-behaved client needs).
pub const MAX_SUBSCRIPTIONS: usize = 64;

/// The Server Info message, sent first on every connection.
#[must_use]
pub fn server_info(name: &str, session: &str) -> String {
    json!({
        "op": "serverInfo",
        "name": name,
        "capabilities": [],
        "metadata": {},
        "sessionId": session,
    })
    .to_string()
}

/// A topic's channel id: its place in [`Topic::ALL`], from 1.
#[must_use]
pub fn channel_id(topic: Topic) -> u32 {
    // ALL has 10 entries.
    #[allow(clippy::cast_possible_truncation)]
    let i = topic.index() as u32;
    i + 1
}

/// The Advertise message for every topic.
#[must_use]
pub fn advertise() -> String {
    let channels: Vec<_> = Topic::ALL
        .iter()
        .map(|&t| {
            let s = t.schema();
            json!({
                "id": channel_id(t),
                "topic": t.name(),
                "encoding": MESSAGE_ENCODING,
                "schemaName": s.name,
                "schema": s.data,
                "schemaEncoding": SCHEMA_ENCODING,
            })
        })
        .collect();
    json!({ "op": "advertise", "channels": channels }).to_string()
}

/// A Status message: `level` 0 info, 1 warning, 2 error.
#[must_use]
pub fn status(level: u8, message: &str) -> String {
    json!({ "op": "status", "level": level, "message": message }).to_string()
}

#[derive(Deserialize)]
#[serde(tag = "op", rename_all = "camelCase")]
enum ClientOp {
    Subscribe {
        subscriptions: Vec<Subscription>,
    },
    Unsubscribe {
        #[serde(rename = "subscriptionIds")]
        subscription_ids: Vec<u32>,
    },
}

#[derive(Deserialize)]
struct Subscription {
    id: u32,
    #[serde(rename = "channelId")]
    channel_id: u32,
}

/// One client's subscriptions: which subscription id receives each
/// channel.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Subscriptions {
    by_channel: BTreeMap<u32, u32>,
}

impl Subscriptions {
    /// Applies a text message from the client. Returns a Status message to
    /// send back when the message is not understood or asks for what does
    /// not exist (the connection stays open: the spec's "may ignore").
    pub fn apply(&mut self, text: &str) -> Option<String> {
        let op: ClientOp = match serde_json::from_str(text) {
            Ok(op) => op,
            Err(e) => {
                return Some(status(1, &format!("ignored a client message: {e}")));
            }
        };
        match op {
            ClientOp::Subscribe { subscriptions } => {
                let mut refused = Vec::new();
                for s in subscriptions {
                    let known = (1..=Topic::ALL.len()).any(|c| c as u32 == s.channel_id);
                    let reused = self.by_channel.values().any(|&id| id == s.id);
                    if !known || reused || self.by_channel.len() >= MAX_SUBSCRIPTIONS {
                        refused.push(s.channel_id);
                    } else {
                        self.by_channel.insert(s.channel_id, s.id);
                    }
                }
                (!refused.is_empty()).then(|| {
                    status(
                        1,
                        &format!("refused subscriptions to channels {refused:?}: unknown channel or reused id"),
                    )
                })
            }
            ClientOp::Unsubscribe { subscription_ids } => {
                self.by_channel
                    .retain(|_, id| !subscription_ids.contains(id));
                None
            }
        }
    }

    /// The Message Data frame of `m` for this client, if it subscribed to
    /// its topic.
    #[must_use]
    pub fn frame(&self, m: &Message) -> Option<Vec<u8>> {
        let id = *self.by_channel.get(&channel_id(m.topic))?;
        Some(message_data(id, m.time, &m.payload))
    }

    /// Whether the client subscribed to nothing.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.by_channel.is_empty()
    }
}

/// A Message Data frame: opcode, subscription id, time (ns), payload.
#[must_use]
pub fn message_data(subscription: u32, time: u64, payload: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(13 + payload.len());
    out.push(MESSAGE_DATA);
    out.extend_from_slice(&subscription.to_le_bytes());
    out.extend_from_slice(&time.to_le_bytes());
    out.extend_from_slice(payload);
    out
}
