//! Connect-time compatibility check: protocol version and schema hash.

use crate::messages::{Hello, HelloRequest, SCHEMA_HASH};
use crate::PROTOCOL_VERSION;

/// Why the peer is not compatible. Its `Display` is meant for an operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandshakeError {
    /// Different frame/protocol version: the peers cannot talk; update one of them.
    VersionMismatch { ours: u8, theirs: u8 },
    /// Same version but different message definitions (schema hash): payloads would misdecode.
    SchemaMismatch { ours: u32, theirs: u32 },
}

impl core::fmt::Display for HandshakeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HandshakeError::VersionMismatch { ours, theirs } => write!(
                f,
                "link protocol version mismatch: this side speaks v{ours}, the peer v{theirs}; \
                 build both from the same fcc_msgs"
            ),
            HandshakeError::SchemaMismatch { ours, theirs } => write!(
                f,
                "link schema mismatch: this side 0x{ours:08x}, the peer 0x{theirs:08x} \
                 (same protocol version, different message definitions); build both from the same fcc_msgs"
            ),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for HandshakeError {}

/// Check a peer's version and schema hash against ours.
pub fn check_peer(protocol_version: u8, schema_hash: u32) -> Result<(), HandshakeError> {
    if protocol_version != PROTOCOL_VERSION {
        Err(HandshakeError::VersionMismatch {
            ours: PROTOCOL_VERSION,
            theirs: protocol_version,
        })
    } else if schema_hash != SCHEMA_HASH {
        Err(HandshakeError::SchemaMismatch {
            ours: SCHEMA_HASH,
            theirs: schema_hash,
        })
    } else {
        Ok(())
    }
}

impl Hello {
    /// Our `Hello` with the given firmware version.
    pub const fn ours(firmware_version: [u8; 3]) -> Self {
        Hello {
            protocol_version: PROTOCOL_VERSION,
            schema_hash: SCHEMA_HASH,
            firmware_version,
        }
    }
    /// Is the MCU that sent this compatible with us?
    pub fn check(&self) -> Result<(), HandshakeError> {
        check_peer(self.protocol_version, self.schema_hash)
    }
}

impl HelloRequest {
    /// Our request.
    pub const fn ours() -> Self {
        HelloRequest {
            protocol_version: PROTOCOL_VERSION,
            schema_hash: SCHEMA_HASH,
        }
    }
    /// Is the Linux side that sent this compatible with us?
    pub fn check(&self) -> Result<(), HandshakeError> {
        check_peer(self.protocol_version, self.schema_hash)
    }
}
