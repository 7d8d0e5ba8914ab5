//! CDR as bags store ROS 2 messages: the encapsulation header (little-endian
//! CDR) followed by the message in the layout DDS puts on the wire, through
//! the `cdr` crate.

use serde::de::DeserializeOwned;
use serde::Serialize;

/// A message that does not decode as the type its channel names.
#[derive(Debug, thiserror::Error)]
#[error("message does not decode as CDR: {0}")]
pub struct CdrError(#[source] cdr::Error);

/// The message as a bag stores it, encapsulation header first.
pub fn encode<T: Serialize>(message: &T) -> Vec<u8> {
    cdr::serialize::<_, _, cdr::CdrLe>(message, cdr::Infinite)
        .expect("the messages in crate::ros::msg serialise without limits")
}

/// A message from a bag's bytes (either byte order: the header says which).
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, CdrError> {
    cdr::deserialize(bytes).map_err(CdrError)
}
