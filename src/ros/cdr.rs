//! CDR as bags store ROS 2 messages: the encapsulation header (little-endian
//! CDR) followed by the message in the layout DDS puts on the wire, through
//! the `cdr` crate.

use serde::de::DeserializeOwned;
use serde::Serialize;

/// A message that does not decode as the type its channel names.
#[derive(Debug, thiserror::Error)]
pub enum CdrError {
    /// The `cdr` crate's decoder refused it.
    #[error("message does not decode as CDR: {0}")]
    Decode(#[source] cdr::Error),
    /// A string, byte array or sequence declares more than the message
    /// holds.
    #[error("message declares {what} of {declared} bytes, but only {present} bytes follow")]
    Length {
        /// Which kind of field.
        what: &'static str,
        /// The length it declares, bytes.
        declared: u64,
        /// The bytes left in the message.
        present: u64,
    },
}

/// The message as a bag stores it, encapsulation header first.
pub fn encode<T: Serialize>(message: &T) -> Vec<u8> {
    cdr::serialize::<_, _, cdr::CdrLe>(message, cdr::Infinite)
        .expect("the messages in crate::ros::msg serialise without limits")
}

/// A message from a bag's bytes (either byte order: the header says which).
/// Every length the message declares is checked against the bytes present
/// first: the decoder allocates what a length says before it reads, so a
/// 100-byte message claiming a 4 GB image would take 4 GB.
pub fn decode<T: DeserializeOwned + Layout>(bytes: &[u8]) -> Result<T, CdrError> {
    check_lengths(bytes, T::LAYOUT)?;
    cdr::deserialize(bytes).map_err(CdrError::Decode)
}

/// One field of a message as CDR lays it out (nested structs flattened:
/// CDR aligns each primitive to its own size, never a struct as a whole).
#[derive(Debug, Clone, Copy)]
pub enum Field {
    /// One byte (`uint8`, `bool`).
    U8,
    /// Four bytes (`int32`, `uint32`).
    U32,
    /// `n` doubles in a fixed-size array.
    F64s(usize),
    /// A string: a 4-byte length, then that many bytes.
    Str,
    /// A byte sequence (`uint8[]`): a 4-byte length, then the bytes.
    Bytes,
    /// A double sequence (`float64[]`): a 4-byte count, then the doubles.
    F64Seq,
}

/// The CDR layout of a message type the bag reader decodes.
pub trait Layout {
    /// Its fields in order.
    const LAYOUT: &'static [Field];
}

/// `std_msgs/Header`: the stamp's two words, the frame ID.
const HEADER: [Field; 3] = [Field::U32, Field::U32, Field::Str];

/// `[HEADER, rest]` as one slice, in a constant.
macro_rules! after_header {
    ($($field:expr),* $(,)?) => {
        &[HEADER[0], HEADER[1], HEADER[2], $($field),*]
    };
}

// The layouts follow the field order of `super::msg`'s structs; the tests
// round-trip each type through them.
impl Layout for super::msg::Image {
    const LAYOUT: &'static [Field] = after_header![
        Field::U32, // height
        Field::U32, // width
        Field::Str, // encoding
        Field::U8,  // is_bigendian
        Field::U32, // step
        Field::Bytes,
    ];
}

impl Layout for super::msg::CompressedImage {
    const LAYOUT: &'static [Field] = after_header![Field::Str, Field::Bytes];
}

impl Layout for super::msg::CameraInfo {
    const LAYOUT: &'static [Field] = after_header![
        Field::U32, // height
        Field::U32, // width
        Field::Str, // distortion_model
        Field::F64Seq,
        Field::F64s(9),
        Field::F64s(9),
        Field::F64s(12),
        Field::U32, // binning_x
        Field::U32, // binning_y
        Field::U32, // roi
        Field::U32,
        Field::U32,
        Field::U32,
        Field::U8, // do_rectify
    ];
}

/// Walks `bytes` by `layout` and refuses a length beyond the bytes left. A
/// message too short for its fixed fields is left to the decoder, whose
/// error says so.
fn check_lengths(bytes: &[u8], layout: &[Field]) -> Result<(), CdrError> {
    // The encapsulation header: byte 1 odd is little-endian.
    let Some((header, body)) = bytes.split_at_checked(4) else {
        return Ok(());
    };
    let little = header[1] & 1 == 1;
    let mut pos = 0usize;
    let align = |pos: usize, n: usize| pos.div_ceil(n) * n;
    let length_at = |pos: usize| -> Option<u64> {
        let word: [u8; 4] = body.get(pos..pos + 4)?.try_into().ok()?;
        Some(u64::from(if little {
            u32::from_le_bytes(word)
        } else {
            u32::from_be_bytes(word)
        }))
    };
    for field in layout {
        let (what, element) = match field {
            Field::U8 => {
                pos += 1;
                continue;
            }
            Field::U32 => {
                pos = align(pos, 4) + 4;
                continue;
            }
            Field::F64s(n) => {
                pos = align(pos, 8) + 8 * n;
                continue;
            }
            Field::Str => ("a string", 1),
            Field::Bytes => ("a byte array", 1),
            Field::F64Seq => ("a sequence", 8),
        };
        pos = align(pos, 4);
        let Some(count) = length_at(pos) else {
            return Ok(());
        };
        pos += 4;
        if element == 8 && count > 0 {
            pos = align(pos, 8);
        }
        let declared = count * element;
        let present = body.len().saturating_sub(pos) as u64;
        if declared > present {
            return Err(CdrError::Length {
                what,
                declared,
                present,
            });
        }
        pos += declared as usize;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ros::msg::{CameraInfo, CompressedImage, Header, Image};

    #[test]
    fn sound_messages_pass_and_a_length_past_the_end_is_refused_before_allocating() {
        let image = Image {
            header: Header {
                frame_id: "cam".into(),
                ..Header::default()
            },
            height: 2,
            width: 3,
            encoding: "mono8".into(),
            step: 3,
            data: vec![7; 6],
            ..Image::default()
        };
        let bytes = encode(&image);
        assert_eq!(decode::<Image>(&bytes).unwrap(), image);
        let info = CameraInfo {
            d: vec![0.1, 0.2, 0.0, 0.0, 0.0],
            distortion_model: "plumb_bob".into(),
            ..CameraInfo::default()
        };
        assert_eq!(decode::<CameraInfo>(&encode(&info)).unwrap(), info);
        let compressed = CompressedImage {
            format: "png".into(),
            data: vec![1, 2, 3],
            ..CompressedImage::default()
        };
        let mut bytes = encode(&compressed);
        assert_eq!(decode::<CompressedImage>(&bytes).unwrap(), compressed);
        // The data's length word sits 4 + 3 bytes before the end.
        let at = bytes.len() - 7;
        bytes[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let err = decode::<CompressedImage>(&bytes).unwrap_err().to_string();
        assert_eq!(
            err,
            "message declares a byte array of 4294967295 bytes, but only 3 bytes follow"
        );
    }
}
