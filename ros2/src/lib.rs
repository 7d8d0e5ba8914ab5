//! whycode-ros2: a ROS 2 node for WhyCode markers, on ros2-client (RustDDS,
//! pure Rust), so that neither building nor running it needs a ROS
//! installation. It reads a camera topic and publishes each identified
//! marker's pose on /tf and the detections on `~/markers`.
//!
//! Modules by job: [`args`] (the ROS command line and name resolution),
//! [`params`] (parameters, and the one mapping to the library's detector
//! configuration), [`msg`] (the ROS message types), [`image`] (camera
//! messages to grey pixels), [`log`] (rclcpp-style log lines, once per
//! cause) and [`node`] (the DDS entities and the frame loop).

pub mod args;
pub mod image;
pub mod log;
pub mod msg;
pub mod node;
pub mod params;
