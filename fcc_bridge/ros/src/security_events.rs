//! DDS Security events (issue 19): what the participant's security plugins refused, counted
//! for `/diagnostics` and told once each on `/rosout`.
//!
//! | event (rustdds participant status) | counted as |
//! |---|---|
//! | `Authentication { status: Rejected }`: identity or handshake failed (no certificate, another CA, expired) | `participants_rejected` |
//! | `RemoteEndpointDenied` (vendored rustdds): access control refused a remote reader or writer (its permissions do not grant the topic) | `readers_denied` / `writers_denied` |
//!
//! Each remote participant or endpoint counts once, however often discovery repeats it. The
//! events reach the node through ros2-client's status channel ([`ros2_client::NodeEvent`]),
//! which needs the node's spinner running; [`watch`] drains it on a thread of its own.

use ros2_client::dds::{Node, NodeEvent, SecurityEvent};
use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};

/// The security events seen so far.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SecurityCounts {
    pub participants_rejected: u64,
    pub writers_denied: u64,
    pub readers_denied: u64,
    /// The last event, as told on `/rosout`.
    pub last: Option<String>,
    seen: BTreeSet<String>,
}

/// The counts, shared between the watcher thread and the node's `/diagnostics`.
pub type SharedSecurityCounts = Arc<Mutex<SecurityCounts>>;

impl SecurityCounts {
    /// Counts `e` unless its participant or endpoint was counted before; returns the line to
    /// tell when it is new.
    pub fn count(&mut self, e: &SecurityEvent) -> Option<String> {
        let (key, line) = match e {
            SecurityEvent::ParticipantRejected { participant } => (
                format!("p {participant}"),
                format!(
                    "DDS Security: participant {participant} refused (authentication failed): \
                     it discovers nothing and nothing of it is matched"
                ),
            ),
            SecurityEvent::EndpointDenied {
                participant,
                endpoint,
                topic_name,
                is_writer,
            } => (
                format!("e {endpoint}"),
                format!(
                    "DDS Security: {} of participant {participant} on {topic_name} denied by \
                     access control (its permissions do not grant it): not matched",
                    if *is_writer { "writer" } else { "reader" },
                ),
            ),
        };
        if !self.seen.insert(key) {
            return None;
        }
        match e {
            SecurityEvent::ParticipantRejected { .. } => self.participants_rejected += 1,
            SecurityEvent::EndpointDenied {
                is_writer: true, ..
            } => self.writers_denied += 1,
            SecurityEvent::EndpointDenied { .. } => self.readers_denied += 1,
        }
        self.last = Some(line.clone());
        Some(line)
    }
}

/// Drains `node`'s status events on a thread of its own, counting the security events and
/// calling `tell` with each new one's line (the node's WARN log, hence `/rosout`). `None` when
/// the node has no running spinner (no events would come).
pub fn watch(node: &Node, tell: impl Fn(&str) + Send + 'static) -> Option<SharedSecurityCounts> {
    let rx = node.status_receiver()?;
    let counts = SharedSecurityCounts::default();
    let c = counts.clone();
    std::thread::Builder::new()
        .name("security-events".into())
        .spawn(move || {
            while let Ok(ev) = rx.recv_blocking() {
                if let NodeEvent::Security(e) = ev {
                    let new = c.lock().map(|mut k| k.count(&e)).ok().flatten();
                    if let Some(line) = new {
                        tell(&line);
                    }
                }
            }
        })
        .ok()?;
    Some(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_participant_and_endpoint_counts_once() {
        let mut c = SecurityCounts::default();
        let rejected = SecurityEvent::ParticipantRejected {
            participant: "GuidPrefix {01020304}".into(),
        };
        assert!(c
            .count(&rejected)
            .unwrap()
            .contains("authentication failed"));
        assert!(c.count(&rejected).is_none());
        let w = SecurityEvent::EndpointDenied {
            participant: "GuidPrefix {05060708}".into(),
            endpoint: "GUID {05060708 000102}".into(),
            topic_name: "rt/fcc/cmd/arm".into(),
            is_writer: true,
        };
        let line = c.count(&w).unwrap();
        assert!(
            line.contains("writer") && line.contains("rt/fcc/cmd/arm"),
            "{line}"
        );
        assert!(c.count(&w).is_none());
        assert_eq!(
            (c.participants_rejected, c.writers_denied, c.readers_denied),
            (1, 1, 0)
        );
        assert_eq!(c.last.as_deref(), Some(line.as_str()));
    }
}
