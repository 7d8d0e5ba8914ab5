//! ROS 2 messages, in one place for the ROS 2 node (which sends and reads
//! them over DDS) and for bags (which the command line reads and writes):
//! the message types ([`msg`]), camera messages to grey pixels ([`image`]),
//! detections to `/tf` and marker arrays ([`describe`]) and CDR as bags
//! store it ([`cdr`]). Feature `ros`.

pub mod cdr;
pub mod describe;
pub mod image;
pub mod msg;

/// A marker's /tf frame is this followed by its ID, unless named otherwise.
pub const DEFAULT_FRAME_PREFIX: &str = "whycode_";

/// The arena's floor frame on /tf (`whycode arena`'s arena), unless named.
pub const DEFAULT_ARENA_FRAME: &str = "arena";

/// The camera_info topic of an image topic, by image_transport's rule: the
/// compressed topic hangs below the image topic, and camera_info sits
/// beside the image topic (`/cam/image_raw/compressed` → `/cam/camera_info`).
pub fn camera_info_beside(image_topic: &str) -> String {
    let image = image_topic
        .strip_suffix("/compressed")
        .unwrap_or(image_topic);
    match image.rsplit_once('/') {
        Some(("", _)) | None => "/camera_info".to_string(),
        Some((parent, _)) => format!("{parent}/camera_info"),
    }
}

#[cfg(test)]
mod tests {
    use super::camera_info_beside;

    #[test]
    fn camera_info_sits_beside_the_image_topic() {
        assert_eq!(camera_info_beside("/cam/image_raw"), "/cam/camera_info");
        assert_eq!(
            camera_info_beside("/robot/cam/image_raw/compressed"),
            "/robot/cam/camera_info"
        );
        assert_eq!(camera_info_beside("/image"), "/camera_info");
    }
}
